//! The authors' in-sample allocation (`reproduce`): P(BO) updated after every BRDF sample of a
//! shading point from its outcome, so that the final counts weight samples drawn under earlier
//! probabilities (slightly biased; the default fixes the counts before drawing, see
//! [`super::allocation`]).

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
