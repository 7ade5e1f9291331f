//! A pixel's initial reservoir: M light candidates from a light technique plus one BSDF
//! candidate, resampled by target p̂ with balance-heuristic weights over the M + 1 slots
//! (RIS with multiple techniques, as ReSTIR DI draws them).
//!
//! Candidate y from any slot gets w = p̂(y) / Σ_slots p_slot(y) (all in the lights' measure:
//! a solid-angle density times G); one is kept ∝ w and W = Σ w / p̂(y). Given y, p̂'s G
//! cancels, so w is the unshadowed luminance f·cos·L over the slots' solid-angle densities.
use super::light_point::{LightPoint, Seen, target};
use super::reservoir::{Reservoir, Stream};
use crate::baselines::selection::LightSelection;
use crate::bsdf_sampling::sample_bsdf;
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::stats::Counters;
use std::cell::RefCell;

/// Where a pixel's light candidates come from.
pub trait Candidates {
    /// Light candidates drawn (M).
    fn count(&self) -> u32;
    /// Draws light candidate `j` (0 ≤ j < M); `None`: a candidate of weight 0.
    fn draw(&self, j: u32, rng: &mut SampleStream) -> Option<LightPoint>;
    /// Σ over the M slots of their density of `y` (solid angle at the shading point; the
    /// selection probability alone on a point light).
    fn density_sum(&self, y: &LightPoint, seen: &Seen) -> f32;
}

/// M candidates from a light selection (power, or one light-tree descent), each light's point
/// drawn by the light's own sampling.
pub struct SelectionCandidates<'a, S: LightSelection> {
    /// The scene and the shading point the candidates are for.
    pub scene: &'a Scene,
    #[allow(missing_docs)]
    pub sp: &'a ShadingPoint,
    /// The light selection and its state at `sp`.
    pub selection: &'a S,
    #[allow(missing_docs)]
    pub state: S::State,
    /// Candidates drawn (M).
    pub m: u32,
    /// Scratch for the selection's picks.
    pub picks: RefCell<Vec<(u32, f32)>>,
}

impl<S: LightSelection> Candidates for SelectionCandidates<'_, S> {
    fn count(&self) -> u32 {
        self.m
    }

    fn draw(&self, _j: u32, rng: &mut SampleStream) -> Option<LightPoint> {
        let mut picks = self.picks.borrow_mut();
        picks.clear();
        self.selection.pick(&self.state, self.sp, rng, &mut picks);
        let &(light, _) = picks.first()?;
        let s = self
            .scene
            .sample_light(light, self.sp.point(), self.sp.normal(), rng.next_2d())?;
        Some(LightPoint {
            light,
            point: s.point,
            normal: s.normal,
        })
    }

    fn density_sum(&self, y: &LightPoint, seen: &Seen) -> f32 {
        let pmf = self.selection.pmf(&self.state, self.sp, y.light);
        if seen.is_delta || !(pmf > 0.0) {
            return self.m as f32 * pmf;
        }
        let (x, n) = (self.sp.point(), self.sp.normal());
        self.m as f32 * pmf * self.scene.light_pdf(y.light, x, n, y.point, y.normal)
    }
}

/// Index of the light candidates in the technique counters.
pub const TECHNIQUE_LIGHT: usize = 0;
/// Index of the BSDF candidates.
pub const TECHNIQUE_BSDF: usize = 1;

/// The initial reservoir of `sp`: the M light candidates of `source` and one BSDF candidate
/// (`bsdf`: whether to draw it). Its confidence is the number of slots.
pub fn initial_reservoir(
    scene: &Scene,
    sp: &ShadingPoint,
    source: &impl Candidates,
    bsdf: bool,
    rng: &mut SampleStream,
    counters: &mut Counters,
) -> Reservoir {
    let m = source.count();
    let slots = m + bsdf as u32;
    let mut stream = Stream::default();
    for j in 0..m {
        counters.technique_samples[TECHNIQUE_LIGHT] += 1;
        let y = source.draw(j, rng);
        let u = rng.next_f32();
        let Some(y) = y else { continue };
        let Some((p, _, seen)) = target(scene, sp, &y) else {
            continue;
        };
        let mut den = source.density_sum(&y, &seen);
        if bsdf && !seen.is_delta {
            den += sp.bsdf.pdf(sp.wo, seen.wi);
        }
        let g = if seen.is_delta { 1.0 } else { seen.g };
        stream.offer(y, p / (den * g), p, u);
    }
    if bsdf {
        counters.technique_samples[TECHNIQUE_BSDF] += 1;
        let b = sample_bsdf(scene, sp, rng, counters);
        let u = rng.next_f32();
        if let Some(b) = b.filter(|b| b.found_light()) {
            let y = LightPoint {
                light: b.light,
                point: b.point,
                normal: b.normal,
            };
            if let Some((p, _, seen)) = target(scene, sp, &y) {
                let den = source.density_sum(&y, &seen) + sp.bsdf.pdf(sp.wo, seen.wi);
                stream.offer(y, p / (den * seen.g), p, u);
            }
        }
    }
    stream.finish(slots as f32)
}
