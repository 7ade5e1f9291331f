//! pbrt-v3's `plastic` material: f = Kd/π + Ks · D · G · F / (4 cos θo cos θi), with a
//! Trowbridge–Reitz (GGX) D, height-correlated Smith G and pbrt-v3's `FresnelDielectric(1.5, 1)`
//! evaluated at the angle between ωi and the half vector, whose swapped indices make it total
//! reflection past 41.8° ([`crate::bsdf::fresnel::dielectric`]). The two lobes are added with no
//! coupling, and sampling picks either with probability ½, as pbrt-v3's BSDF does over its
//! BxDFs. [`crate::bsdf::Bsdf`] evaluates and samples it ([`crate::bsdf::Specular::PbrtPlastic`]);
//! the glTF loader (`extras.pbrt`) and the pbrt scene loader build it here.
use crate::material::{Material, Model};
use glam::Vec3;

/// pbrt-v3's defaults for `plastic`.
pub const DEFAULT_KD: f32 = 0.25;
pub const DEFAULT_KS: f32 = 0.25;
pub const DEFAULT_ROUGHNESS: f32 = 0.1;

/// pbrt-v3's `TrowbridgeReitzDistribution::RoughnessToAlpha`: a quartic in ln(roughness)
/// (roughness clamped to ≥ 1e-3), used when `remaproughness` is true (its default).
pub fn roughness_to_alpha(roughness: f32) -> f32 {
    let x = roughness.max(1e-3).ln();
    1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x
}

