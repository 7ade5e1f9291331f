//! The per-shading-point BRDF record and the BRDF-oriented node importance I_BO
//! (Liu, Xu & Yan 2019; method.md §1.2, §1.4).
//!
//! For a node with bounding sphere (c, r) seen from x, cap(C) is the cone the sphere subtends,
//! expressed in the BSDF's local frame (z = shading normal, x = ωo projected). Then
//!
//! I_BO(C) = Φ_C · cos̄θ_C / d² · (Ks · ∫_{cap∩H} f_GGX·cos + Kd/π · ∫_{cap∩H} cos) / |cap ∩ H|
//!
//! where Φ_C·cos̄θ_C/d² is the light tree's emitter bound (Conty Estevez & Kulla) without the
//! receiver cosine (the cosine sits inside the integrals). The default adds the diffuse term;
//! `reproduce` keeps the authors' glossy-only importance and Oat–Sander cap ∩ cap.
use brdf_integrals::LobeIntegral;
use brdf_integrals::cap::{Cap, intersection_area_exact, intersection_area_oat_sander};
use glam::Vec4;
use light_tree::Node;
use render_core::Vec3;
use render_core::colour::luminance;
use render_core::estimator::ShadingPoint;
use render_core::frame::Frame;
use std::f32::consts::PI;

/// What the BO importance needs of a shading point; built once per shading point.
#[derive(Clone, Copy, Debug)]
pub struct BoRecord<L> {
    /// The shading position.
    pub x: Vec3,
    /// The shading frame (z = normal, x = ωo projected).
    pub frame: Frame,
    /// The glossy lobe's cap integral (SPTD or LTC), un-Fresnelled, without Ks.
    pub lobe: L,
    /// Luminance of the glossy lobe's weight, which multiplies its cap integral: by default the
    /// lobe's actual weight at its peak (Ks·F for pbrt's plastic, Schlick's F for the glTF
    /// lobe, both at θo: [`render_core::bsdf::Bsdf::glossy_weight`]); in `reproduce` the
    /// Fresnel-free lobe colour, as the authors' `PrepareForLTC` reports R.y (method.md §1.2:
    /// "Fresnel is ignored"; Ks = 0.7 on their plastic). Without a diffuse term a constant
    /// weight cancels from I_BO's distribution anyway; it matters beside `kd`.
    pub ks: f32,
    /// Luminance of the diffuse albedo.
    pub kd: f32,
    /// Add the diffuse term Kd/π × projected solid angle (our default; off in `reproduce`).
    pub diffuse_term: bool,
    /// Oat–Sander approximation for |cap ∩ H| (the authors' code) instead of the exact lens.
    pub oat_sander: bool,
    /// Use the lobe density at the axis for small caps or caps far from the lobe's peak
    /// (see `point_estimate`); off in `reproduce`.
    pub point_approx: bool,
    /// The lobe's peak, precomputed for `point_estimate` (None without a peak).
    pub(super) peak: Option<PeakBound>,
    /// At a transmitting point, the transmitted lobe (see [`Transmitted`]).
    pub transmitted: Option<Transmitted<L>>,
}

/// The transmitted lobe of a transmitting shading point, as the BO importance integrates it:
/// the GGX reflection lobe of [`render_core::bsdf::dielectric::MirroredTransmission`] (a
/// lobe around the refracted direction, mirrored above the surface), evaluated on the
/// mirror image of the part of a cap below the surface, times `kt`, the luminance of the
/// transmitted albedo. An approximation of ∫ f_t·|cos|; BO's density stays exact because it
/// is evaluated from these same numbers.
#[derive(Clone, Copy, Debug)]
pub struct Transmitted<L> {
    /// The mirrored reflection lobe.
    pub lobe: L,
    /// Luminance of the transmitted albedo that multiplies its cap integral.
    pub kt: f32,
}

