//! ReSTIR (issue 51, `reuse/`): every unbiased variant converges to `power+bsdf`'s image, the
//! paper's biased 1/M form is caught by the same check, the image is the same on 1 and 2
//! threads, and the reservoir keeps candidates in proportion to their weights (chi-square).
//!
//! Pixels of one ReSTIR pass share samples, so a render's per-pixel variances say nothing of a
//! region mean's error. The check uses independent renders instead (one seed each): a region's
//! mean over seeds and its standard error from their spread.
mod common;
use chi2_test::chi2_test;
use render_core::render::RenderResult;
use render_core::scene::Scene;
use samplers::StrategyOptions;
use samplers::convergence::region_mean_excluding;
use samplers::reuse::ReuseConfig;
use samplers::reuse::config::CandidateSourceKind;
use samplers::reuse::light_point::LightPoint;
use samplers::reuse::reservoir::Stream;

/// The image's regions: the whole, then a 2 × 2 grid.
fn regions(w: u32, h: u32) -> Vec<(u32, u32, u32, u32)> {
    let mut r = vec![(0, 0, w, h)];
    for cy in 0..2 {
        for cx in 0..2 {
            r.push((cx * w / 2, cy * h / 2, (cx + 1) * w / 2, (cy + 1) * h / 2));
        }
    }
    r
}

/// Each region's z-score of `name` (mean and spread over `seeds` renders of `spp`) against the
/// reference (its own per-pixel standard errors: `power+bsdf`'s pixels are independent).
fn z_scores(
    scene: &Scene,
    name: &str,
    opts: &StrategyOptions,
    reference: &RenderResult,
    (seeds, spp): (u64, u32),
) -> Vec<f64> {
    let (w, h) = (reference.width, reference.height);
    let renders: Vec<RenderResult> = (0..seeds)
        .map(|s| common::render_opts(scene, name, opts, spp, 2, 100 + s, None))
        .collect();
    regions(w, h)
        .into_iter()
        .map(|(x0, y0, x1, y1)| {
            let lit = |i: usize| {
                reference.light_fraction[i] > 0.0
                    || renders.iter().any(|r| r.light_fraction[i] > 0.0)
            };
            let (m_ref, se_ref) = region_mean_excluding(reference, x0, y0, x1, y1, lit);
            let means: Vec<f64> = renders
                .iter()
                .map(|r| region_mean_excluding(r, x0, y0, x1, y1, lit).0)
                .collect();
            let n = means.len() as f64;
            let mean = means.iter().sum::<f64>() / n;
            let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let se = (var / n + se_ref * se_ref).sqrt();
            (mean - m_ref) / se
        })
        .collect()
}

fn opts(reuse: ReuseConfig) -> StrategyOptions {
    StrategyOptions {
        reuse,
        ..Default::default()
    }
}

fn reference(scene: &Scene) -> RenderResult {
    common::render_opts(scene, "power+bsdf", &Default::default(), 1024, 2, 1, None)
}

/// Five regions, two strategies' worth of checks each: |z| ≤ 3.5 is a family-wise false alarm
/// rate well under 1%.
const Z: f64 = 3.5;

#[test]
fn restir_converges_to_the_image_of_power_bsdf() {
    let scene = common::mixed_scene(20);
    let reference = reference(&scene);
    let d = ReuseConfig::default;
    let variants = [
        ("restir", d()),
        (
            "restir",
            ReuseConfig {
                source: CandidateSourceKind::Tree,
                candidates: 8,
                ..d()
            },
        ),
        ("restir", ReuseConfig { rounds: 0, ..d() }),
        ("restir-bo", d()),
        (
            "restir-bo",
            ReuseConfig {
                bo_candidates: 16,
                ..d()
            },
        ),
        (
            "restir",
            ReuseConfig {
                neighbours: 3,
                radius: 8.0,
                rounds: 3,
                candidates: 4,
                ..d()
            },
        ),
    ];
    for (name, reuse) in variants {
        let z = z_scores(&scene, name, &opts(reuse.clone()), &reference, (16, 2));
        eprintln!("{name} {reuse:?}: z = {z:.2?}");
        assert!(
            z.iter().all(|z| z.abs() <= Z),
            "{name} {reuse:?} differs from power+bsdf: z = {z:.2?}"
        );
    }
}

/// Under solid-angle points on the triangle lights (with the cosine warp) the candidates' and
/// the BSDF candidate's densities are the chosen sampler's, and the image is the same.
#[test]
fn restir_converges_under_solid_angle_points() {
    let mut scene = common::mixed_scene(20);
    scene.light_points = render_core::light_points::LightPoints::SolidAngleWarp;
    let reference = reference(&scene);
    for name in ["restir", "restir-bo"] {
        let reuse = ReuseConfig {
            candidates: 8,
            ..Default::default()
        };
        let z = z_scores(&scene, name, &opts(reuse), &reference, (16, 2));
        eprintln!("{name}, solid-angle-warp points: z = {z:.2?}");
        assert!(z.iter().all(|z| z.abs() <= Z), "{name}: z = {z:.2?}");
    }
}

