//! The interface between the render loop and light-sampling strategies.
use crate::pilot::Pilot;
use crate::rng::SampleStream;
use crate::scene::Scene;
use crate::stats::Counters;
use glam::Vec3;

pub use crate::shading_point::ShadingPoint;
pub use crate::stats::MAX_AUX;
/// Floats of per-pixel memory a strategy may keep across passes of the same pixel.
pub const PIXEL_MEMORY: usize = 16;

/// What a strategy may write besides its radiance estimate.
pub struct SampleContext<'a> {
    pub counters: &'a mut Counters,
    /// Diagnostic values of this sample, averaged per pixel (channel names: `aux_channels`).
    pub aux: [f32; MAX_AUX],
    /// Persistent per-pixel memory, carried across the samples and passes of the pixel in
    /// sample order (e.g. statistics that fix sample allocations before later samples are drawn).
    pub pixel_memory: &'a mut [f32; PIXEL_MEMORY],
}

/// A direct-lighting estimator for bounded lights (distant lights are handled by the render loop).
pub trait DirectLighting: Send + Sync {
    /// The strategy's name as the command line spells it.
    fn name(&self) -> String;
    /// Parameters worth recording in the render's JSON.
    fn parameters(&self) -> serde_json::Value {
        serde_json::Value::Null
    }
    /// Names of the techniques whose sample counts go into `Counters::technique_samples`.
    fn techniques(&self) -> Vec<&'static str> {
        Vec::new()
    }
    /// The counters of its own it adds to in `Counters::strategy`, in that order (at most
    /// `MAX_STRATEGY_COUNTERS`).
    fn counters(&self) -> Vec<crate::stats::StrategyCounter> {
        Vec::new()
    }
    /// Names of the per-pixel diagnostic channels written to `SampleContext::aux`.
    fn aux_channels(&self) -> Vec<&'static str> {
        Vec::new()
    }
    /// The false colour of a pixel's value `v` of aux channel `channel` in its PNG preview, or
    /// `None` for a channel shown only as EXR.
    fn aux_colour(&self, _channel: &str, _v: f32) -> Option<Vec3> {
        None
    }
    /// An unbiased (unless documented otherwise) estimate of the radiance reflected towards
    /// `sp.wo` from the scene's bounded lights.
    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3;
    /// The strategy's whole-image form, if it has one: the render loop then runs each pass
    /// through it (`crate::image_space`) instead of calling [`DirectLighting::estimate`] per
    /// camera sample. `estimate` must still be an unbiased estimator of its own (tools and
    /// tests shade single points with it).
    fn image_space(&self) -> Option<&dyn crate::image_space::ImageSpaceLighting> {
        None
    }
    /// The strategy's batched form, if it has one (`crate::batch`): the render loop then
    /// shades a work unit's camera samples together through it (unless the render asks for
    /// the per-sample engine). It must give every point `estimate`'s value bit for bit.
    fn batched(&self) -> Option<&dyn crate::batch::BatchLighting> {
        None
    }
    /// Called once before a render's first sample: forget what an earlier render taught.
    fn begin_render(&self) {}
    /// The weight of pass `pass` (from 0) in every pixel's average, > 0: a function of the
    /// pass's index alone, fixed before the render, so that a weighted average of unbiased
    /// passes stays unbiased. A strategy whose later passes are better (it learns) can weigh
    /// them more; 1 (a plain average) by default.
    fn pass_weight(&self, _pass: u32) -> f64 {
        1.0
    }
    /// Called after each complete pass with every pixel's memory, in pixel order (so what the
    /// strategy learns is the same for any thread count); the next pass sees what it keeps.
    fn end_pass(&self, _pixel_memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {}
    /// The pilot the strategy wants before its first pass (`crate::pilot`) on a sample grid of
    /// `width` × `height` pixels, if any; asked after `begin_render`.
    fn pilot(&self, _width: usize, _height: usize) -> Option<Pilot> {
        None
    }
    /// Called once after the pilot with its pixels' memory, in pixel order; what the strategy
    /// keeps from it applies from the first pass on. The pilot's samples are not in the image.
    fn end_pilot(&self, _pixel_memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {}
}