/// The lobe's peak direction and angular width w, with cos 3w and sin 3w, so that the test
/// "the cap lies farther than 3w from the peak" needs no inverse trigonometry per node.
#[derive(Clone, Copy, Debug)]
pub(super) struct PeakBound {
    pub(super) dir: Vec3,
    pub(super) width: f32,
    pub(super) cos3w: f32,
    pub(super) sin3w: f32,
}

/// A node's BO terms at a shading point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodeTerms {
    /// I_BO (0 when the node cannot be reached or its cap lies below the horizon); in a cut
    /// built under `--bo-importance sg`, the node's SG importance instead.
    pub importance: f32,
    /// ∫_{cap∩H} f·cos of the glossy lobe without Ks (the split test and the allocation's UB).
    pub glossy: f32,
}

/// The approximate lobe's density g(ω) (∫_cap g ≈ the cap integral) and its peak direction
/// and angular width, where the approximation has them.
pub trait LobeDensity {
    /// g(ω) for a local direction `w` (None where the method has no density).
    fn density(&self, w: Vec3) -> Option<f32>;
    /// The peak direction (local) and angular width in radians.
    fn peak(&self) -> Option<(Vec3, f32)>;
    /// g at four local directions above the horizon, in f32 lanes (`quad_importance.rs`);
    /// None where the method has no density.
    fn density4(&self, _w: [Vec4; 3]) -> Option<Vec4> {
        None
    }
}

impl LobeDensity for brdf_integrals::SptdLobe {
    #[inline]
    fn density(&self, w: Vec3) -> Option<f32> {
        Some(brdf_integrals::SptdLobe::density(self, w))
    }
    /// The SPTD peaks towards r_p/ρ; its angular scale is about 1 − ρ.
    #[inline]
    fn peak(&self) -> Option<(Vec3, f32)> {
        let rho = self.pivot.length();
        (rho > 1e-3).then(|| (self.pivot / rho, (1.0 - rho).max(1e-4)))
    }
    /// The pivot Jacobian squared in f32 (the scalar `density` takes f64).
    #[inline]
    fn density4(&self, w: [Vec4; 3]) -> Option<Vec4> {
        let p = self.pivot;
        let num = Vec4::splat(1.0 - p.length_squared());
        let [dx, dy, dz] = [
            w[0] - Vec4::splat(p.x),
            w[1] - Vec4::splat(p.y),
            w[2] - Vec4::splat(p.z),
        ];
        let j = num / (dx * dx + dy * dy + dz * dz);
        Some(Vec4::splat(self.density_scale() as f32) * j * j)
    }
}

impl LobeDensity for brdf_integrals::LtcLobe {
    fn density(&self, _: Vec3) -> Option<f32> {
        None
    }
    fn peak(&self) -> Option<(Vec3, f32)> {
        None
    }
}

impl<L: LobeIntegral + LobeDensity> BoRecord<L> {
    /// A record from raw inputs, for a renderer other than ours: the shading position `x`, its
    /// shading `frame` (z = normal, x = ωo projected, as the lobe's tables expect), the glossy
    /// `lobe` (`brdf_integrals::CapIntegral::lobe` for ωo in that frame and GGX α), the
    /// luminances of the glossy lobe's weight `ks` (0 for a pure diffuse point) and of the
    /// diffuse albedo `kd`. `diffuse_term` adds Kd/π × projected solid angle to I_BO (our
    /// default); `oat_sander` takes the authors' approximate |cap ∩ H| (and no point estimate).
    pub fn from_parts(
        x: Vec3,
        frame: Frame,
        lobe: L,
        ks: f32,
        kd: f32,
        diffuse_term: bool,
        oat_sander: bool,
    ) -> Self {
        let peak = lobe.peak().map(|(dir, width)| PeakBound {
            dir,
            width,
            cos3w: (3.0 * width).cos(),
            sin3w: (3.0 * width).sin(),
        });
        BoRecord {
            peak,
            point_approx: !oat_sander,
            x,
            frame,
            lobe,
            ks: ks.max(0.0),
            kd: kd.max(0.0),
            diffuse_term,
            oat_sander,
            transmitted: None,
        }
    }

