//! Liu, Xu & Yan 2019 (issue 5): convergence of the three-technique strategies, pdf
//! consistency of every technique, chi-square tests of BO and of pivot cap sampling.
mod common;
use brdf_integrals::{CapIntegral, Sptd};
use chi2_test::{chi2_directions, chi2_test};
use light_tree::{SplitCriterion, SplitParams};
use render_core::Vec3;
use render_core::estimator::{PIXEL_MEMORY, SampleContext, ShadingPoint};
use render_core::render::RenderResult;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::stats::Counters;
use samplers::brdf_oriented::BoImportance;
use samplers::brdf_oriented::importance::BoRecord;
use samplers::brdf_oriented::pivot_sphere::PivotSphere;
use samplers::brdf_oriented::sg_importance::SgImportance;
use samplers::brdf_oriented::technique::BoState;
use samplers::convergence::compare;
use samplers::selection::LightSelection;
use samplers::tree_selection::{PowerUnits, TreeMode, TreeSelection};
use samplers::{StrategyOptions, create};

/// [`common::render_opts`] on two threads.
fn render_opts(
    scene: &Scene,
    name: &str,
    opts: &StrategyOptions,
    spp: u32,
    seed: u64,
    size: Option<(u32, u32)>,
) -> RenderResult {
    common::render_opts(scene, name, opts, spp, 2, seed, size)
}

fn check_against_reference(scene: &Scene, size: Option<(u32, u32)>, ref_spp: u32, spp: u32) {
    let d = StrategyOptions::default();
    let reference = render_opts(scene, "power+bsdf", &d, ref_spp, 1, size);
    let (mean, se) = samplers::convergence::region_mean(
        &reference,
        0,
        0,
        reference.width,
        reference.height,
        true,
    );
    assert!(
        mean > 0.0 && se < 0.05 * mean,
        "reference lacks power: {mean} ± {se}"
    );
    let pivot = StrategyOptions {
        pivot_sphere: true,
        ..d.clone()
    };
    let no_h = StrategyOptions {
        adaptive_total: false,
        adaptive_split: false,
        ..d.clone()
    };
    let ltc = StrategyOptions {
        brdf_integral: samplers::brdf_oriented::BrdfIntegral::Ltc,
        ..d.clone()
    };
    let weighted_ub = StrategyOptions {
        weighted_ub: true,
        ..d.clone()
    };
    let fixed_n_max = StrategyOptions {
        efficient_total: false,
        ..d.clone()
    };
    let split_ls = StrategyOptions {
        split_ls_at_glossy: true,
        ..d.clone()
    };
    let independent = StrategyOptions {
        stratified: false,
        ..d.clone()
    };
    let sg = StrategyOptions {
        bo_importance: BoImportance::Sg,
        ..d.clone()
    };
    for (name, opts, label) in [
        ("mis3-adaptive", &ltc, "mis3-adaptive --brdf-integral ltc"),
        ("mis3-adaptive", &sg, "mis3-adaptive --bo-importance sg"),
        // The SG importance is zero only where the E&K bound is: BO alone is complete.
        ("brdf-oriented", &sg, "brdf-oriented --bo-importance sg"),
        ("mis3-equal", &d, "mis3-equal"),
        ("mis3-adaptive", &d, "mis3-adaptive"),
        ("mis3-adaptive", &pivot, "mis3-adaptive --pivot-sphere"),
        ("mis3-adaptive", &no_h, "mis3-adaptive without heuristics"),
        ("mis3-adaptive", &weighted_ub, "mis3-adaptive --weighted-ub"),
        ("mis3-adaptive", &fixed_n_max, "mis3-adaptive --fixed-n-max"),
        (
            "mis3-adaptive",
            &independent,
            "mis3-adaptive --independent-samples",
        ),
        (
            "mis3-adaptive",
            &split_ls,
            "mis3-adaptive --split-ls-at-glossy",
        ),
    ] {
        let r = render_opts(scene, name, opts, spp, 2, size);
        let failures = compare(&reference, &r, 2, 3.0);
        assert!(
            failures.is_empty(),
            "{label} vs power+bsdf on {}:\n{}",
            scene.name,
            failures.join("\n")
        );
    }
}

