//! Light sampling through a [`LightSelection`], optionally combined with BSDF sampling by
//! MIS (power heuristic, one sample of each; a splitting selection counts as one sample).
use crate::bsdf_sampling::{sample_bsdf, sample_bsdf_at};
use crate::mis::power2;
use crate::scratch::Pooled;
use crate::selection::{LightSelection, PowerSelection, UniformSelection};
use crate::strategy::Strategy;
use render_core::accel::StreamRay;
use render_core::estimator::{DirectLighting, SampleContext, ShadingPoint};
use render_core::light::LightSample;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::stats::Counters;
use render_core::{Vec2, Vec3};

/// Light selection (one or several lights per shading point), with or without BSDF sampling
/// combined by MIS, as a strategy.
pub struct LightStrategy<S: LightSelection> {
    /// The strategy's registered name.
    pub name: String,
    /// Which lights a shading point samples.
    pub selection: S,
    /// Add one BSDF sample, combined by the power heuristic.
    pub with_bsdf: bool,
    /// What the render's JSON records of it.
    pub parameters: serde_json::Value,
}

/// Per-thread buffer of the lights a selection picked at one shading point (light, pmf).
#[derive(Default)]
pub struct Picks(pub Vec<(u32, f32)>);
crate::scratch_pool!(Picks, |p| p.0.clear());

/// Per-thread buffer of each pick's two numbers for its point on the light.
#[derive(Default)]
pub(crate) struct PickNumbers(pub(crate) Vec<Vec2>);
crate::scratch_pool!(PickNumbers, |p| p.0.clear());

/// Index of light sampling in the technique counters.
pub const TECHNIQUE_LIGHT: usize = 0;
/// Index of BSDF sampling in the technique counters.
pub const TECHNIQUE_BSDF: usize = 1;

/// Samples a point on a picked light (`pmf`: its selection probability) and shades it:
/// `(sample, pmf × point pdf, f·L with visibility, the BSDF's density of its direction)`, or
/// `None` when it contributes nothing.
pub(crate) fn sample_pick(
    scene: &Scene,
    sp: &ShadingPoint,
    light: u32,
    pmf: f32,
    rng: &mut SampleStream,
    counters: &mut Counters,
) -> Option<(LightSample, f32, Vec3, f32)> {
    sample_pick_at(scene, sp, light, pmf, rng.next_2d(), counters)
}

/// [`sample_pick_at`] before visibility: the sample, pmf × point pdf, the unshadowed f·L, the
/// BSDF's density of its direction and the shadow ray that decides it (counted), or `None`
/// where the sample adds nothing whatever the ray finds.
pub(crate) fn sample_pick_unshadowed(
    scene: &Scene,
    sp: &ShadingPoint,
    (light, pmf): (u32, f32),
    u: Vec2,
    counters: &mut Counters,
) -> Option<(LightSample, f32, Vec3, f32, StreamRay)> {
    let s = scene.sample_light(light, sp.point(), sp.normal(), u)?;
    let p = pmf * s.pdf;
    if !(p > 0.0) {
        return None;
    }
    let (f, p_bsdf) = sp.unshadowed_with_pdf(&s);
    if f == Vec3::ZERO {
        return None;
    }
    counters.shadow_rays += 1;
    let ray = sp.shadow_ray(scene, &s);
    Some((s, p, f, p_bsdf, ray))
}

/// [`sample_pick`] with the point's two numbers given.
fn sample_pick_at(
    scene: &Scene,
    sp: &ShadingPoint,
    light: u32,
    pmf: f32,
    u: Vec2,
    counters: &mut Counters,
) -> Option<(LightSample, f32, Vec3, f32)> {
    let s = scene.sample_light(light, sp.point(), sp.normal(), u)?;
    let p = pmf * s.pdf;
    if !(p > 0.0) {
        return None;
    }
    let (f, p_bsdf) = sp.shade_with_pdf(scene, &s, counters);
    (f != Vec3::ZERO).then_some((s, p, f, p_bsdf))
}

impl<S: LightSelection> DirectLighting for LightStrategy<S> {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn parameters(&self) -> serde_json::Value {
        self.parameters.clone()
    }

    fn counters(&self) -> Vec<render_core::stats::StrategyCounter> {
        crate::work_counters::names()
    }

