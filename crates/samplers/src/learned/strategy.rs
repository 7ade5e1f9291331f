//! Strategies `learned`, `learned+bsdf`, `learned-descent` and `learned-descent+bsdf`: N lights
//! by a learned selection (one by default; ± one BSDF sample, power heuristic with counts), the
//! first light sample leaving its observation in the pixel's memory for the merge between
//! passes.
use super::Learner;
use super::regions::Observation;
use super::selection::{LearnedSelection, sample_observed};
use crate::bsdf_sampling::sample_bsdf;
use crate::light_strategy::{Picks, TECHNIQUE_BSDF, TECHNIQUE_LIGHT};
use crate::mis::power_heuristic;
use crate::scratch::Pooled;
use render_core::Vec3;
use render_core::estimator::{DirectLighting, PIXEL_MEMORY, SampleContext, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;

/// A learned selection as a strategy.
pub struct LearnedStrategy<S = LearnedSelection> {
    /// `learned`, `learned+bsdf`, `learned-descent` or `learned-descent+bsdf`.
    pub name: String,
    /// The selection and its statistics.
    pub selection: S,
    /// Add one BSDF sample, combined by the power heuristic.
    pub with_bsdf: bool,
    /// Light samples per shading point (at least 1).
    pub light_samples: u32,
}

impl<S: Learner> DirectLighting for LearnedStrategy<S> {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn parameters(&self) -> serde_json::Value {
        self.selection.describe()
    }

    fn techniques(&self) -> Vec<&'static str> {
        if self.with_bsdf {
            vec!["light", "bsdf"]
        } else {
            vec!["light"]
        }
    }

    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        let sel = &self.selection;
        let state = sel.prepare(scene, sp);
        Observation::clear(&mut ctx.pixel_memory[..]);
        ctx.counters
            .record_selection(!sp.bsdf.is_pure_diffuse(), 0, 0, self.with_bsdf as usize);
        let mut picks = Pooled::<Picks>::take();
        let x = sp.point();
        let mut l = Vec3::ZERO;
        let n = self.light_samples.max(1);
        // Where the second and later samples' observations go (one is learnt per pass).
        let mut unlearnt = [0.0f32; PIXEL_MEMORY];
        for i in 0..n {
            picks.0.clear();
            sel.pick(&state, sp, rng, &mut picks.0);
            // The point on the light is drawn even without a pick, so later draws keep their
            // dimensions.
            let u = rng.next_2d();
            ctx.counters.technique_samples[TECHNIQUE_LIGHT] += 1;
            let Some(&(light, pmf)) = picks.0.first() else {
                continue;
            };
            let memory = if i == 0 {
                &mut ctx.pixel_memory[..]
            } else {
                &mut unlearnt[..]
            };
            if let Some((s, p, f)) =
                sample_observed(scene, sp, light, pmf, u, ctx.counters, memory, sel, &state)
            {
                let w = if self.with_bsdf && !s.is_delta {
                    power_heuristic(0, &[(n as f32, p), (1.0, sp.bsdf.pdf(sp.wo, s.wi))])
                } else {
                    1.0
                };
                l += f * (w / (n as f32 * p));
            }
        }
        if self.with_bsdf {
            ctx.counters.technique_samples[TECHNIQUE_BSDF] += 1;
            if let Some(b) = sample_bsdf(scene, sp, rng, ctx.counters)
                && b.found_light()
            {
                let p_light = sel.pmf(&state, sp, b.light)
                    * scene.lights[b.light as usize].pdf(x, b.point, b.normal);
                let w = power_heuristic(1, &[(n as f32, p_light), (1.0, b.pdf)]);
                l += b.f_cos * b.radiance * (w / b.pdf);
            }
        }
        l
    }

    fn begin_render(&self) {
        self.selection.forget();
    }

    fn end_pass(&self, pixel_memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
        self.selection.merge(pixel_memory);
    }
}
