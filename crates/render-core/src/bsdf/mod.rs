//! The BSDF at a surface point: Lambert plus a GGX lobe weighted by its Fresnel
//! ([`Specular`]: glTF's Schlick, or pbrt-v3 `plastic`'s Ks × dielectric Fresnel), the lobes
//! added, not coupled; or a rough dielectric that reflects and transmits ([`dielectric`]).
//!
//! Directions are in world space; the BSDF works in the local frame of the shading normal,
//! flipped to the viewer's side. For the reflecting materials a direction below the geometric
//! surface (as seen from the viewer) gets zero; the dielectric takes it as transmitted, and
//! zero only where the geometric and the shading normal disagree on the side.
pub mod dielectric;
pub mod fresnel;
pub mod microfacet;
mod params;
pub mod plastic;

pub use params::{BsdfParams, Specular};

use crate::colour::luminance;
use crate::frame::Frame;
use glam::{Vec2, Vec3};
use microfacet::{Ggx, PairTerms, reflect};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    /// Shading frame; z is the shading normal on the viewer's side.
    pub frame: Frame,
    /// Geometric normal on the viewer's side.
    pub ng: Vec3,
    pub params: BsdfParams,
    pub ggx: Ggx,
    /// η beyond the surface over η on the viewer's side for a dielectric, 1 otherwise.
    pub eta: f32,
}

/// f · |cos θi| and the solid-angle density of one direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfValue {
    pub f_cos: Vec3,
    pub pdf: f32,
}

#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// f · |cos θi| (shading normal).
    pub f_cos: Vec3,
    /// Solid-angle density of `wi`.
    pub pdf: f32,
}

impl Bsdf {
    /// `ns`, `ng`: shading and geometric normals (any orientation); `wo` points away from the surface.
    pub fn new(ns: Vec3, ng: Vec3, wo: Vec3, params: BsdfParams) -> Bsdf {
        let eta = match params.specular {
            // the index lies behind the geometric normal: a viewer there looks out of it
            Specular::Dielectric { ior, .. } if ng.dot(wo) < 0.0 => 1.0 / ior,
            Specular::Dielectric { ior, .. } => ior,
            _ => 1.0,
        };
        let ng = if ng.dot(wo) < 0.0 { -ng } else { ng };
        let mut ns = if ns.dot(ng) < 0.0 { -ns } else { ns };
        if !ns.is_finite() || ns.length_squared() < 0.5 {
            ns = ng;
        }
        Bsdf {
            frame: Frame::from_normal_and_direction(ns, wo),
            ng,
            params,
            ggx: Ggx::new(params.alpha),
            eta,
        }
    }

    /// True when the BSDF transmits: light from below the surface reaches the viewer, so no
    /// light may be culled by the receiver's hemisphere.
    #[inline]
    pub fn transmits(&self) -> bool {
        matches!(self.params.specular, Specular::Dielectric { .. })
    }

    /// True when the specular lobe is absent (the paper skips BRDF-oriented sampling there).
    pub fn is_pure_diffuse(&self) -> bool {
        self.params.specular.is_none()
    }

    /// The glossy lobe's weight where it peaks, in the mirror configuration (half vector =
    /// normal, so ωi makes θo with it): the Fresnel-weighted colour the lobe reflects with
    /// (for a dielectric, from the side the viewer is on).
    pub fn glossy_weight(&self, wo_local: Vec3) -> Vec3 {
        if self.is_pure_diffuse() {
            return Vec3::ZERO;
        }
        if self.transmits() {
            return Vec3::splat(self.reflectance(wo_local.z));
        }
        self.params.specular.weight(wo_local.z)
    }

    pub fn has_diffuse(&self) -> bool {
        self.params.diffuse.max_element() > 0.0
    }

    /// Probability of choosing the specular lobe when sampling, a fixed function of (wo, params).
    /// pbrt-v3 picks one of its BxDFs uniformly, so `plastic` takes ½; the glTF lobe follows
    /// the lobes' weights at ωo.
    pub fn specular_probability(&self, wo_local: Vec3) -> f32 {
        if self.is_pure_diffuse() {
            return 0.0;
        }
        if !self.has_diffuse() {
            return 1.0;
        }
        if let Specular::PbrtPlastic { .. } = self.params.specular {
            return 0.5;
        }
        let s = luminance(self.params.specular.weight(wo_local.z));
        let d = luminance(self.params.diffuse);
        (s / (s + d)).clamp(0.25, 0.9)
    }

