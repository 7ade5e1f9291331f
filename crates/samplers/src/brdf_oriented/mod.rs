//! Liu, Xu & Yan 2019, "Adaptive BRDF-Oriented Multiple Importance Sampling of Many Lights":
//! BRDF-oriented light sampling (BO) over a second light cut, three-technique MIS with
//! tree-splitting light sampling (LS) and BRDF sampling, and adaptive sample allocation.
//!
//! * [`importance`]: the per-shading-point record and I_BO of a node.
//! * [`cut`]: the BO cut with its cached cap integrals.
//! * [`technique`]: BO sampling and its pdf for any light point.
//! * [`allocation`]: the two allocation heuristics and the unbiased fixed-count variant.
//! * [`mis3`]: the strategies `brdf-oriented`, `mis3-equal`, `mis3-adaptive`.
//! * [`quad_importance`]: I_BO of four nodes at once, for BO's four-wide descent.
//! * [`pivot_sphere`]: optional pivot-transformed point sampling on sphere lights.
//! * [`ltc_triangle`]: optional BRDF-aware (LTC) point sampling on triangle lights.
//! * [`sg_importance`]: the SG node importance (Tokuyoshi et al. 2024) as BO's cluster and
//!   descent importance (`--bo-importance sg`).
pub mod allocation;
pub mod cut;
pub mod importance;
pub mod in_sample;
pub mod ls_technique;
pub mod ltc_triangle;
pub mod mis3;
pub mod pivot_sphere;
pub mod pixel_memory;
pub mod quad_importance;
pub mod sg_importance;
pub mod strategies;
pub mod technique;
pub mod three_techniques;

use brdf_integrals::{LtcLobe, SptdLobe};
use render_core::Vec3;
use serde::{Deserialize, Serialize};

/// Which cap-integral approximation drives BO.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BrdfIntegral {
    /// Spherical pivot-transformed distributions (the authors' choice).
    #[default]
    Sptd,
    /// Linearly transformed cosines (Heitz et al. 2016).
    Ltc,
}

impl BrdfIntegral {
    /// Every method, in the order `--help` lists them.
    pub const ALL: [BrdfIntegral; 2] = [BrdfIntegral::Sptd, BrdfIntegral::Ltc];

    /// The name on the command line and in the render's JSON.
    pub fn name(self) -> &'static str {
        match self {
            BrdfIntegral::Sptd => "sptd",
            BrdfIntegral::Ltc => "ltc",
        }
    }
}

impl std::fmt::Display for BrdfIntegral {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for BrdfIntegral {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        BrdfIntegral::ALL
            .into_iter()
            .find(|b| b.name() == s)
            .ok_or_else(|| format!("unknown BRDF integral `{s}` (known: sptd, ltc)"))
    }
}

/// Which node importance chooses BO's clusters and its descent inside a cluster. The BO cut's
/// split test and heuristic 1's UB use the cap integrals of [`BrdfIntegral`] under either.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BoImportance {
    /// I_BO from the cap integrals of [`BrdfIntegral`] (the paper).
    #[default]
    Cap,
    /// The spherical-Gaussian lighting integral of each node with the BSDF (Tokuyoshi et al.
    /// 2024, [`crate::sg::importance`]), with its floor that keeps every node the bounds admit.
    Sg,
}

impl BoImportance {
    /// Every choice, in the order `--help` lists them.
    pub const ALL: [BoImportance; 2] = [BoImportance::Cap, BoImportance::Sg];

    /// The name on the command line and in the render's JSON.
    pub fn name(self) -> &'static str {
        match self {
            BoImportance::Cap => "cap",
            BoImportance::Sg => "sg",
        }
    }
}

impl std::fmt::Display for BoImportance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for BoImportance {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        BoImportance::ALL
            .into_iter()
            .find(|b| b.name() == s)
            .ok_or_else(|| format!("unknown BO importance `{s}` (known: cap, sg)"))
    }
}

/// Knobs of the method (recorded in the render's JSON).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BoConfig {
    /// BO cut: split a node whose cap integral exceeds δ.
    pub delta: f32,
    /// Heuristic 1's N_max (BRDF-aware samples beyond the forced two).
    pub n_max: u32,
    /// Weight λ of a BRDF-sampling hit in P(BO).
    pub lambda: f32,
    /// The LS cut's splitting threshold τ.
    pub tau: f32,
    /// Most clusters in the LS cut.
    pub max_cut: usize,
    /// Most clusters in the BO cut.
    pub max_cut_bo: usize,
    /// Cap-integral approximation behind BO.
    pub brdf_integral: BrdfIntegral,
    /// The node importance of BO's cluster choice and descent (the cut and UB keep the cap
    /// integrals).
    #[serde(default)]
    pub bo_importance: BoImportance,
    /// The authors' code's behaviour throughout.
    pub reproduce: bool,
    /// Pivot-sphere point sampling on sphere lights.
    pub pivot_sphere: bool,
    /// BRDF-aware (LTC) point sampling on triangle lights. Named only when on, so that the
    /// parameters recorded before it existed keep their keys.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub ltc_triangles: bool,
    /// Heuristic 1 (N from UB); off: N = N_max/2.
    pub adaptive_total: bool,
    /// Heuristic 1's UB times the glossy lobe's weight (Ks·F at θo).
    pub weighted_ub: bool,
    /// Heuristic 1's N_max chosen after each pass by variance × cost (off: `n_max` throughout).
    pub efficient_total: bool,
    /// With fixed counts: a shading point's BO cluster choices stratified (a shifted 1D
    /// lattice) and its BRDF samples' numbers a shifted R3 point set, instead of independent.
    pub stratified: bool,
    /// LS at glossy points (where BO runs) is one descent from the root instead of the E&K cut.
    pub single_ls_at_glossy: bool,
    /// Heuristic 2 (P(BO) from hit/miss counts); off: P = 1/2.
    pub adaptive_split: bool,
    /// BO's descent below its cut is the tree's four-wide one (two levels a step, I_BO of four
    /// nodes at once); off (the authors' code, and under the SG importance): the binary one.
    #[serde(default)]
    pub four_wide_bo_descent: bool,
    /// With `efficient_total`: N_max learnt from a pilot before the first pass
    /// (`render_core::pilot`) instead of keeping `n_max` until two passes are done.
    #[serde(default)]
    pub pilot: bool,
}

/// The SPTD pivot of a lobe, where the approximation has one.
pub trait LobePivot {
    /// The pivot in the lobe's local frame (None for methods without one).
    fn pivot(&self) -> Option<Vec3>;
}

impl LobePivot for SptdLobe {
    fn pivot(&self) -> Option<Vec3> {
        Some(self.pivot)
    }
}

impl LobePivot for LtcLobe {
    fn pivot(&self) -> Option<Vec3> {
        None
    }
}
