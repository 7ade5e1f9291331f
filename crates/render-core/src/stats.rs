//! Counters of work done, gathered per thread and merged.
use serde::Serialize;

/// Most techniques a strategy can report sample counts for.
pub const MAX_TECHNIQUES: usize = 8;

#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct Counters {
    pub camera_rays: u64,
    /// Of the camera rays, those traced only for the emission they see (`emission_rays.rs`).
    pub emission_rays: u64,
    pub shadow_rays: u64,
    /// Rays traced from BSDF-sampled directions to find the light they hit.
    pub bsdf_rays: u64,
    /// Camera hits where a direct-lighting estimate was made.
    pub shading_points: u64,
    /// Samples drawn per technique, in the order of `DirectLighting::techniques`.
    pub technique_samples: [u64; MAX_TECHNIQUES],
    /// Shading points whose BSDF has a glossy lobe (where BRDF-oriented sampling runs).
    pub glossy_points: u64,
    /// Light-selection work summed over shading points (all, and glossy ones only): clusters
    /// of the E&K (LS) cut, clusters of the BRDF-oriented (BO) cut, and BRDF-aware samples
    /// (BO samples + BRDF samples).
    pub ls_clusters: u64,
    pub ls_clusters_glossy: u64,
    pub bo_clusters: u64,
    pub brdf_aware_samples: u64,
    pub brdf_aware_samples_glossy: u64,
}

impl Counters {
    pub fn merge(&mut self, o: &Counters) {
        self.camera_rays += o.camera_rays;
        self.emission_rays += o.emission_rays;
        self.shadow_rays += o.shadow_rays;
        self.bsdf_rays += o.bsdf_rays;
        self.shading_points += o.shading_points;
        for (a, b) in self.technique_samples.iter_mut().zip(o.technique_samples) {
            *a += b;
        }
        self.glossy_points += o.glossy_points;
        self.ls_clusters += o.ls_clusters;
        self.ls_clusters_glossy += o.ls_clusters_glossy;
        self.bo_clusters += o.bo_clusters;
        self.brdf_aware_samples += o.brdf_aware_samples;
        self.brdf_aware_samples_glossy += o.brdf_aware_samples_glossy;
    }

    /// Records one shading point's light-selection work (`glossy`: its BSDF has a glossy lobe).
    pub fn record_selection(
        &mut self,
        glossy: bool,
        ls_clusters: usize,
        bo_clusters: usize,
        brdf_aware: usize,
    ) {
        self.ls_clusters += ls_clusters as u64;
        self.bo_clusters += bo_clusters as u64;
        self.brdf_aware_samples += brdf_aware as u64;
        if glossy {
            self.ls_clusters_glossy += ls_clusters as u64;
            self.brdf_aware_samples_glossy += brdf_aware as u64;
        }
    }

    /// Means per shading point and per glossy point of the light-selection work, as JSON:
    /// `{"per_shading_point": {ls_clusters, bo_clusters, brdf_aware_samples},
    ///   "per_glossy_point": {…}, "glossy_points": n}`.
    pub fn selection_means(&self) -> serde_json::Value {
        let per = |v: u64, n: u64| if n > 0 { v as f64 / n as f64 } else { 0.0 };
        let (n, g) = (self.shading_points, self.glossy_points);
        serde_json::json!({
            "shading_points": n,
            "glossy_points": g,
            "per_shading_point": {
                "ls_clusters": per(self.ls_clusters, n),
                "bo_clusters": per(self.bo_clusters, n),
                "brdf_aware_samples": per(self.brdf_aware_samples, n),
            },
            "per_glossy_point": {
                "ls_clusters": per(self.ls_clusters_glossy, g),
                "bo_clusters": per(self.bo_clusters, g),
                "brdf_aware_samples": per(self.brdf_aware_samples_glossy, g),
            },
        })
    }
}