    fn techniques(&self) -> Vec<&'static str> {
        if self.with_bsdf {
            vec!["light", "bsdf"]
        } else {
            vec!["light"]
        }
    }

    fn batched(&self) -> Option<&dyn render_core::batch::BatchLighting> {
        Some(self)
    }

    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        let state = self.selection.prepare(scene, sp);
        let mut picks = Pooled::<Picks>::take();
        self.selection.pick(&state, sp, rng, &mut picks.0);
        crate::work_counters::record(
            ctx.counters,
            !sp.bsdf.is_pure_diffuse(),
            self.selection.clusters(&state),
            0,
            self.with_bsdf as usize,
        );
        // Every number is drawn first, in the order the samples use them, so that the picked
        // lights' records (a cache miss each, among many lights) load while the BSDF ray is
        // traced. The same numbers and the same sum in the same order: the same image.
        let mut numbers = Pooled::<PickNumbers>::take();
        numbers.0.extend(picks.0.iter().map(|_| rng.next_2d()));
        let bsdf_numbers = self.with_bsdf.then(|| (rng.next_f32(), rng.next_2d()));
        for &(light, _) in &picks.0 {
            scene.prefetch_light(light);
        }
        let from_bsdf = bsdf_numbers.and_then(|(u_lobe, u)| {
            ctx.counters.technique_samples[TECHNIQUE_BSDF] += 1;
            let b = sample_bsdf_at(scene, sp, u_lobe, u, ctx.counters)?;
            b.found_light().then(|| {
                let p_light = self.selection.pmf(&state, sp, b.light)
                    * scene.light_pdf(b.light, sp.point(), sp.normal(), b.point, b.normal);
                b.f_cos * b.radiance * (power2(b.pdf, p_light) / b.pdf)
            })
        });
        let mut l = Vec3::ZERO;
        for (&(light, pmf), &u) in picks.0.iter().zip(&numbers.0) {
            ctx.counters.technique_samples[TECHNIQUE_LIGHT] += 1;
            let Some((s, p_light, f, p_bsdf)) =
                sample_pick_at(scene, sp, light, pmf, u, ctx.counters)
            else {
                continue;
            };
            let w = if self.with_bsdf && !s.is_delta {
                power2(p_light, p_bsdf)
            } else {
                1.0
            };
            l += f * (w / p_light);
        }
        if let Some(c) = from_bsdf {
            l += c;
        }
        l
    }
}

/// BSDF sampling alone: complete for area and sphere lights, blind to delta lights.
pub struct BsdfStrategy;

impl DirectLighting for BsdfStrategy {
    fn name(&self) -> String {
        "bsdf".into()
    }

    fn techniques(&self) -> Vec<&'static str> {
        vec!["bsdf"]
    }

    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        ctx.counters.technique_samples[0] += 1;
        match sample_bsdf(scene, sp, rng, ctx.counters) {
            Some(b) if b.found_light() => b.f_cos * b.radiance / b.pdf,
            _ => Vec3::ZERO,
        }
    }
}

fn no_parameters(_: &str, _: &crate::StrategyOptions) -> serde_json::Value {
    serde_json::json!({})
}

/// A strategy of one selection with or without BSDF sampling, recording no parameters.
fn plain<S: LightSelection + 'static>(
    name: &str,
    selection: S,
    with_bsdf: bool,
) -> Result<Box<dyn DirectLighting>, crate::StrategyError> {
    Ok(Box::new(LightStrategy {
        name: name.into(),
        selection,
        with_bsdf,
        parameters: serde_json::Value::Null,
    }))
}

/// `uniform`.
pub const UNIFORM: Strategy = Strategy::new(
    "uniform",
    "one light chosen uniformly, sampled by its shape",
    no_parameters,
    |name, scene, _| plain(name, UniformSelection::new(scene), false),
);

/// `power`.
pub const POWER: Strategy = Strategy::new(
    "power",
    "one light chosen by power (alias table), sampled by its shape",
    no_parameters,
    |name, scene, _| plain(name, PowerSelection::new(scene), false),
);

/// `bsdf`.
pub const BSDF: Strategy = Strategy::new(
    "bsdf",
    "BSDF sampling only (misses delta lights)",
    no_parameters,
    |_, _, _| Ok(Box::new(BsdfStrategy)),
);

/// `power+bsdf`.
pub const POWER_BSDF: Strategy = Strategy::new(
    "power+bsdf",
    "power light sampling and BSDF sampling, power-heuristic MIS",
    no_parameters,
    |name, scene, _| plain(name, PowerSelection::new(scene), true),
);