    /// This record with the transmitted lobe of `sp` added, when its BSDF transmits (and ωo
    /// refracts through the macro-surface); `lobe_at(view, α)` builds a reflection lobe.
    /// The point form of the importance is turned off: it knows one lobe only.
    pub fn with_transmission(
        mut self,
        sp: &ShadingPoint,
        lobe_at: impl Fn(Vec3, f32) -> L,
    ) -> Self {
        let lo = sp.bsdf.frame.to_local(sp.wo);
        if let Some(m) = sp.bsdf.mirrored_transmission(lo) {
            self.transmitted = Some(Transmitted {
                lobe: lobe_at(m.view, m.alpha),
                kt: luminance(m.weight).max(0.0),
            });
            self.point_approx = false;
            self.peak = None;
        }
        self
    }

    /// The record of our renderer's shading point `sp` (its BSDF gives the frame, `ks`, `kd`).
    pub fn new(sp: &ShadingPoint, lobe: L, diffuse_term: bool, oat_sander: bool) -> Self {
        let p = &sp.bsdf.params;
        let weight = if diffuse_term {
            sp.bsdf.glossy_weight(sp.bsdf.frame.to_local(sp.wo))
        } else {
            p.specular.tint()
        };
        let ks = if sp.bsdf.is_pure_diffuse() {
            0.0
        } else {
            luminance(weight).max(0.0)
        };
        Self::from_parts(
            sp.point(),
            sp.bsdf.frame,
            lobe,
            ks,
            luminance(p.diffuse).max(0.0),
            diffuse_term,
            oat_sander,
        )
    }

    /// BO terms of `node`.
    pub fn terms(&self, node: &Node) -> NodeTerms {
        // Φ · cos̄θ_C / max(d², r²/4): the tree's importance without a receiver normal.
        let emit = node.importance(self.x, Vec3::ZERO);
        if !(emit > 0.0) {
            return NodeTerms::default();
        }
        if let Some(t) = &self.transmitted {
            return self.terms_both_sides(node, emit, t);
        }
        let to_c = node.center() - self.x;
        let d2 = to_c.length_squared();
        let r = node.radius();
        let r2 = r * r;
        if d2 <= r2 {
            // x inside the bounding sphere: the whole hemisphere is the cap.
            let glossy = if self.ks > 0.0 {
                self.lobe.hemisphere().max(0.0)
            } else {
                0.0
            };
            let diffuse = if self.diffuse_term { self.kd } else { 0.0 };
            return NodeTerms {
                importance: emit * (self.ks * glossy + diffuse) / (2.0 * PI),
                glossy,
            };
        }
        let d = d2.sqrt();
        let axis = self.frame.to_local(to_c / d).normalize();
        let sin2 = (r2 / d2).min(1.0);
        let cos = (1.0 - sin2).max(0.0).sqrt();
        let omega = clipped_solid_angle(axis, sin2, cos, self.oat_sander);
        if !(omega > 0.0) {
            return NodeTerms::default();
        }
        let glossy = if self.ks > 0.0 {
            match self.point_estimate(axis, sin2) {
                Some(g) => g * omega,
                None => self.lobe.integral(axis, cos).max(0.0),
            }
        } else {
            0.0
        };
        let diffuse = if self.diffuse_term && self.kd > 0.0 {
            self.kd / PI * clipped_projected_solid_angle(axis.z, sin2)
        } else {
            0.0
        };
        NodeTerms {
            importance: emit * (self.ks * glossy + diffuse) / omega,
            glossy,
        }
    }
}

