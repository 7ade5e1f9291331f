//! Learning to cluster (issue 50, `rivals/varl.rs`): after passes of learning, picks follow the
//! pmf (chi-square) and replay it bit for bit with every light the tree reaches still
//! reachable; regions refine their cuts and learn shares from the observed contributions;
//! `varl` and `varl+bsdf` converge to `power+bsdf`; the image is the same for 1 and 2 threads.
mod common;
use chi2_test::chi2_test;
use light_tree::LightTree;
use render_core::estimator::{PIXEL_MEMORY, ShadingPoint};
use render_core::render::{RenderResult, RenderSettings, render};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use samplers::convergence::compare;
use samplers::learned::PassWeights;
use samplers::learned::strategy::LearnedStrategy;
use samplers::rivals::varl::{INITIAL_CUT, VarlOptions, VarlSelection};
use samplers::rivals::varl_table::{Observation, SPLIT_SAMPLES, VarlTable};
use samplers::selection::LightSelection;
use samplers::tree_selection::PowerUnits;
use samplers::{StrategyOptions, create};

fn rooms() -> Scene {
    scene_formats::load_scene("builtin:rooms?lights=400", None).unwrap()
}

fn varl(scene: &Scene, with_bsdf: bool) -> LearnedStrategy<VarlSelection> {
    LearnedStrategy {
        name: if with_bsdf { "varl+bsdf" } else { "varl" }.into(),
        selection: VarlSelection::new(scene, PowerUnits::Watts, VarlOptions::default()).unwrap(),
        with_bsdf,
        light_samples: 1,
        pass_weights: PassWeights::Equal,
    }
}

fn settings(scene: &Scene, (w, h): (u32, u32), spp: u32, threads: usize) -> RenderSettings {
    let mut camera = scene.camera(None).unwrap();
    (camera.width, camera.height) = (w, h);
    RenderSettings {
        width: w,
        height: h,
        spp: Some(spp),
        seed: 5,
        time_budget: None,
        threads: Some(threads),
        camera,
        sampler: Default::default(),
        filter: Default::default(),
        reconstruction: Default::default(),
        emission_rays: Default::default(),
        engine: Default::default(),
    }
}

/// Shading points seen by the camera: a few of its rays across the image.
fn camera_points(scene: &Scene) -> Vec<ShadingPoint> {
    let cam = scene.camera(None).unwrap();
    let right = cam.forward.cross(render_core::Vec3::Y).normalize();
    let targets: Vec<_> = [
        (0.0, 0.0),
        (0.3, -0.2),
        (-0.4, -0.3),
        (0.05, 0.05),
        (-0.3, 0.2),
    ]
    .iter()
    .map(|&(dx, dy)| cam.position + cam.forward + right * dx + render_core::Vec3::Y * dy)
    .collect();
    common::shading_points_towards(scene, cam.position, &targets)
}

/// After 8 passes of learning (statistics frozen): the pmf sums to one, every light the tree
/// reaches keeps a positive probability, picks follow the pmf (chi-square), each pick's
/// probability is the replayed pmf bit for bit, and some region has refined its cut.
#[test]
fn varl_picks_follow_their_pmf_after_learning_and_regions_refine() {
    let scene = rooms();
    let s = varl(&scene, true);
    render(&scene, &s, &settings(&scene, (48, 32), 8, 2), &|_, _| {}).unwrap();
    let sel = &s.selection;
    let table = sel.table.read().unwrap();
    assert!(table.pass == 8 && !table.is_empty(), "it learnt something");
    assert!(
        table.nodes() > table.len() * INITIAL_CUT,
        "no region refined its cut: {} nodes in {} regions",
        table.nodes(),
        table.len()
    );
    let tree = sel.tree.as_ref().unwrap();
    let mut learnt = 0;
    for (i, sp) in camera_points(&scene).iter().enumerate() {
        let state = sel.prepare_with(sp, &table);
        learnt += table.region(state.key).is_some_and(|r| r.passes > 0) as usize;
        picks_match_pmf(&scene, sel, &state, sp, i, tree);
    }
    assert!(learnt >= 3, "only {learnt} points in learnt regions");
}

fn picks_match_pmf<S: LightSelection>(
    scene: &Scene,
    sel: &S,
    state: &S::State,
    sp: &ShadingPoint,
    i: usize,
    tree: &LightTree,
) {
    let n = scene.lights.len();
    let expected: Vec<f64> = (0..n as u32)
        .map(|l| sel.pmf(state, sp, l) as f64)
        .collect();
    let total: f64 = expected.iter().sum();
    assert!((total - 1.0).abs() < 1e-3, "pmf sums to {total}");
    for (l, &p) in expected.iter().enumerate() {
        if tree.pmf(sp.point(), sp.bsdf.ng, l) > 0.0 {
            assert!(p > 0.0, "light {l} unreachable");
        }
    }
    let samples = 200_000u64;
    let mut observed = vec![0.0f64; n];
    let mut picks = Vec::new();
    for k in 0..samples {
        let mut rng = SampleStream::new(11 + i as u64, k, 0);
        picks.clear();
        sel.pick(state, sp, &mut rng, &mut picks);
        for &(light, p) in &picks {
            observed[light as usize] += 1.0;
            assert_eq!(
                p.to_bits(),
                sel.pmf(state, sp, light).to_bits(),
                "light {light}"
            );
        }
    }
    let expected: Vec<f64> = expected
        .iter()
        .map(|p| p * samples as f64 / total)
        .collect();
    let r = chi2_test(&observed, &expected);
    assert!(r.p_value > 1e-3, "point {i}: {}", r.message);
}

