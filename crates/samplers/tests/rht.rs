//! The resampled hierarchical tree (issue 50, `rivals/rht.rs`): each light's gathering
//! frequency against its probability π (chi-square), π and the single-descent pmf at gathering
//! against their replays, the biased traversal caught and the corrected one not on a scene
//! with an exact answer, convergence to `power+bsdf`'s image, thread-count determinism.
mod common;
use chi2_test::{chi2_test, sidak_significance};
use render_core::Vec3;
use render_core::estimator::{DirectLighting, ShadingPoint};
use render_core::render::{RenderResult, RenderSettings, render};
use render_core::rng::SampleStream;
use render_core::scene::{Scene, SceneBuilder};
use samplers::StrategyOptions;
use samplers::convergence::compare;
use samplers::rivals::rht::{self, Rht, RhtConfig, RhtOptions, RhtTraversal};
use samplers::tree_selection::PowerUnits;

fn config(with_bsdf: bool, bo: bool, opts: RhtOptions) -> RhtConfig {
    RhtConfig {
        opts,
        with_bsdf,
        bo,
        units: PowerUnits::Watts,
    }
}

fn opts(tau: f32, picks: u32, traversal: RhtTraversal) -> RhtOptions {
    RhtOptions {
        tau,
        picks,
        traversal,
    }
}

/// The defaults' options.
fn default_opts() -> RhtOptions {
    RhtOptions::default()
}

/// Shading points on the mixed scene's glossy floor, metal panel and diffuse panel.
fn shading_points(scene: &Scene) -> Vec<ShadingPoint> {
    let mut targets = common::MIXED_TARGETS.to_vec();
    targets.push(Vec3::new(0.6, 0.3, -0.2));
    let sps = common::shading_points_towards(scene, common::MIXED_CAMERA, &targets);
    assert!(sps.len() >= 4);
    sps
}

/// Renders `scene` through its camera at `size` with `strategy`.
fn render_with(
    scene: &Scene,
    strategy: &dyn DirectLighting,
    spp: u32,
    (threads, seed): (usize, u64),
    size: Option<(u32, u32)>,
) -> RenderResult {
    let mut camera = scene.camera(None).unwrap();
    if let Some((w, h)) = size {
        (camera.width, camera.height) = (w, h);
    }
    let settings = RenderSettings {
        width: camera.width,
        height: camera.height,
        spp: Some(spp),
        seed,
        time_budget: None,
        threads: Some(threads),
        camera,
        sampler: Default::default(),
        filter: Default::default(),
        reconstruction: Default::default(),
        emission_rays: Default::default(),
        engine: Default::default(),
    };
    render(scene, strategy, &settings, &|_, _| {}).unwrap()
}

fn power_bsdf(scene: &Scene, spp: u32, size: Option<(u32, u32)>) -> RenderResult {
    let opts = StrategyOptions::default();
    let strategy = samplers::create("power+bsdf", scene, &opts).unwrap();
    render_with(scene, strategy.as_ref(), spp, (2, 1), size)
}

/// (a) and (b): every light's gathering count over many traversals against Binomial(N, π)
/// (a two-bin chi-square per light, Šidák-corrected over lights and points), and each
/// candidate's π at gathering equal, bit for bit, to the replayed π.
#[test]
fn each_light_is_gathered_with_its_probability_chi2_and_pi_replays() {
    let scene = common::mixed_scene(60);
    let sps = shading_points(&scene);
    let samples = 20_000u64;
    let mut outcomes = Vec::new();
    let mut fractional = 0;
    for bo in [false, true] {
        let strategy = Rht::new(&scene, config(true, bo, default_opts())).unwrap();
        for (p, sp) in sps.iter().enumerate() {
            let mut counts = vec![0.0f64; scene.lights.len()];
            let mut total = 0usize;
            for i in 0..samples {
                let mut rng = SampleStream::new(3 + p as u64, 0, i);
                let gathered = strategy.gather(sp, &mut rng);
                total += gathered.len();
                for g in &gathered {
                    let (replayed, descent) = strategy.inclusion(sp, g.light);
                    assert_eq!(g.pi.to_bits(), replayed.to_bits());
                    assert_eq!(
                        descent.to_bits(),
                        strategy.descent_pmf(sp, g.light).to_bits()
                    );
                    assert_eq!(g.descent.to_bits(), descent.to_bits());
                    counts[g.light as usize] += 1.0;
                }
            }
            eprintln!(
                "bo {bo}, point {p}: {:.1} candidates per traversal",
                total as f64 / samples as f64
            );
            for (l, &c) in counts.iter().enumerate() {
                let pi = strategy.inclusion(sp, l as u32).0 as f64;
                if pi == 0.0 {
                    assert_eq!(c, 0.0, "light {l} gathered with π = 0");
                    continue;
                }
                fractional += (pi < 0.999) as usize;
                let n = samples as f64;
                let out = chi2_test(&[c, n - c], &[n * pi, n * (1.0 - pi)]);
                outcomes.push((bo, p, l, pi, out));
            }
        }
    }
    assert!(fractional > 100, "the test must have bins: {fractional}");
    let alpha = sidak_significance(1e-3, outcomes.len());
    for (bo, p, l, pi, out) in outcomes {
        assert!(
            out.p_value > alpha,
            "bo {bo}, point {p}, light {l} (π = {pi}): p = {} ({})",
            out.p_value,
            out.message
        );
    }
}