impl<L: LobeIntegral + LobeDensity> BoRecord<L> {
    /// [`BoRecord::terms`] at a transmitting point: the cap's part above the surface weighed
    /// by the reflection lobe, its part below by the mirrored transmitted lobe, both divided
    /// by the cap's whole solid angle (so I_BO is still emitted power × the BSDF's mean over
    /// the cap). No diffuse term: a dielectric has none.
    fn terms_both_sides(&self, node: &Node, emit: f32, t: &Transmitted<L>) -> NodeTerms {
        let to_c = node.center() - self.x;
        let d2 = to_c.length_squared();
        let r2 = node.radius() * node.radius();
        let (ks, kt) = (self.ks, t.kt);
        if d2 <= r2 {
            let up = if ks > 0.0 {
                self.lobe.hemisphere().max(0.0)
            } else {
                0.0
            };
            let down = if kt > 0.0 {
                t.lobe.hemisphere().max(0.0)
            } else {
                0.0
            };
            return NodeTerms {
                importance: emit * (ks * up + kt * down) / (4.0 * PI),
                glossy: up + down,
            };
        }
        let axis = self.frame.to_local(to_c / d2.sqrt()).normalize();
        let mirrored = Vec3::new(axis.x, axis.y, -axis.z);
        let sin2 = (r2 / d2).min(1.0);
        let cos = (1.0 - sin2).max(0.0).sqrt();
        let omega_up = clipped_solid_angle(axis, sin2, cos, self.oat_sander);
        let omega_down = clipped_solid_angle(mirrored, sin2, cos, self.oat_sander);
        let omega = omega_up.max(0.0) + omega_down.max(0.0);
        if !(omega > 0.0) {
            return NodeTerms::default();
        }
        let up = if ks > 0.0 && omega_up > 0.0 {
            self.lobe.integral(axis, cos).max(0.0)
        } else {
            0.0
        };
        let down = if kt > 0.0 && omega_down > 0.0 {
            t.lobe.integral(mirrored, cos).max(0.0)
        } else {
            0.0
        };
        NodeTerms {
            importance: emit * (ks * up + kt * down) / omega,
            glossy: up + down,
        }
    }

    /// The lobe density at the cap's axis, used instead of the closed-form cap integral
    /// (as density × |cap|) for caps wholly above the horizon that are either much narrower
    /// than the lobe or well away from its peak, with half-angle below 0.25 rad. I_BO only
    /// has to be a deterministic function of (node, shading point) for BO to stay exact in
    /// its pdf, and this spares most of the f64 cap transforms of a descent.
    #[inline]
    fn point_estimate(&self, axis: Vec3, sin2: f32) -> Option<f32> {
        if !self.point_approx || sin2 > 0.0606 || axis.z * axis.z <= sin2 || axis.z <= 0.0 {
            return None;
        }
        let pk = self.peak?;
        let narrow = sin2 < (0.25 * pk.width) * (0.25 * pk.width);
        // angle(axis, peak) > σ + 3w with sin σ = s: for σ + 3w < π this is
        // cos(angle) < cos(σ + 3w) = cos σ·cos 3w − s·sin 3w, and σ + 3w < π ⇔ 3w ≤ π/2 or
        // s < sin 3w (σ ≤ π/2 here).
        let far = {
            let s = sin2.sqrt();
            let cos_sigma = (1.0 - sin2).max(0.0).sqrt();
            let below_pi = pk.cos3w >= 0.0 || s < pk.sin3w;
            below_pi && axis.dot(pk.dir) < cos_sigma * pk.cos3w - s * pk.sin3w
        };
        if narrow || far {
            self.lobe.density(axis)
        } else {
            None
        }
    }
}

