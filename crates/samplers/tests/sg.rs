//! The SG light tree (issue 24): its importance against exact contributions where the SG
//! light is exact (point lights), its support against the tree's conservative bounds, and its
//! selection against its own pmf (chi-square, replay).
mod common;
use chi2_test::chi2_test;
use light_tree::{LightBounds, LightTree, SgEmitter, SgNodes};
use render_core::Vec3;
use render_core::bsdf::{Bsdf, BsdfParams, Specular};
use render_core::colour::luminance;
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::{NO_LIGHT, SurfaceHit};
use samplers::selection::LightSelection;
use samplers::sg::{SgShading, SgTreeSelection};
use samplers::tree_selection::PowerUnits;
use std::f32::consts::PI;

/// A shading point at the origin, normal +z, viewed from `wo`.
fn shading_point(wo: Vec3, params: BsdfParams) -> ShadingPoint {
    ShadingPoint {
        hit: SurfaceHit {
            point: Vec3::ZERO,
            t: 1.0,
            ng: Vec3::Z,
            ns: Vec3::Z,
            uv: render_core::Vec2::ZERO,
            material: Some(0),
            light: NO_LIGHT,
        },
        wo,
        bsdf: Bsdf::new(Vec3::Z, Vec3::Z, wo, params),
    }
}

/// The SG importance of one isotropic point light of intensity 1 at `p`.
fn point_importance(sp: &ShadingPoint, p: Vec3) -> f32 {
    let tree = LightTree::build(&[LightBounds::point(p, 1.0)]).unwrap();
    let sg = SgNodes::build(&tree, &[SgEmitter::point(p)]).unwrap();
    SgShading::new(sp).importance(tree.node(0), sg.node(0))
}

