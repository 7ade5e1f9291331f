//! Learned cluster selection (issue 25, after Vévoda et al. 2018): which cluster of a fixed
//! light-tree cut a shading point samples is weighed by what earlier passes observed of each
//! cluster's visibility in the point's region, with the unshadowed tree importance as the
//! prior and a defensive share of the prior alone, so that every light the tree can reach
//! stays reachable.
//!
//! * `regions.rs`: the hash grid of regions (position cell × normal bucket), the per-region
//!   tallies, and the observation a sample leaves in its pixel's memory;
//! * `selection.rs`: the per-point cluster probabilities, `pick` beside `pmf`;
//! * `strategy.rs`: `learned` and `learned+bsdf`, which merge the pass's observations in
//!   pixel order between passes (`DirectLighting::end_pass`).
//!
//! Unbiased: a sample's probabilities are functions of the shading point and of statistics
//! frozen before its pass began, so each pass is an unbiased estimate (as the per-pass N_max of
//! `mis3-adaptive`). The same for any thread count: a pass's observations are merged in pixel
//! order.
pub mod regions;
pub mod selection;
pub mod strategy;

use serde::Serialize;

/// Parameters of the learned selection.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct LearnedConfig {
    /// Clusters of the fixed cut (breadth-first from the root).
    pub clusters: usize,
    /// Region cells per scene diagonal (cell edge = diagonal / this).
    pub cells_per_diagonal: f32,
    /// Share α of the prior alone in the selection pmf.
    pub defensive: f32,
    /// Prior strength a of V̂ = (hits + a)/(rays + a).
    pub prior_strength: f32,
    /// Most regions kept (observations of further regions are dropped).
    pub max_regions: usize,
}

impl Default for LearnedConfig {
    fn default() -> Self {
        LearnedConfig {
            clusters: 64,
            cells_per_diagonal: 64.0,
            defensive: 0.2,
            prior_strength: 1.0,
            max_regions: 1 << 16,
        }
    }
}
