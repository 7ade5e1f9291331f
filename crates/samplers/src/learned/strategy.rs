//! Strategies `learned`, `learned+bsdf`, `learned-descent` and `learned-descent+bsdf`: N lights
//! by a learned selection (one by default; ± one BSDF sample, power heuristic with counts), the
//! first light sample leaving its observation in the pixel's memory for the merge between
//! passes.
use super::Learner;
use super::selection::{LearnedSelection, sample_observed};
use crate::bsdf_sampling::sample_bsdf_at;
use crate::light_strategy::{PickNumbers, Picks, TECHNIQUE_BSDF, TECHNIQUE_LIGHT};
use crate::mis::power_heuristic;
use crate::scratch::Pooled;
use crate::strategy::Strategy;
use render_core::Vec3;
use render_core::estimator::{DirectLighting, PIXEL_MEMORY, SampleContext, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;

/// A light sample without a pick (every light unreachable from the point).
const NO_PICK: u32 = u32::MAX;

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
    /// How the passes are weighed in each pixel's average.
    pub pass_weights: super::PassWeights,
}

impl<S: Learner> DirectLighting for LearnedStrategy<S> {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn parameters(&self) -> serde_json::Value {
        let mut p = self.selection.describe();
        p["pass_weights"] = serde_json::json!(self.pass_weights.name());
        p
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

    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        let sel = &self.selection;
        let state = sel.prepare(scene, sp);
        sel.clear_observation(&mut ctx.pixel_memory[..]);
        crate::work_counters::record(
            ctx.counters,
            !sp.bsdf.is_pure_diffuse(),
            0,
            0,
            self.with_bsdf as usize,
        );
        // Every number first, in the order the samples use them (a light pick and its point
        // per light sample, then the BSDF sample's), so that the picked lights' records can be
        // fetched while the BSDF ray is traced.
        let n = self.light_samples.max(1);
        let mut picks = Pooled::<Picks>::take();
        let mut numbers = Pooled::<PickNumbers>::take();
        for _ in 0..n {
            let drawn = picks.0.len();
            sel.pick(&state, sp, rng, &mut picks.0);
            if picks.0.len() == drawn {
                picks.0.push((NO_PICK, 0.0));
            }
            // The point on the light is drawn even without a pick, so later draws keep their
            // dimensions.
            numbers.0.push(rng.next_2d());
        }
        ctx.counters.technique_samples[TECHNIQUE_LIGHT] += n as u64;
        let bsdf_numbers = self.with_bsdf.then(|| (rng.next_f32(), rng.next_2d()));
        for &(light, _) in &picks.0 {
            if light != NO_PICK {
                scene.prefetch_light(light);
            }
        }
        let from_bsdf = bsdf_numbers.and_then(|(u_lobe, u)| {
            ctx.counters.technique_samples[TECHNIQUE_BSDF] += 1;
            let b = sample_bsdf_at(scene, sp, u_lobe, u, ctx.counters)?;
            b.found_light().then(|| {
                let p_light = sel.pmf(&state, sp, b.light)
                    * scene.light_pdf(b.light, sp.point(), sp.normal(), b.point, b.normal);
                let w = power_heuristic(1, &[(n as f32, p_light), (1.0, b.pdf)]);
                b.f_cos * b.radiance * (w / b.pdf)
            })
        });
        let mut l = Vec3::ZERO;
        // Where the second and later samples' observations go (one is learnt per pass).
        let mut unlearnt = [0.0f32; PIXEL_MEMORY];
        for (i, (&(light, pmf), &u)) in picks.0.iter().zip(&numbers.0).enumerate() {
            if light == NO_PICK {
                continue;
            }
            let memory = if i == 0 {
                &mut ctx.pixel_memory[..]
            } else {
                &mut unlearnt[..]
            };
            if let Some((s, p, f, p_bsdf)) =
                sample_observed(scene, sp, light, pmf, u, ctx.counters, memory, sel, &state)
            {
                let w = if self.with_bsdf && !s.is_delta {
                    power_heuristic(0, &[(n as f32, p), (1.0, p_bsdf)])
                } else {
                    1.0
                };
                l += f * (w / (n as f32 * p));
            }
        }
        if let Some(b) = from_bsdf {
            l += b;
        }
        l
    }

    fn begin_render(&self) {
        self.selection.forget();
    }

