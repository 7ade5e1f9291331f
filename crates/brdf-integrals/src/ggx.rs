//! The GGX (Trowbridge–Reitz) microfacet lobe used by the renderer: isotropic, height-correlated
//! Smith masking-shadowing, no Fresnel. Local frame: z is the normal. `alpha` is the GGX α itself.
//!
//! The `f32` functions are the public API; the `*_64` twins are used by the reference integrator
//! and the fits, where α = 0.001 makes the lobe very sharp.

use crate::qmc::{R2, SplitMix64};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// Normal distribution D(h) = α² / (π (cos²θ (α² − 1) + 1)²), zero for h below the surface.
pub fn d(alpha: f32, h: Vec3) -> f32 {
    d_64(alpha as f64, h.as_dvec3()) as f32
}

/// Smith Λ(w) = (−1 + √(1 + α² tan²θ)) / 2.
pub fn lambda(alpha: f32, w: Vec3) -> f32 {
    lambda_64(alpha as f64, w.as_dvec3()) as f32
}

/// Height-correlated Smith G2 = 1 / (1 + Λ(wo) + Λ(wi)); zero if either direction is below the
/// surface.
pub fn g2_height_correlated(alpha: f32, wo: Vec3, wi: Vec3) -> f32 {
    g2_64(alpha as f64, wo.as_dvec3(), wi.as_dvec3()) as f32
}

/// The integrand of every cap integral in this crate: f(wo, wi) · cos θi = D(h) G2 / (4 cos θo),
/// no Fresnel, zero when wo or wi is at or below the horizon. `wo` and `wi` must be unit vectors.
pub fn eval_cos(alpha: f32, wo: Vec3, wi: Vec3) -> f32 {
    eval_cos_64(alpha as f64, wo.as_dvec3(), wi.as_dvec3()) as f32
}

/// Directional albedo ∫_H f · cos dωi by randomly shifted quasi-Monte Carlo with visible-normal
/// sampling (its weight G2/G1 lies in [0, 1], so this converges fast). Returns (value, standard
/// error estimated from 8 independent replicates).
pub fn albedo_reference(alpha: f32, wo: Vec3, samples: usize) -> (f32, f32) {
    let (v, e) = albedo_64(alpha as f64, wo.as_dvec3(), samples, 8, 0x5eed);
    (v as f32, e as f32)
}

#[inline]
pub(crate) fn d_64(alpha: f64, h: DVec3) -> f64 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let c2 = h.z * h.z / h.length_squared();
    let t = c2 * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

#[inline]
pub(crate) fn lambda_64(alpha: f64, w: DVec3) -> f64 {
    let c2 = w.z * w.z;
    let s2 = (w.x * w.x + w.y * w.y).max(0.0);
    if s2 == 0.0 {
        return 0.0;
    }
    if c2 == 0.0 {
        return f64::INFINITY;
    }
    let a2t2 = alpha * alpha * s2 / c2;
    // (√(1+x) − 1)/2 written without cancellation for small x
    0.5 * a2t2 / ((1.0 + a2t2).sqrt() + 1.0)
}

#[inline]
pub(crate) fn g1_64(alpha: f64, w: DVec3) -> f64 {
    if w.z <= 0.0 {
        return 0.0;
    }
    1.0 / (1.0 + lambda_64(alpha, w))
}

#[inline]
pub(crate) fn g2_64(alpha: f64, wo: DVec3, wi: DVec3) -> f64 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    1.0 / (1.0 + lambda_64(alpha, wo) + lambda_64(alpha, wi))
}

#[inline]
pub(crate) fn eval_cos_64(alpha: f64, wo: DVec3, wi: DVec3) -> f64 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let h = wo + wi;
    let l2 = h.length_squared();
    if l2 == 0.0 {
        return 0.0;
    }
    let h = h / l2.sqrt();
    d_64(alpha, h) * g2_64(alpha, wo, wi) / (4.0 * wo.z)
}

/// Visible-normal sampling (Heitz 2018). Returns the microfacet normal h for uniform `u`.
#[inline]
pub(crate) fn sample_vndf_64(alpha: f64, wo: DVec3, u: [f64; 2]) -> DVec3 {
    let vh = DVec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        DVec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
    } else {
        DVec3::X
    };
    let t2 = vh.cross(t1);
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let p1 = r * phi.cos();
    let mut p2 = r * phi.sin();
    let s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// Samples wi by reflecting wo about a visible normal; returns wi (may be below the horizon).
