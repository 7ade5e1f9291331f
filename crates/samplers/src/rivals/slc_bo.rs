//! `slc-bo+bsdf` (issue 50, "beyond the papers"): stochastic lightcuts whose descent inside
//! each cut node weighs a node, at glossy points, by the paper's BRDF-oriented importance
//! I_BO (Liu, Xu & Yan 2019; [`crate::brdf_oriented::importance`]) instead of the tree's E&K
//! importance. The cut is the same as `slc`'s (the error bound must bound, and I_BO is an
//! estimate), and pure diffuse points keep the tree's descent.
//!
//! The weight of node C at a glossy point is
//!
//!   w(C) = I_BO(C) + β · (k_s + k_d)/π · I_EK(C),   β = [`EK_FLOOR`],
//!
//! with I_BO the cap-integral importance (SPTD, with its diffuse term, our defaults: the one
//! `ris` builds), I_EK the tree's importance on the node's exact bounds, k_s, k_d the
//! luminances of the lobe's weight and the diffuse albedo. The floor is not in the paper's I_BO.
//! It is there because `slc` has no other light technique: I_BO is 0 for delta lights (a cap
//! of no solid angle) and can be 0 where the SPTD lobe is but GGX is not. In `mis3` the E&K
//! technique covers those lights; here, without the floor, nothing would, and the estimator
//! would be biased. With it w is zero only where I_EK is, so every light that can contribute
//! keeps a positive pmf. (k_s + k_d)/π turns I_EK's power/length² into I_BO's units: I_BO is
//! that power × the BSDF's mean over the node's cap.
//!
//! The descent is the tree's binary one (`LightTree::sample_subtree` / `pmf_subtree`, the same
//! quotients in both, so sampling and replay agree bit for bit), with one fresh 64-bit number
//! per cut node rescaled down the subtree, as in `slc`.
use crate::brdf_oriented::importance::BoRecord;
use brdf_integrals::{CapIntegral, Sptd, SptdLobe};
use light_tree::Node;
use render_core::Vec3;
use render_core::estimator::ShadingPoint;
use std::f32::consts::PI;

/// β, the weight of the E&K importance in the BO variant's node weight (see the module docs).
pub const EK_FLOOR: f32 = 0.1;

/// The BO variant's node weight at one glossy shading point.
pub struct BoWeight {
    rec: BoRecord<SptdLobe>,
    /// The receiver normal of the E&K floor (the tree's, the geometric normal).
    n: Vec3,
    /// β · (k_s + k_d)/π.
    floor: f32,
}

impl BoWeight {
    /// The weight at `sp`, or `None` at a pure diffuse point (where `slc`'s descent stays).
    pub fn at(sp: &ShadingPoint, integral: &Sptd) -> Option<BoWeight> {
        if sp.bsdf.is_pure_diffuse() {
            return None;
        }
        let lobe = integral.lobe(sp.bsdf.frame.to_local(sp.wo), sp.bsdf.params.alpha);
        let rec = BoRecord::new(sp, lobe, true, false)
            .with_transmission(sp, |view, alpha| integral.lobe(view, alpha));
        // Any positive floor keeps the estimator complete; a dark lobe keeps a tiny one.
        let albedo = (rec.ks + rec.kd + rec.transmitted.as_ref().map_or(0.0, |t| t.kt)).max(1e-3);
        Some(BoWeight {
            rec,
            n: sp.cull_normal(),
            floor: EK_FLOOR * albedo / PI,
        })
    }

    /// w(`node`) ≥ 0, zero only where the tree's importance is.
    pub fn weight(&self, node: &Node) -> f32 {
        let bo = self.rec.terms(node).importance;
        let ek = node.importance(self.rec.x, self.n);
        let bo = if bo > 0.0 { bo } else { 0.0 };
        let ek = if ek > 0.0 { ek } else { 0.0 };
        bo + self.floor * ek
    }
}
