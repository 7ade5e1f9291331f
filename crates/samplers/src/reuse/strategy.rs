//! `restir` and `restir-biased`: ReSTIR DI (Bitterli et al. 2020) on a still image. Per pixel
//! M light candidates and one BSDF candidate resampled to one reservoir, its sample
//! shadow-tested, then rounds of spatial reuse between pixels, then one estimate per pixel.
//!
//! Parameters (`--restir-*`, [`ReuseConfig`]): candidates M (32), their source (`power`, or
//! `tree`: one light-tree descent), neighbours per round (5), their radius in pixels (30),
//! rounds (2), reuse of the previous pass's reservoirs (`--restir-history CAP`, off; see
//! `history`). Where it differs from the paper: no temporal reuse by default (each pass is an
//! independent estimate of a still image, so passes average without correlation); samples are
//! points in the lights' area measure, so reuse needs no Jacobian; the unbiased combination
//! uses the pairwise MIS weights of GRIS (Lin et al. 2022) with the shadow rays they need
//! instead of the paper's 1/Z count, which `restir-biased`'s 1/M form drops.
//!
//! `restir-bo` draws its candidates (`--restir-bo-candidates`, 4) with the paper's techniques
//! instead (`sources::FromBo`):
//! at glossy points half BRDF-oriented samples from the BO cut and half light-tree samples
//! (a fixed split, where the paper's allocation adapts it), tree samples elsewhere, their
//! mixture density in every candidate's weight, so a neighbour reuses a glossy pixel's BO sample.
//!
//! `estimate` alone (a single shading point, no neighbours) is the initial reservoir's
//! estimate: unbiased RIS with M + 1 candidates, used by tools that shade single points.
use super::config::{CandidateSourceKind, ReuseConfig};
use super::history::{HISTORY_PHASE, History};
use super::light_point::{occluded, target};
use super::reservoir::Reservoir;
use super::sources::{FromBo, FromSelection, InitialSource};
use super::spatial::{biased_round, neighbours, pairwise_round, shade};
use crate::baselines::selection::PowerSelection;
use crate::brdf_oriented::BrdfIntegral;
use crate::ris::CandidateCount;
use crate::ris::strategy::Ris;
use crate::strategy::Strategy;
use crate::tree_selection::{TreeMode, TreeSelection};
use crate::{StrategyError, StrategyOptions};
use render_core::Vec3;
use render_core::estimator::{DirectLighting, MAX_AUX, SampleContext, ShadingPoint};
use render_core::image_space::{ImagePass, ImageSpaceLighting, PassCarry};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::stats::Counters;

/// Index of the neighbours reused in the technique counters (after the two candidate kinds).
pub const TECHNIQUE_NEIGHBOURS: usize = 2;

/// ReSTIR DI.
pub struct ReStir {
    /// The registered name.
    pub name: String,
    /// Where the first reservoirs come from.
    pub source: Box<dyn InitialSource>,
    /// Candidates, neighbours, radius, rounds.
    pub config: ReuseConfig,
    /// The paper's 1/M combination instead of the unbiased pairwise one.
    pub biased: bool,
}

impl ReStir {
    /// The pixel's initial reservoir, its sample shadow-tested (W = 0 when hidden).
    fn visible_initial(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        c: &mut Counters,
    ) -> Reservoir {
        let mut r = self
            .source
            .initial(scene, sp, self.config.candidates, rng, c);
        if r.w > 0.0 {
            match target(scene, sp, &r.y) {
                Some((_, _, seen)) if !occluded(scene, sp, &r.y, &seen, c) => {}
                _ => r.w = 0.0,
            }
        }
        r
    }
}

impl DirectLighting for ReStir {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::json!({ "reuse": self.config, "biased": self.biased })
    }

    fn techniques(&self) -> Vec<&'static str> {
        vec![
            "light candidates",
            "bsdf candidates",
            "neighbours",
            "neighbour samples seen",
        ]
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

impl ImageSpaceLighting for ReStir {
    fn estimate_image(
        &self,
        pass: &ImagePass,
        carry: &mut PassCarry,
    ) -> Vec<(Vec3, [f32; MAX_AUX])> {
        let mut cur: Vec<Reservoir> = pass.run(0, |i, rng, c| match &pass.points[i] {
            Some(sp) => self.visible_initial(pass.scene, sp, rng, c),
            None => Reservoir::default(),
        });
        let cfg = &self.config;
        if let Some(h) = History::of(pass, carry).filter(|_| cfg.history > 0.0) {
            let first = cur;
            cur = pass.run(HISTORY_PHASE, |i, rng, c| {
                h.reuse(pass, (&first, i), (cfg.history, !self.biased), rng, c)
            });
        }
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
        let out = pass.run(cfg.rounds + 1, |i, _, c| {
            let l = match &pass.points[i] {
                Some(sp) => shade(pass, sp, &cur[i], !self.biased, c),
                None => Vec3::ZERO,
            };
            (l, [0.0; MAX_AUX])
        });
        if cfg.history > 0.0 {
            History::keep(pass, cur, carry);
        }
        out
    }