/// The table's update and refinement, exactly: observations of one region in which one initial
/// node carries every contribution, unevenly between its lights, make that node's share 1 after
/// the pass and split it in two, its share divided as its children's observations were.
#[test]
fn a_node_carrying_uneven_contributions_takes_the_share_and_splits() {
    let scene = rooms();
    let sel = VarlSelection::new(&scene, PowerUnits::Watts, VarlOptions::default()).unwrap();
    let tree = sel.tree.as_ref().unwrap();
    let mut table = VarlTable::new(Some(tree), 64, 16);
    let node = table.initial[3];
    let (l, r) = tree.node(node).children(node).unwrap();
    let light_under = |id| tree.node(tree.subtree_range(id).1).light().unwrap() as u32;
    let (a, b) = (light_under(l), light_under(r));
    // 3 : 1 between the two children, half of the samples occluded (y = 0): the squared
    // coefficient of variation is 64 · 640 / 128² − 1 = 1.5.
    let mut pixels = Vec::new();
    for i in 0..2 * SPLIT_SAMPLES {
        let (light, y) = match i % 4 {
            0 => (a, 6.0),
            1 => (a, 0.0),
            2 => (b, 2.0),
            _ => (b, 0.0),
        };
        let mut m = [0.0f32; PIXEL_MEMORY];
        Observation { key: 7, light, y }.write(&mut m, 1);
        pixels.push(m);
    }
    table.merge_pass(tree, &mut pixels.iter(), 0);
    let region = table.region(7).unwrap();
    assert_eq!((table.pass, region.passes), (1, 1));
    assert_eq!(region.nodes.len(), INITIAL_CUT + 1, "one node split");
    let share = |id| region.nodes.iter().find(|n| n.id == id).unwrap().share;
    assert!(region.nodes.iter().all(|n| n.id != node));
    let total: f32 = region.nodes.iter().map(|n| n.share).sum();
    assert!((total - 1.0).abs() < 1e-6, "{total}");
    // Sides 96 : 32 (+5 % of their sum each): (96 + 6.4) / (128 + 12.8).
    let left = (96.0 + 6.4) / (128.0 + 12.8);
    assert!((share(l) - left).abs() < 1e-5, "{} vs {left}", share(l));
    assert!((share(r) - (1.0 - left)).abs() < 1e-5);
}

fn assert_bit_identical(a: &RenderResult, b: &RenderResult, name: &str) {
    let same = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .all(|(p, q)| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits));
    assert!(same, "{name}");
    assert_eq!(a.counters, b.counters, "{name}");
}

#[test]
fn varl_image_is_identical_for_any_thread_count() {
    let scene = rooms();
    for name in ["varl", "varl+bsdf"] {
        let s = create(name, &scene, &StrategyOptions::default()).unwrap();
        let run = |threads| {
            render(
                &scene,
                s.as_ref(),
                &settings(&scene, (40, 30), 6, threads),
                &|_, _| {},
            )
            .unwrap()
        };
        let (a, b) = (run(1), run(2));
        assert_bit_identical(&a, &b, name);
        let p = s.parameters();
        assert_eq!(p["passes_learnt"], 6);
        assert!(p["regions"].as_u64().unwrap() > 0, "{p}");
    }
}

#[test]
fn varl_converges_to_power_bsdf() {
    let mixed = common::mixed_scene(40);
    let rooms = rooms();
    for (scene, ref_spp, spp, size) in [
        (&mixed, 1024, 512, None),
        (&rooms, 512, 256, Some((32, 24))),
    ] {
        let d = StrategyOptions::default();
        let reference = common::render_opts(scene, "power+bsdf", &d, ref_spp, 2, 1, size);
        for name in ["varl", "varl+bsdf"] {
            let r = common::render_opts(scene, name, &d, spp, 2, 2, size);
            let failures = compare(&reference, &r, 2, 3.0);
            assert!(
                failures.is_empty(),
                "{name} vs power+bsdf on {}:\n{}",
                scene.name,
                failures.join("\n")
            );
        }
    }
}

#[test]
fn bad_varl_settings_are_errors() {
    let scene = common::mixed_scene(4);
    for bad in [
        VarlOptions {
            max_cut: 2,
            ..Default::default()
        },
        VarlOptions {
            max_cut: 100_000,
            ..Default::default()
        },
        VarlOptions {
            defensive: 0.0,
            ..Default::default()
        },
        VarlOptions {
            cells_per_diagonal: f32::NAN,
            ..Default::default()
        },
    ] {
        let o = StrategyOptions {
            varl: bad,
            ..StrategyOptions::default()
        };
        assert!(create("varl+bsdf", &scene, &o).is_err(), "{bad:?}");
    }
    let flag = |f: &str, v: &str| vec![(f.to_string(), v.to_string())];
    let s = samplers::registry::find("varl").unwrap();
    assert_eq!(
        s.options(&flag("varl-max-cut", "32")).unwrap().varl.max_cut,
        32
    );
    assert!(s.options(&flag("varl-cells", "x")).is_err());
}
