//! Issue 13: the oracle's selection and the RIS candidate source and resampling step against
//! their own probabilities (chi-square), and their densities at sampling against replays.
mod common;
use brdf_integrals::Sptd;
use chi2_test::chi2_test;
use render_core::Vec3;
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use samplers::oracle::OracleSelection;
use samplers::ris::CandidateCount;
use samplers::ris::candidates::CandidateSource;
use samplers::ris::resample;
use samplers::ris::strategy::Ris;
use samplers::selection::LightSelection;
use samplers::tree_selection::{PowerUnits, TreeMode, TreeSelection};

/// Shading points on the mixed scene's glossy floor, metal panel and diffuse panel.
fn shading_points(scene: &Scene) -> Vec<ShadingPoint> {
    // The method tests' points and one more on the metal panel.
    let mut targets = common::MIXED_TARGETS.to_vec();
    targets.push(Vec3::new(0.6, 0.3, -0.2));
    common::shading_points_towards(scene, common::MIXED_CAMERA, &targets)
}

/// Chi-square of `draw` (a light index or `None`) against `pmf` over the lights, the missing
/// mass in one extra bin.
fn chi2_lights(
    n_lights: usize,
    samples: u64,
    mut draw: impl FnMut(u64) -> Option<usize>,
    pmf: impl Fn(usize) -> f64,
) -> (f64, String) {
    let mut observed = vec![0.0; n_lights + 1];
    for i in 0..samples {
        match draw(i) {
            Some(l) => observed[l] += 1.0,
            None => observed[n_lights] += 1.0,
        }
    }
    let mut expected: Vec<f64> = (0..n_lights).map(|l| pmf(l) * samples as f64).collect();
    let total: f64 = expected.iter().sum();
    expected.push((samples as f64 - total).max(0.0));
    let out = chi2_test(&observed, &expected);
    (out.p_value, out.message)
}

/// The unshadowed oracle and the shadowed one (issue 25's bound).
fn oracles(scene: &Scene) -> [OracleSelection; 2] {
    [
        OracleSelection::new(scene),
        OracleSelection::shadowed(scene),
    ]
}

#[test]
fn oracle_pmf_sums_to_one_and_covers_every_emitting_light() {
    let scene = common::mixed_scene(40);
    for oracle in oracles(&scene) {
        pmf_sums_to_one_and_covers_every_emitting_light(&scene, &oracle);
    }
}

fn pmf_sums_to_one_and_covers_every_emitting_light(scene: &Scene, oracle: &OracleSelection) {
    let sps = shading_points(scene);
    assert!(sps.len() >= 4);
    for sp in &sps {
        let state = oracle.prepare(scene, sp);
        let sum: f64 = (0..scene.lights.len())
            .map(|l| oracle.pmf(&state, sp, l as u32) as f64)
            .sum();
        assert!((sum - 1.0).abs() < 1e-5, "Σ pmf = {sum}");
        // The defensive mix: a light that emits can always be chosen, even where its
        // stratified estimate is 0 (lights behind the point, say).
        for (l, light) in scene.lights.iter().enumerate() {
            if light.power() > 0.0 {
                assert!(oracle.pmf(&state, sp, l as u32) > 0.0, "light {l}");
            }
        }
    }
}

#[test]
fn oracle_selection_matches_its_pmf_chi2() {
    let scene = common::mixed_scene(40);
    for oracle in oracles(&scene) {
        selection_matches_its_pmf_chi2(&scene, &oracle);
    }
}

