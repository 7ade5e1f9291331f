//! The SG node importance at a shading point (Tokuyoshi et al. 2024): the lighting integral of
//! a node's SG light with the BSDF, diffuse and glossy, plus a floor that keeps every node the
//! conservative bounds cannot rule out at a non-zero probability.
//!
//! Seen from x, a node of power Φ, mean μ, variance σ² and intensity lobe I(ω) becomes an SG
//! light around l = (μ − x)/d of sharpness λ = d²/σ², whose amplitude I(−l)/(2πσ²) makes its
//! integral over directions E = I(−l)(1 − e^{−2λ})/d²: the point-light irradiance I/d² far
//! away, bounded (2I/σ²) at the cluster's mean. Then
//!
//! * diffuse: E · Kd/π · ∫ vMF_l(ω) max(ω·n, 0) dω ([`super::lobe::clamped_cosine`]);
//! * glossy: E · F(ωi·h) · p_M(ωo → l) · V, where p_M is the GGX reflection density
//!   D_M(h)/(4√(ωoᵀMωo)) with the NDF filtered by the light's lobe (the paper's extension of
//!   NDF filtering: the light's angular variance 1/λ, carried into slope space through the
//!   Jacobian JJᵀ of the reflection at h = n, is added to the projected roughness
//!   α²/(1 − α²) and mapped back, M = Σ(I + Σ)⁻¹), and V the fraction above the surface of the
//!   product of the reflection lobe's SG (sharpness (1 − α²)/(2α²) around the mirror
//!   direction) and the light's SG ([`super::lobe::hemisphere_fraction`]);
//! * floor: ε · ρ · I_EK/(4π²), with I_EK the light tree's conservative E&K importance and ρ
//!   the albedo proxy luminance(Kd) + luminance(glossy weight at θo). The whole importance is 0
//!   exactly when I_EK is, i.e. only where the bounds prove the node dark at x, so the
//!   descent never gives a probability of 0 to a light that could contribute.
//!
//! All luminances; only ratios between nodes matter.
use light_tree::{Node, SgNode};
use render_core::Vec3;
use render_core::bsdf::Specular;
use render_core::colour::luminance;
use render_core::estimator::ShadingPoint;
use render_core::frame::Frame;
use std::f32::consts::PI;

use super::lobe::{clamped_cosine, hemisphere_fraction};

/// ε of the floor: the fraction of a diffuse point-light estimate every node the bounds
/// admit keeps.
pub const FLOOR: f32 = 0.01;
/// The smallest σ² relative to d² (λ ≤ 10⁷): point lights have σ² = 0.
const MIN_RELATIVE_VARIANCE: f32 = 1e-7;

/// What the SG importance needs of one shading point, built once per point.
#[derive(Clone, Copy, Debug)]
pub struct SgShading {
    x: Vec3,
    /// Geometric normal (for the conservative E&K gate, as the plain tree).
    ng: Vec3,
    frame: Frame,
    /// ωo in the shading frame (x axis = ωo's tangent direction, so ωo.y = 0).
    wo: Vec3,
    /// luminance(Kd)/π.
    kd: f32,
    specular: Specular,
    glossy: bool,
    /// Projected roughness α²/(1 − α²).
    proj_alpha2: f32,
    /// Diagonal of JJᵀ, J the Jacobian from reflected directions to half vectors at h = n.
    jjt: [f32; 2],
    /// The reflection lobe's SG as one vector: sharpness × mirror direction (world space).
    reflection: Vec3,
    /// ε · ρ / (4π²), the factor of I_EK in the floor.
    floor: f32,
}

impl SgShading {
    /// The record of shading point `sp`.
    pub fn new(sp: &ShadingPoint) -> SgShading {
        let bsdf = &sp.bsdf;
        let frame = bsdf.frame;
        let wo = frame.to_local(sp.wo);
        let glossy = !bsdf.is_pure_diffuse();
        let alpha2 = bsdf.ggx.alpha * bsdf.ggx.alpha;
        let vz = wo.z.max(1e-4);
        let n = frame.z;
        let mirror = n * (2.0 * sp.wo.dot(n)) - sp.wo;
        let reflection_sharpness = (1.0 - alpha2) / (2.0 * alpha2).max(1e-12);
        let rho = luminance(bsdf.params.diffuse) + luminance(bsdf.glossy_weight(wo));
        SgShading {
            x: sp.point(),
            ng: sp.cull_normal(),
            frame,
            wo,
            kd: luminance(bsdf.params.diffuse) / PI,
            specular: bsdf.params.specular,
            glossy,
            proj_alpha2: alpha2 / (1.0 - alpha2).max(1e-6),
            jjt: [0.25, 0.25 / (vz * vz)],
            reflection: mirror * reflection_sharpness,
            floor: FLOOR * rho.max(1e-3) / (4.0 * PI * PI),
        }
    }

    /// The SG importance of a node (its tree node and its SG light); see the module docs.
    #[inline]
    pub fn importance(&self, node: &Node, sg: &SgNode) -> f32 {
        let gate = node.importance(self.x, self.ng);
        if !(gate > 0.0) {
            return 0.0;
        }
        self.sg_integral(node.power(), sg) + self.floor * gate
    }

    /// The SG lighting integral alone, without the gate and the floor (may underflow to 0).
    pub fn sg_integral(&self, power: f32, sg: &SgNode) -> f32 {
        let to = sg.mean() - self.x;
        let d2 = to.length_squared().max(1e-12);
        let l = to * d2.sqrt().recip();
        let variance = sg.variance().max(MIN_RELATIVE_VARIANCE * d2);
        let lambda = d2 / variance;
        let irradiance = sg.intensity(power, -l) * -(-2.0 * lambda).exp_m1() / d2;
        let n = self.frame.z;
        let mut value = self.kd * clamped_cosine(n.dot(l), lambda);
        if self.glossy {
            value += self.glossy_term(l, lambda);
        }
        irradiance * value
    }

    /// F(ωi·h) · p_M(ωo → l) · V for a light lobe of sharpness `lambda` around `l`.
    #[inline]
    fn glossy_term(&self, l: Vec3, lambda: f32) -> f32 {
        let li = self.frame.to_local(l);
        let h = self.wo + li;
        let len = h.length();
        let h = if len > 1e-6 { h / len } else { Vec3::Z };
        // NDF filtering: Σ = α²/(1 − α²) + 2·JJᵀ/λ, M = Σ(I + Σ)⁻¹ (diagonal here: ωo.y = 0).
        let v2 = 2.0 / lambda;
        let s0 = self.proj_alpha2 + v2 * self.jjt[0];
        let s1 = self.proj_alpha2 + v2 * self.jjt[1];
        let m0 = (s0 / (1.0 + s0)).max(1e-12);
        let m1 = (s1 / (1.0 + s1)).max(1e-12);
        let q = h.x * h.x / m0 + h.y * h.y / m1 + h.z * h.z;
        let d = 1.0 / (PI * (m0 * m1).sqrt() * q * q);
        let wo = self.wo;
        let pdf = d / (4.0 * (m0 * wo.x * wo.x + m1 * wo.y * wo.y + wo.z * wo.z).sqrt());
        // Visibility: the product of the reflection SG and the light SG above the surface.
        let product = self.reflection + l * lambda;
        let sharpness = product.length();
        let z = if sharpness > 0.0 {
            product.dot(self.frame.z) / sharpness
        } else {
            0.0
        };
        let visibility = hemisphere_fraction(z, sharpness);
        let fresnel = luminance(self.specular.weight(li.dot(h).max(0.0)));
        fresnel * pdf * visibility
    }
}