#[test]
fn mis3_converges_on_the_mixed_scene() {
    check_against_reference(&common::mixed_scene(40), None, 256, 64);
}

#[test]
fn mis3_converges_on_glossy_spheres() {
    let scene = scene_formats::load_scene(
        "builtin:glossy-spheres?lights=64&radius=0.1&roughness=0.5",
        None,
    )
    .unwrap();
    // Small lights on a sharp glossy ground have heavy-tailed estimates for every strategy
    // (the sample mean at low spp sits below the converged value), so the test uses lights
    // and roughness for which 32 spp is already in the asymptotic regime.
    check_against_reference(&scene, Some((32, 24)), 512, 32);
}

#[test]
fn mis3_converges_on_diffuse_quads() {
    let scene = scene_formats::load_scene("builtin:diffuse-quads?lights=64", None).unwrap();
    check_against_reference(&scene, Some((32, 24)), 128, 32);
}

/// From 64 × 64 on, mis3-adaptive learns N_max from a pilot before its first pass (none with
/// `--no-pilot`): the image still converges to power+bsdf's and is the same for any thread
/// count.
#[test]
fn mis3_with_its_pilot_converges_and_is_the_same_for_any_thread_count() {
    let scene = common::mixed_scene(40);
    let size = Some((64, 64));
    let d = StrategyOptions::default();
    let reference = render_opts(&scene, "power+bsdf", &d, 128, 1, size);
    let r = render_opts(&scene, "mis3-adaptive", &d, 16, 2, size);
    assert_eq!(r.pilot_samples, 2 * 16 * 16);
    let failures = compare(&reference, &r, 2, 3.0);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let one = common::render_opts(&scene, "mis3-adaptive", &d, 2, 1, 5, size);
    let two = common::render_opts(&scene, "mis3-adaptive", &d, 2, 2, 5, size);
    assert_eq!(one.pixels, two.pixels);
    assert_eq!(one.variance_of_mean, two.variance_of_mean);
    let no_pilot = StrategyOptions {
        pilot: false,
        ..d.clone()
    };
    let without = common::render_opts(&scene, "mis3-adaptive", &no_pilot, 2, 1, 5, size);
    assert_eq!(without.pilot_samples, 0);
}

#[test]
fn reproduce_mode_and_bo_alone_run() {
    let scene = common::mixed_scene(20);
    let opts = StrategyOptions {
        reproduce: true,
        ..Default::default()
    };
    for name in [
        "brdf-oriented",
        "mis3-equal",
        "mis3-adaptive",
        "tree",
        "tree-split+bsdf",
    ] {
        let r = render_opts(&scene, name, &opts, 2, 3, None);
        assert!(r.pixels.iter().all(|p| p.is_finite()), "{name}");
    }
    let r = render_opts(
        &scene,
        "brdf-oriented",
        &StrategyOptions::default(),
        2,
        3,
        None,
    );
    assert!(r.pixels.iter().any(|p| p.x > 0.0));
}

/// `--stats`' light-selection counters: LS clusters everywhere, BO clusters and the extra
/// BRDF-aware samples only at glossy points, the authors' uncapped cut under `--reproduce`.
#[test]
fn selection_counters_are_recorded() {
    let scene = common::mixed_scene(40);
    let d = StrategyOptions::default();
    let r = render_opts(&scene, "mis3-adaptive", &d, 2, 3, Some((24, 18)));
    let c = &r.counters;
    let [glossy, ls, ls_glossy, bo, aware, aware_glossy] = samplers::work_counters::totals(c);
    assert!(glossy > 0 && glossy < c.shading_points, "{c:?}");
    assert!(ls >= c.shading_points);
    assert!(ls_glossy <= ls);
    assert!(bo >= glossy);
    // Diffuse points take one BRDF sample, glossy ones at least one BO and one BRDF sample.
    assert!(aware_glossy >= 2 * glossy);
    assert_eq!(aware - aware_glossy, c.shading_points - glossy);
    let e = render_opts(&scene, "tree-split+bsdf", &d, 2, 3, Some((24, 18))).counters;
    assert_eq!(
        samplers::work_counters::totals(&e)[3],
        0,
        "E&K has no BO cut"
    );
    assert_eq!(samplers::work_counters::totals(&e)[4], e.shading_points);
    assert!(samplers::work_counters::totals(&e)[1] >= e.shading_points);
    let p = StrategyOptions {
        reproduce: true,
        ..d.clone()
    }
    .split_params();
    assert_eq!(p.max_size, usize::MAX);
    assert_eq!(p.criterion, light_tree::SplitCriterion::Authors);
    assert_eq!(
        d.split_params().criterion,
        light_tree::SplitCriterion::UnitFree
    );
}

