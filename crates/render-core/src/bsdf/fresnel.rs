//! Fresnel reflectance: Schlick's approximation (the glTF lobe) and pbrt-v3's dielectric
//! Fresnel as its `plastic` material calls it.
use glam::Vec3;

/// Schlick's approximation from the normal-incidence reflectance `f0`.
pub fn schlick(f0: Vec3, cos_theta: f32) -> Vec3 {
    let m = (1.0 - cos_theta.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

/// Unpolarised Fresnel reflectance of a smooth dielectric interface for light arriving at
/// cos θi = `cos_i` on the side of index `eta_i` (the other side has `eta_t`); a negative
/// `cos_i` means the light arrives from the `eta_t` side. Total internal reflection gives 1.
///
/// pbrt-v3's `plastic` evaluates this with `eta_i` = 1.5 and `eta_t` = 1 for light arriving
/// from outside (the indices are swapped with respect to the physics), so its specular weight
/// is 0.04 at normal incidence and 1 once the angle between ωi and the half vector passes
/// asin(1/1.5) ≈ 41.8°. [`crate::bsdf::plastic`] reproduces that on purpose.
pub fn dielectric(cos_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let (mut eta_i, mut eta_t) = (eta_i, eta_t);
    if cos_i <= 0.0 {
        std::mem::swap(&mut eta_i, &mut eta_t);
        cos_i = -cos_i;
    }
    let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
    let sin_t = eta_i / eta_t * sin_i;
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let parallel = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    let perpendicular = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    0.5 * (parallel * parallel + perpendicular * perpendicular)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values from the textbook formulas, evaluated independently: air → glass at normal
    /// incidence is ((1.5 − 1)/(1.5 + 1))² = 0.04 from either side; Brewster's angle
    /// (tan θ = 1.5) zeroes the parallel part; the critical angle of 1.5 → 1 is asin(1/1.5).
    #[test]
    fn dielectric_matches_closed_forms() {
        assert!((dielectric(1.0, 1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((dielectric(1.0, 1.5, 1.0) - 0.04).abs() < 1e-6);
        let brewster = 1.5f32.atan();
        let (ci, si) = (brewster.cos(), brewster.sin());
        let ct = (1.0 - (si / 1.5).powi(2)).sqrt();
        let perp = ((ci - 1.5 * ct) / (ci + 1.5 * ct)).powi(2);
        assert!((dielectric(ci, 1.0, 1.5) - 0.5 * perp).abs() < 1e-5);
        let critical = (1.0f32 / 1.5).asin();
        assert_eq!(dielectric((critical + 1e-3).cos(), 1.5, 1.0), 1.0);
        assert!(dielectric((critical - 1e-2).cos(), 1.5, 1.0) < 1.0);
        // arriving from the other side swaps the indices
        assert_eq!(dielectric(-0.3, 1.0, 1.5), dielectric(0.3, 1.5, 1.0));
        // Schlick is exact at both ends
        assert_eq!(schlick(Vec3::splat(0.04), 1.0), Vec3::splat(0.04));
        assert_eq!(schlick(Vec3::splat(0.04), 0.0), Vec3::ONE);
    }
}