#[inline]
pub(crate) fn sample_wi_64(alpha: f64, wo: DVec3, u: [f64; 2]) -> DVec3 {
    let h = sample_vndf_64(alpha, wo, u);
    2.0 * wo.dot(h) * h - wo
}

/// Solid-angle pdf of `sample_wi_64`: G1(wo) D(h) / (4 cos θo).
#[inline]
pub(crate) fn pdf_wi_64(alpha: f64, wo: DVec3, wi: DVec3) -> f64 {
    let h = wo + wi;
    let l2 = h.length_squared();
    if l2 == 0.0 || wo.z <= 0.0 {
        return 0.0;
    }
    let h = h / l2.sqrt();
    g1_64(alpha, wo) * d_64(alpha, h) / (4.0 * wo.z)
}

/// Directional albedo by `replicates` randomly shifted R2 point sets of `samples / replicates`
/// points each; returns (mean, standard error of the mean).
pub(crate) fn albedo_64(
    alpha: f64,
    wo: DVec3,
    samples: usize,
    replicates: usize,
    seed: u64,
) -> (f64, f64) {
    let mut rng = SplitMix64::new(seed);
    let per = (samples / replicates).max(1);
    let g1o = g1_64(alpha, wo);
    let mut means = Vec::with_capacity(replicates);
    for _ in 0..replicates {
        let seq = R2::new(&mut rng);
        let mut s = 0.0;
        for i in 0..per {
            let wi = sample_wi_64(alpha, wo, seq.get(i));
            if wi.z > 0.0 {
                s += g2_64(alpha, wo, wi) / g1o;
            }
        }
        means.push(s / per as f64);
    }
    mean_and_se(&means)
}

pub(crate) fn mean_and_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    if xs.len() < 2 {
        return (m, f64::NAN);
    }
    let var = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// ωo = (sin θo, 0, cos θo).
pub fn wo_from_theta(theta_o: f32) -> Vec3 {
    Vec3::new(theta_o.sin(), 0.0, theta_o.cos())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn d_is_normalised_projected_area() {
        // ∫ D(h) cos θh dh = 1, by midpoint quadrature in (cos θ, φ)-independent form.
        for &alpha in &[0.05f64, 0.3, 1.0] {
            let n = 20000;
            let mut s = 0.0;
            for i in 0..n {
                // substitute t = tan²θ spread: integrate over μ = cos θ with 2π symmetry
                let mu = (i as f64 + 0.5) / n as f64;
                let h = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                s += d_64(alpha, h) * mu * 2.0 * PI / n as f64;
            }
            assert!((s - 1.0).abs() < 2e-3, "alpha {alpha}: {s}");
        }
    }

    #[test]
    fn vndf_pdf_matches_weight() {
        // f·cos / pdf must equal G2/G1 for every sample above the horizon.
        let alpha = 0.3;
        let wo = DVec3::new(0.6, 0.0, 0.8);
        let mut rng = SplitMix64::new(1);
        for _ in 0..1000 {
            let u = [rng.next_f64(), rng.next_f64()];
            let wi = sample_wi_64(alpha, wo, u);
            if wi.z <= 0.0 {
                continue;
            }
            let w = eval_cos_64(alpha, wo, wi) / pdf_wi_64(alpha, wo, wi);
            let expect = g2_64(alpha, wo, wi) / g1_64(alpha, wo);
            assert!(
                (w - expect).abs() < 1e-9 * expect.max(1.0),
                "{w} vs {expect}"
            );
        }
    }

    #[test]
    fn albedo_is_one_at_normal_incidence_for_smooth_surfaces() {
        let (a, se) = albedo_reference(0.001, wo_from_theta(0.0), 4096);
        assert!((a - 1.0).abs() < 1e-3 && se < 1e-3, "{a} ± {se}");
        // rough surfaces lose energy to single-scattering
        let (a, _) = albedo_reference(1.0, wo_from_theta(1.0), 4096);
        assert!(a > 0.3 && a < 0.9, "{a}");
    }

    #[test]
    fn eval_cos_zero_below_horizon() {
        let wo = wo_from_theta(0.5);
        assert_eq!(eval_cos(0.3, wo, Vec3::new(0.0, 0.6, -0.8)), 0.0);
        assert_eq!(eval_cos(0.3, Vec3::new(0.0, 0.6, -0.8), wo), 0.0);
        assert!(eval_cos(0.3, wo, Vec3::Z) > 0.0);
    }
}
