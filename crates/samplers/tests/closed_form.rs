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