    fn valid(&self, wo: Vec3, wi: Vec3) -> bool {
        wo.dot(self.ng) > 0.0 && wi.dot(self.ng) > 0.0
    }

    /// Both directions in the shading frame, if both lie above the geometric and the shading
    /// surface (else the value and the density are zero).
    #[inline]
    fn local_pair(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3)> {
        if !self.valid(wo, wi) {
            return None;
        }
        let lo = self.frame.to_local(wo);
        let li = self.frame.to_local(wi);
        if lo.z <= 0.0 || li.z <= 0.0 {
            return None;
        }
        Some((lo, li))
    }

    /// The glossy lobe's shared terms at (lo, li), if it has one.
    #[inline]
    fn glossy_terms(&self, lo: Vec3, li: Vec3) -> Option<PairTerms> {
        (!self.is_pure_diffuse()).then(|| self.ggx.pair(lo, li))
    }

    #[inline]
    fn f_cos_local(&self, lo: Vec3, li: Vec3, glossy: Option<&PairTerms>) -> Vec3 {
        let mut f = self.params.diffuse * (li.z / PI);
        if let Some(t) = glossy {
            f += self.params.specular.weight(li.dot(t.h)) * self.ggx.eval_cos_at(t, lo, li);
        }
        f
    }

    #[inline]
    fn pdf_local(&self, lo: Vec3, li: Vec3, glossy: Option<&PairTerms>) -> f32 {
        let ps = self.specular_probability(lo);
        let mut pdf = (1.0 - ps) * li.z / PI;
        if ps > 0.0
            && let Some(t) = glossy
        {
            pdf += ps * self.ggx.reflection_pdf_at(t, lo);
        }
        pdf
    }

    /// f(wo, wi) · cos θi (shading normal).
    pub fn eval_cos(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if self.transmits() {
            return self.eval_dielectric(wo, wi).f_cos;
        }
        let Some((lo, li)) = self.local_pair(wo, wi) else {
            return Vec3::ZERO;
        };
        self.f_cos_local(lo, li, self.glossy_terms(lo, li).as_ref())
    }

