//! A rough dielectric interface that reflects and transmits: GGX microfacets as Walter,
//! Marschner, Li and Torrance (EGSR 2007) describe them, with height-correlated Smith
//! masking-shadowing (as for the reflection lobe), the exact dielectric Fresnel term choosing
//! between reflection and refraction, and visible-normal sampling of the microfacet.
//!
//! Conventions (local frame of [`super::Bsdf`]: z is the shading normal on the viewer's side):
//! * `eta` is the index of refraction beyond the surface over the one on the viewer's side
//!   (the material's `ior` when the viewer is on the side the geometric normal faces, 1/`ior`
//!   otherwise). Reflection keeps ωi above the surface, transmission puts it below.
//! * The half vector of a refracted pair is the generalised one, h ∝ ωo + η ωi, turned to +z;
//!   a pair whose ωo or ωi lies on the wrong side of its microfacet has zero value and density.
//! * The BTDF is the one for radiance: f = T·D·G·|ωi·h||ωo·h| / (|cos θi| cos θo (ωo·h + η ωi·h)²)
//!   with the indices relative to the viewer's side, which carries the (ηo/ηi)² factor by which
//!   radiance changes across the interface. Its energy balance is R + η²·T_albedo ≤ 1, not
//!   R + T_albedo ≤ 1, and it is reciprocal in the generalised form f(ωo, ωi)/ηo² = f(ωi, ωo)/ηi².
//! * The tint multiplies transmission only (glTF's transmission colour); reflection is the
//!   uncoloured Fresnel reflectance, as from clear glass.
use super::microfacet::{Ggx, MIN_ALPHA, reflect};
use super::{BsdfSample, BsdfValue, Specular, fresnel};
use crate::material::{Material, Model};
use glam::{Vec2, Vec3};

/// The least |ior − 1| accepted: an index-matched interface refracts nothing and its
/// microfacet BTDF degenerates to a delta.
pub const MIN_IOR_GAP: f32 = 1e-3;

/// A rough dielectric material: `tint` colours the transmitted light, `alpha` is GGX's α.
pub fn material(name: &str, tint: Vec3, ior: f32, alpha: f32) -> Material {
    Material {
        model: Model::Dielectric {
            ior,
            alpha: alpha.clamp(MIN_ALPHA, 1.0),
        },
        ..Material::diffuse(name, tint.max(Vec3::ZERO))
    }
}

/// The range of indices of refraction accepted (beyond it 1/ior and η² leave f32's range
/// in the BSDF's arithmetic; real materials lie far inside).
pub const IOR_RANGE: (f32, f32) = (0.01, 100.0);

/// Why an index of refraction cannot be used, if it cannot.
pub fn check_ior(ior: f32) -> Result<(), String> {
    if !(IOR_RANGE.0..=IOR_RANGE.1).contains(&ior) {
        return Err(format!(
            "ior {ior} is outside [{}, {}]",
            IOR_RANGE.0, IOR_RANGE.1
        ));
    }
    if (ior - 1.0).abs() < MIN_IOR_GAP {
        return Err(format!(
            "ior {ior} is within {MIN_IOR_GAP} of 1 (an index-matched interface that refracts nothing)"
        ));
    }
    Ok(())
}

/// f·|cos θi| (before the tint) and the sampling density of one pair of local directions, and
/// whether ωi is transmitted (so the caller knows whether to tint it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalValue {
    pub f_cos: f32,
    pub pdf: f32,
    pub transmitted: bool,
}

const ZERO: LocalValue = LocalValue {
    f_cos: 0.0,
    pdf: 0.0,
    transmitted: false,
};

/// The dielectric lobe at one shading point, in the local frame.
#[derive(Clone, Copy, Debug)]
pub struct RoughDielectric {
    pub ggx: Ggx,
    /// η beyond the surface over η on the viewer's side.
    pub eta: f32,
}

