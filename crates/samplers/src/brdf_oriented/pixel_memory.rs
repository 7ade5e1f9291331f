//! The method's per-pixel memory (`SampleContext::pixel_memory`, carried across a pixel's samples
//! and passes in sample order), declared in one place: which slot holds what.
//!
//! | slots | what | written by |
//! |---|---|---|
//! | 0–1 | heuristic 2's BRDF-sampling hits and misses | [`super::mis3`] |
//! | 2–9 | the efficiency tally behind the learnt N_max | [`super::allocation::EfficiencyTally`] |
//! | 10.. | the learned LS's observation (`mis3-adaptive-learned`) | [`crate::learned::regions`] |
use render_core::estimator::PIXEL_MEMORY;

/// BRDF-sampling hits of the pixel's earlier samples (heuristic 2).
pub const HITS: usize = 0;
/// BRDF-sampling misses of the pixel's earlier samples (heuristic 2).
pub const MISSES: usize = 1;
/// Samples the efficiency tally has recorded.
pub const SAMPLES: usize = 2;
/// Σ y, the luminance of each sample's estimate.
pub const SUM: usize = 3;
/// Σ y².
pub const SUM_SQ: usize = 4;
/// Σ W, the variance the BRDF-aware samples added, at glossy points.
pub const WITHIN: usize = 5;
/// Σ W·K.
pub const UNIT: usize = 6;
/// Σ UB at glossy points.
pub const UB: usize = 7;
/// Glossy samples.
pub const GLOSSY: usize = 8;
/// Σ the cost of the rest of each sample, in BRDF-aware samples.
pub const REST: usize = 9;
/// First slot of the learned LS's observation.
pub const LEARNED: usize = 10;

const _: () = assert!(LEARNED + crate::learned::regions::SLOTS <= PIXEL_MEMORY);
