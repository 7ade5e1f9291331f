//! Shading in batches (the engine's wavefront form): a work unit's camera samples go through
//! phases together instead of one after another. The render loop traces the unit's camera
//! rays as one stream ([`crate::scene::Scene::intersect_stream`]) and hands the shading points
//! to the strategy's [`BatchLighting`], which draws every point's numbers, queues the points'
//! shadow and BSDF rays, traces them as streams and finishes the estimates.
//!
//! The contract: each point's estimate is the one [`crate::estimator::DirectLighting::estimate`]
//! gives it, bit for bit. A point draws its numbers from its own stream in the order `estimate`
//! draws them, the same operations run on them, and its sums are added in the same order; only
//! when each ray is traced changes. So a strategy that opts in renders the same image in both
//! engines (the golden test), and the batch is as deterministic as the per-sample path.
//! The batched path offers no per-pixel memory and no diagnostic channels: strategies that use
//! them keep the per-sample path.
use crate::rng::SampleStream;
use crate::scene::Scene;
use crate::shading_point::ShadingPoint;
use crate::stats::Counters;
use glam::Vec3;

/// A batch of shading points, as a strategy's batched form sees it.
pub struct ShadingBatch<'a> {
    /// The unit's shading points, in pixel order (none: no hit, or a hit on a light).
    pub points: &'a [Option<ShadingPoint>],
    /// Each point's sample stream, positioned where `estimate` would start drawing.
    pub rngs: &'a mut [SampleStream],
    pub counters: &'a mut Counters,
    /// Each point's direct-lighting estimate (zero where `points` has none), written by the
    /// strategy.
    pub out: &'a mut [Vec3],
}

/// A strategy's batched form: every point's estimate, as its per-sample `estimate` gives it.
pub trait BatchLighting: Sync {
    fn estimate_batch(&self, scene: &Scene, batch: ShadingBatch<'_>);
}
