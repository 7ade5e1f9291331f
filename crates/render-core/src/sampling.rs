//! Warping functions from the unit square and their densities.
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Cosine-weighted direction in the local frame (z up); pdf = cos θ / π.
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) / PI
}

/// Shirley–Chiu concentric map of the square onto the unit disk.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, PI / 4.0 * (o.y / o.x))
    } else {
        (o.y, PI / 2.0 - PI / 4.0 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Uniform direction in the cone around +z whose half-angle has
/// `1 − cos θmax = one_minus_cos_max`. Taking 1 − cos rather than cos keeps precision for
/// tiny cones (a sphere of radius 0.001 seen from distance 1 has 1 − cos ≈ 5e-7).
/// pdf = 1 / (2π · one_minus_cos_max).
pub fn uniform_cone(u: Vec2, one_minus_cos_max: f32) -> Vec3 {
    let omc = u.x * one_minus_cos_max;
    let cos_t = 1.0 - omc;
    let sin_t = (omc * (2.0 - omc)).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

pub fn uniform_cone_pdf(one_minus_cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos_max)
}

/// 1 − cos θ of the cone subtended by a sphere of radius r at distance d (d > r), accurate for
/// tiny spheres.
pub fn sphere_cone_one_minus_cos(radius: f32, dist: f32) -> f32 {
    let sin2 = (radius / dist).powi(2).min(1.0);
    sin2 / (1.0 + (1.0 - sin2).sqrt())
}

/// Uniform barycentrics (b1, b2) on a triangle; b0 = 1 − b1 − b2. Low-distortion square-root map.
pub fn uniform_triangle(u: Vec2) -> Vec2 {
    let su = u.x.sqrt();
    Vec2::new(1.0 - su, u.y * su)
}

/// Uniform direction on the sphere; pdf = 1/(4π).
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}