fn selection_matches_its_pmf_chi2(scene: &Scene, oracle: &OracleSelection) {
    for (k, sp) in shading_points(scene).iter().enumerate() {
        let state = oracle.prepare(scene, sp);
        let mut picks = Vec::new();
        let (p, msg) = chi2_lights(
            scene.lights.len(),
            100_000,
            |i| {
                let mut rng = SampleStream::new(31 + k as u64, 0, i);
                picks.clear();
                oracle.pick(&state, sp, &mut rng, &mut picks);
                let &(l, pmf) = picks.first()?;
                assert_eq!(pmf, oracle.pmf(&state, sp, l), "pick pmf vs pmf");
                Some(l as usize)
            },
            |l| oracle.pmf(&state, sp, l as u32) as f64,
        );
        assert!(p > 1e-4, "point {k}: p = {p} ({msg})");
    }
}

/// The shadowed oracle's weight of a light is its unshadowed one with the occluded stratum
/// midpoints left out: never more, the same for most lights of the open scene, and zero for
/// every light once an opaque slab hides the floor from all of them (the floor's points then
/// keep only the defensive power share).
#[test]
fn shadowed_oracle_drops_exactly_the_occluded_midpoints() {
    use samplers::oracle::{shadowed_contribution, unshadowed_contribution};
    let open = common::mixed_scene(40);
    // A slab at y = 0.3 over the whole floor: the lights are all above it (y ≥ 0.43).
    let mut b = common::mixed_scene_builder(40);
    let slab = b
        .add_material(render_core::material::Material::diffuse("slab", Vec3::ONE))
        .unwrap();
    let p = [(-4.0, -4.0), (4.0, -4.0), (4.0, 4.0), (-4.0, 4.0)].map(|(x, z)| Vec3::new(x, 0.3, z));
    b.add_mesh(
        "slab",
        &p,
        None,
        None,
        &[0, 1, 2, 0, 2, 3],
        glam::Mat4::IDENTITY,
        slab,
    )
    .unwrap();
    let walled = b.build().unwrap();
    assert_eq!(open.lights.len(), walled.lights.len());
    let (mut same, mut lit, mut floor_pairs) = (0, 0, 0);
    for sp in &shading_points(&open) {
        for (l, light) in open.lights.iter().enumerate() {
            let free = unshadowed_contribution(light, sp);
            let seen = shadowed_contribution(light, sp, &open);
            assert!(
                seen <= free,
                "light {l}: shadowed {seen} > unshadowed {free}"
            );
            lit += (free > 0.0) as usize;
            same += (free > 0.0 && seen == free) as usize;
            if sp.point().y.abs() < 1e-3 && free > 0.0 {
                floor_pairs += 1;
                let hidden = shadowed_contribution(&walled.lights[l], sp, &walled);
                assert_eq!(hidden, 0.0, "light {l} seen through the slab");
            }
        }
    }
    assert!(
        same * 2 > lit,
        "{same} of {lit} lit pairs unoccluded in the open scene"
    );
    assert!(floor_pairs > 0, "no floor point to hide");
}

fn ris_strategy(scene: &Scene) -> Ris<Sptd> {
    Ris {
        name: "ris".into(),
        tree: TreeSelection::new(scene, TreeMode::Single, PowerUnits::Watts)
            .unwrap()
            .tree,
        integral: Sptd::default(),
        count: CandidateCount::Fixed(8),
        delta: 0.5,
        max_cut: 64,
    }
}