/// Shading points on the mixed scene's glossy floor, metal panel and diffuse panel.
fn shading_points(scene: &Scene) -> Vec<ShadingPoint> {
    common::shading_points_towards(scene, common::MIXED_CAMERA, &common::MIXED_TARGETS)
}

fn bo_state<'a>(
    sel: &TreeSelection,
    sp: &ShadingPoint,
    pivot: bool,
) -> BoState<'a, <Sptd as CapIntegral>::Lobe> {
    let sptd = Sptd::default();
    let lobe = sptd.lobe(sp.bsdf.frame.to_local(sp.wo), sp.bsdf.params.alpha);
    let pivot = pivot.then_some(PivotSphere { pivot: lobe.pivot });
    BoState::new(
        sel.tree.as_ref().unwrap(),
        BoRecord::new(sp, lobe, true, false),
        0.5,
        64,
        pivot,
    )
}

#[test]
fn every_technique_pdf_at_sampling_equals_its_replay() {
    let scene = common::mixed_scene(40);
    let sel = TreeSelection::new(
        &scene,
        TreeMode::Split(SplitParams {
            tau: 0.85,
            max_size: 64,
            criterion: SplitCriterion::Authors,
        }),
        PowerUnits::Watts,
    )
    .unwrap();
    let tree = sel.tree.as_ref().unwrap();
    let sps = shading_points(&scene);
    assert!(sps.len() >= 3);
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs());
    for sp in &sps {
        let x = sp.point();
        for pivot in [false, true] {
            let bo = bo_state(&sel, sp, pivot);
            assert!(!bo.cut().cut.is_empty());
            let mut checked = 0;
            for i in 0..2000 {
                let mut rng = SampleStream::new(5, 0, i);
                let Some((light, p_sel)) = bo.select(tree, &mut rng, true) else {
                    continue;
                };
                assert!(
                    close(p_sel, bo.selection_pmf(tree, light)),
                    "BO selection pmf"
                );
                let l = &scene.lights[light];
                if let Some(s) = bo.sample_point(l, &mut rng) {
                    let replay = bo.point_pdf(l, s.point, s.normal, s.wi);
                    assert!(close(s.pdf, replay), "BO point pdf {} vs {replay}", s.pdf);
                    checked += 1;
                }
            }
            assert!(checked > 500);
        }
        // LS: the splitting selection's pick probability equals its pmf; light pdfs replay.
        let state = sel.prepare(&scene, sp);
        for i in 0..200 {
            let mut rng = SampleStream::new(6, 0, i);
            let mut picks = Vec::new();
            sel.pick(&state, sp, &mut rng, &mut picks);
            for (light, pmf) in picks {
                assert!(close(pmf, sel.pmf(&state, sp, light)));
                let l = &scene.lights[light as usize];
                if let Some(s) = l.sample(x, rng.next_2d()) {
                    assert!(close(s.pdf, l.pdf(x, s.point, s.normal)));
                }
            }
        }
        // BRDF sampling.
        for i in 0..500 {
            let mut rng = SampleStream::new(7, 0, i);
            if let Some(s) = sp.bsdf.sample(sp.wo, rng.next_f32(), rng.next_2d()) {
                assert!(close(s.pdf, sp.bsdf.pdf(sp.wo, s.wi)));
            }
        }
    }
}

