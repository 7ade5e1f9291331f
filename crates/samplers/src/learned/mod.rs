//! Learned cluster selection (issue 25, after Vévoda et al. 2018): which cluster of a fixed
//! light-tree cut a shading point samples is weighed by what earlier passes observed of each
//! cluster in the point's region (its contribution over its prior, or its visibility), with the
//! unshadowed tree importance as the prior and a defensive share of the prior alone, so that
//! every light the tree can reach stays reachable.
//!
//! * `regions.rs`: the hash grid of regions (position cell × normal bucket), the per-region
//!   tallies, and the observation a sample leaves in its pixel's memory;
//! * `selection.rs`: the per-point cluster probabilities, `pick` beside `pmf`;
//! * `descent.rs`: the learned descent, a factor learnt per region for every node of the
//!   tree's top levels, applied at each step of the descent (`learned-descent`);
//!   `descent_table.rs`: its per-region tallies and the observation a sample leaves;
//!   `descent_walk.rs`: its walk, eight lanes at a time on the tree's own eight-wide nodes;
//! * `strategy.rs`: `learned`, `learned+bsdf` and the descent's strategies, which merge the
//!   pass's observations in pixel order between passes (`DirectLighting::end_pass`).
//!
//! Unbiased: a sample's probabilities are functions of the shading point and of statistics
//! frozen before its pass began, so each pass is an unbiased estimate (as the per-pass N_max of
//! `mis3-adaptive`). The same for any thread count: a pass's observations are merged in pixel
//! order.
pub mod descent;
pub mod descent_table;
mod descent_walk;
pub mod regions;
pub mod selection;
pub mod strategy;

use crate::selection::LightSelection;
use render_core::estimator::PIXEL_MEMORY;
use serde::{Deserialize, Serialize};

/// A selection that learns between passes from the light samples it is shown.
pub trait Learner: LightSelection {
    /// Leaves in `memory` (the pixel's) what the light sample of `light` taught at the point
    /// of `state`: the luminance `lum_f` of its unshadowed f·L, the density `p` it was drawn
    /// with (pmf × point density) and whether its shadow ray reached the light.
    fn observe(
        &self,
        state: &Self::State,
        light: u32,
        lum_f: f32,
        p: f32,
        hit: bool,
        memory: &mut [f32],
    );
    /// Marks `memory` (the pixel's) as holding no observation of this pass, before a sample
    /// that may leave none.
    fn clear_observation(&self, memory: &mut [f32]);
    /// Forgets everything learnt (a new render).
    fn forget(&self);
    /// Merges the observations the pass just finished left in the pixels' memory, in pixel
    /// order.
    fn merge(&self, pixels: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>);
    /// Its parameters and what it holds, for the render's JSON.
    fn describe(&self) -> serde_json::Value;
}

/// What a region learns of each cluster, the factor that multiplies its prior at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LearnTarget {
    /// The hit rate of its shadow rays, V̂ = (hits + a)/(rays + a).
    Visibility,
    /// The mean ratio of its observed (shadowed) contribution to its prior,
    /// (Σ ratio + a·r̄)/(rays + a) with r̄ the region's mean ratio over all clusters: corrects the
    /// tree importance's own error in the region as well as visibility (closer to Vévoda et
    /// al.'s regression of the contribution).
    #[default]
    Contribution,
}

impl LearnTarget {
    /// Every target, in `--help` order.
    pub const ALL: [LearnTarget; 2] = [LearnTarget::Contribution, LearnTarget::Visibility];

    /// The name the CLI and the JSON use.
    pub fn name(self) -> &'static str {
        match self {
            LearnTarget::Visibility => "visibility",
            LearnTarget::Contribution => "contribution",
        }
    }

    /// The target called `name`.
    pub fn from_name(name: &str) -> Option<LearnTarget> {
        LearnTarget::ALL.into_iter().find(|t| t.name() == name)
    }
}

/// How `learned-descent` weighs its passes in each pixel's average (the cluster strategies
/// always weigh them equally).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PassWeights {
    /// Every pass alike.
    Equal,
    /// Pass i (from 1) by √i: later passes, drawn from more learning, count more. A function
    /// of the index alone, so the average stays unbiased; where learning gains nothing it
    /// costs at most 9/8 in variance.
    #[default]
    Sqrt,
}

impl PassWeights {
    /// Every choice, in `--help` order.
    pub const ALL: [PassWeights; 2] = [PassWeights::Sqrt, PassWeights::Equal];

    /// The name the CLI and the JSON use.
    pub fn name(self) -> &'static str {
        match self {
            PassWeights::Equal => "equal",
            PassWeights::Sqrt => "sqrt",
        }
    }

    /// The choice called `name`.
    pub fn from_name(name: &str) -> Option<PassWeights> {
        PassWeights::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The weight of pass `pass` (from 0).
    pub fn weight(self, pass: u32) -> f64 {
        match self {
            PassWeights::Equal => 1.0,
            PassWeights::Sqrt => (pass as f64 + 1.0).sqrt(),
        }
    }
}

/// Parameters of the learned selection.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LearnedConfig {
    /// What is learnt per region and cluster.
    pub target: LearnTarget,
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
    /// Light samples per shading point in `learned` and `learned+bsdf` (one BSDF sample
    /// beside them, power heuristic with counts); the first one's observation is learnt.
    pub light_samples: u32,
    /// How `learned-descent` weighs its passes.
    pub pass_weights: PassWeights,
}

impl Default for LearnedConfig {
    fn default() -> Self {
        LearnedConfig {
            target: LearnTarget::default(),
            clusters: 32,
            cells_per_diagonal: 64.0,
            defensive: 0.2,
            prior_strength: 1.0,
            max_regions: 1 << 16,
            light_samples: 1,
            pass_weights: PassWeights::default(),
        }
    }
}