#[test]
fn ris_candidate_sources_match_their_pmfs_chi2_and_replay() {
    let scene = common::mixed_scene(40);
    let ris = ris_strategy(&scene);
    let tree = ris.tree.as_ref().unwrap();
    let n = scene.lights.len();
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs());
    let mut with_bo = 0;
    for (k, sp) in shading_points(&scene).iter().enumerate() {
        let bo = ris.bo_state(&scene, sp);
        with_bo += bo.is_some() as usize;
        let source = CandidateSource::new(&scene, tree, sp, bo.as_ref(), 8);
        assert_eq!(source.count(), 8);
        // Slot 0 is LS; the last slot is BO where the point has a BO state.
        let slots: Vec<(u32, &str)> = if source.n_bo > 0 {
            vec![(0, "LS"), (7, "BO")]
        } else {
            vec![(0, "LS")]
        };
        for (slot, label) in slots {
            let pmf = |l: usize| {
                if slot < source.n_ls {
                    source.ls_pmf(l as u32) as f64
                } else {
                    bo.as_ref().unwrap().selection_pmf(tree, l) as f64
                }
            };
            let mut replayed = 0;
            let (p, msg) = chi2_lights(
                n,
                60_000,
                |i| {
                    let mut rng = SampleStream::new(41 + k as u64, slot as u64, i);
                    let d = source.sample(slot, &mut rng)?;
                    let s = d.sample;
                    // The light's point density at sampling equals the source's replay.
                    let point_pdf = if slot < source.n_ls {
                        source.ls_pdf(d.light, s.point, s.normal, s.is_delta)
                            / source.ls_pmf(d.light)
                    } else {
                        source.bo_pdf(d.light, s.point, s.normal, s.wi)
                            / bo.as_ref().unwrap().selection_pmf(tree, d.light as usize)
                    };
                    assert!(close(s.pdf, point_pdf), "{label}: {} vs {point_pdf}", s.pdf);
                    replayed += 1;
                    Some(d.light as usize)
                },
                pmf,
            );
            assert!(p > 1e-4, "point {k} {label}: p = {p} ({msg})");
            assert!(replayed > 1000, "point {k} {label}: {replayed} candidates");
        }
        // The mixture density is the slot-count-weighted mean of the two.
        let mut rng = SampleStream::new(3, 0, k as u64);
        if let Some(d) = source.sample(0, &mut rng) {
            let s = d.sample;
            let ls = source.ls_pdf(d.light, s.point, s.normal, s.is_delta);
            let bo_p = source.bo_pdf(d.light, s.point, s.normal, s.wi);
            let mix = source.mixture_pdf(d.light, s.point, s.normal, s.wi, s.is_delta);
            let expect = (source.n_ls as f32 * ls + source.n_bo as f32 * bo_p) / 8.0;
            assert!(close(mix, expect), "{mix} vs {expect}");
        }
    }
    assert!(with_bo >= 2, "the test must reach BO candidates");
}

#[test]
fn resampling_picks_in_proportion_to_the_weights_chi2() {
    let weights = [0.5f32, 0.0, 3.0, 1e-3, 1.25, 0.0, 7.0, 0.2];
    let samples = 200_000u64;
    let mut observed = vec![0.0f64; weights.len()];
    for i in 0..samples {
        let mut rng = SampleStream::new(51, 0, i);
        let (k, total) = resample::pick(&weights, rng.next_f32()).unwrap();
        assert_eq!(total, weights.iter().sum::<f32>());
        assert!(weights[k] > 0.0);
        observed[k] += 1.0;
    }
    let expected: Vec<f64> = (0..weights.len())
        .map(|i| resample::pmf(&weights, i) as f64 * samples as f64)
        .collect();
    let out = chi2_test(&observed, &expected);
    assert!(out.p_value > 1e-4, "p = {} ({})", out.p_value, out.message);
    assert_eq!(resample::pick(&[0.0, 0.0], 0.3), None);
    assert_eq!(resample::pick(&[], 0.3), None);
}

#[test]
fn adaptive_candidate_count_follows_the_bo_upper_bound() {
    let c = CandidateCount::Adaptive { min: 4, max: 32 };
    assert_eq!(c.at(0.0), 4);
    assert_eq!(c.at(1.0), 32);
    assert_eq!(c.at(0.5), 18);
    assert_eq!(c.at(f32::NAN), 4);
    assert_eq!(CandidateCount::Fixed(0).at(0.3), 1);
    // The BO cut of a glossy point has a positive UB.
    let scene = common::mixed_scene(40);
    let ris = ris_strategy(&scene);
    let sp = shading_points(&scene)[0];
    let ub = ris.bo_state(&scene, &sp).unwrap().cut().upper_bound();
    assert!(ub > 0.0 && ub <= 1.0);
}