#[test]
fn bo_selection_matches_its_pmf_chi2() {
    let scene = common::mixed_scene(40);
    let sel = TreeSelection::new(
        &scene,
        TreeMode::Split(SplitParams {
            tau: 0.85,
            max_size: 64,
            criterion: SplitCriterion::Authors,
        }),
        PowerUnits::Watts,
    )
    .unwrap();
    let tree = sel.tree.as_ref().unwrap();
    for (k, sp) in shading_points(&scene).iter().enumerate() {
        for fresh in [true, false] {
            let bo = bo_state(&sel, sp, false);
            let n = scene.lights.len();
            let mut observed = vec![0.0; n + 1];
            let samples = 100_000;
            for i in 0..samples {
                let mut rng = SampleStream::new(11 + k as u64, 0, i);
                match bo.select(tree, &mut rng, fresh) {
                    Some((light, _)) => observed[light] += 1.0,
                    None => observed[n] += 1.0,
                }
            }
            let mut expected: Vec<f64> = (0..n)
                .map(|l| bo.selection_pmf(tree, l) as f64 * samples as f64)
                .collect();
            let total: f64 = expected.iter().sum();
            expected.push((samples as f64 - total).max(0.0));
            let out = chi2_test(&observed, &expected);
            assert!(
                out.p_value > 1e-4,
                "point {k} fresh {fresh}: p = {} ({})",
                out.p_value,
                out.message
            );
        }
    }
}

#[test]
fn pivot_sphere_sampling_matches_its_pdf_chi2() {
    let scene = common::mixed_scene(40);
    let sel = TreeSelection::new(
        &scene,
        TreeMode::Split(SplitParams {
            tau: 0.85,
            max_size: 64,
            criterion: SplitCriterion::Authors,
        }),
        PowerUnits::Watts,
    )
    .unwrap();
    let sp = shading_points(&scene)[0];
    // A large sphere light close to the point, so the cap spans many histogram bins.
    let mut b = render_core::scene::SceneBuilder::new("one sphere");
    b.add_sphere_light(sp.point() + Vec3::new(0.2, 0.5, 0.1), 0.3, Vec3::ONE, None)
        .unwrap();
    let one = b.build().unwrap();
    let light = &one.lights[0];
    let bo = bo_state(&sel, &sp, true);
    let pivot = bo.pivot.unwrap();
    let mut i = 0u64;
    let out = chi2_directions(
        200_000,
        32,
        64,
        16,
        |_| {
            i += 1;
            let mut rng = SampleStream::new(13, 0, i);
            pivot.sample(&bo.rec, light, &mut rng).map(|s| s.wi)
        },
        |w| {
            // The density of the direction: the cap is the sphere's visible side.
            let c = sp.point() + Vec3::new(0.2, 0.5, 0.1);
            let to_c = c - sp.point();
            let b = w.dot(to_c);
            let disc = 0.09 - (to_c.length_squared() - b * b);
            if disc < 0.0 || b <= 0.0 {
                return 0.0;
            }
            let p = sp.point() + w * (b - disc.sqrt());
            pivot.pdf(&bo.rec, light, p, (p - c).normalize(), w) as f64
        },
    );
    assert!(out.p_value > 1e-4, "p = {} ({})", out.p_value, out.message);
}

#[test]
fn reproduce_and_default_allocations_agree_at_a_glossy_point() {
    // Not an assertion of bias: a smoke test that both allocations estimate the same value
    // at one glossy point to within a loose tolerance (the bias is measured in the report).
    let scene = common::mixed_scene(40);
    let sp = shading_points(&scene)[0];
    let est = |opts: &StrategyOptions, seed: u64| {
        let s = create("mis3-adaptive", &scene, opts).unwrap();
        let mut counters = Counters::default();
        let mut memory = [0.0; PIXEL_MEMORY];
        let n = 4000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let mut rng = SampleStream::new(seed, 0, i);
            let mut ctx = SampleContext {
                counters: &mut counters,
                aux: [0.0; 4],
                pixel_memory: &mut memory,
            };
            sum += s.estimate(&scene, &sp, &mut rng, &mut ctx).x as f64;
        }
        sum / n as f64
    };
    let a = est(&StrategyOptions::default(), 1);
    let b = est(
        &StrategyOptions {
            reproduce: true,
            ..Default::default()
        },
        2,
    );
    assert!(a > 0.0 && (a - b).abs() < 0.2 * a, "{a} vs {b}");
}