/// |cap ∩ H| for the cap of axis `axis` (local, unit) with sin² and cos of its half-angle.
/// Caps wholly above the horizon use 2π sin²/(1 + cos), free of cancellation for tiny caps.
pub fn clipped_solid_angle(axis: Vec3, sin2: f32, cos: f32, oat_sander: bool) -> f32 {
    let sin = sin2.sqrt();
    // elevation test: the lowest point of the cap has z = axis.z·cos − sin_axis·sin
    let sin_axis = (1.0 - axis.z * axis.z).max(0.0).sqrt();
    let lowest = axis.z * cos - sin_axis * sin;
    let highest = axis.z * cos + sin_axis * sin;
    if highest <= 0.0 && !(cos <= 0.0) {
        return 0.0;
    }
    if lowest >= 0.0 {
        return 2.0 * PI * sin2 / (1.0 + cos);
    }
    let cap = Cap::new(axis, cos);
    let h = Cap::upper_hemisphere();
    if oat_sander {
        intersection_area_oat_sander(&cap, &h)
    } else {
        intersection_area_exact(&cap, &h)
    }
}

/// ∫_{cap ∩ H} cos θ dω for a cap whose axis makes cos θ = `cos_t` with the normal and whose
/// half-angle σ has sin²σ = `sin2` < 1 (the illuminance of a unit-radiance sphere with the
/// horizon clipped; Snyder 1996 closed form, as in Lagarde & de Rousiers 2014).
pub fn clipped_projected_solid_angle(cos_t: f32, sin2: f32) -> f32 {
    if cos_t * cos_t > sin2 {
        return if cos_t > 0.0 { PI * sin2 * cos_t } else { 0.0 };
    }
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let x = (1.0 / sin2 - 1.0).max(0.0).sqrt();
    let y = if sin_t > 0.0 {
        (-x * cos_t / sin_t).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    let s = sin_t * (1.0 - y * y).max(0.0).sqrt();
    let a = if x > 0.0 { (s / x).atan() } else { PI / 2.0 };
    ((cos_t * y.acos() - x * s) * sin2 + a).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Monte Carlo ∫_{cap∩H} g over uniform directions in the cap.
    fn mc(axis: Vec3, cos: f32, g: impl Fn(Vec3) -> f32, n: usize) -> f64 {
        let f = Frame::from_normal(axis);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let omc = 1.0 - cos as f64;
        let mut s = 0.0;
        for _ in 0..n {
            let c = 1.0 - rng.random::<f64>() * omc;
            let phi = 2.0 * std::f64::consts::PI * rng.random::<f64>();
            let r = (1.0 - c * c).max(0.0).sqrt();
            let w = f.to_world(Vec3::new(
                (r * phi.cos()) as f32,
                (r * phi.sin()) as f32,
                c as f32,
            ));
            if w.z > 0.0 {
                s += g(w) as f64;
            }
        }
        s / n as f64 * 2.0 * std::f64::consts::PI * omc
    }

    #[test]
    fn clipped_integrals_match_monte_carlo() {
        for (elev, half) in [
            (1.2f32, 0.3f32),
            (0.2, 0.5),
            (-0.1, 0.4),
            (0.0, 1.2),
            (0.7, 1.4),
            (1.55, 0.2),
        ] {
            let axis = Vec3::new(elev.cos(), 0.0, elev.sin());
            let (sin2, cos) = (half.sin().powi(2), half.cos());
            let ps = clipped_projected_solid_angle(axis.z, sin2) as f64;
            let ps_mc = mc(axis, cos, |w| w.z, 200_000);
            assert!(
                (ps - ps_mc).abs() < 0.01 * ps_mc.max(0.05),
                "{elev} {half}: {ps} vs {ps_mc}"
            );
            let sa = clipped_solid_angle(axis, sin2, cos, false) as f64;
            let sa_mc = mc(axis, cos, |_| 1.0, 200_000);
            assert!(
                (sa - sa_mc).abs() < 0.01 * sa_mc.max(0.05),
                "{elev} {half}: {sa} vs {sa_mc}"
            );
        }
        // below the horizon
        let axis = Vec3::new(0.0, 0.6, -0.8);
        assert_eq!(clipped_projected_solid_angle(axis.z, 0.01), 0.0);
        assert_eq!(clipped_solid_angle(axis, 0.01, 0.99f32.sqrt(), false), 0.0);
    }
}