fn direction(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// For a point light the SG light is a delta, so on a Lambertian surface the importance is
/// the exact contribution Kd/π · cos θ · I/d², plus the 1 % floor.
#[test]
fn point_light_importance_is_the_diffuse_contribution() {
    let params = BsdfParams {
        diffuse: Vec3::new(0.2, 0.5, 0.7),
        specular: Specular::None,
        alpha: 0.5,
    };
    let sp = shading_point(direction(0.4, 0.0), params);
    for &(theta, phi, d) in &[(0.0, 0.0, 1.0), (0.7, 1.0, 3.0), (1.4, -2.0, 0.5)] {
        let p = direction(theta, phi) * d;
        let exact = luminance(params.diffuse) / PI * theta.cos() / (d * d);
        let ratio = point_importance(&sp, p) / exact;
        assert!(
            (ratio - (1.0 + samplers::sg::importance::FLOOR)).abs() < 2e-3,
            "θ = {theta}: ratio {ratio}"
        );
    }
    // Below the horizon: nothing, exactly.
    assert_eq!(point_importance(&sp, Vec3::new(0.0, 1.0, -0.1)), 0.0);
}

/// On a glossy surface the point-light importance F · D/(4√(α²sin²θo + cos²θo)) tracks the exact
/// F · D · G2/(4 cos θo) wherever the exact value is above 1 % of its peak, for α 0.1–0.6 and
/// θo up to 70°: measured ratios 0.79–1.41 for cos θi > 0.35, 1.0–3.9 below (it lacks the
/// shadowing of ωi, so it overestimates towards the horizon, never underestimates much).
#[test]
fn point_light_importance_tracks_the_glossy_brdf() {
    const GRAZING: f32 = 0.35;
    for &alpha in &[0.1f32, 0.3, 0.6] {
        for &theta_o in &[0.2f32, 0.8, 1.2] {
            let params = BsdfParams {
                diffuse: Vec3::ZERO,
                specular: Specular::Schlick {
                    f0: Vec3::splat(0.9),
                },
                alpha,
            };
            let wo = direction(theta_o, 0.0);
            let sp = shading_point(wo, params);
            let mut cases = Vec::new();
            for i in 0..40 {
                for j in 0..40 {
                    let wi = direction(
                        (i as f32 + 0.5) / 40.0 * 1.5,
                        (j as f32 + 0.5) / 40.0 * 2.0 * PI,
                    );
                    let exact = luminance(sp.bsdf.eval_cos(sp.wo, wi));
                    cases.push((wi, exact, point_importance(&sp, wi * 2.0) * 4.0));
                }
            }
            let peak = cases.iter().map(|c| c.1).fold(0.0, f32::max);
            for (wi, exact, got) in cases {
                assert!(got > 0.0, "positive above the horizon");
                if exact > 0.01 * peak {
                    let ratio = got / exact;
                    let high = if wi.z > GRAZING { 1.5 } else { 4.5 };
                    assert!(
                        (1.0 / 1.5..high).contains(&ratio),
                        "α = {alpha}, θo = {theta_o}, ωi = {wi}: {got} vs {exact}"
                    );
                }
            }
        }
    }
}

/// The importance is zero exactly where the tree's conservative E&K importance is, for every
/// node of the mixed scene at its shading points: a node the bounds admit keeps a non-zero
/// probability.
#[test]
fn importance_vanishes_only_where_the_bounds_do() {
    let scene = common::mixed_scene(40);
    let sel = SgTreeSelection::new(&scene, PowerUnits::Watts).unwrap();
    let (tree, sg) = sel.tree().unwrap();
    let sps = common::shading_points_towards(&scene, common::MIXED_CAMERA, &common::MIXED_TARGETS);
    assert!(sps.len() >= 3);
    let (mut zero, mut positive) = (0, 0);
    for sp in &sps {
        let shading = SgShading::new(sp);
        for (id, node) in tree.nodes().iter().enumerate() {
            let ek = node.importance(sp.point(), sp.bsdf.ng);
            let imp = shading.importance(node, sg.node(id as u32));
            assert!(imp.is_finite() && imp >= 0.0);
            assert_eq!(ek > 0.0, imp > 0.0, "node {id}: E&K {ek}, SG {imp}");
            if imp > 0.0 {
                positive += 1;
            } else {
                zero += 1;
            }
        }
    }
    assert!(positive > 0 && zero > 0, "{positive} positive, {zero} zero");
}

/// Shading points of the mixed scene plus one on its metal panel.
fn mixed_points(scene: &render_core::scene::Scene) -> Vec<ShadingPoint> {
    let mut targets = common::MIXED_TARGETS.to_vec();
    targets.push(Vec3::new(0.6, 0.3, -0.2));
    common::shading_points_towards(scene, common::MIXED_CAMERA, &targets)
}

/// Drawn lights follow the selection's pmf (chi-square, the missing mass of dead ends in one
/// extra bin), and the pmf a pick reports is the pmf replayed for its light, bit for bit.
#[test]
fn selection_matches_its_pmf_chi2_and_replay() {
    let scene = common::mixed_scene(40);
    let sel = SgTreeSelection::new(&scene, PowerUnits::Watts).unwrap();
    let n = scene.lights.len();
    let samples = 200_000u64;
    for (k, sp) in mixed_points(&scene).iter().enumerate() {
        let state = sel.prepare(&scene, sp);
        let mut observed = vec![0.0; n + 1];
        let mut picks = Vec::new();
        for i in 0..samples {
            let mut rng = SampleStream::new(17 + k as u64, 0, i);
            picks.clear();
            sel.pick(&state, sp, &mut rng, &mut picks);
            match picks.first() {
                Some(&(l, pmf)) => {
                    assert_eq!(pmf, sel.pmf(&state, sp, l), "pick pmf vs replay");
                    observed[l as usize] += 1.0;
                }
                None => observed[n] += 1.0,
            }
        }
        let mut expected: Vec<f64> = (0..n)
            .map(|l| sel.pmf(&state, sp, l as u32) as f64 * samples as f64)
            .collect();
        let total: f64 = expected.iter().sum();
        assert!(total <= samples as f64 * (1.0 + 1e-5));
        expected.push((samples as f64 - total).max(0.0));
        let out = chi2_test(&observed, &expected);
        assert!(out.p_value > 1e-4, "point {k}: {}", out.message);
    }
}

/// The SG descent follows the BSDF: at every shading point of the mixed scene with a diffuse
/// lobe (plastic floor, diffuse panel), the relative variance of a one-light estimate of the
/// unshadowed direct light, Σ c²/p / (Σ c)² − 1 with c the lights' exact unshadowed
/// contributions, is lower under the SG pmf than under the plain tree's binary descent, the
/// same descent under E&K's importance (measured: 0.014 vs 0.084, 0.041 vs 0.046, 0.034 vs
/// 0.071, 0.25 vs 1.05). The plain strategy's own four-wide descent (`quad.rs` in light-tree)
/// is printed beside them, not asserted: it beats the SG pmf at the third point (0.015 vs
/// 0.036). Not asserted either: the metal panel
/// (α = 0.0225, no light within 45° of its mirror direction, all contribution from the GGX
/// tails), where it is worse, 1.79 vs 0.54: a cluster's SG is evaluated at its mean direction,
/// and the tails fall off too fast across a cluster for that to rank its lights.
#[test]
fn diffuse_points_get_lower_variance_than_the_plain_tree() {
    use samplers::tree_selection::{TreeMode, TreeSelection};
    let scene = common::mixed_scene(40);
    let sg = SgTreeSelection::new(&scene, PowerUnits::Watts).unwrap();
    let plain = TreeSelection::new(&scene, TreeMode::Single, PowerUnits::Watts).unwrap();
    let mut with_diffuse = 0;
    for (k, sp) in mixed_points(&scene).iter().enumerate() {
        let c: Vec<f64> = scene
            .lights
            .iter()
            .map(|l| samplers::oracle::unshadowed_contribution(l, sp))
            .collect();
        let total: f64 = c.iter().sum();
        let variance = |pmf: &dyn Fn(u32) -> f32| {
            c.iter()
                .enumerate()
                .filter(|(_, c)| **c > 0.0)
                .map(|(l, c)| c * c / pmf(l as u32) as f64)
                .sum::<f64>()
                / (total * total)
                - 1.0
        };
        let s_state = sg.prepare(&scene, sp);
        let p_state = plain.prepare(&scene, sp);
        let v_sg = variance(&|l| sg.pmf(&s_state, sp, l));
        let (tree, _) = sg.tree().expect("the mixed scene has lights");
        let (x, n) = (sp.point(), sp.bsdf.ng);
        let binary =
            |l: u32| tree.pmf_subtree(tree.root(), |c| tree.importance(c, x, n), l as usize);
        let v_plain = variance(&binary);
        let v_four = variance(&|l| plain.pmf(&p_state, sp, l));
        eprintln!(
            "point {k}: α {} Kd {}: relative variance SG {v_sg:.4}, plain binary {v_plain:.4}, \
             plain four-wide {v_four:.4}",
            sp.bsdf.ggx.alpha, sp.bsdf.params.diffuse
        );
        if sp.bsdf.has_diffuse() {
            with_diffuse += 1;
            assert!(v_sg < v_plain, "point {k}: SG {v_sg} vs plain {v_plain}");
        }
    }
    assert!(with_diffuse >= 3);
}
