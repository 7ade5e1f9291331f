//! Image-space passes: a strategy that shares work between pixels (ReSTIR's spatial reuse)
//! sees a whole pass at once instead of one camera sample at a time.
//!
//! The render loop first traces every pixel's camera sample to its shading point (phase 0's
//! input, [`ImagePass::points`]); the strategy then runs its own phases over the image with
//! [`ImagePass::run`], each parallel over pixels and reading only the buffers of the phases
//! before it, and returns every pixel's direct lighting. Random numbers are keyed by (seed,
//! pixel, pass, phase, dimension): phase 0 continues the pixel sample's own stream (the
//! sampler's stratification carries on from the film position), every later phase draws from
//! an independent stream of its own. So the image is bit-identical whatever the thread count.
//!
//! What differs from the per-sample path: a time budget is checked between passes only (a
//! pass is never cut short; another starts while at least half of the last one's time is
//! left, so the budget is missed by at most half a pass either way), a strategy's per-pixel
//! memory and pilot are not offered, and the passes' pixels are no longer independent (a
//! pixel's estimate uses its neighbours' samples of the same pass). Passes stay independent
//! unless the strategy carries state from one pass to the next ([`PassCarry`]; ReSTIR's reuse
//! of the previous pass's reservoirs), which it then declares with
//! [`ImageSpaceLighting::correlates_passes`]: the per-pixel variance of such a render's passes
//! no longer estimates its error.
use crate::rng::SampleStream;
use crate::scene::Scene;
use crate::shading_point::ShadingPoint;
use crate::stats::Counters;
use crate::stats::MAX_AUX;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Mutex;

/// Pixels a worker takes at a time in a phase.
const CHUNK: usize = 256;

/// What a strategy hands from one pass to the next: empty before the first pass; the render
/// loop keeps it between passes and never looks inside.
pub type PassCarry = Option<Box<dyn std::any::Any + Send + Sync>>;

/// A strategy's direct lighting of a whole pass.
pub trait ImageSpaceLighting: Sync {
    /// Every pixel's direct-lighting estimate and its diagnostic values (the channels of
    /// `DirectLighting::aux_channels`), in pixel order; zero where `pass.points` has none.
    /// `carry` is what the previous pass of this render left (empty for the first).
    fn estimate_image(
        &self,
        pass: &ImagePass,
        carry: &mut PassCarry,
    ) -> Vec<(Vec3, [f32; MAX_AUX])>;
    /// Bytes it holds per pixel while a pass runs (its buffers, and what it carries to the
    /// next pass), for the memory check and the render's record.
    fn bytes_per_pixel(&self) -> usize;
    /// Whether a pass's estimates depend on earlier passes' samples (through `carry`): the
    /// passes are then correlated and their spread understates the error.
    fn correlates_passes(&self) -> bool {
        false
    }
}

/// One pass over the image, as a strategy's phases see it.
pub struct ImagePass<'a> {
    pub scene: &'a Scene,
    /// The sample grid's size (the image's, plus a border when splatting).
    pub width: usize,
    pub height: usize,
    /// Where the camera rays start (for depth tests between neighbours).
    pub camera_position: Vec3,
    /// Each pixel's shading point of this pass, row-major (none: no hit, or a hit on a light).
    pub points: &'a [Option<ShadingPoint>],
    /// Each pixel's sample stream after its film position (phase 0's numbers).
    pub(crate) streams: &'a [SampleStream],
    pub(crate) seed: u64,
    /// The pass's sample index (0 for the first pass).
    pub sample_index: u64,
    pub(crate) pool: &'a rayon::ThreadPool,
    pub(crate) counters: Mutex<Counters>,
}

impl ImagePass<'_> {
    /// Runs `f(pixel, rng, counters)` for every pixel of the grid, in parallel, and returns its
    /// results in pixel order. Phase 0 continues each pixel sample's own stream; every other
    /// phase number gives an independent stream (use each number once per pass).
    pub fn run<T: Send>(
        &self,
        phase: u32,
        f: impl Fn(usize, &mut SampleStream, &mut Counters) -> T + Sync,
    ) -> Vec<T> {
        let (out, counters) = par_pixels(self.pool, self.width * self.height, |i, c| {
            f(i, &mut self.stream(i, phase), c)
        });
        let mut total = self.counters.lock().unwrap_or_else(|e| e.into_inner());
        total.merge(&counters);
        out
    }

    /// The random numbers of pixel `pixel` in phase `phase` of this pass.
    pub fn stream(&self, pixel: usize, phase: u32) -> SampleStream {
        if phase == 0 {
            return self.streams[pixel].clone();
        }
        let key = self.seed ^ (phase as u64).wrapping_mul(PHASE_KEY);
        SampleStream::new(key, pixel as u64, self.sample_index)
    }

    /// Row-major index of pixel (x, y).
    pub fn index(&self, x: usize, y: usize) -> usize {
        y * self.width + x
    }
}

/// `f(pixel, counters)` for pixels 0..n on `pool`, in parallel: the results in pixel order and
/// the counters' sum.
pub(crate) fn par_pixels<T: Send>(
    pool: &rayon::ThreadPool,
    n: usize,
    f: impl Fn(usize, &mut Counters) -> T + Sync,
) -> (Vec<T>, Counters) {
    let chunks: Vec<(Vec<T>, Counters)> = pool.install(|| {
        (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut counters = Counters::default();
                let out = (c * CHUNK..((c + 1) * CHUNK).min(n))
                    .map(|i| f(i, &mut counters))
                    .collect();
                (out, counters)
            })
            .collect()
    });
    let mut total = Counters::default();
    let mut out = Vec::with_capacity(n);
    for (v, c) in chunks {
        total.merge(&c);
        out.extend(v);
    }
    (out, total)
}

/// Separates the phases' streams from each other and from the pixel samples'.
const PHASE_KEY: u64 = 0xa076_1d64_78bd_642f;
