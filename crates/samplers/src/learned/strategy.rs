//! Strategies `learned` and `learned+bsdf`: N lights by the learned cluster selection (one by
//! default; ± one BSDF sample, power heuristic with counts), the first light sample leaving
//! its observation in the pixel's memory for the merge between passes.
use super::regions::{Observation, SLOTS};
use super::selection::{LearnedSelection, sample_observed};
use crate::bsdf_sampling::sample_bsdf;
use crate::light_strategy::{Picks, TECHNIQUE_BSDF, TECHNIQUE_LIGHT};
use crate::mis::power_heuristic;
use crate::scratch::Pooled;
use crate::selection::LightSelection;
use render_core::Vec3;
use render_core::estimator::{DirectLighting, PIXEL_MEMORY, SampleContext, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;

/// The learned selection as a strategy.
pub struct LearnedStrategy {
    /// `learned` or `learned+bsdf`.
    pub name: String,
    /// The selection and its statistics.
    pub selection: LearnedSelection,
    /// Add one BSDF sample, combined by the power heuristic.
    pub with_bsdf: bool,
}

impl DirectLighting for LearnedStrategy {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn parameters(&self) -> serde_json::Value {
        let t = self
            .selection
            .table
            .read()
            .unwrap_or_else(|e| e.into_inner());
        serde_json::json!({
            "config": self.selection.config,
            "clusters": self.selection.cut.len(),
            "cell_size": self.selection.grid.cell,
            "regions": t.len(),
            "region_memory_bytes": t.memory_bytes(),
            "dropped_observations": t.dropped,
            "passes_learnt": t.pass,
        })
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
        let state = {
            let table = sel.table.read().unwrap_or_else(|e| e.into_inner());
            sel.prepare_with(scene, sp, &table)
        };
        Observation::clear(&mut ctx.pixel_memory[..]);
        ctx.counters
            .record_selection(!sp.bsdf.is_pure_diffuse(), 0, 0, self.with_bsdf as usize);
        let mut picks = Pooled::<Picks>::take();
        let x = sp.point();
        let mut l = Vec3::ZERO;
        // At least 1: `LearnedSelection::new` refuses 0.
        let n = sel.config.light_samples;
        // Where the second and later samples' observations go (one is learnt per pass).
        let mut unlearnt = [0.0f32; SLOTS];
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
        self.selection
            .table
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
    }

    fn end_pass(&self, pixel_memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
        self.selection
            .table
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .merge_pass(pixel_memory, 0);
    }
}