/// The paper's 1/M combination darkens pixels whose neighbours cannot see what they see: the
/// same check must catch it.
#[test]
fn the_biased_combination_is_caught() {
    let scene = common::mixed_scene(20);
    let reference = reference(&scene);
    let z = z_scores(
        &scene,
        "restir-biased",
        &opts(ReuseConfig::default()),
        &reference,
        (16, 2),
    );
    eprintln!("restir-biased: z = {z:.2?}");
    assert!(
        z.iter().any(|z| z.abs() > Z),
        "the biased form passed as unbiased: z = {z:.2?}"
    );
}

#[test]
fn restir_image_is_identical_for_any_thread_count() {
    let scene = common::mixed_scene(10);
    for name in ["restir", "restir-biased", "restir-bo"] {
        let o = StrategyOptions::default();
        let a = common::render_opts(&scene, name, &o, 2, 1, 7, None);
        let b = common::render_opts(&scene, name, &o, 2, 2, 7, None);
        assert!(a.pixels.iter().any(|p| p.x > 0.0));
        assert_eq!(a.pixels, b.pixels, "{name}: 1 and 2 threads differ");
        assert_eq!(a.counters.shadow_rays, b.counters.shadow_rays);
    }
}

/// The reservoir keeps candidate i with probability w_i / Σ w (weighted reservoir sampling).
#[test]
fn the_reservoir_keeps_candidates_in_proportion_to_their_weights() {
    let weights = [0.5f32, 3.0, 0.0, 1.25, 7.0, 0.25, 2.0];
    let total: f32 = weights.iter().sum();
    let n = 200_000u64;
    let mut counts = vec![0f64; weights.len()];
    let mut rng = render_core::rng::SampleStream::new(3, 0, 0);
    for _ in 0..n {
        let mut s = Stream::default();
        for (i, &w) in weights.iter().enumerate() {
            let y = LightPoint {
                light: i as u32,
                ..Default::default()
            };
            s.offer(y, w, 1.0, rng.next_f32());
        }
        let r = s.finish(1.0);
        counts[r.y.light as usize] += 1.0;
        assert!((r.w - total).abs() < 1e-3 * total, "W = Σw / p̂ with p̂ = 1");
    }
    let expected: Vec<f64> = weights
        .iter()
        .map(|&w| n as f64 * (w / total) as f64)
        .collect();
    assert_eq!(counts[2], 0.0, "a zero weight is never kept");
    let out = chi2_test(&counts, &expected);
    assert!(
        out.p_value > 1e-3,
        "chi-square {out:?}: {counts:?} vs {expected:?}"
    );
}

/// Reuse across passes (`--restir-history`) keeps the image unbiased: the previous pass's
/// reservoir is one more domain of the pairwise weights, its confidence capped. Renders of 4
/// passes, so that three of them reuse.
#[test]
fn reuse_across_passes_converges_to_the_image_of_power_bsdf() {
    let scene = common::mixed_scene(20);
    let reference = reference(&scene);
    let with_history = |candidates, history| ReuseConfig {
        candidates,
        history,
        ..Default::default()
    };
    for (name, reuse) in [
        ("restir", with_history(4, 20.0)),
        ("restir", with_history(2, 1000.0)),
        ("restir-bo", with_history(4, 20.0)),
    ] {
        let z = z_scores(&scene, name, &opts(reuse.clone()), &reference, (16, 4));
        eprintln!("{name} {reuse:?}: z = {z:.2?}");
        assert!(
            z.iter().all(|z| z.abs() <= Z),
            "{name} {reuse:?}: z = {z:.2?}"
        );
    }
}

/// The first pass has no history, so it is the same with and without; later passes reuse it
/// (other bytes), the same on 1 and 2 threads.
#[test]
fn reuse_across_passes_starts_at_the_second_pass_and_is_deterministic() {
    let scene = common::mixed_scene(10);
    let on = opts(ReuseConfig {
        history: 20.0,
        ..Default::default()
    });
    let off = StrategyOptions::default();
    for name in ["restir", "restir-biased", "restir-bo"] {
        let first_on = common::render_opts(&scene, name, &on, 1, 2, 7, None);
        let first_off = common::render_opts(&scene, name, &off, 1, 2, 7, None);
        assert_eq!(first_on.pixels, first_off.pixels, "{name}: first pass");
        let a = common::render_opts(&scene, name, &on, 3, 1, 7, None);
        let b = common::render_opts(&scene, name, &on, 3, 2, 7, None);
        let plain = common::render_opts(&scene, name, &off, 3, 2, 7, None);
        assert_eq!(a.pixels, b.pixels, "{name}: 1 and 2 threads differ");
        assert_ne!(a.pixels, plain.pixels, "{name}: the history was not used");
    }
}

#[test]
fn bad_reuse_parameters_are_refused() {
    for history in [-1.0, f32::NAN, 1e6] {
        let reuse = ReuseConfig {
            history,
            ..Default::default()
        };
        assert!(reuse.check().is_err(), "history {history} accepted");
    }
    for bo_candidates in [0, 5000] {
        let reuse = ReuseConfig {
            bo_candidates,
            ..Default::default()
        };
        assert!(
            reuse.check().is_err(),
            "{bo_candidates} BO candidates accepted"
        );
    }
}