    /// Solid-angle density with which [`Bsdf::sample`] picks `wi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.transmits() {
            return self.eval_dielectric(wo, wi).pdf;
        }
        let Some((lo, li)) = self.local_pair(wo, wi) else {
            return 0.0;
        };
        self.pdf_local(lo, li, self.glossy_terms(lo, li).as_ref())
    }

    /// [`Bsdf::eval_cos`] and [`Bsdf::pdf`] of one direction from one evaluation (the frame
    /// change, the half vector, D and Λ(wo) shared), bit for bit what the two give.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> BsdfValue {
        if self.transmits() {
            return self.eval_dielectric(wo, wi);
        }
        let Some((lo, li)) = self.local_pair(wo, wi) else {
            return BsdfValue {
                f_cos: Vec3::ZERO,
                pdf: 0.0,
            };
        };
        let glossy = self.glossy_terms(lo, li);
        BsdfValue {
            f_cos: self.f_cos_local(lo, li, glossy.as_ref()),
            pdf: self.pdf_local(lo, li, glossy.as_ref()),
        }
    }

    /// Sample a direction: `u_lobe` picks the lobe, `u` drives it.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let lo = self.frame.to_local(wo);
        if lo.z <= 0.0 || wo.dot(self.ng) <= 0.0 {
            return None;
        }
        if self.transmits() {
            return self.sample_dielectric(wo, lo, u_lobe, u);
        }
        let ps = self.specular_probability(lo);
        let li = if u_lobe < ps {
            let h = self.ggx.sample_visible_normal(lo, u);
            reflect(lo, h)
        } else {
            crate::sampling::cosine_hemisphere(u)
        };
        if li.z <= 0.0 {
            return None;
        }
        let wi = self.frame.to_world(li);
        let v = self.eval(wo, wi);
        if v.pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi,
            f_cos: v.f_cos,
            pdf: v.pdf,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SampleStream;
    use chi2_test::{chi2_directions, sidak_significance};

    fn bsdf(alpha: f32, diffuse: f32, f0: f32, wo: Vec3) -> Bsdf {
        let params = BsdfParams {
            diffuse: Vec3::splat(diffuse),
            specular: if f0 > 0.0 {
                Specular::Schlick {
                    f0: Vec3::splat(f0),
                }
            } else {
                Specular::None
            },
            alpha,
        };
        Bsdf::new(Vec3::Z, Vec3::Z, wo, params)
    }

    /// Every sampled direction's density matches `pdf` (chi-square), for glossy, mixed and diffuse lobes.
    #[test]
    fn sampling_matches_pdf_chi2() {
        let cases = [
            (0.05, 0.0, 1.0, 0.3),
            (0.2, 0.5, 0.04, 1.0),
            (0.6, 0.3, 0.5, 0.1),
            (1.0, 0.8, 0.0, 0.7),
            (0.1, 0.2, 0.04, 1.45),
        ];
        let alpha_sig = sidak_significance(0.01, cases.len());
        for (k, &(alpha, kd, f0, theta)) in cases.iter().enumerate() {
            let wo = Vec3::new((theta as f32).sin(), 0.0, (theta as f32).cos());
            let b = bsdf(alpha, kd, f0, wo);
            let out = chi2_directions(
                200_000,
                40,
                80,
                6,
                |i| {
                    let mut r = SampleStream::new(k as u64, i as u64, 0);
                    b.sample(wo, r.next_f32(), r.next_2d()).map(|s| s.wi)
                },
                |w| b.pdf(wo, w) as f64,
            );
            assert!(
                out.p_value > alpha_sig,
                "case {k} (α={alpha}, θo={theta}): {out:?}"
            );
        }
    }

    /// The sample's returned value and density are those `eval_cos`/`pdf` give later.
    #[test]
    fn sample_agrees_with_eval_and_pdf() {
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let b = bsdf(0.01, 0.3, 0.04, wo);
        let mut r = SampleStream::new(3, 0, 0);
        for _ in 0..1000 {
            if let Some(s) = b.sample(wo, r.next_f32(), r.next_2d()) {
                assert_eq!(s.pdf, b.pdf(wo, s.wi));
                assert_eq!(s.f_cos, b.eval_cos(wo, s.wi));
                assert!(s.pdf > 0.0 && s.f_cos.is_finite());
            }
        }
    }

    /// The one-evaluation `eval` gives `eval_cos` and `pdf` bit for bit, in every lobe mix and
    /// for directions below either surface (a shading normal tilted off the geometric one).
    #[test]
    fn eval_is_eval_cos_and_pdf() {
        let mut r = SampleStream::new(5, 0, 0);
        let cases = [
            (0.01, 0.3, 0.04),
            (0.4, 0.0, 1.0),
            (1.0, 0.8, 0.0),
            (0.2, 0.5, 0.5),
        ];
        for (alpha, kd, f0) in cases {
            for _ in 0..2000 {
                let wo = crate::sampling::uniform_sphere(r.next_2d());
                let wi = crate::sampling::uniform_sphere(r.next_2d());
                let ns = (Vec3::Z + 0.3 * crate::sampling::uniform_sphere(r.next_2d())).normalize();
                let mut b = bsdf(alpha, kd, f0, wo);
                b.frame = Frame::from_normal_and_direction(ns, wo);
                let v = b.eval(wo, wi);
                assert_eq!(v.f_cos, b.eval_cos(wo, wi));
                assert_eq!(v.pdf.to_bits(), b.pdf(wo, wi).to_bits());
            }
        }
    }

    /// White furnace: ∫ f·cos for a pure white Lambert lobe is 1 (MC estimate through sample()).
    #[test]
    fn lambert_albedo_is_its_colour() {
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let b = bsdf(1.0, 0.7, 0.0, wo);
        let mut r = SampleStream::new(9, 0, 0);
        let n = 20_000;
        let mut sum = 0.0;
        for _ in 0..n {
            if let Some(s) = b.sample(wo, r.next_f32(), r.next_2d()) {
                sum += (s.f_cos.x / s.pdf) as f64;
            }
        }
        assert!(
            (sum / n as f64 - 0.7).abs() < 1e-4,
            "cosine sampling of Lambert is exact: {}",
            sum / n as f64
        );
    }
}
