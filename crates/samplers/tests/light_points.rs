//! Every strategy converges to the same image whichever way the points on triangle lights are
//! drawn (`--light-points`), and the strategies' MIS weighs a BSDF-sampled hit by the density
//! the chosen point sampler gives it.
mod common;
use glam::Mat4;
use render_core::Vec3;
use render_core::camera::Camera;
use render_core::light_points::LightPoints;
use render_core::material::Material;
use render_core::scene::{Scene, SceneBuilder};
use samplers::StrategyOptions;
use samplers::convergence::compare;

fn render(scene: &Scene, name: &str, spp: u32, seed: u64) -> render_core::render::RenderResult {
    common::render_opts(scene, name, &StrategyOptions::default(), spp, 2, seed, None)
}

/// Where the point samplers differ most: a large square light 0.5 above a glossy metal floor
/// (z = 0) and close to a rough metal wall, seen from above at an angle. The mixed scene's small
/// lights alone would not catch a wrong density (its samplers nearly agree there).
fn panel(points: LightPoints) -> Scene {
    let mut b = SceneBuilder::new("panel");
    let metal = |b: &mut SceneBuilder, name: &str, roughness: f32| {
        b.add_material(Material::simple(
            name,
            Vec3::new(0.9, 0.8, 0.6),
            1.0,
            roughness,
        ))
        .unwrap()
    };
    let (floor, wall) = (metal(&mut b, "floor", 0.15), metal(&mut b, "wall", 0.3));
    let quad = |b: &mut SceneBuilder, p: [Vec3; 4], m: u32| {
        b.add_mesh(
            "quad",
            &p,
            None,
            None,
            &[0, 1, 2, 0, 2, 3],
            Mat4::IDENTITY,
            m,
        )
        .unwrap();
    };
    let v = Vec3::new;
    quad(
        &mut b,
        [
            v(-3., -3., 0.),
            v(3., -3., 0.),
            v(3., 3., 0.),
            v(-3., 3., 0.),
        ],
        floor,
    );
    quad(
        &mut b,
        [
            v(-3., 1.2, 0.),
            v(3., 1.2, 0.),
            v(3., 1.2, 2.),
            v(-3., 1.2, 2.),
        ],
        wall,
    );
    common::ceiling_square(&mut b, 1.6, 0.5, 3.0);
    b.add_camera(
        Camera::look_at(
            "cam",
            v(0.0, -2.2, 1.6),
            v(0.0, 0.2, 0.0),
            Vec3::Z,
            50f32.to_radians(),
            40,
            30,
        )
        .unwrap(),
    );
    let mut scene = b.build().unwrap();
    scene.light_points = points;
    scene
}

/// Every point sampler, and the method's BRDF-aware points, converge to area sampling's image
/// of the panel.
#[test]
fn point_samplers_agree_on_a_large_close_light() {
    let reference = render(&panel(LightPoints::Area), "power+bsdf", 1024, 1);
    let ltc = StrategyOptions {
        ltc_triangles: true,
        ..StrategyOptions::default()
    };
    for points in [LightPoints::SolidAngle, LightPoints::SolidAngleWarp] {
        let scene = panel(points);
        for (name, opts, spp) in [
            ("power+bsdf", StrategyOptions::default(), 256),
            ("mis3-adaptive", StrategyOptions::default(), 32),
            ("mis3-adaptive", ltc.clone(), 32),
        ] {
            let r = common::render_opts(&scene, name, &opts, spp, 2, 5, None);
            let failures = compare(&reference, &r, 4, 3.0);
            assert!(
                failures.is_empty(),
                "{name} (ltc {}) under {}:\n{}",
                opts.ltc_triangles,
                points.name(),
                failures.join("\n")
            );
        }
    }
}

/// The mixed scene: glossy, metal and diffuse surfaces lit by two quads of triangle lights
/// (one two-sided) close to them, and sphere lights.
#[test]
fn every_strategy_converges_under_every_point_sampler() {
    let area = common::mixed_scene(20);
    let reference = render(&area, "power+bsdf", 256, 1);
    for points in [LightPoints::SolidAngle, LightPoints::SolidAngleWarp] {
        let mut scene = common::mixed_scene(20);
        scene.light_points = points;
        for (name, spp) in [
            ("power+bsdf", 64),
            ("tree+bsdf", 64),
            ("mis3-adaptive", 16),
            ("slc+bsdf", 16),
            ("rht+bsdf", 64),
            ("varl+bsdf", 64),
        ] {
            let r = render(&scene, name, spp, 2);
            let failures = compare(&reference, &r, 2, 3.0);
            assert!(
                failures.is_empty(),
                "{name} under {} vs power+bsdf by area:\n{}",
                points.name(),
                failures.join("\n")
            );
        }
    }
}

/// The method with BRDF-aware points on triangle lights, mixed with each point sampler.
#[test]
fn the_method_converges_with_ltc_points() {
    let area = common::mixed_scene(20);
    let reference = render(&area, "power+bsdf", 256, 1);
    let opts = StrategyOptions {
        ltc_triangles: true,
        ..StrategyOptions::default()
    };
    for points in [LightPoints::Area, LightPoints::SolidAngle] {
        let mut scene = common::mixed_scene(20);
        scene.light_points = points;
        let r = common::render_opts(&scene, "mis3-adaptive", &opts, 16, 2, 4, None);
        let failures = compare(&reference, &r, 2, 3.0);
        assert!(
            failures.is_empty(),
            "mis3-adaptive --ltc-triangles under {}:\n{}",
            points.name(),
            failures.join("\n")
        );
    }
}

/// The default draws what it always drew: `area` renders the image of a scene built without
/// naming a point sampler, bit for bit, and another sampler renders a different one.
#[test]
fn area_is_the_default_and_the_others_differ() {
    let base = common::mixed_scene(4);
    let mut area = common::mixed_scene(4);
    area.light_points = LightPoints::Area;
    let mut solid = common::mixed_scene(4);
    solid.light_points = LightPoints::SolidAngle;
    let bits = |s: &Scene| {
        let r = render(s, "power+bsdf", 4, 3);
        r.pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&base), bits(&area));
    assert_ne!(bits(&base), bits(&solid));
}
