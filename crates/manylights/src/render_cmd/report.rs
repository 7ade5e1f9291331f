//! What `render` writes and prints once the image is made: the EXR, the PNG preview and the aux
//! images, the JSON record of the render, and the summary on stderr.
use super::outputs::sibling;
use super::{BudgetClockArg, Choices, RenderArgs};
use render_core::estimator::DirectLighting;
use render_core::output::{FileSet, exr_encoder, mask_png_encoder, png_encoder};
use render_core::render::{RenderResult, RenderSettings};
use render_core::scene::Scene;
use render_core::stats::StrategyCounter;
use std::path::{Path, PathBuf};

/// The images written: the preview's exposure in stops and the aux files.
pub(super) struct Written {
    exposure: f32,
    aux_files: Vec<PathBuf>,
}

impl Written {
    /// No preview and no aux file (a render kept in memory).
    pub(super) fn nothing() -> Written {
        Written {
            exposure: 0.0,
            aux_files: Vec::new(),
        }
    }
}

/// The EXR, the PNG preview (`--png`) and, with `--aux`, the light mask and each aux channel as
/// EXR and, where the strategy colours it, as PNG, staged in `files` (put in place with the
/// render's record, so that a failed write leaves the previous render's files as they were).
pub(super) fn write_images(
    args: &RenderArgs,
    strategy: &dyn DirectLighting,
    settings: &RenderSettings,
    result: &RenderResult,
    files: &mut FileSet,
) -> anyhow::Result<Written> {
    let (width, height) = (settings.width, settings.height);
    stage(files, &args.out, exr_encoder(width, height, &result.pixels))?;
    let exposure = args.exposure.unwrap_or_else(|| {
        render_core::colour::auto_exposure_scale(&result.pixels, &result.unlit_mask()).log2()
    });
    if let Some(p) = &args.png {
        stage(
            files,
            p,
            png_encoder(width, height, &result.pixels, exposure),
        )?;
    }
    let mut aux_files = Vec::new();
    if args.aux {
        let mask = sibling(&args.out, ".mask.png");
        stage(
            files,
            &mask,
            mask_png_encoder(width, height, &result.light_fraction),
        )?;
        aux_files.push(mask);
        for (name, values) in &result.aux {
            let exr = sibling(&args.out, &format!(".{name}.exr"));
            let px: Vec<glam::Vec3> = values.iter().map(|&v| glam::Vec3::splat(v)).collect();
            stage(files, &exr, exr_encoder(width, height, &px))?;
            aux_files.push(exr);
            let colours: Option<Vec<glam::Vec3>> = values
                .iter()
                .map(|&v| strategy.aux_colour(name, v))
                .collect();
            if let Some(colours) = colours {
                let png = sibling(&args.out, &format!(".{name}.png"));
                stage(files, &png, png_encoder(width, height, &colours, 0.0))?;
                aux_files.push(png);
            }
        }
    }
    Ok(Written {
        exposure,
        aux_files,
    })
}

/// One file of the render's set.
pub(super) fn stage(
    files: &mut FileSet,
    path: &Path,
    encode: impl FnOnce(&Path) -> Result<(), String>,
) -> anyhow::Result<()> {
    files.stage(path, encode).map_err(anyhow::Error::msg)
}

