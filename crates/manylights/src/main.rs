//! `manylights`: render, inspect and list scenes and strategies.
use clap::{Parser, Subcommand};
use manylights::render_cmd;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "manylights",
    version,
    about = "Many-light direct-illumination research renderer"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene with a light-sampling strategy to a linear EXR (+ JSON metadata).
    Render(render_cmd::RenderArgs),
    /// Print a scene's triangles, lights by kind, total power, bounds and load warnings.
    Info {
        /// A glTF file (.gltf/.glb), a pbrt scene (.pbrt), a composition (.toml) or
        /// `builtin:NAME?key=value&...`.
        scene: String,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Write a loaded scene as binary glTF (.glb), with pbrt materials in `extras.pbrt`.
    Convert {
        /// Any scene `render` accepts (e.g. a .pbrt file).
        scene: String,
        /// Output .glb.
        out: std::path::PathBuf,
    },
    /// List the built-in scenes and their keys.
    Scenes,
    /// List the strategies, each with its description (and with --json its knobs, their
    /// defaults and its emission rays).
    Strategies {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Print a strategy's resolved parameters (every default filled in) and sampler as JSON:
    /// what `render` with the same flags records as `resolved_strategy`.
    Strategy {
        #[command(flatten)]
        args: render_cmd::StrategyArgs,
        /// Print JSON (the only format; accepted for symmetry with `info --json`).
        #[arg(long)]
        json: bool,
    },
    /// ∫ over a spherical cap of the un-Fresnelled GGX lobe times cos θ (height-correlated
    /// Smith), zero below the horizon. Reads CSV rows `alpha,theta_o,cap_x,cap_y,cap_z,cap_cos`
    /// on stdin (θo in radians, ωo = (sin θo, 0, cos θo), cap axis in the local frame with z the
    /// normal) and writes one value per row.
    CapIntegral {
        /// sptd, ltc or reference
        #[arg(long, default_value = "sptd")]
        method: String,
    },
    /// Error of an EXR against a reference EXR: relMSE and MSE, over all pixels and, with
    /// --mask (a render's `.mask.png`), over the pixels whose camera ray sees no light.
    Compare {
        image: std::path::PathBuf,
        reference: std::path::PathBuf,
        /// Light mask written by `render --aux` (non-black = the camera sees a light there).
        /// Given more than once, a pixel is unlit only if it is in every mask: pass the
        /// reference's mask and the image's own, as the experiment harness does, so that a
        /// light the image's camera rays hit but the reference's never did is left out too.
        #[arg(long)]
        mask: Vec<std::path::PathBuf>,
        /// Print JSON.
        #[arg(long)]
        json: bool,
        /// Also list the N pixels (among the unlit ones with --mask) that carry the most relMSE,
        /// with their share of the total: the way to find the fireflies behind an error.
        #[arg(long, default_value_t = 0)]
        worst: usize,
    },
}

fn main() -> ExitCode {
    host::exit_quietly_on_closed_pipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => match render_cmd::run(args) {
            Ok(code) => return code,
            Err(e) => Err(e),
        },
        Command::Info { scene, json } => info(&scene, json),
        Command::Convert { scene, out } => convert(&scene, &out),
        Command::Scenes => {
            list_scenes();
            Ok(())
        }
        Command::Compare {
            image,
            reference,
            mask,
            json,
            worst,
        } => compare(&image, &reference, &mask, json, worst),
        Command::CapIntegral { method } => cap_integral(&method),
        Command::Strategy { args, json: _ } => args.resolved().and_then(|v| {
            println!("{}", serde_json::to_string_pretty(&v)?);
            Ok(())
        }),
        Command::Strategies { json } => list_strategies(json),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn list_strategies(json: bool) -> anyhow::Result<()> {
    if !json {
        for s in samplers::strategies() {
            println!("{:<22} {}", s.name, s.description);
        }
        return Ok(());
    }
    println!(
        "{}",
        serde_json::to_string_pretty(&manylights::strategies_json())?
    );
    Ok(())
}

fn list_scenes() {
    for b in scene_formats::builtin::list_builtins() {
        println!("builtin:{}\n    {}", b.name, b.description);
        for (key, default, help) in &b.keys {
            println!("    {key:<10} default {default:<10} {help}");
        }
    }
}

fn convert(spec: &str, out: &std::path::Path) -> anyhow::Result<()> {
    // Binary glTF whatever the name: a .gltf name would send other tools to their JSON reader.
    render_cmd::check_extension(out, ("convert", "binary glTF", "glb"), "")?;
    render_cmd::check_output_file(out, "convert's output")?;
    let scene = scene_formats::load_scene(spec, None)?;
    for w in &scene.stats.warnings {
        eprintln!("warning: {w}");
    }
    // The writer's errors come as a scene's I/O error, whose text says "read": its message
    // already names the file written.
    let written = scene_formats::gltf_writer::write_glb(&scene, out).map_err(|e| match e {
        render_core::error::SceneError::Io { message, .. } => anyhow::Error::msg(message),
        other => other.into(),
    })?;
    for w in written {
        eprintln!("warning: {w}");
    }
    println!(
        "wrote {} ({} triangles, {} lights)",
        out.display(),
        scene.triangles.len(),
        scene.lights.len() + scene.distant_lights.len()
    );
    Ok(())
}

fn info(spec: &str, json: bool) -> anyhow::Result<()> {
    let scene = scene_formats::load_scene(spec, None)?;
    let s = &scene.stats;
    if json {
        let v = manylights::scene_info_json((spec, &scene.content_hash()), &scene);
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!("scene          {spec}");
    println!("content hash   {}", scene.content_hash());
    println!(
        "triangles      {} ({} degenerate skipped)",
        s.triangles, s.degenerate_triangles_skipped
    );
    println!(
        "lights         {} triangle, {} sphere, {} point, {} spot, {} directional",
        s.triangle_lights, s.sphere_lights, s.point_lights, s.spot_lights, s.distant_lights
    );
    if s.black_emissive_triangles > 0 {
        println!(
            "               ({} emissive triangles average to black: not lights)",
            s.black_emissive_triangles
        );
    }
    println!("total power    {:.6e} W (bounded lights)", s.total_power_w);
    println!(
        "bounds         {:?} .. {:?}",
        scene.bounds.0.to_array(),
        scene.bounds.1.to_array()
    );
    println!(
        "cameras        {}",
        if scene.cameras.is_empty() {
            "none (a default camera frames the bounds)".to_string()
        } else {
            scene
                .cameras
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    for w in &s.warnings {
        println!("warning        {w}");
    }
    Ok(())
}

/// Warns of an image's NaN or infinite pixels, which make its errors NaN: how many and the
/// first (a render should have none; a reference with them is no reference).
fn warn_non_finite(path: &std::path::Path, px: &[glam::Vec3], width: usize) {
    let bad = px.iter().filter(|p| !p.is_finite()).count();
    if let Some(i) = px.iter().position(|p| !p.is_finite()) {
        eprintln!(
            "warning: {} has {bad} pixels that are not finite (NaN or infinite), the first at \
             ({}, {}): the errors involving them are NaN",
            path.display(),
            i % width,
            i / width
        );
    }
}

fn compare(
    image: &std::path::Path,
    reference: &std::path::Path,
    masks: &[std::path::PathBuf],
    json: bool,
    worst: usize,
) -> anyhow::Result<()> {
    use render_core::metrics::{error_metrics, rel_mse_map};
    let (w, h, x) = render_core::output::read_exr(image).map_err(anyhow::Error::msg)?;
    let (rw, rh, r) = render_core::output::read_exr(reference).map_err(anyhow::Error::msg)?;
    if (w, h) != (rw, rh) {
        anyhow::bail!(
            "{} is {w}x{h} but the reference {} is {rw}x{rh}",
            image.display(),
            reference.display()
        );
    }
    for (path, px) in [(image, &x), (reference, &r)] {
        warn_non_finite(path, px, w as usize);
    }
    let all = error_metrics(&x, &r, None);
    let mut unlit_mask: Option<Vec<bool>> = None;
    for m in masks {
        let unlit = render_core::output::read_mask_png(m, w, h).map_err(anyhow::Error::msg)?;
        unlit_mask = Some(match unlit_mask {
            Some(acc) => acc.iter().zip(&unlit).map(|(a, b)| *a && *b).collect(),
            None => unlit,
        });
    }
    let unlit = unlit_mask
        .as_deref()
        .map(|m| error_metrics(&x, &r, Some(m)));
    // Pixels by their share of the (masked) error sum, largest first.
    let map = rel_mse_map(&x, &r);
    let mut order: Vec<usize> = (0..map.len())
        .filter(|&i| unlit_mask.as_ref().is_none_or(|m| m[i]))
        .collect();
    let total: f64 = order.iter().map(|&i| map[i] as f64).sum();
    order.sort_by(|&a, &b| map[b].total_cmp(&map[a]).then(a.cmp(&b)));
    order.truncate(worst);
    let share = |i: usize| {
        if total > 0.0 {
            map[i] as f64 / total
        } else {
            0.0
        }
    };
    let width = w as usize;
    if json {
        let worst_pixels: Vec<serde_json::Value> = order
            .iter()
            .map(|&i| {
                serde_json::json!({
                    "x": i % width, "y": i / width, "rel_mse": map[i], "share": share(i),
                    "value": x[i].to_array(), "reference": r[i].to_array(),
                })
            })
            .collect();
        println!(
            "{}",
            serde_json::json!({ "all": all, "unlit": unlit, "worst": worst_pixels })
        );
    } else {
        println!(
            "all pixels    relMSE {:.6e}  MSE {:.6e}  ({} px)",
            all.rel_mse, all.mse, all.pixels
        );
        if let Some(u) = unlit {
            println!(
                "unlit pixels  relMSE {:.6e}  MSE {:.6e}  ({} px)",
                u.rel_mse, u.mse, u.pixels
            );
        }
        for &i in &order {
            println!(
                "pixel ({:>4}, {:>4})  relMSE {:.3e}  {:5.1} % of the sum  value {:?}  reference {:?}",
                i % width,
                i / width,
                map[i],
                100.0 * share(i),
                x[i].to_array(),
                r[i].to_array()
            );
        }
    }
    Ok(())
}

fn cap_integral(method: &str) -> anyhow::Result<()> {
    let method: brdf_integrals::Method = method.parse().map_err(|e| anyhow::anyhow!("{e}"))?;
    let stdin = std::io::stdin();
    let stdout = std::io::stdout();
    brdf_integrals::run_batch(method, stdin.lock(), std::io::BufWriter::new(stdout.lock()))?;
    Ok(())
}
