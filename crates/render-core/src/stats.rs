//! Counters of work done, gathered per thread and merged.
use serde::Serialize;

/// Most techniques a strategy can report sample counts for.
pub const MAX_TECHNIQUES: usize = 8;

#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct Counters {
    pub camera_rays: u64,
    pub shadow_rays: u64,
    /// Rays traced from BSDF-sampled directions to find the light they hit.
    pub bsdf_rays: u64,
    /// Camera hits where a direct-lighting estimate was made.
    pub shading_points: u64,
    /// Samples drawn per technique, in the order of `DirectLighting::techniques`.
    pub technique_samples: [u64; MAX_TECHNIQUES],
}

impl Counters {
    pub fn merge(&mut self, o: &Counters) {
        self.camera_rays += o.camera_rays;
        self.shadow_rays += o.shadow_rays;
        self.bsdf_rays += o.bsdf_rays;
        self.shading_points += o.shading_points;
        for (a, b) in self.technique_samples.iter_mut().zip(o.technique_samples) {
            *a += b;
        }
    }
}
