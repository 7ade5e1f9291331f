//! Adaptive sample allocation between BRDF-oriented light sampling and BRDF sampling
//! (method.md §1.7).
//!
//! * Heuristic 1: N = floor(N_max · UB) BRDF-aware samples beyond one forced sample of each,
//!   UB = clamp(max over the BO cut of the cached glossy cap integrals, 0, 1).
//! * Heuristic 2: P(BO) = n_nohit / (n_nohit + λ·n_hit), with the authors' counters (both start
//!   at 1; a BRDF sample that reaches an emitter adds λ to the hit counter, any other adds 1 to
//!   the miss counter), i.e. P = (1 + misses) / (2 + misses + λ·hits).
//!
//! Unbiased default: the counts that weight a shading point's samples are fixed before any of
//! them is drawn. The hit/miss tallies come from the BRDF samples of *earlier* samples of the
//! same pixel (kept in `SampleContext::pixel_memory`, which the renderer carries in sample order,
//! deterministically for any thread count); with fixed counts the multi-sample MIS estimator
//! is unbiased. `reproduce` instead runs the authors' in-sample loop, where the outcome of each
//! BRDF sample changes the probability of the next choice and the final counts weight all
//! samples (slightly biased).

/// Slots of the pixel memory used by the tallies.
pub const SLOT_HITS: usize = 0;
pub const SLOT_MISSES: usize = 1;

/// Heuristic 1: BRDF-aware samples beyond the forced two. With `adaptive` off, N_max/2.
pub fn total_brdf_aware(upper_bound: f32, n_max: u32, adaptive: bool) -> u32 {
    if adaptive {
        ((n_max as f32) * upper_bound.clamp(0.0, 1.0)).floor() as u32
    } else {
        n_max / 2
    }
}

/// Heuristic 2 from tallies of BRDF samples that hit / missed an emitter.
pub fn probability_bo(hits: f32, misses: f32, lambda: f32) -> f32 {
    let f = 1.0 + misses.max(0.0);
    let s = 1.0 + lambda * hits.max(0.0);
    f / (f + s)
}

/// Fixed counts (n_BO, n_BRDF) for N extra samples split with probability `p_bo`.
pub fn fixed_counts(n: u32, p_bo: f32) -> (u32, u32) {
    let k = ((n as f32) * p_bo.clamp(0.0, 1.0)).round() as u32;
    let k = k.min(n);
    (1 + k, 1 + n - k)
}

/// The authors' sequential counters (`reproduce`).
#[derive(Clone, Copy, Debug)]
pub struct InSampleCounters {
    pub fail: f32,
    pub success: f32,
    pub lambda: f32,
}

impl InSampleCounters {
    pub fn new(lambda: f32) -> Self {
        InSampleCounters {
            fail: 1.0,
            success: 1.0,
            lambda,
        }
    }
    pub fn record(&mut self, hit: bool) {
        if hit {
            self.success += self.lambda;
        } else {
            self.fail += 1.0;
        }
    }
    pub fn p_bo(&self) -> f32 {
        self.fail / (self.fail + self.success)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heuristics() {
        assert_eq!(total_brdf_aware(0.999, 50, true), 49);
        assert_eq!(total_brdf_aware(2.0, 50, true), 50);
        assert_eq!(total_brdf_aware(0.0, 50, true), 0);
        assert_eq!(total_brdf_aware(0.0, 50, false), 25);
        assert_eq!(probability_bo(0.0, 0.0, 10.0), 0.5);
        assert!((probability_bo(1.0, 3.0, 10.0) - 4.0 / 15.0).abs() < 1e-6);
        assert_eq!(fixed_counts(10, 0.26), (4, 8));
        assert_eq!(fixed_counts(0, 0.9), (1, 1));
        let mut c = InSampleCounters::new(10.0);
        c.record(true);
        c.record(false);
        assert!((c.p_bo() - 2.0 / 13.0).abs() < 1e-6);
    }
}