/// The bias of `--reproduce` (the authors' in-sample allocation): whole-image means of unlit
/// pixels, default and reproduce vs a `tree-split+bsdf` reference, with standard errors. The
/// default must agree with the reference within 3 combined standard errors (it is unbiased);
/// reproduce within 3 standard errors plus 1 % of the mean (its bias is small). Minutes in the
/// debug profile, so not in the default run:
/// `cargo test --release -p samplers --test method measure_reproduce_bias -- --ignored --nocapture`.
#[test]
#[ignore]
fn measure_reproduce_bias() {
    let scenes = [
        ("mixed(40)", common::mixed_scene(40), None),
        (
            "glossy-spheres lights=256 r=0.1 rough=0.5",
            scene_formats::load_scene(
                "builtin:glossy-spheres?lights=256&radius=0.1&roughness=0.5",
                None,
            )
            .unwrap(),
            Some((32, 24)),
        ),
    ];
    for (label, scene, size) in scenes {
        let w = size.map_or(48, |s: (u32, u32)| s.0);
        let h = size.map_or(36, |s: (u32, u32)| s.1);
        let d = StrategyOptions::default();
        let rep = StrategyOptions {
            reproduce: true,
            ..Default::default()
        };
        let mut means = Vec::new();
        for (name, opts, spp, tag) in [
            ("tree-split+bsdf", &d, 2048, "reference"),
            ("mis3-adaptive", &d, 512, "default"),
            ("mis3-adaptive", &rep, 512, "reproduce"),
        ] {
            let r = render_opts(&scene, name, opts, spp, 21, size);
            let (m, se) = samplers::convergence::region_mean(&r, 0, 0, w, h, true);
            eprintln!(
                "{label}: {tag:>9} {name} {spp} spp: {m:.6} ± {se:.6} ({:+.3} % ± {:.3} % of the reference)",
                100.0 * (m / means.first().map_or(m, |r: &(f64, f64)| r.0) - 1.0),
                100.0 * se / m
            );
            means.push((m, se));
        }
        let (r, rse) = means[0];
        for (k, slack) in [(1, 0.0), (2, 0.01 * r)] {
            let (m, se) = means[k];
            let sigma = (se * se + rse * rse).sqrt();
            assert!(
                (m - r).abs() <= 3.0 * sigma + slack,
                "{label}: {} mean {m} vs reference {r} (σ {sigma})",
                ["", "default", "reproduce"][k]
            );
        }
    }
}

/// The issue-7 built-ins, small and rough enough that 96 spp is past the heavy-tailed regime
/// (at 24 spp the lamp's image mean still wanders by ±3 estimated standard errors with the
/// seed, for every strategy).
#[test]
fn mis3_converges_on_the_other_builtins() {
    let d = StrategyOptions::default();
    for spec in [
        "builtin:car?lights=64&radius=0.1&roughness=0.5",
        "builtin:lamp?lights=64&radius=0.05&roughness=0.5",
        "builtin:statue?lights=64&radius=0.1&roughness=0.5",
        // builtin:cornell (lights 1 mm from the walls) is left out: its hot spots make the
        // per-pixel variance estimates unreliable at test sample counts (3.1 SE at
        // 4096 vs 512 spp); at 4096 spp power+bsdf and mis3-adaptive agree within 1.8 SE.
        "builtin:staircase?lights=64&radius=0.05&roughness=0.5",
        "builtin:grid?lights=64&roughness=0.5",
    ] {
        let scene = scene_formats::load_scene(spec, None).unwrap();
        let size = Some((24, 18));
        let reference = render_opts(&scene, "power+bsdf", &d, 1024, 1, size);
        let r = render_opts(&scene, "mis3-adaptive", &d, 96, 2, size);
        let failures = compare(&reference, &r, 2, 3.0);
        assert!(
            failures.is_empty(),
            "mis3-adaptive vs power+bsdf on {spec}:\n{}",
            failures.join("\n")
        );
    }
}