    fn bytes_per_pixel(&self) -> usize {
        let history = if self.config.history > 0.0 {
            size_of::<Reservoir>() + size_of::<Option<ShadingPoint>>()
        } else {
            0
        };
        2 * size_of::<Reservoir>() + history
    }

    fn correlates_passes(&self) -> bool {
        self.config.history > 0.0
    }
}

/// The reuse parameters strategy `name` runs with.
fn config(name: &str, opts: &StrategyOptions) -> ReuseConfig {
    if name == RESTIR_BO.name {
        opts.reuse.for_bo()
    } else {
        opts.reuse.clone()
    }
}

fn resolve(name: &str, opts: &StrategyOptions) -> serde_json::Value {
    let mut v = serde_json::json!({
        "reuse": config(name, opts),
        "biased": name == RESTIR_BIASED.name,
        "power_units": crate::resolve::units(opts),
    });
    // Each strategy reads one of the two counts, as `candidates`.
    if let Some(reuse) = v["reuse"].as_object_mut() {
        reuse.remove("bo_candidates");
    }
    if name == RESTIR_BO.name {
        v["reuse"]["source"] = "tree+bo".into();
        v["delta"] = opts.delta.into();
        v["max_cut"] = opts.max_cut.into();
        v["integral"] = crate::resolve::integral(&StrategyOptions {
            reproduce: false,
            ..opts.clone()
        });
    }
    v
}

/// The first reservoirs' source of strategy `name` under `opts`.
fn source(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn InitialSource>, StrategyError> {
    let tree = || {
        TreeSelection::new(scene, TreeMode::Single, opts.power_units())
            .map_err(StrategyError::Scene)
    };
    if name == RESTIR_BO.name {
        fn ris<C: brdf_integrals::CapIntegral>(
            opts: &StrategyOptions,
            tree: Option<crate::shared_tree::SharedTree>,
            integral: C,
        ) -> Ris<C> {
            Ris {
                name: RESTIR_BO.name.into(),
                tree,
                integral,
                count: CandidateCount::Fixed(opts.reuse.bo_candidates),
                delta: opts.delta,
                max_cut: opts.max_cut,
            }
        }
        let t = tree()?.tree;
        return Ok(match opts.brdf_integral {
            BrdfIntegral::Sptd => Box::new(FromBo(ris(opts, t, brdf_integrals::Sptd::default()))),
            BrdfIntegral::Ltc => Box::new(FromBo(ris(opts, t, brdf_integrals::Ltc::default()))),
        });
    }
    Ok(match opts.reuse.source {
        CandidateSourceKind::Power => Box::new(FromSelection(PowerSelection::new(scene))),
        CandidateSourceKind::Tree => Box::new(FromSelection(tree()?)),
    })
}

fn build(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    opts.reuse.check().map_err(StrategyError::BadOption)?;
    Ok(Box::new(ReStir {
        name: name.into(),
        source: source(name, scene, opts)?,
        config: config(name, opts),
        biased: name == RESTIR_BIASED.name,
    }))
}

const KNOBS: &[&str] = &[
    "restir-candidates",
    "restir-source",
    "restir-neighbours",
    "restir-radius",
    "restir-rounds",
    "restir-history",
];

const BO_KNOBS: &[&str] = &[
    "restir-bo-candidates",
    "restir-neighbours",
    "restir-radius",
    "restir-rounds",
    "restir-history",
    "delta",
    "max-cut",
    "brdf-integral",
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

/// `restir-bo`: the paper's BRDF-oriented candidates inside unbiased ReSTIR.
pub const RESTIR_BO: Strategy = Strategy {
    knobs: BO_KNOBS,
    // Ours, like the method it carries: the emission seen directly gathered as `mis3` does.
    emission_rays: crate::brdf_oriented::strategies::METHOD_EMISSION_RAYS,
    golden_variants: &["ltc"],
    ..Strategy::new(
        "restir-bo",
        "restir whose 4 candidates are Liu et al.'s: BRDF-oriented (BO cut) + light-tree samples at glossy points, tree samples elsewhere, + 1 BSDF; shared between pixels",
        resolve,
        build,
    )
};
