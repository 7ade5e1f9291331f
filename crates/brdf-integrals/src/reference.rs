//! Reference integrator for ∫_{C ∩ H} f(ωo, ω) cos θ dω (un-Fresnelled GGX, height-correlated
//! Smith): multi-sample MIS (balance heuristic) of visible-normal sampling and uniform sampling of
//! the cap, each with a randomly shifted R2 low-discrepancy point set. The error estimate is the
//! standard error over 8 independent random shifts, so it is honest for the QMC estimate.

use crate::cap::{Cap, Cap64};
use crate::ggx;
use crate::pivot::sample_uniform_cap64;
use crate::qmc::{R2, SplitMix64};
use glam::{DVec3, Vec3};

/// Number of independent replicates used for the error estimate.
pub const REPLICATES: usize = 8;

/// ∫_{cap ∩ H} f·cos dω with `samples` evaluations in total. Returns (value, standard error).
/// `wo` must be a unit vector above the horizon; `alpha` is GGX α.
pub fn cap_integral(wo: Vec3, alpha: f32, cap: &Cap, samples: usize) -> (f32, f32) {
    let (v, e) = cap_integral_64(
        wo.as_dvec3().normalize(),
        alpha as f64,
        &cap.to64(),
        samples,
        0x0c0f_fee5,
    );
    (v as f32, e as f32)
}

/// Same with an explicit seed for the random shifts.
pub fn cap_integral_seeded(
    wo: Vec3,
    alpha: f32,
    cap: &Cap,
    samples: usize,
    seed: u64,
) -> (f32, f32) {
    let (v, e) = cap_integral_64(
        wo.as_dvec3().normalize(),
        alpha as f64,
        &cap.to64(),
        samples,
        seed,
    );
    (v as f32, e as f32)
}

/// Directional albedo (the integral over the upper hemisphere), with its standard error.
pub fn hemisphere(wo: Vec3, alpha: f32, samples: usize) -> (f32, f32) {
    ggx::albedo_reference(alpha, wo, samples)
}

pub(crate) fn cap_integral_64(
    wo: DVec3,
    alpha: f64,
    cap: &Cap64,
    samples: usize,
    seed: u64,
) -> (f64, f64) {
    if wo.z <= 0.0 {
        return (0.0, 0.0);
    }
    if crate::cap::below_horizon(cap) {
        return (0.0, 0.0);
    }
    let area = if cap.cos > 0.0 {
        2.0 * std::f64::consts::PI * cap.sin * cap.sin / (1.0 + cap.cos)
    } else {
        cap.area()
    };
    if area <= 0.0 {
        return (0.0, 0.0);
    }
    let per = (samples / REPLICATES).max(2);
    let n1 = per / 2;
    let n2 = per - n1;
    let (n1f, n2f) = (n1 as f64, n2 as f64);
    let inside = |w: DVec3| w.dot(cap.axis) >= cap.cos;
    let mut rng = SplitMix64::new(seed);
    let mut reps = [0.0f64; REPLICATES];
    for r in reps.iter_mut() {
        let s1 = R2::new(&mut rng);
        let s2 = R2::new(&mut rng);
        let mut sum = 0.0;
        for i in 0..n1 {
            let wi = ggx::sample_wi_64(alpha, wo, s1.get(i));
            if wi.z <= 0.0 || !inside(wi) {
                continue;
            }
            let f = ggx::eval_cos_64(alpha, wo, wi);
            let p1 = ggx::pdf_wi_64(alpha, wo, wi);
            sum += f / (n1f * p1 + n2f / area);
        }
        for i in 0..n2 {
            let wi = sample_uniform_cap64(cap, s2.get(i));
            if wi.z <= 0.0 {
                continue;
            }
            let f = ggx::eval_cos_64(alpha, wo, wi);
            if f == 0.0 {
                continue;
            }
            let p1 = ggx::pdf_wi_64(alpha, wo, wi);
            sum += f / (n1f * p1 + n2f / area);
        }
        *r = sum;
    }
    ggx::mean_and_se(&reps)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ggx::wo_from_theta;

    #[test]
    fn hemisphere_cap_equals_albedo() {
        for &(alpha, th) in &[(0.001f32, 0.3f32), (0.1, 1.0), (0.6, 0.0), (1.0, 1.4)] {
            let wo = wo_from_theta(th);
            let (a, ae) = hemisphere(wo, alpha, 1 << 14);
            let (c, ce) = cap_integral(wo, alpha, &Cap::upper_hemisphere(), 1 << 14);
            assert!(
                (a - c).abs() < 4.0 * (ae * ae + ce * ce).sqrt() + 1e-4,
                "{alpha} {th}: {a}±{ae} vs {c}±{ce}"
            );
        }
    }

    #[test]
    fn tiny_cap_is_f_cos_times_solid_angle() {
        // a cap much smaller than the lobe: integral ≈ f·cos(axis)·|C|
        let wo = wo_from_theta(0.7);
        let alpha = 0.3;
        let axis = Vec3::new(-0.5, 0.2, 0.7).normalize();
        let cap = Cap::new(axis, (0.01f32).cos());
        let (v, se) = cap_integral(wo, alpha, &cap, 4096);
        let approx = ggx::eval_cos(alpha, wo, axis) * cap.solid_angle();
        assert!((v / approx - 1.0).abs() < 2e-3, "{v} ± {se} vs {approx}");
    }

    #[test]
    fn additivity_over_split_sphere() {
        // a cap and its complement add up to the albedo
        let wo = wo_from_theta(0.9);
        let alpha = 0.05;
        let axis = Vec3::new(-0.6, 0.3, 0.74).normalize();
        let c = Cap::new(axis, 0.97);
        let cc = Cap::new(-axis, -0.97);
        let (a, ae) = cap_integral(wo, alpha, &c, 1 << 14);
        let (b, be) = cap_integral(wo, alpha, &cc, 1 << 14);
        let (h, he) = hemisphere(wo, alpha, 1 << 14);
        assert!(
            ((a + b) - h).abs() < 4.0 * (ae + be + he) + 1e-4,
            "{a}+{b} vs {h}"
        );
    }
}
