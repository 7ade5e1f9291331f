//! A reservoir: one light point kept from a stream of weighted candidates, with its unbiased
//! contribution weight W (GRIS: E[f(Y)·W] = ∫ f over the target's support) and its confidence.
use super::light_point::LightPoint;

/// What a pixel keeps between phases.
#[derive(Clone, Copy, Debug, Default)]
pub struct Reservoir {
    /// The kept sample.
    pub y: LightPoint,
    /// Unbiased contribution weight of `y` for the pixel's target; 0: no sample.
    pub w: f32,
    /// Confidence: how many candidates it stands for (M), for the reuse weights.
    pub c: f32,
}

/// Weighted reservoir sampling over a stream of candidates: each replaces the kept one with
/// probability weight / (sum so far), so the kept one is chosen ∝ its weight.
#[derive(Default)]
pub struct Stream {
    kept: Option<LightPoint>,
    /// The kept candidate's target value at the pixel that resamples.
    kept_target: f32,
    sum: f32,
}

impl Stream {
    /// Offers `y` with resampling weight `w` (its target at this pixel `target`); `u` uniform.
    pub fn offer(&mut self, y: LightPoint, w: f32, target: f32, u: f32) {
        if !(w > 0.0) || !w.is_finite() {
            return;
        }
        self.sum += w;
        if u * self.sum < w {
            self.kept = Some(y);
            self.kept_target = target;
        }
    }

    /// The reservoir: W = Σ w / p̂(y) (0 when nothing was kept).
    pub fn finish(&self, c: f32) -> Reservoir {
        match self.kept {
            Some(y) if self.kept_target > 0.0 => Reservoir {
                y,
                w: self.sum / self.kept_target,
                c,
            },
            _ => Reservoir {
                c,
                ..Reservoir::default()
            },
        }
    }

    /// The kept candidate's target value (0 when none).
    pub fn kept_target(&self) -> f32 {
        self.kept.map_or(0.0, |_| self.kept_target)
    }
}
