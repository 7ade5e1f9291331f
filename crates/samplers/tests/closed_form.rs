//! Every baseline strategy against irradiance known in closed form.
mod common;
use common::*;
use render_core::Vec3;
use render_core::scene::SceneBuilder;
use samplers::{StrategyOptions, create};
use std::f64::consts::PI;

const STRATEGIES: [&str; 8] = [
    "uniform",
    "power",
    "bsdf",
    "power+bsdf",
    "tree",
    "tree+bsdf",
    "tree-split",
    "tree-split+bsdf",
];

#[test]
fn sphere_light_over_lambertian_plane() {
    // E = π L sin²θ cos β; a white Lambertian surface reflects L·sin²θ·cos β.
    let (radius, centre, radiance) = (0.3f32, Vec3::new(0.4, 0.0, 1.0), 5.0f32);
    let mut b = SceneBuilder::new("sphere");
    floor(&mut b, 50.0);
    b.add_sphere_light(centre, radius, Vec3::splat(radiance), None)
        .unwrap();
    let scene = b.build().unwrap();
    let d = centre.length() as f64;
    let sin2 = (radius as f64 / d).powi(2);
    let cos_beta = centre.z as f64 / d;
    let expected = radiance as f64 * sin2 * cos_beta;
    for name in STRATEGIES {
        let s = create(name, &scene, &StrategyOptions::default()).unwrap();
        let (mean, se) = estimate_at_origin(&scene, s.as_ref(), 40_000, 1);
        assert!(
            (mean - expected).abs() < 3.0 * se + 1e-6,
            "{name}: {mean} ± {se}, expected {expected}"
        );
        assert!(se < 0.05 * expected, "{name}: too noisy to test ({se})");
    }
}

/// Form factor from a point to a parallel rectangle whose corner lies above it.
fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let sx = (1.0 + x * x).sqrt();
    let sy = (1.0 + y * y).sqrt();
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

#[test]
fn emissive_square_over_lambertian_plane() {
    let (side, h, radiance) = (1.0f32, 0.8f32, 3.0f32);
    let mut b = SceneBuilder::new("square");
    floor(&mut b, 50.0);
    ceiling_square(&mut b, side, h, radiance);
    let scene = b.build().unwrap();
    // The estimate is taken at (1e-3, 2e-3): split the square into four corner rectangles around it.
    let (px, py) = (1e-3f64, 2e-3f64);
    let s = side as f64 / 2.0;
    let ff = corner_form_factor(s - px, s - py, h as f64)
        + corner_form_factor(s + px, s - py, h as f64)
        + corner_form_factor(s - px, s + py, h as f64)
        + corner_form_factor(s + px, s + py, h as f64);
    let expected = radiance as f64 * ff;
    for name in STRATEGIES {
        let st = create(name, &scene, &StrategyOptions::default()).unwrap();
        let (mean, se) = estimate_at_origin(&scene, st.as_ref(), 40_000, 2);
        assert!(
            (mean - expected).abs() < 3.0 * se + 1e-6,
            "{name}: {mean} ± {se}, expected {expected}"
        );
        assert!(se < 0.05 * expected, "{name}: too noisy to test ({se})");
    }
}

#[test]
fn point_light_is_exact_for_light_sampling() {
    // Lo = ρ/π · I cos β / d² with a delta light: no noise at all.
    let mut b = SceneBuilder::new("point");
    floor(&mut b, 50.0);
    let p = Vec3::new(0.3, -0.2, 1.5);
    b.add_point_light(p, Vec3::splat(10.0), None).unwrap();
    let scene = b.build().unwrap();
    let x = Vec3::new(1e-3, 2e-3, 0.0);
    let d = p - x;
    let expected = 10.0 * (d.z / d.length()) as f64 / (d.length_squared() as f64) / PI;
    for name in ["uniform", "power", "power+bsdf", "tree", "tree-split+bsdf"] {
        let st = create(name, &scene, &StrategyOptions::default()).unwrap();
        let (mean, _) = estimate_at_origin(&scene, st.as_ref(), 100, 3);
        assert!(
            (mean - expected).abs() < 1e-5 * expected,
            "{name}: {mean} vs {expected}"
        );
    }
}

/// Point-to-polygon irradiance of a unit-radiance polygon facing the point (Lambert's
/// formula), for a receiver at the origin with normal +z.
fn polygon_irradiance(v: &[[f64; 3]]) -> f64 {
    let mut e = 0.0;
    for k in 0..v.len() {
        let a = glam::DVec3::from(v[k]).normalize();
        let b = glam::DVec3::from(v[(k + 1) % v.len()]).normalize();
        let g = a.cross(b);
        e += a.dot(b).clamp(-1.0, 1.0).acos() * g.z / g.length();
    }
    0.5 * e.abs()
}

/// The pbrt loader's sphere and disk lights (a `Shape "sphere"` and a `Shape "disk"` under an
/// `AreaLightSource`) against closed-form irradiance, with every baseline strategy.
#[test]
fn pbrt_sphere_and_disk_lights_over_lambertian_plane() {
    let dir = std::env::temp_dir().join(format!("samplers-pbrt-lights-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (radius, centre, radiance) = (0.3f64, [0.4, 0.0, 1.0], 5.0f64);
    let (disk_r, disk_h, disk_l) = (0.6f64, 0.9f64, 3.0f64);
    let scenes = [
        (
            "sphere.pbrt",
            format!(
                "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ {radiance} {radiance} {radiance} ]\nTranslate {} {} {}\nShape \"sphere\" \"float radius\" {radius}\nAttributeEnd\n",
                centre[0], centre[1], centre[2]
            ),
        ),
        (
            "disk.pbrt",
            // the disk faces +z in object space: turn it over to face the floor
            format!(
                "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ {disk_l} {disk_l} {disk_l} ]\nTranslate 0 0 {disk_h}\nScale 1 1 -1\nShape \"disk\" \"float radius\" {disk_r}\nAttributeEnd\n"
            ),
        ),
    ];
    for (name, text) in scenes {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let mut b = SceneBuilder::new(name);
        floor(&mut b, 50.0);
        scene_formats::pbrt::add_pbrt(&mut b, &path, glam::Mat4::IDENTITY).unwrap();
        let scene = b.build().unwrap();
        let expected = if name == "sphere.pbrt" {
            assert_eq!(scene.stats.sphere_lights, 1);
            let d = glam::DVec3::from(centre).length();
            radiance * (radius / d).powi(2) * centre[2] / d
        } else {
            let n = scene_formats::pbrt::shapes::SEGMENTS;
            assert_eq!(scene.stats.triangle_lights, n);
            // the tessellated disk: a regular n-gon inscribed in the circle
            let v: Vec<[f64; 3]> = (0..n)
                .map(|k| {
                    let phi = 2.0 * PI * k as f64 / n as f64;
                    [disk_r * phi.cos() - 1e-3, disk_r * phi.sin() - 2e-3, disk_h]
                })
                .collect();
            disk_l * polygon_irradiance(&v) / PI
        };
        for s in STRATEGIES {
            let st = create(s, &scene, &StrategyOptions::default()).unwrap();
            let (mean, se) = estimate_at_origin(&scene, st.as_ref(), 40_000, 4);
            assert!(
                (mean - expected).abs() < 3.0 * se + 1e-6,
                "{name} {s}: {mean} ± {se}, expected {expected}"
            );
            assert!(se < 0.05 * expected, "{name} {s}: too noisy to test ({se})");
        }
    }
    // Left behind only when an assertion failed, to look at.
    std::fs::remove_dir_all(&dir).unwrap();
}