/// A pbrt-v3 `plastic` material.
pub fn material(name: &str, kd: Vec3, ks: Vec3, roughness: f32, remap_roughness: bool) -> Material {
    let alpha = if remap_roughness {
        roughness_to_alpha(roughness)
    } else {
        roughness
    };
    Material {
        model: Model::PbrtPlastic {
            ks: ks.max(Vec3::ZERO),
            alpha,
        },
        ..Material::diffuse(name, kd.max(Vec3::ZERO))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::rng::SampleStream;
    use chi2_test::{chi2_directions, sidak_significance};
    use glam::Vec2;
    use std::f64::consts::PI;

    fn plastic(kd: f32, ks: f32, alpha: f32, wo: Vec3) -> Bsdf {
        let m = material("p", Vec3::splat(kd), Vec3::splat(ks), alpha, false);
        Bsdf::new(Vec3::Z, Vec3::Z, wo, m.params_at(Vec2::ZERO))
    }

    fn dir(theta: f64, phi: f64) -> Vec3 {
        Vec3::new(
            (theta.sin() * phi.cos()) as f32,
            (theta.sin() * phi.sin()) as f32,
            theta.cos() as f32,
        )
    }

    /// pbrt-v3 plastic written out independently in f64, straight from its formulas.
    fn reference_f_cos(kd: f64, ks: f64, alpha: f64, wo: Vec3, wi: Vec3) -> f64 {
        let (wo, wi) = (wo.as_dvec3(), wi.as_dvec3());
        let h = (wo + wi).normalize();
        let a2 = alpha * alpha;
        let d = a2 / (PI * (h.z * h.z * (a2 - 1.0) + 1.0).powi(2));
        let lambda = |w: glam::DVec3| {
            let tan2 = (1.0 - w.z * w.z) / (w.z * w.z);
            0.5 * ((1.0 + a2 * tan2).sqrt() - 1.0)
        };
        let g = 1.0 / (1.0 + lambda(wo) + lambda(wi));
        // FrDielectric(cos, ηi = 1.5, ηt = 1), as pbrt-v3's plastic calls it
        let ci = wi.dot(h);
        let si = (1.0 - ci * ci).sqrt();
        let st = 1.5 * si;
        let fr = if st >= 1.0 {
            1.0
        } else {
            let ct = (1.0 - st * st).sqrt();
            let rpar = (ci - 1.5 * ct) / (ci + 1.5 * ct);
            let rperp = (1.5 * ci - ct) / (1.5 * ci + ct);
            0.5 * (rpar * rpar + rperp * rperp)
        };
        kd / PI * wi.z + ks * d * g * fr / (4.0 * wo.z)
    }

    /// f·cos against the independent formula, over directions on both sides of the 41.8° quirk.
    #[test]
    #[allow(clippy::approx_constant)] // φ = 3.14159: just short of π, on purpose
    fn eval_matches_pbrt_v3_formula() {
        for &(kd, ks, alpha) in &[(0.3, 0.7, 0.008), (0.1, 0.7, 0.3), (0.5, 0.25, 0.8)] {
            for &(to, ti, phi) in &[
                (0.3, 0.35, 3.1),
                (0.2, 1.2, 3.14159),
                (1.0, 0.9, 3.0),
                (0.5, 0.7, 1.0),
                (1.3, 1.4, 2.5),
            ] {
                let wo = dir(to, 0.0);
                let wi = dir(ti, phi);
                let b = plastic(kd, ks, alpha, wo);
                let got = b.eval_cos(wo, wi).x as f64;
                let want = reference_f_cos(kd as f64, ks as f64, alpha as f64, wo, wi);
                assert!(
                    (got - want).abs() <= 2e-4 * want.abs() + 1e-6,
                    "kd {kd} ks {ks} α {alpha} θo {to} θi {ti}: {got} vs {want}"
                );
            }
        }
    }

    /// The specular weight Ks·F at the angles of the scene README's table (Ks = 0.7).
    #[test]
    fn fresnel_weight_has_pbrt_v3_quirk() {
        let spec = crate::bsdf::Specular::PbrtPlastic {
            ks: Vec3::splat(0.7),
        };
        for (deg, want) in [
            (0.0f32, 0.028f32),
            (30.0, 0.039),
            (40.0, 0.17),
            (42.0, 0.7),
            (70.0, 0.7),
        ] {
            let got = spec.weight(deg.to_radians().cos()).x;
            assert!((got - want).abs() < 0.006, "{deg}°: {got} vs {want}");
        }
    }

    #[test]
    fn roughness_remap_is_pbrt_v3_polynomial() {
        for r in [0.001f64, 0.01, 0.1, 0.5, 1.0] {
            let x = r.ln();
            let want = 1.62142
                + 0.819955 * x
                + 0.1734 * x.powi(2)
                + 0.0171201 * x.powi(3)
                + 0.000640711 * x.powi(4);
            assert!((roughness_to_alpha(r as f32) as f64 - want).abs() < 1e-4 * want.abs());
        }
        // roughness 0.1 (pbrt's default) remaps to α ≈ 0.46
        assert!((roughness_to_alpha(0.1) - 0.4618).abs() < 1e-3);
    }

    /// Sampling matches `pdf` (chi-square) with both lobes, the glossy lobe alone and Lambert alone.
    #[test]
    fn sampling_matches_pdf_chi2() {
        let cases = [
            (0.3, 0.7, 0.05, 0.3),
            (0.1, 0.7, 0.2, 1.0),
            (0.0, 0.7, 0.1, 0.6),
            (0.5, 0.0, 0.1, 0.4),
            (0.2, 0.5, 0.6, 1.45),
        ];
        let sig = sidak_significance(0.01, cases.len());
        for (k, &(kd, ks, alpha, theta)) in cases.iter().enumerate() {
            let wo = dir(theta, 0.0);
            let b = plastic(kd, ks, alpha, wo);
            let out = chi2_directions(
                200_000,
                40,
                80,
                6,
                |i| {
                    let mut r = SampleStream::new(100 + k as u64, i as u64, 0);
                    b.sample(wo, r.next_f32(), r.next_2d()).map(|s| s.wi)
                },
                |w| b.pdf(wo, w) as f64,
            );
            assert!(out.p_value > sig, "case {k}: {out:?}");
        }
    }

    /// Each lobe is picked with probability ½ (pbrt-v3 picks one of its two BxDFs uniformly),
    /// and a sample's value and density are those `eval_cos` and `pdf` give later.
    #[test]
    fn lobes_are_picked_evenly_and_samples_agree_with_eval() {
        let wo = dir(0.7, 0.0);
        let b = plastic(0.3, 0.7, 0.01, wo);
        assert_eq!(b.specular_probability(b.frame.to_local(wo)), 0.5);
        let wi = dir(0.9, 2.0);
        let lambert = (wi.z as f64) / PI;
        let glossy = b
            .ggx
            .reflection_pdf(b.frame.to_local(wo), b.frame.to_local(wi)) as f64;
        assert!(((b.pdf(wo, wi) as f64) - 0.5 * (lambert + glossy)).abs() < 1e-5);
        let mut r = SampleStream::new(5, 0, 0);
        for _ in 0..1000 {
            if let Some(s) = b.sample(wo, r.next_f32(), r.next_2d()) {
                assert_eq!(s.pdf, b.pdf(wo, s.wi));
                assert_eq!(s.f_cos, b.eval_cos(wo, s.wi));
            }
        }
    }

    /// Albedo ∫ f cos dωi through `sample` against closed forms: a narrow lobe (α = 0.01) seen
    /// at θo reflects Ks·F(θo) (G ≈ 1, all half vectors ≈ the normal), and Lambert reflects Kd.
    #[test]
    fn albedo_matches_closed_form() {
        for (kd, ks, theta) in [(0.0f32, 0.7f32, 1.1f32), (0.0, 0.7, 0.35), (0.4, 0.0, 0.8)] {
            let wo = dir(theta as f64, 0.0);
            let b = plastic(kd, ks, 0.01, wo);
            let mut r = SampleStream::new(11, 0, 0);
            let n = 40_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                if let Some(s) = b.sample(wo, r.next_f32(), r.next_2d()) {
                    sum += (s.f_cos.x / s.pdf) as f64;
                }
            }
            let got = sum / n as f64;
            let want = kd as f64
                + ks as f64 * crate::bsdf::fresnel::dielectric(theta.cos(), 1.5, 1.0) as f64;
            assert!(
                (got - want).abs() < 0.01 * want,
                "kd {kd} ks {ks} θo {theta}: {got} vs {want}"
            );
        }
    }
}
