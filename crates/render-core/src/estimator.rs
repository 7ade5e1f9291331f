//! The interface between the render loop and light-sampling strategies.
use crate::bsdf::Bsdf;
use crate::light::LightSample;
use crate::pilot::Pilot;
use crate::rng::SampleStream;
use crate::scene::{Scene, SurfaceHit, offset_origin};
use crate::stats::Counters;
use glam::Vec3;

/// Most per-pixel diagnostic channels a strategy can write.
pub const MAX_AUX: usize = 4;
/// Floats of per-pixel memory a strategy may keep across passes of the same pixel.
pub const PIXEL_MEMORY: usize = 16;

/// A camera-ray hit on a reflecting surface, ready for direct lighting.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint {
    pub hit: SurfaceHit,
    /// Unit direction towards the viewer.
    pub wo: Vec3,
    pub bsdf: Bsdf,
}

impl ShadingPoint {
    pub fn point(&self) -> Vec3 {
        self.hit.point
    }

    /// The shading normal on the viewer's side: the receiver's normal of light sampling.
    pub fn normal(&self) -> Vec3 {
        self.bsdf.frame.z
    }

    /// Ray origin for a ray leaving in direction `w`.
    pub fn origin_towards(&self, w: Vec3) -> Vec3 {
        offset_origin(self.hit.point, self.hit.ng, w)
    }

    /// Unoccluded contribution f·cos·L of a light sample, before dividing by any pdf; traces the
    /// shadow ray only when the unshadowed value is non-zero.
    pub fn shade(&self, scene: &Scene, s: &LightSample, counters: &mut Counters) -> Vec3 {
        let f = self.bsdf.eval_cos(self.wo, s.wi) * s.radiance;
        self.unless_occluded(scene, s, f, counters)
    }

    /// [`ShadingPoint::shade`] and the BSDF's sampling density of the light sample's direction
    /// (for its MIS weight), both from one BSDF evaluation.
    pub fn shade_with_pdf(
        &self,
        scene: &Scene,
        s: &LightSample,
        counters: &mut Counters,
    ) -> (Vec3, f32) {
        let v = self.bsdf.eval(self.wo, s.wi);
        let f = self.unless_occluded(scene, s, v.f_cos * s.radiance, counters);
        (f, v.pdf)
    }

    /// `f`, or zero when it is zero or the light sample's shadow ray is blocked.
    #[inline]
    fn unless_occluded(
        &self,
        scene: &Scene,
        s: &LightSample,
        f: Vec3,
        counters: &mut Counters,
    ) -> Vec3 {
        if f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        counters.shadow_rays += 1;
        let o = self.origin_towards(s.wi);
        if scene.occluded(o, s.wi, (s.point - o).length()) {
            Vec3::ZERO
        } else {
            f
        }
    }
}

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
