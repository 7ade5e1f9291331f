//! `restir` and `restir-biased`: ReSTIR DI (Bitterli et al. 2020) on a still image. Per pixel
//! M light candidates and one BSDF candidate resampled to one reservoir, its sample
//! shadow-tested, then rounds of spatial reuse between pixels, then one estimate per pixel.
//!
//! Parameters (`--restir-*`, [`ReuseConfig`]): candidates M (32), their source (`power`, or
//! `tree`: one light-tree descent), neighbours per round (5), their radius in pixels (30),
//! rounds (2). Where it differs from the paper: no temporal reuse (each pass is an
//! independent estimate of a still image, so passes average without correlation); samples are
//! points in the lights' area measure, so reuse needs no Jacobian; the unbiased combination
//! uses the pairwise MIS weights of GRIS (Lin et al. 2022) with the shadow rays they need
//! instead of the paper's 1/Z count, which `restir-biased`'s 1/M form drops.
//!
//! `estimate` alone (a single shading point, no neighbours) is the initial reservoir's
//! estimate: unbiased RIS with M + 1 candidates, used by tools that shade single points.
use super::config::{CandidateSourceKind, ReuseConfig};
use super::initial::{Candidates, SelectionCandidates, initial_reservoir};
use super::light_point::{occluded, target};
use super::reservoir::Reservoir;
use super::spatial::{biased_round, neighbours, pairwise_round, shade};
use crate::baselines::selection::{LightSelection, PowerSelection};
use crate::strategy::Strategy;
use crate::tree_selection::{TreeMode, TreeSelection};
use crate::{StrategyError, StrategyOptions};
use render_core::Vec3;
use render_core::estimator::{DirectLighting, MAX_AUX, SampleContext, ShadingPoint};
use render_core::image_space::{ImagePass, ImageSpaceLighting};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::stats::Counters;
use std::cell::RefCell;

/// Index of the neighbours reused in the technique counters (after the two candidate kinds).
pub const TECHNIQUE_NEIGHBOURS: usize = 2;

/// ReSTIR DI over a light selection `S`.
pub struct ReStir<S: LightSelection> {
    /// The registered name.
    pub name: String,
    /// Where the light candidates come from.
    pub selection: S,
    /// Candidates, neighbours, radius, rounds.
    pub config: ReuseConfig,
    /// The paper's 1/M combination instead of the unbiased pairwise one.
    pub biased: bool,
}

impl<S: LightSelection> ReStir<S> {
    /// The pixel's initial reservoir, its sample shadow-tested (W = 0 when hidden).
    fn visible_initial(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        c: &mut Counters,
    ) -> Reservoir {
        let source = SelectionCandidates {
            scene,
            sp,
            selection: &self.selection,
            state: self.selection.prepare(scene, sp),
            m: self.config.candidates,
            picks: RefCell::new(Vec::with_capacity(1)),
        };
        debug_assert_eq!(source.count(), self.config.candidates);
        let mut r = initial_reservoir(scene, sp, &source, true, rng, c);
        if r.w > 0.0 {
            match target(scene, sp, &r.y) {
                Some((_, _, seen)) if !occluded(scene, sp, &r.y, &seen, c) => {}
                _ => r.w = 0.0,
            }
        }
        r
    }
}

impl<S: LightSelection> DirectLighting for ReStir<S> {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::json!({ "reuse": self.config, "biased": self.biased })
    }

    fn techniques(&self) -> Vec<&'static str> {
        vec!["light candidates", "bsdf candidates", "neighbours"]
    }

    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        let r = self.visible_initial(scene, sp, rng, ctx.counters);
        match target(scene, sp, &r.y) {
            Some((_, f, _)) if r.w > 0.0 => f * r.w,
            _ => Vec3::ZERO,
        }
    }

    fn image_space(&self) -> Option<&dyn ImageSpaceLighting> {
        Some(self)
    }
}

impl<S: LightSelection> ImageSpaceLighting for ReStir<S> {
    fn estimate_image(&self, pass: &ImagePass) -> Vec<(Vec3, [f32; MAX_AUX])> {
        let mut cur: Vec<Reservoir> = pass.run(0, |i, rng, c| match &pass.points[i] {
            Some(sp) => self.visible_initial(pass.scene, sp, rng, c),
            None => Reservoir::default(),
        });
        let cfg = &self.config;
        for round in 0..cfg.rounds {
            let prev = cur;
            cur = pass.run(1 + round, |i, rng, c| {
                let mut nbrs = Vec::with_capacity(cfg.neighbours as usize);
                neighbours(pass, i, (cfg.neighbours, cfg.radius), rng, &mut nbrs);
                c.technique_samples[TECHNIQUE_NEIGHBOURS] += nbrs.len() as u64;
                if self.biased {
                    biased_round(pass, &prev, i, &nbrs, rng)
                } else {
                    pairwise_round(pass, &prev, i, &nbrs, rng, c)
                }
            });
        }
        pass.run(cfg.rounds + 1, |i, _, c| {
            let l = match &pass.points[i] {
                Some(sp) => shade(pass, sp, &cur[i], !self.biased, c),
                None => Vec3::ZERO,
            };
            (l, [0.0; MAX_AUX])
        })
    }

    fn bytes_per_pixel(&self) -> usize {
        2 * size_of::<Reservoir>()
    }
}

fn resolve(name: &str, opts: &StrategyOptions) -> serde_json::Value {
    serde_json::json!({
        "reuse": opts.reuse,
        "biased": name == RESTIR_BIASED.name,
        "power_units": crate::resolve::units(opts),
    })
}

fn build(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    opts.reuse.check().map_err(StrategyError::BadOption)?;
    let (config, biased) = (opts.reuse.clone(), name == RESTIR_BIASED.name);
    Ok(match opts.reuse.source {
        CandidateSourceKind::Power => Box::new(ReStir {
            name: name.into(),
            selection: PowerSelection::new(scene),
            config,
            biased,
        }),
        CandidateSourceKind::Tree => Box::new(ReStir {
            name: name.into(),
            selection: TreeSelection::new(scene, TreeMode::Single, opts.power_units())
                .map_err(StrategyError::BadOption)?,
            config,
            biased,
        }),
    })
}

const KNOBS: &[&str] = &[
    "restir-candidates",
    "restir-source",
    "restir-neighbours",
    "restir-radius",
    "restir-rounds",
];

/// `restir`: unbiased spatial reuse.
pub const RESTIR: Strategy = Strategy {
    knobs: KNOBS,
    ..Strategy::new(
        "restir",
        "ReSTIR DI (Bitterli et al. 2020): 32 power + 1 BSDF candidates per pixel, 2 rounds of spatial reuse from 5 neighbours, unbiased (GRIS pairwise MIS, Lin et al. 2022)",
        resolve,
        build,
    )
};

/// `restir-biased`: the paper's biased 1/M combination.
pub const RESTIR_BIASED: Strategy = Strategy {
    knobs: KNOBS,
    ..Strategy::new(
        "restir-biased",
        "restir with the paper's biased 1/M combination (darkens where neighbours differ; not unbiased)",
        resolve,
        build,
    )
};
