//! Counters of work done, gathered per thread and merged.
use serde::Serialize;

/// Most per-pixel diagnostic channels a strategy can write.
pub const MAX_AUX: usize = 4;

/// Most techniques a strategy can report sample counts for.
pub const MAX_TECHNIQUES: usize = 8;
/// Most counters of its own a strategy can declare.
pub const MAX_STRATEGY_COUNTERS: usize = 8;

/// A counter a strategy declares: its name, and what its mean is taken per: the shading points
/// (`None`) or the total of another of its counters (e.g. the points where one technique ran).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrategyCounter {
    /// Its name in `render --stats` and the render's JSON.
    pub name: &'static str,
    /// The name of the counter it is a mean per, or `None`: per shading point.
    pub per: Option<&'static str>,
}

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
    /// The strategy's own counters, in the order of `DirectLighting::counters`.
    pub strategy: [u64; MAX_STRATEGY_COUNTERS],
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
        for (a, b) in self.strategy.iter_mut().zip(o.strategy) {
            *a += b;
        }
    }

    /// The strategy's counters as JSON, each with its total, what its mean is per and the mean:
    /// `{name: {"total": n, "per": "shading point" | other counter, "mean": x}}`.
    pub fn strategy_means(&self, names: &[StrategyCounter]) -> serde_json::Value {
        let total = |name: &str| {
            names
                .iter()
                .position(|c| c.name == name)
                .map_or(0, |i| self.strategy[i])
        };
        let map: serde_json::Map<String, serde_json::Value> = names
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let n = c.per.map_or(self.shading_points, total);
                let mean = if n > 0 {
                    self.strategy[i] as f64 / n as f64
                } else {
                    0.0
                };
                let v = serde_json::json!({
                    "total": self.strategy[i],
                    "per": c.per.unwrap_or("shading point"),
                    "mean": mean,
                });
                (c.name.to_string(), v)
            })
            .collect();
        serde_json::Value::Object(map)
    }
}