impl RoughDielectric {
    /// Fresnel reflectance for ωo meeting a microfacet at cos θ = `cos_oh`.
    #[inline]
    pub fn fresnel(&self, cos_oh: f32) -> f32 {
        fresnel::dielectric(cos_oh, 1.0, self.eta)
    }

    /// The direction ωo refracts to through microfacet `h` (ωo·h > 0), or `None` under total
    /// internal reflection.
    pub fn refract(&self, lo: Vec3, h: Vec3) -> Option<Vec3> {
        let cos_o = lo.dot(h);
        let sin2_t = (1.0 - cos_o * cos_o).max(0.0) / (self.eta * self.eta);
        if sin2_t >= 1.0 {
            return None;
        }
        let cos_t = (1.0 - sin2_t).sqrt();
        Some((-lo / self.eta + (cos_o / self.eta - cos_t) * h).normalize())
    }

    /// A direction for `lo` (lo.z > 0): a visible microfacet from `u`, then reflection with
    /// the Fresnel reflectance's probability (`u_lobe` below it), else refraction.
    pub fn sample(&self, lo: Vec3, u_lobe: f32, u: Vec2) -> Option<Vec3> {
        let h = self.ggx.sample_visible_normal(lo, u);
        let cos_oh = lo.dot(h);
        if cos_oh <= 0.0 {
            return None;
        }
        if u_lobe < self.fresnel(cos_oh) {
            Some(reflect(lo, h)).filter(|li| li.z > 0.0)
        } else {
            self.refract(lo, h).filter(|li| li.z < 0.0)
        }
    }

    /// The value and density of (lo, li), lo.z > 0, li on either side.
    pub fn eval(&self, lo: Vec3, li: Vec3) -> LocalValue {
        if lo.z <= 0.0 || li.z == 0.0 {
            return ZERO;
        }
        let transmitted = li.z < 0.0;
        let h = if transmitted {
            lo + self.eta * li
        } else {
            lo + li
        };
        let Some(mut h) = h.try_normalize() else {
            return ZERO;
        };
        if h.z < 0.0 {
            h = -h;
        }
        let (cos_oh, cos_ih) = (lo.dot(h), li.dot(h));
        // ωo must see the front of its microfacet; ωi leaves on the side it is on.
        if cos_oh <= 0.0 || (cos_ih <= 0.0) != transmitted || cos_ih == 0.0 {
            return ZERO;
        }
        let d = self.ggx.d(h);
        let lambda_o = self.ggx.lambda(lo);
        let g1 = 1.0 / (1.0 + lambda_o);
        let g2 = 1.0 / (1.0 + lambda_o + self.ggx.lambda(li));
        let fr = self.fresnel(cos_oh);
        // density of the visible normal h: G1(ωo)·(ωo·h)·D(h)/cos θo
        let visible = g1 * cos_oh * d / lo.z;
        if !transmitted {
            // dωh/dωi = 1/(4 ωi·h), and ωi·h = ωo·h for a reflection
            let jacobian = 1.0 / (4.0 * cos_oh);
            return LocalValue {
                f_cos: fr * d * g2 / (4.0 * lo.z),
                pdf: fr * visible * jacobian,
                transmitted,
            };
        }
        let denom = cos_oh + self.eta * cos_ih;
        let denom2 = denom * denom;
        if denom2 <= 0.0 {
            return ZERO;
        }
        // dωh/dωi = η²|ωi·h| / (ωo·h + η ωi·h)²
        let jacobian = self.eta * self.eta * (-cos_ih) / denom2;
        let t = 1.0 - fr;
        LocalValue {
            f_cos: t * d * g2 * (-cos_ih) * cos_oh / (lo.z * denom2),
            pdf: t * visible * jacobian,
            transmitted,
        }
    }
}

