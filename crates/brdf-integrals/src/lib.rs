//! ∫_{C ∩ H} f(ωo, ω) cos θ dω for the un-Fresnelled GGX lobe (height-correlated Smith) over a
//! spherical cap C, by SPTD (Dupuy et al. 2017) and by LTC (Heitz et al. 2016, Heitz & Hill 2017),
//! with tables fitted by this crate's own code, and a reference integrator.
//!
//! Conventions: local shading frame with z the normal; ωo = (sin θo, 0, cos θo) (other azimuths
//! are accepted and rotated); GGX α used directly (clamped to [0.001, 1] by the tables).
//!
//! Normalisation (both approximations): the approximate lobe g is normalised so that its
//! integral over the upper hemisphere equals the GGX directional albedo A(θo, α) stored in the
//! table, i.e. `integral(C) = A · mass(C ∩ H) / mass(H)` where `mass` is the SPTD or LTC
//! distribution. The hemisphere value is therefore exactly the tabulated albedo.

pub mod batch;
pub mod cap;
pub mod fit;
pub mod ggx;
pub mod ltc;
pub mod pivot;
pub mod qmc;
pub mod reference;
pub mod sptd;
pub mod table;

pub use batch::{BatchError, Method, run_batch};
pub use cap::Cap;
pub use ltc::{Ltc, LtcLobe};
pub use sptd::{Intersection, Normalization, Sptd, SptdLobe};
pub use table::Lookup;

use glam::Vec3;

/// A per-shading-point lobe whose integral over caps can be evaluated quickly.
pub trait LobeIntegral {
    /// ∫_{C ∩ H} f·cos dω for the cap {ω : ω · cap_axis ≥ cap_cos} (`cap_axis` unit, local frame).
    fn integral(&self, cap_axis: Vec3, cap_cos: f32) -> f32;
    /// The value for the whole upper hemisphere (directional albedo).
    fn hemisphere(&self) -> f32;
    /// The tabulated GGX directional albedo (equal to `hemisphere` with the default normalisation).
    fn albedo(&self) -> f32 {
        self.hemisphere()
    }
}

/// A method for ∫_cap f·cos; `lobe` does the per-shading-point work once.
pub trait CapIntegral: Send + Sync {
    type Lobe: LobeIntegral;
    fn lobe(&self, wo_local: Vec3, alpha: f32) -> Self::Lobe;
    fn integral(&self, wo_local: Vec3, alpha: f32, cap_axis: Vec3, cap_cos: f32) -> f32 {
        self.lobe(wo_local, alpha).integral(cap_axis, cap_cos)
    }
    fn hemisphere(&self, wo_local: Vec3, alpha: f32) -> f32 {
        self.lobe(wo_local, alpha).hemisphere()
    }
}

/// The reference integrator behind the same interface (slow: `samples` GGX evaluations per call).
#[derive(Clone, Copy, Debug)]
pub struct Reference {
    pub samples: usize,
}

impl Default for Reference {
    fn default() -> Self {
        Self { samples: 1 << 16 }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct ReferenceLobe {
    pub wo: Vec3,
    pub alpha: f32,
    pub samples: usize,
}

impl LobeIntegral for ReferenceLobe {
    fn integral(&self, cap_axis: Vec3, cap_cos: f32) -> f32 {
        reference::cap_integral(
            self.wo,
            self.alpha,
            &Cap::new(cap_axis, cap_cos),
            self.samples,
        )
        .0
    }
    fn hemisphere(&self) -> f32 {
        reference::hemisphere(self.wo, self.alpha, self.samples).0
    }
}

impl CapIntegral for Reference {
    type Lobe = ReferenceLobe;
    fn lobe(&self, wo_local: Vec3, alpha: f32) -> ReferenceLobe {
        ReferenceLobe {
            wo: wo_local,
            alpha,
            samples: self.samples,
        }
    }
}