/// BO under `--bo-importance sg` at the mixed scene's points: the same cut (nodes and cap
/// integrals, so the same UB) as under I_BO, every cluster's importance the SG importance (zero
/// exactly where the E&K bound is), the selection probability at sampling equal to the replayed
/// pmf bit for bit, and the drawn lights distributed as that pmf (chi-square, fresh and
/// rescaled descents).
#[test]
fn bo_under_sg_importance_matches_its_pmf_chi2_and_replay() {
    let scene = common::mixed_scene(40);
    let sel = TreeSelection::new(
        &scene,
        TreeMode::Split(SplitParams {
            tau: 0.85,
            max_size: 64,
            criterion: SplitCriterion::Authors,
        }),
        PowerUnits::Watts,
    )
    .unwrap();
    let tree = sel.tree.as_ref().unwrap();
    let nodes = light_tree::SgNodes::build(tree, &samplers::sg::sg_emitters(&scene)).unwrap();
    let sptd = Sptd::default();
    let n = scene.lights.len();
    for (k, sp) in shading_points(&scene).iter().enumerate() {
        let lobe = sptd.lobe(sp.bsdf.frame.to_local(sp.wo), sp.bsdf.params.alpha);
        let rec = BoRecord::new(sp, lobe, true, false);
        let sg = SgImportance::new(&nodes, sp);
        let cap = BoState::new(tree, rec, 0.5, 64, None);
        let bo = BoState::with_importance(tree, rec, Some(sg), 0.5, 64, None);
        assert_eq!(
            bo.cut().cut.nodes,
            cap.cut().cut.nodes,
            "point {k}: same cut"
        );
        assert_eq!(bo.cut().upper_bound(), cap.cut().upper_bound());
        for (i, &id) in bo.cut().cut.nodes.iter().enumerate() {
            let t = bo.cut().terms[i];
            assert_eq!(t.glossy, cap.cut().terms[i].glossy);
            assert_eq!(t.importance, sg.importance(tree, id));
            let ek = tree.node(id).importance(sp.point(), sp.bsdf.ng);
            assert_eq!(t.importance > 0.0, ek > 0.0, "point {k} node {id}");
        }
        for fresh in [true, false] {
            let mut observed = vec![0.0; n + 1];
            let samples = 100_000;
            for i in 0..samples {
                let mut rng = SampleStream::new(23 + k as u64, 0, i);
                match bo.select(tree, &mut rng, fresh) {
                    Some((light, p)) => {
                        assert_eq!(
                            p,
                            bo.selection_pmf(tree, light),
                            "pmf at sampling vs replay"
                        );
                        observed[light] += 1.0;
                    }
                    None => observed[n] += 1.0,
                }
            }
            let mut expected: Vec<f64> = (0..n)
                .map(|l| bo.selection_pmf(tree, l) as f64 * samples as f64)
                .collect();
            let total: f64 = expected.iter().sum();
            assert!(total <= samples as f64 * (1.0 + 1e-5));
            expected.push((samples as f64 - total).max(0.0));
            let out = chi2_test(&observed, &expected);
            assert!(
                out.p_value > 1e-4,
                "point {k} fresh {fresh}: p = {} ({})",
                out.p_value,
                out.message
            );
        }
    }
}

/// `mis3-adaptive --bo-importance sg` renders the same image on one thread and on two, and
/// another image than under I_BO.
#[test]
fn sg_importance_image_is_identical_for_any_thread_count() {
    let scene = common::mixed_scene(10);
    let sg = StrategyOptions {
        bo_importance: BoImportance::Sg,
        ..Default::default()
    };
    let a = common::render_opts(&scene, "mis3-adaptive", &sg, 4, 1, 7, None);
    let b = common::render_opts(&scene, "mis3-adaptive", &sg, 4, 2, 7, None);
    let bits = |r: &RenderResult| -> Vec<[u32; 3]> {
        r.pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert!(bits(&a) == bits(&b), "1 vs 2 threads");
    assert_eq!(a.counters, b.counters);
    let c = common::render_opts(
        &scene,
        "mis3-adaptive",
        &StrategyOptions::default(),
        4,
        2,
        7,
        None,
    );
    assert!(a.pixels != c.pixels, "the option changes the image");
}
