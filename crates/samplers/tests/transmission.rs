//! Direct lighting at a transmitting surface (a rough dielectric): every light-sampling
//! strategy stays unbiased when most of the light arrives from below the receiver's horizon,
//! and the BO technique's density at such a point is the one it samples with.
mod common;
use brdf_integrals::{CapIntegral, Sptd};
use chi2_test::chi2_test;
use common::estimate_at_origin;
use glam::Mat4;
use light_tree::{SplitCriterion, SplitParams};
use render_core::Vec3;
use render_core::bsdf::dielectric;
use render_core::estimator::ShadingPoint;
use render_core::material::Material;
use render_core::render::shading_point;
use render_core::rng::SampleStream;
use render_core::scene::{Scene, SceneBuilder};
use samplers::brdf_oriented::importance::BoRecord;
use samplers::brdf_oriented::technique::BoState;
use samplers::tree_selection::{PowerUnits, TreeMode, TreeSelection};
use samplers::{StrategyOptions, create};

/// A frosted pane in the plane z = 0 (normal +z, glass behind it) with sphere and two-sided
/// triangle lights below it and one sphere light above: seen from +z, most of its light is
/// transmitted.
fn pane_scene() -> Scene {
    let mut b = SceneBuilder::new("pane");
    let glass = b
        .add_material(dielectric::material("glass", Vec3::ONE, 1.5, 0.3))
        .unwrap();
    let h = 20.0;
    let p = [
        Vec3::new(-h, -h, 0.0),
        Vec3::new(h, -h, 0.0),
        Vec3::new(h, h, 0.0),
        Vec3::new(-h, h, 0.0),
    ];
    b.add_mesh(
        "pane",
        &p,
        None,
        None,
        &[0, 1, 2, 0, 2, 3],
        Mat4::IDENTITY,
        glass,
    )
    .unwrap();
    let lamp = b
        .add_material(Material {
            emission: Vec3::splat(4.0),
            double_sided: true,
            ..Material::diffuse("lamp", Vec3::ZERO)
        })
        .unwrap();
    let mut rng = SampleStream::new(3, 0, 0);
    for k in 0..24 {
        let u = rng.next_2d();
        let c = Vec3::new(
            3.0 * u.x - 1.5,
            3.0 * u.y - 1.5,
            -0.4 - 1.5 * rng.next_f32(),
        );
        if k % 2 == 0 {
            b.add_sphere_light(c, 0.05, Vec3::splat(6.0), None).unwrap();
        } else {
            let t = [
                c,
                c + Vec3::new(0.15, 0.0, 0.05),
                c + Vec3::new(0.0, 0.15, 0.1),
            ];
            b.add_mesh("tri", &t, None, None, &[0, 1, 2], Mat4::IDENTITY, lamp)
                .unwrap();
        }
    }
    b.add_sphere_light(Vec3::new(1.0, 0.3, 1.5), 0.1, Vec3::splat(3.0), None)
        .unwrap();
    b.build().unwrap()
}

/// The share of `scene`'s power that lies below z = 0.
fn share_below(scene: &Scene) -> f32 {
    let (mut below, mut all) = (0.0, 0.0);
    for l in &scene.lights {
        let p = l.power();
        all += p;
        if l.bounds().0.z < 0.0 {
            below += p;
        }
    }
    below / all
}

/// Every strategy that estimates at one point, against power + BSDF with many samples: the
/// lights behind the pane must be found, and weighed right.
#[test]
fn every_strategy_sees_the_lights_behind_a_transmitting_point() {
    let scene = pane_scene();
    assert!(share_below(&scene) > 0.8);
    let d = StrategyOptions::default();
    let reference = create("power+bsdf", &scene, &d).unwrap();
    let (want, want_se) = estimate_at_origin(&scene, reference.as_ref(), 200_000, 1);
    assert!(want > 0.0 && want_se < 0.01 * want, "{want} ± {want_se}");
    for name in [
        "uniform",
        "power",
        "bsdf",
        "tree",
        "tree+bsdf",
        "tree-split",
        "tree-split+bsdf",
        "sg-tree",
        "sg-tree+bsdf",
        "mis3-equal",
        "mis3-adaptive",
        "slc+bsdf",
        "slc-bo+bsdf",
        "rht+bsdf",
        "rht-bo+bsdf",
        "varl+bsdf",
        "ris",
    ] {
        let s = create(name, &scene, &d).unwrap();
        let (got, se) = estimate_at_origin(&scene, s.as_ref(), 40_000, 2);
        let tol = 3.5 * (se * se + want_se * want_se).sqrt();
        assert!(
            (got - want).abs() < tol,
            "{name}: {got} ± {se}, power+bsdf {want} ± {want_se}"
        );
    }
}

/// Where ωo looks at the pane from above, in the middle of its lights.
fn pane_point(scene: &Scene) -> ShadingPoint {
    let hit = scene
        .intersect(
            Vec3::new(0.1, 0.05, 1.0),
            Vec3::new(-0.3, 0.0, -1.0).normalize(),
            0.0,
            f32::INFINITY,
        )
        .unwrap();
    shading_point(scene, hit, Vec3::new(0.3, 0.0, 1.0).normalize()).unwrap()
}

/// BO at a transmitting point: its selection matches its pmf (chi-square), it selects lights
/// behind the pane, and a light point's density is the one its replay gives.
#[test]
fn bo_at_a_transmitting_point_is_exact_and_reaches_behind() {
    let scene = pane_scene();
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
    let sp = pane_point(&scene);
    assert!(sp.bsdf.transmits());
    let sptd = Sptd::default();
    let lobe = sptd.lobe(sp.bsdf.frame.to_local(sp.wo), sp.bsdf.params.alpha);
    let rec = BoRecord::new(&sp, lobe, true, false)
        .with_transmission(&sp, |view, alpha| sptd.lobe(view, alpha));
    assert!(rec.transmitted.is_some());
    let bo = BoState::new(tree, rec, 0.5, 64, None);
    let n = scene.lights.len();
    let below: f32 = (0..n)
        .filter(|&l| scene.lights[l].bounds().0.z < 0.0)
        .map(|l| bo.selection_pmf(tree, l))
        .sum();
    assert!(
        below > 0.5,
        "BO's probability of the lights behind: {below}"
    );
    let samples = 60_000;
    let mut observed = vec![0.0; n + 1];
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs());
    for i in 0..samples {
        let mut rng = SampleStream::new(9, 0, i);
        match bo.select(tree, &mut rng, true) {
            Some((light, p)) => {
                observed[light] += 1.0;
                assert!(close(p, bo.selection_pmf(tree, light)));
                let l = &scene.lights[light];
                if let Some(s) = bo.sample_point(l, &mut rng) {
                    let replay = bo.point_pdf(l, s.point, s.normal, s.wi);
                    assert!(close(s.pdf, replay), "{} vs {replay}", s.pdf);
                }
            }
            None => observed[n] += 1.0,
        }
    }
    let mut expected: Vec<f64> = (0..n)
        .map(|l| bo.selection_pmf(tree, l) as f64 * samples as f64)
        .collect();
    let total: f64 = expected.iter().sum();
    expected.push((samples as f64 - total).max(0.0));
    let out = chi2_test(&observed, &expected);
    assert!(out.p_value > 1e-4, "{out:?}");
}