/// Point lights of varied intensity over a white diffuse floor (no occluder): the radiance
/// leaving the origin upwards is (1/π) Σ I cos θ / d², exactly.
fn point_lights_over_a_floor() -> (Scene, f64) {
    let mut b = SceneBuilder::new("points");
    common::floor(&mut b, 20.0);
    let mut exact = 0.0f64;
    for i in 0..120 {
        let t = i as f32 / 120.0;
        let a = 37.0 * t;
        let r = 0.3 + 4.0 * t * t;
        let p = Vec3::new(r * a.cos(), r * a.sin(), 0.2 + 1.5 * (3.0 * a).sin().abs());
        let intensity = 1.0 + 9.0 * ((i * 7) % 5) as f32;
        b.add_point_light(p, Vec3::splat(intensity), None).unwrap();
        let d2 = p.length_squared() as f64;
        exact += intensity as f64 * (p.z as f64 / d2.sqrt()) / d2;
    }
    (b.build().unwrap(), exact / std::f64::consts::PI)
}

/// The corrected traversal's mean is the exact answer; the biased one's is dark, many
/// standard errors off (its bias is a product of per-level factors below 1).
#[test]
fn the_biased_traversal_is_dark_and_the_corrected_one_is_exact() {
    let (scene, exact) = point_lights_over_a_floor();
    let n = 40_000;
    let z = |traversal| {
        let s = Rht::new(&scene, config(false, false, opts(0.85, 1, traversal))).unwrap();
        let (mean, se) = common::estimate_at_origin(&scene, &s, n, 9);
        eprintln!("{}: {mean} ± {se} (exact {exact})", traversal.name());
        (mean - exact) / se
    };
    let corrected = z(RhtTraversal::Corrected);
    assert!(corrected.abs() < 4.0, "corrected: z = {corrected}");
    let biased = z(RhtTraversal::Biased);
    assert!(biased < -6.0, "biased: z = {biased}");
}

/// (c): `rht`, `rht+bsdf` and `rht-bo+bsdf` converge to `power+bsdf`'s image, at the default
/// τ and R and at more picks and a smaller τ, on the mixed scene and on glossy spheres; the
/// biased traversal does not.
#[test]
fn rht_converges_to_the_image_of_power_bsdf_and_the_biased_form_does_not() {
    let mixed = common::mixed_scene(40);
    let spheres = scene_formats::load_scene(
        "builtin:glossy-spheres?lights=64&radius=0.1&roughness=0.5",
        None,
    )
    .unwrap();
    let d = default_opts();
    let few = opts(0.3, 3, RhtTraversal::Corrected);
    let all = [
        config(true, false, d),
        config(true, true, d),
        config(false, false, d),
        config(true, false, few),
        config(true, true, few),
    ];
    for (scene, size) in [(&mixed, None), (&spheres, Some((32, 24)))] {
        let reference = power_bsdf(scene, 1024, size);
        for c in all {
            let strategy = Rht::new(scene, c).unwrap();
            let r = render_with(scene, &strategy, 64, (2, 2), size);
            let failures = compare(&reference, &r, 2, 3.0);
            assert!(
                failures.is_empty(),
                "{} ({:?}) vs power+bsdf on {}:\n{}",
                strategy.name(),
                c.opts,
                scene.name,
                failures.join("\n")
            );
        }
        let biased = config(true, false, opts(0.85, 1, RhtTraversal::Biased));
        let r = render_with(scene, &Rht::new(scene, biased).unwrap(), 64, (2, 2), size);
        let failures = compare(&reference, &r, 2, 3.0);
        eprintln!("biased on {}:\n{}", scene.name, failures.join("\n"));
        assert!(
            !failures.is_empty(),
            "the biased form went unnoticed on {}",
            scene.name
        );
    }
}