    fn pass_weight(&self, pass: u32) -> f64 {
        self.pass_weights.weight(pass)
    }

    fn end_pass(&self, pixel_memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
        self.selection.merge(pixel_memory);
    }
}

/// The learned options as the cluster strategies use them: their passes always weigh alike.
pub(crate) fn cluster_learned(opts: &crate::StrategyOptions) -> super::LearnedConfig {
    super::LearnedConfig {
        pass_weights: super::PassWeights::Equal,
        ..opts.learned
    }
}

fn resolve_cluster(_: &str, opts: &crate::StrategyOptions) -> serde_json::Value {
    serde_json::json!({
        "power_units": crate::resolve::units(opts),
        "cut": "breadth-first",
        "learned": cluster_learned(opts),
    })
}

fn resolve_descent(_: &str, opts: &crate::StrategyOptions) -> serde_json::Value {
    serde_json::json!({
        "power_units": crate::resolve::units(opts),
        "max_levels": super::descent_table::LEVELS,
        "max_pairs_per_region": super::descent_table::MAX_PAIRS,
        "learned": opts.learned,
    })
}

fn build_cluster(
    name: &str,
    scene: &Scene,
    opts: &crate::StrategyOptions,
) -> Result<Box<dyn DirectLighting>, crate::StrategyError> {
    Ok(Box::new(LearnedStrategy {
        name: name.into(),
        selection: LearnedSelection::new(scene, opts.power_units(), opts.learned)
            .map_err(crate::StrategyError::BadOption)?,
        with_bsdf: name == LEARNED_BSDF.name,
        light_samples: opts.learned.light_samples,
        pass_weights: super::PassWeights::Equal,
    }))
}

fn build_descent(
    name: &str,
    scene: &Scene,
    opts: &crate::StrategyOptions,
) -> Result<Box<dyn DirectLighting>, crate::StrategyError> {
    Ok(Box::new(LearnedStrategy {
        name: name.into(),
        selection: super::descent::DescentSelection::new(scene, opts.power_units(), opts.learned)
            .map_err(crate::StrategyError::BadOption)?,
        with_bsdf: name == LEARNED_DESCENT_BSDF.name,
        light_samples: opts.learned.light_samples,
        pass_weights: opts.learned.pass_weights,
    }))
}

/// The knobs of the learned cluster strategies.
const CLUSTER_STRATEGY_KNOBS: &[&str] = &[
    "learned-target",
    "learned-clusters",
    "learned-cells",
    "learned-defensive",
    "learned-prior",
    "learned-samples",
];
const DESCENT_KNOBS: &[&str] = &[
    "learned-cells",
    "learned-defensive",
    "learned-prior",
    "learned-samples",
    "learned-pass-weights",
];

/// `learned`.
pub const LEARNED: Strategy = Strategy {
    knobs: CLUSTER_STRATEGY_KNOBS,
    golden_variants: &["learned-visibility"],
    ..Strategy::new(
        "learned",
        "learned cluster selection (issue 25): a fixed 32-cluster cut, each cluster weighed by the tree importance × its contribution (or visibility) learnt per region in earlier passes (+20 % the tree importance alone), then the tree's descent",
        resolve_cluster,
        build_cluster,
    )
};

/// `learned+bsdf`.
pub const LEARNED_BSDF: Strategy = Strategy {
    knobs: CLUSTER_STRATEGY_KNOBS,
    golden_variants: &["learned-visibility"],
    ..Strategy::new(
        "learned+bsdf",
        "learned + BSDF sampling, MIS",
        resolve_cluster,
        build_cluster,
    )
};

/// `learned-descent`.
pub const LEARNED_DESCENT: Strategy = Strategy {
    knobs: DESCENT_KNOBS,
    ..Strategy::new(
        "learned-descent",
        "learned descent (issue 25): the tree's descent with a factor per node of its top levels (all of them up to 4,096 sibling pairs per region), its contribution over its importance learnt per region in earlier passes (+20 % the plain descent)",
        resolve_descent,
        build_descent,
    )
};

/// `learned-descent+bsdf`.
pub const LEARNED_DESCENT_BSDF: Strategy = Strategy {
    knobs: DESCENT_KNOBS,
    ..Strategy::new(
        "learned-descent+bsdf",
        "learned-descent + BSDF sampling, MIS",
        resolve_descent,
        build_descent,
    )
};
