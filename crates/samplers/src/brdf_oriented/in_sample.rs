//! The authors' in-sample allocation (`reproduce`): P(BO) updated after every BRDF sample of a
//! shading point from its outcome, so that the final counts weight samples drawn under earlier
//! probabilities (slightly biased; the default fixes the counts before drawing, see
//! [`super::allocation`]).

use super::allocation::Counts;
use super::importance::LobeDensity;
use super::ls_technique::LsTechnique;
use super::three_techniques::{PointTechniques, Taken};
use brdf_integrals::LobeIntegral;
use render_core::estimator::SampleContext;
use render_core::rng::SampleStream;

/// The authors' sequential counters (`reproduce`).
#[derive(Clone, Copy, Debug)]
pub struct InSampleCounters {
    /// BRDF samples that found no light, plus the prior 1.
    pub fail: f32,
    /// λ × BRDF samples that found a light, plus the prior 1.
    pub success: f32,
    /// Weight λ of a hit.
    pub lambda: f32,
}

impl InSampleCounters {
    /// Counters at the authors' priors (1, 1).
    pub fn new(lambda: f32) -> Self {
        InSampleCounters {
            fail: 1.0,
            success: 1.0,
            lambda,
        }
    }
    /// Counts one BRDF sample's outcome.
    pub fn record(&mut self, hit: bool) {
        if hit {
            self.success += self.lambda;
        } else {
            self.fail += 1.0;
        }
    }
    /// P(BO) = n_nohit / (n_nohit + λ·n_hit).
    pub fn p_bo(&self) -> f32 {
        self.fail / (self.fail + self.success)
    }
}

/// The authors' in-sample loop (`reproduce`; biased: the outcomes pick the counts): after the
/// forced BO and BRDF samples, each of the `n` more is BO with the current P(BO) (1/2 without
/// `adaptive_split`), their one random number rescaled at every step.
pub fn in_sample_allocation<L: LobeIntegral + LobeDensity, S: LsTechnique>(
    point: &PointTechniques<L, S>,
    n: u32,
    lambda: f32,
    adaptive_split: bool,
    taken: &mut Vec<Taken>,
    rng: &mut SampleStream,
    ctx: &mut SampleContext,
) -> Counts {
    let mut c = InSampleCounters::new(lambda);
    point.bo_sample(taken, rng, ctx, 0, None);
    c.record(point.bsdf_sample(taken, rng, ctx, None));
    let (mut n_bo, mut n_brdf) = (1, 1);
    let mut u = rng.next_f32();
    for _ in 0..n {
        let p = if adaptive_split { c.p_bo() } else { 0.5 };
        if u < p {
            point.bo_sample(taken, rng, ctx, 0, None);
            n_bo += 1;
            u /= p;
        } else {
            c.record(point.bsdf_sample(taken, rng, ctx, None));
            n_brdf += 1;
            u = (u - p) / (1.0 - p);
        }
    }
    Counts {
        n_bo,
        n_brdf,
        n_extra: n,
        stratified: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_start_at_the_priors_and_weigh_a_hit_by_lambda() {
        let mut c = InSampleCounters::new(10.0);
        assert_eq!(c.p_bo(), 0.5);
        c.record(true);
        c.record(false);
        assert!((c.p_bo() - 2.0 / 13.0).abs() < 1e-6);
    }
}
