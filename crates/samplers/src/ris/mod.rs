//! Resampled importance sampling (Talbot et al. 2005; the candidate step of ReSTIR DI, Bitterli
//! et al. 2020, without spatial or temporal reuse) over light-tree and BRDF-oriented candidates.
//!
//! * [`candidates`]: the candidate source, a fixed-proportion mixture of a single light-tree
//!   descent (LS) and BRDF-oriented sampling (BO), and the density of any light point under it.
//! * [`resample`]: choosing one candidate in proportion to its resampling weight.
//! * [`strategy`]: the strategies `ris`, `ris-N`, `ris-adaptive`: M candidates weighted by
//!   unshadowed f·L·G over their source density, one kept and shadow-tested, combined with BSDF
//!   sampling by MIS (the argument for unbiasedness is in [`strategy`] and docs/method.md).
pub mod candidates;
pub mod resample;
pub mod strategy;

use serde::Serialize;

/// How many candidates a shading point draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CandidateCount {
    /// M candidates at every shading point.
    Fixed(u32),
    /// M = min + round((max − min)·UB), UB the BO cut's largest cap integral (the paper's
    /// heuristic 1: sharp lobes facing bright clusters get more candidates); `min` where the
    /// point has no BO cut (pure diffuse).
    Adaptive {
        /// M at UB = 0 (and at pure diffuse points).
        min: u32,
        /// M at UB = 1.
        max: u32,
    },
}

impl CandidateCount {
    /// M at a point whose BO cut has upper bound `ub` (0 without a cut). Deterministic per
    /// shading point, so the weights that use M are functions of the point alone.
    pub fn at(&self, ub: f32) -> u32 {
        match *self {
            CandidateCount::Fixed(m) => m.max(1),
            CandidateCount::Adaptive { min, max } => {
                let ub = if ub.is_finite() {
                    ub.clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (min as f32 + (max.saturating_sub(min)) as f32 * ub)
                    .round()
                    .max(1.0) as u32
            }
        }
    }
}