/// The mixed scene with six point lights (delta lights: no BSDF hit, no cap for I_BO).
#[test]
fn point_lights_in_the_mixed_scene_agree() {
    let mut b = common::mixed_scene_builder(40);
    for i in 0..6 {
        let t = i as f32 / 6.0;
        let p = Vec3::new(-1.2 + 2.4 * t, 0.5 + 0.4 * (5.0 * t).sin().abs(), -1.0 + t);
        b.add_point_light(p, Vec3::new(1.0, 0.8, 0.6) * (0.5 + t), None)
            .unwrap();
    }
    let scene = b.build().unwrap();
    let reference = power_bsdf(&scene, 1024, None);
    for c in [
        config(true, true, default_opts()),
        config(true, false, default_opts()),
    ] {
        let strategy = Rht::new(&scene, c).unwrap();
        let r = render_with(&scene, &strategy, 64, (2, 2), None);
        let failures = compare(&reference, &r, 2, 3.0);
        assert!(
            failures.is_empty(),
            "{} with point lights:\n{}",
            strategy.name(),
            failures.join("\n")
        );
    }
}

/// (e): the same image and counters on 1 and 2 threads (per-thread scratch).
#[test]
fn rht_image_is_identical_for_any_thread_count() {
    let scene = common::mixed_scene(10);
    for c in [
        config(false, false, default_opts()),
        config(true, false, opts(0.5, 2, RhtTraversal::Corrected)),
        config(true, true, default_opts()),
    ] {
        let strategy = Rht::new(&scene, c).unwrap();
        let a = render_with(&scene, &strategy, 2, (1, 7), None);
        let b = render_with(&scene, &strategy, 2, (2, 7), None);
        let same = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .all(|(p, q)| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits));
        assert!(same, "{}", strategy.name());
        assert_eq!(a.counters, b.counters, "{}", strategy.name());
    }
}

#[test]
fn config_names_parameters_and_bad_knobs() {
    let o = StrategyOptions::default();
    let c = RhtConfig::for_name("rht+bsdf", &o).unwrap();
    assert_eq!((c.name(), c.opts), ("rht+bsdf", default_opts()));
    assert_eq!(RhtConfig::for_name("rht", &o).unwrap().name(), "rht");
    let bo = RhtConfig::for_name("rht-bo+bsdf", &o).unwrap();
    assert!(rht::resolved_parameters(&bo)["glossy_weight"].is_string());
    assert!(RhtConfig::for_name("rht-nope", &o).is_err());
    let p = rht::resolved_parameters(&c);
    assert_eq!(p["traversal"], serde_json::json!("corrected"));
    let scene = common::mixed_scene(4);
    let s = Rht::new(&scene, c).unwrap();
    assert_eq!(s.parameters(), p);
    for (tau, picks) in [(0.0, 1), (1.5, 1), (f32::NAN, 1), (0.5, 0)] {
        let bad = RhtOptions {
            tau,
            picks,
            ..default_opts()
        };
        assert!(Rht::new(&scene, config(true, false, bad)).is_err());
        let o = StrategyOptions {
            rht: bad,
            ..StrategyOptions::default()
        };
        assert!(samplers::create("rht+bsdf", &scene, &o).is_err());
    }
    let flag = |f: &str, v: &str| vec![(f.to_string(), v.to_string())];
    let s = samplers::registry::find("rht").unwrap();
    let biased = s.options(&flag("rht-traversal", "biased")).unwrap();
    assert_eq!(biased.rht.traversal, RhtTraversal::Biased);
    assert!(s.options(&flag("rht-traversal", "both")).is_err());
    assert!(s.options(&flag("rht-picks", "x")).is_err());
}
