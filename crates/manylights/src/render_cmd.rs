//! `manylights render`.
use anyhow::{Context, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use render_core::output::{write_exr, write_json, write_mask_png, write_png};
use render_core::render::{RenderSettings, render};
use samplers::StrategyOptions;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct RenderArgs {
    /// A glTF file (.gltf/.glb) or `builtin:NAME?key=value&...`.
    pub scene: String,
    #[arg(long, default_value = "power+bsdf")]
    pub strategy: String,
    /// Samples per pixel (default 16; with --time-budget, the most to take, unlimited if not given).
    #[arg(long)]
    pub spp: Option<u32>,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[arg(long)]
    pub width: Option<u32>,
    #[arg(long)]
    pub height: Option<u32>,
    /// Camera name (default: the scene's first camera).
    #[arg(long)]
    pub camera: Option<String>,
    /// Output EXR (linear RGB float). A JSON file with the same stem is written beside it.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write an sRGB PNG preview.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Render passes until this many seconds are spent.
    #[arg(long)]
    pub time_budget: Option<f64>,
    #[arg(long)]
    pub threads: Option<usize>,
    /// Also write the mask of pixels that see a light directly and the strategy's diagnostics.
    #[arg(long)]
    pub aux: bool,
    /// Adaptive tree splitting threshold τ (tree-split strategies).
    #[arg(long, default_value_t = StrategyOptions::default().tau)]
    pub tau: f32,
    /// Most clusters in an adaptive light cut (tree-split strategies).
    #[arg(long, default_value_t = StrategyOptions::default().max_cut)]
    pub max_cut: usize,
    /// Print ray throughput.
    #[arg(long)]
    pub stats: bool,
    #[arg(long)]
    pub quiet: bool,
}

fn sibling(out: &Path, suffix: &str) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "render".into());
    out.with_file_name(format!("{stem}{suffix}"))
}

/// Fails early, before a long render, when the output cannot be written.
fn check_writable(path: &Path) -> anyhow::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        bail!("output directory {} does not exist", dir.display());
    }
    let probe = dir.join(format!(".manylights-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .with_context(|| format!("output directory {} is not writable", dir.display()))?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    if args.spp == Some(0) {
        bail!("--spp must be at least 1");
    }
    if let Some(t) = args.time_budget
        && !(t > 0.0 && t.is_finite())
    {
        bail!("--time-budget must be a positive number of seconds");
    }
    if args.threads == Some(0) {
        bail!("--threads must be at least 1");
    }
    check_writable(&args.out)?;
    if let Some(p) = &args.png {
        check_writable(p)?;
    }
    let scene = render_core::load_scene(&args.scene, args.camera.as_deref())?;
    let opts = StrategyOptions {
        tau: args.tau,
        max_cut: args.max_cut,
    };
    let strategy = samplers::create(&args.strategy, &scene, &opts)?;
    if scene.lights.is_empty() && scene.distant_lights.is_empty() {
        eprintln!("warning: the scene has no lights; the image will be black");
    }
    let mut camera = scene.camera(None)?;
    let width = args.width.unwrap_or(camera.width);
    let height = args.height.unwrap_or(camera.height);
    if width == 0 || height == 0 {
        bail!("--width and --height must be positive");
    }
    camera.width = width;
    camera.height = height;
    let spp = match (args.spp, args.time_budget) {
        (Some(n), _) => Some(n),
        (None, Some(_)) => None,
        (None, None) => Some(16),
    };
    let settings = RenderSettings {
        width,
        height,
        spp,
        seed: args.seed,
        time_budget: args.time_budget,
        threads: args.threads,
        camera: camera.clone(),
    };
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else if let Some(n) = spp.filter(|_| args.time_budget.is_none()) {
        ProgressBar::new(n as u64)
    } else {
        ProgressBar::new_spinner()
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} spp {msg}",
        )
        .unwrap_or(ProgressStyle::default_bar()),
    );
    let result = render(&scene, strategy.as_ref(), &settings, &|_, spp_done| {
        bar.set_position(spp_done as u64)
    })
    .map_err(anyhow::Error::msg)?;
    bar.finish_and_clear();

    write_exr(&args.out, width, height, &result.pixels).map_err(anyhow::Error::msg)?;
    if let Some(p) = &args.png {
        write_png(p, width, height, &result.pixels, args.exposure).map_err(anyhow::Error::msg)?;
    }
    let mut aux_files = Vec::new();
    if args.aux {
        let mask = sibling(&args.out, ".mask.png");
        write_mask_png(&mask, width, height, &result.light_fraction).map_err(anyhow::Error::msg)?;
        aux_files.push(mask);
        for (name, values) in &result.aux {
            let exr = sibling(&args.out, &format!(".{name}.exr"));
            let px: Vec<glam::Vec3> = values.iter().map(|&v| glam::Vec3::splat(v)).collect();
            write_exr(&exr, width, height, &px).map_err(anyhow::Error::msg)?;
            aux_files.push(exr);
        }
    }
    let techniques = strategy.techniques();
    let technique_samples: serde_json::Map<String, serde_json::Value> = techniques
        .iter()
        .enumerate()
        .map(|(i, t)| (t.to_string(), result.counters.technique_samples[i].into()))
        .collect();
    let closest = result.counters.camera_rays + result.counters.bsdf_rays;
    let meta = serde_json::json!({
        "scene": args.scene,
        "scene_stats": scene.stats,
        "strategy": strategy.name(),
        "strategy_parameters": strategy.parameters(),
        "spp": result.spp,
        "spp_requested": spp,
        "time_budget_s": args.time_budget,
        "seed": args.seed,
        "width": width,
        "height": height,
        "camera": camera,
        "threads": args.threads,
        "wall_seconds": result.wall_seconds,
        "cpu_seconds": result.cpu_seconds,
        "rays": { "camera": result.counters.camera_rays, "shadow": result.counters.shadow_rays, "bsdf": result.counters.bsdf_rays },
        "shading_points": result.counters.shading_points,
        "technique_samples": technique_samples,
        "unlit_pixel_fraction": result.light_fraction.iter().filter(|&&f| f == 0.0).count() as f64 / result.light_fraction.len() as f64,
        "aux_files": aux_files,
        "version": env!("CARGO_PKG_VERSION"),
        "git_commit": option_env!("MANYLIGHTS_GIT_COMMIT").filter(|s| !s.is_empty()),
    });
    write_json(&args.out.with_extension("json"), &meta).map_err(anyhow::Error::msg)?;
    if args.stats || !args.quiet {
        let secs = result.wall_seconds.max(1e-9);
        eprintln!(
            "{} spp in {:.2} s ({} passes); closest-hit rays {:.3} M/s, shadow rays {:.3} M/s (whole render, shading included)",
            result.spp,
            secs,
            result.passes,
            closest as f64 / secs / 1e6,
            result.counters.shadow_rays as f64 / secs / 1e6
        );
    }
    Ok(())
}