/// The transmitted lobe of a rough dielectric pictured as a reflection lobe mirrored through
/// the surface, for light-selection heuristics that have cap integrals of GGX reflection only
/// (the BRDF-oriented importance). A direction ω below the surface is looked up as its mirror
/// image (ωx, ωy, −ωz) in the reflection lobe seen from `view` with width `alpha`.
///
/// * `view` = −t, t the direction ωo refracts to through the macro-surface, so that the
///   mirrored lobe peaks at t's mirror image, as the transmitted lobe peaks near t.
/// * A microfacet tilted by δ turns a reflected direction by 2δ and a refracted one by about
///   |1 − 1/η|·δ (at normal incidence), so the mirrored lobe's GGX width is α·|1 − 1/η|/2.
/// * `weight` = tint·(1 − F(θo))/η², the smooth interface's transmitted albedo in radiance.
///
/// It is a heuristic only: whatever it returns, a technique that samples by it stays exact as
/// long as it evaluates its density by the same numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MirroredTransmission {
    pub view: Vec3,
    pub alpha: f32,
    pub weight: Vec3,
}

impl super::Bsdf {
    /// [`MirroredTransmission`] of a transmitting BSDF for `lo` (local ωo); `None` when the
    /// BSDF does not transmit or ωo meets the macro-surface beyond the critical angle.
    pub fn mirrored_transmission(&self, lo: Vec3) -> Option<MirroredTransmission> {
        if !self.transmits() || lo.z <= 0.0 {
            return None;
        }
        let d = self.rough_dielectric();
        let t = d.refract(lo, Vec3::Z)?;
        let fr = d.fresnel(lo.z);
        Some(MirroredTransmission {
            view: -t,
            alpha: (self.ggx.alpha * (1.0 - 1.0 / self.eta).abs() * 0.5).clamp(MIN_ALPHA, 1.0),
            weight: self.tint() * ((1.0 - fr) / (self.eta * self.eta)),
        })
    }

    /// The Fresnel reflectance of a dielectric for the viewer at cos θ = `cos_o` to a microfacet.
    pub fn reflectance(&self, cos_o: f32) -> f32 {
        self.rough_dielectric().fresnel(cos_o)
    }

    /// The dielectric lobe of a transmitting BSDF.
    #[inline]
    fn rough_dielectric(&self) -> RoughDielectric {
        RoughDielectric {
            ggx: self.ggx,
            eta: self.eta,
        }
    }

    fn tint(&self) -> Vec3 {
        match self.params.specular {
            Specular::Dielectric { tint, .. } => tint,
            _ => Vec3::ONE,
        }
    }

    /// Value and density of a transmitting BSDF: zero where ωi lies on different sides of the
    /// geometric and the shading surface (light leaking through a bent shading normal).
    pub(super) fn eval_dielectric(&self, wo: Vec3, wi: Vec3) -> BsdfValue {
        let zero = BsdfValue {
            f_cos: Vec3::ZERO,
            pdf: 0.0,
        };
        let (lo, li) = (self.frame.to_local(wo), self.frame.to_local(wi));
        let gi = wi.dot(self.ng);
        if wo.dot(self.ng) <= 0.0 || gi == 0.0 || (gi > 0.0) != (li.z > 0.0) {
            return zero;
        }
        let v = self.rough_dielectric().eval(lo, li);
        if v.pdf <= 0.0 && v.f_cos <= 0.0 {
            return zero;
        }
        let colour = if v.transmitted {
            self.tint()
        } else {
            Vec3::ONE
        };
        BsdfValue {
            f_cos: colour * v.f_cos,
            pdf: v.pdf,
        }
    }

    pub(super) fn sample_dielectric(
        &self,
        wo: Vec3,
        lo: Vec3,
        u_lobe: f32,
        u: Vec2,
    ) -> Option<BsdfSample> {
        let li = self.rough_dielectric().sample(lo, u_lobe, u)?;
        let wi = self.frame.to_world(li);
        let v = self.eval_dielectric(wo, wi);
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
#[path = "dielectric_tests.rs"]
mod tests;
