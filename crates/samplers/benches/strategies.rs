//! Per-shading-point cost of every strategy in the registry (`samplers::strategies()`) on
//! glossy-spheres, the emissive-mesh built-in and the authors' Cornell box (when
//! `../shared/scenes/` is present): one `DirectLighting::estimate` call per shading point,
//! over the camera hits of a 16 × 16 grid of pixels. Camera rays are not timed.
//!
//! `cargo bench -p samplers --bench strategies` (about a minute); a filter after `--`
//! (e.g. `-- emissive-mesh/power`) runs a subset. Figures: `results/bench/strategies.md`.
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use render_core::Vec2;
use render_core::estimator::{MAX_AUX, PIXEL_MEMORY, SampleContext, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::stats::Counters;
use samplers::StrategyOptions;
use std::hint::black_box;
use std::time::Duration;

/// The authors' box in `../shared/scenes/` beside the repository root, or under
/// `$MANYLIGHTS_SHARED/scenes/` (for a checkout that lives elsewhere, e.g. a git worktree).
fn bisml_path() -> String {
    let shared = std::env::var("MANYLIGHTS_SHARED")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared").into());
    format!("{shared}/scenes/bisml_cornell/bisml_cornell.glb")
}

/// Shading points seen through a `grid` × `grid` lattice of pixel centres.
fn shading_points(scene: &Scene, grid: u32) -> Vec<ShadingPoint> {
    let cam = scene.camera(None).unwrap();
    let aspect = cam.width as f32 / cam.height as f32;
    let mut out = Vec::new();
    for j in 0..grid {
        for i in 0..grid {
            let film = Vec2::new(
                (i as f32 + 0.5) / grid as f32,
                (j as f32 + 0.5) / grid as f32,
            );
            let dir = cam.ray_direction(film, aspect);
            if let Some(hit) = scene.intersect(cam.position, dir, 0.0, f32::INFINITY)
                && let Some(sp) = render_core::render::shading_point(scene, hit, -dir)
            {
                out.push(sp);
            }
        }
    }
    out
}

fn bench_strategies(c: &mut Criterion) {
    let mut scenes = vec![
        ("glossy-spheres", "builtin:glossy-spheres".to_string()),
        ("emissive-mesh", "builtin:emissive-mesh".to_string()),
    ];
    let bisml = bisml_path();
    if std::path::Path::new(&bisml).exists() {
        scenes.push(("bisml-cornell", bisml));
    } else {
        println!("notice: {bisml} is absent; the authors' box is skipped");
    }
    let options = StrategyOptions::default();
    for (label, spec) in scenes {
        let scene = scene_formats::load_scene(&spec, None).unwrap();
        let points = shading_points(&scene, 16);
        println!("{label}: {} shading points per iteration", points.len());
        let mut g = c.benchmark_group(label);
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(1))
            .throughput(Throughput::Elements(points.len() as u64));
        // Every strategy with the defaults, then the method's variants (issue 24: BO weighed by
        // the SG importance; BO's binary descent) under a name of their own.
        let sg = StrategyOptions {
            bo_importance: samplers::brdf_oriented::BoImportance::Sg,
            ..options.clone()
        };
        let binary = StrategyOptions {
            binary_bo_descent: true,
            ..options.clone()
        };
        let variants = samplers::strategies()
            .into_iter()
            .map(|info| (info.name.to_string(), info.name, &options))
            .chain(
                ["brdf-oriented", "mis3-equal", "mis3-adaptive"]
                    .map(|n| (format!("{n} --bo-importance sg"), n, &sg)),
            )
            // BO's paper descent beside our four-wide default, in the same sitting.
            .chain(
                ["brdf-oriented", "mis3-adaptive", "ris"]
                    .map(|n| (format!("{n} --binary-bo-descent"), n, &binary)),
            );
        for (id, name, opts) in variants {
            let strategy = samplers::create(name, &scene, opts).unwrap();
            g.bench_function(id, |b| {
                let mut counters = Counters::default();
                let mut memory = vec![[0.0f32; PIXEL_MEMORY]; points.len()];
                let mut sample = 0u64;
                b.iter(|| {
                    sample += 1;
                    let mut sum = render_core::Vec3::ZERO;
                    for (k, sp) in points.iter().enumerate() {
                        let mut rng = SampleStream::new(1, k as u64, sample);
                        let mut ctx = SampleContext {
                            counters: &mut counters,
                            aux: [0.0; MAX_AUX],
                            pixel_memory: &mut memory[k],
                        };
                        sum += strategy.estimate(&scene, sp, &mut rng, &mut ctx);
                    }
                    black_box(sum)
                })
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench_strategies);
criterion_main!(benches);