/// The render's JSON record: the scene, the strategy as built and as resolved, the settings and
/// what chose them, the work done and the files written.
#[allow(clippy::too_many_arguments)]
pub(super) fn metadata(
    args: &RenderArgs,
    (scene, scene_hash): (&Scene, &str),
    strategy: &dyn DirectLighting,
    settings: &RenderSettings,
    choices: &Choices,
    result: &RenderResult,
    resolved: serde_json::Value,
    written: &Written,
) -> serde_json::Value {
    let technique_samples: serde_json::Map<String, serde_json::Value> = strategy
        .techniques()
        .iter()
        .enumerate()
        .map(|(i, t)| (t.to_string(), result.counters.technique_samples[i].into()))
        .collect();
    let (sampler, sampler_from) = choices.sampler;
    let (filter, filter_from) = &choices.filter;
    let (reconstruction, reconstruction_from) = choices.reconstruction;
    let budget_clock = |c: BudgetClockArg| format!("{c:?}").to_lowercase();
    let mut meta = serde_json::json!({
        "scene": args.scene,
        "scene_stats": scene.stats,
        "scene_hash": scene_hash,
        "strategy": strategy.name(),
        "strategy_parameters": strategy.parameters(),
        "resolved_strategy": resolved,
        "spp": result.spp,
        "partial_pass_pixels": result.partial_pixels,
        "unsampled_pixels": result.unsampled_pixels(),
        "work_unit_pixels": render_core::render::UNIT_PIXELS,
        "passes": result.passes,
        "pilot_camera_samples": result.pilot_samples,
        "spp_requested": settings.spp,
        "time_budget_s": args.time_budget,
        "budget_clock": args.time_budget.map(|_| budget_clock(args.budget_clock)),
        "seed": args.seed,
        "sampler": sampler.name(),
        "sampler_from": sampler_from,
        "filter": {
            "name": filter.name(),
            "parameters": filter.parameters().into_iter().collect::<std::collections::BTreeMap<_, _>>(),
            "from": filter_from,
            "reconstruction": reconstruction.name(),
            "reconstruction_from": reconstruction_from,
        },
        "emission_rays": settings.emission_rays.get(),
        "light_points": scene.light_points.name(),
        "width": settings.width,
        "height": settings.height,
        "camera": settings.camera,
        "threads": args.threads,
        "engine": settings.engine.name(),
        "engine_used": settings.engine.used_for(strategy),
        "worker_threads": result.threads,
        "wall_seconds": result.wall_seconds,
        "cpu_seconds": result.cpu_seconds,
        "rays": { "camera": result.counters.camera_rays, "emission": result.counters.emission_rays, "shadow": result.counters.shadow_rays, "bsdf": result.counters.bsdf_rays },
        "shading_points": result.counters.shading_points,
        "technique_samples": technique_samples,
        "strategy_counters": result.counters.strategy_means(&strategy.counters()),
        "image_space_bytes_per_pixel": strategy.image_space().map(|s| s.bytes_per_pixel()),
        "unlit_pixel_fraction": result.light_fraction.iter().filter(|&&f| f == 0.0).count() as f64 / result.light_fraction.len() as f64,
        "aux_files": written.aux_files,
        "png_exposure": args.png.as_ref().map(|_| written.exposure),
        "png_exposure_auto": args.png.as_ref().map(|_| args.exposure.is_none()),
        "version": env!("CARGO_PKG_VERSION"),
        "git_commit": option_env!("MANYLIGHTS_GIT_COMMIT").filter(|s| !s.is_empty()),
    });
    // Whether passes share samples (ReSTIR's reuse across passes): the per-pixel variance of
    // the passes then understates the error.
    meta["passes_correlated"] = strategy
        .image_space()
        .is_some_and(|s| s.correlates_passes())
        .into();
    // Ended early by Ctrl-C: the image holds the samples done (`spp`, `partial_pass_pixels`).
    meta["interrupted"] = result.interrupted.into();
    meta
}

/// The one-line summary: spp, passes, seconds and ray throughput.
pub(super) fn print_summary(result: &RenderResult) {
    let secs = result.wall_seconds.max(1e-9);
    let closest = result.counters.camera_rays + result.counters.bsdf_rays;
    eprintln!(
        "{} spp{} in {:.2} s ({} pass{}); closest-hit rays {:.3} M/s, shadow rays {:.3} M/s (whole render, shading included)",
        result.spp,
        if result.partial_pixels > 0 {
            format!(" + {} pixels of one more", result.partial_pixels)
        } else {
            String::new()
        },
        secs,
        result.passes,
        if result.passes == 1 { "" } else { "es" },
        closest as f64 / secs / 1e6,
        result.counters.shadow_rays as f64 / secs / 1e6
    );
}

/// `--stats`: the CPU time and the strategy's own counters, as means per what each is counted per.
pub(super) fn print_stats(result: &RenderResult, names: &[StrategyCounter]) {
    let c = &result.counters;
    let cpu = result.cpu_seconds.unwrap_or(f64::NAN);
    eprintln!(
        "CPU {cpu:.2} s ({:.3} s per spp); {} shading points",
        cpu / result.spp.max(1) as f64,
        c.shading_points
    );
    let means = c.strategy_means(names);
    let mut pers: Vec<&str> = Vec::new();
    for n in names {
        let per = n.per.unwrap_or("shading point");
        if !pers.contains(&per) {
            pers.push(per);
        }
    }
    for per in pers {
        let line: Vec<String> = names
            .iter()
            .filter(|n| n.per.unwrap_or("shading point") == per)
            .map(|n| {
                format!(
                    "{} {:.2}",
                    n.name,
                    means[n.name]["mean"].as_f64().unwrap_or(0.0)
                )
            })
            .collect();
        let header = if per == "shading point" {
            "per shading point".to_string()
        } else {
            format!("per one of the {per}")
        };
        eprintln!("{header}: {}", line.join(", "));
    }
}
