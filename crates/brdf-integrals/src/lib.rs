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
//!
//! The integrals are dimensionless (radiance out per unit radiance in): a cap of constant
//! radiance L reflects L times the integral towards ωo. The approximations always return values
//! in [0, A], A ≤ 1 the directional albedo. Caps are given in the same local frame as ωo
//! (z = shading normal), by a unit axis and the cosine of their half-angle ([`Cap`]); a sphere
//! light seen from the shading point becomes a cap with [`Cap::from_sphere`].
//!
//! Usage: pick a method ([`Sptd`] or [`Ltc`], both [`CapIntegral`]), build the per-shading-point
//! lobe once with [`CapIntegral::lobe`], then evaluate it for as many caps as needed with
//! [`LobeIntegral::integral`]. [`Reference`] and the [`reference`](mod@reference) module give
//! slow, accurate values with standard errors, for validation.
//!
//! # Example
//!
//! The cap integral of a GGX lobe for a spherical light near the mirror direction:
//!
//! ```
//! use brdf_integrals::{Cap, CapIntegral, LobeIntegral, Ltc, Sptd, ggx, reference};
//! use glam::Vec3;
//!
//! // View direction 0.6 rad from the normal (local frame, z = normal), GGX roughness α = 0.2.
//! let wo = ggx::wo_from_theta(0.6);
//! let alpha = 0.2;
//!
//! // A sphere light of radius 0.5 whose centre is 4 units away along the mirror direction.
//! let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
//! let cap = Cap::from_sphere(mirror * 4.0, 0.5).expect("shading point outside the light");
//!
//! // Per shading point: one lobe, then any number of caps.
//! let lobe = Sptd::default().lobe(wo, alpha);
//! let v = lobe.integral(cap.axis, cap.cos_theta);
//! assert!(v > 0.0 && v <= lobe.hemisphere());
//!
//! // The one-shot form, here with the LTC approximation.
//! let v_ltc = Ltc::default().integral(wo, alpha, cap.axis, cap.cos_theta);
//! assert!(v_ltc > 0.0 && v_ltc <= 1.0);
//!
//! // Both approximate the (slow) reference integral.
//! let (r, _std_err) = reference::cap_integral(wo, alpha, &cap, 1 << 14);
//! assert!((v - r).abs() < 0.1 * r + 0.01);
//! ```

#![warn(missing_docs)]

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
    ///
    /// `cap_cos` is the cosine of the cap's half-angle, in [−1, 1] (negative for caps larger
    /// than a hemisphere). The result is ≥ 0, and 0 (up to rounding) for caps wholly below
    /// the horizon.
    fn integral(&self, cap_axis: Vec3, cap_cos: f32) -> f32;
    /// The value for the whole upper hemisphere (directional albedo).
    fn hemisphere(&self) -> f32;
    /// The tabulated GGX directional albedo (equal to `hemisphere` with the default normalisation).
    fn albedo(&self) -> f32 {
        self.hemisphere()
    }
}

/// A method for ∫_cap f·cos; `lobe` does the per-shading-point work once.
///
/// Implementations are cheap to share between threads (tables behind an `Arc`).
pub trait CapIntegral: Send + Sync {
    /// The per-shading-point state this method precomputes.
    type Lobe: LobeIntegral;
    /// Precomputes the lobe for the unit view direction `wo_local` (local frame, z = normal,
    /// any azimuth, expected above the horizon: the tables clamp θo to [0, π/2]) and GGX
    /// roughness `alpha` (α itself, not √α; the tables clamp it to [0.001, 1]).
    fn lobe(&self, wo_local: Vec3, alpha: f32) -> Self::Lobe;
    /// One-shot [`LobeIntegral::integral`]: builds the lobe and evaluates one cap. Prefer
    /// [`CapIntegral::lobe`] when several caps share a shading point.
    fn integral(&self, wo_local: Vec3, alpha: f32, cap_axis: Vec3, cap_cos: f32) -> f32 {
        self.lobe(wo_local, alpha).integral(cap_axis, cap_cos)
    }
    /// One-shot [`LobeIntegral::hemisphere`] (the directional albedo for `wo_local`, `alpha`).
    fn hemisphere(&self, wo_local: Vec3, alpha: f32) -> f32 {
        self.lobe(wo_local, alpha).hemisphere()
    }
}

/// The reference integrator behind the same interface (slow: `samples` GGX evaluations per call).
#[derive(Clone, Copy, Debug)]
pub struct Reference {
    /// Total number of samples per integral, split over 8 replicates (default 2¹⁶).
    pub samples: usize,
}

impl Default for Reference {
    fn default() -> Self {
        Self { samples: 1 << 16 }
    }
}

/// The "lobe" of [`Reference`]: it only records its inputs, and every
/// [`LobeIntegral::integral`] call runs the reference integrator
/// ([`reference::cap_integral`]) from scratch.
#[derive(Clone, Copy, Debug)]
pub struct ReferenceLobe {
    /// View direction in the local frame (unit, z = normal).
    pub wo: Vec3,
    /// GGX roughness α (not clamped).
    pub alpha: f32,
    /// Samples per integral, as in [`Reference::samples`].
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
