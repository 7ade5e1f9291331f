//! `samplers`: light-sampling techniques and the direct-lighting strategies built from them.
//!
//! A strategy is a [`render_core::estimator::DirectLighting`]; [`create`] builds one by name.
//! Every technique can both sample a light point and evaluate the density of any light point,
//! so strategies combine them by multiple importance sampling.
//!
//! **Embedding BRDF-oriented sampling elsewhere.** The BO technique runs from raw inputs: a
//! [`light_tree::LightTree`] built from the host's light bounds, a
//! [`brdf_oriented::importance::BoRecord::from_parts`] (position, frame, GGX lobe from
//! `brdf-integrals`, lobe weights), [`brdf_oriented::technique::BoState::select_from`] with any
//! source of uniform numbers and `selection_pmf` for MIS; `examples/bo_from_raw.rs` does it,
//! and its samples pass the chi-square test in the tests. The crate still depends on
//! `render-core` for `Frame`, `Vec3` and, in the strategies, scenes, lights and `SampleStream`:
//! splitting the renderer-agnostic techniques into a crate of their own needs `Frame` moved
//! down (to `light-tree` or a small geometry crate), a point-on-light callback in place of
//! `BoState::sample_point`'s `Light`, and the three-technique MIS and allocation written
//! against a trait for "trace a BSDF direction, report the light hit".

// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]

pub mod alias;
pub mod brdf_oriented;
pub mod bsdf_sampling;
pub mod convergence;
pub mod learned;
pub mod light_strategy;
mod memo;
pub mod mis;
pub mod oracle;
pub mod point_sets;
pub mod resolve;
pub mod ris;
mod scratch;
pub mod selection;
pub mod sg;
pub mod tree_selection;

use light_strategy::{BsdfStrategy, LightStrategy};
use light_tree::{SplitCriterion, SplitParams};
use render_core::estimator::DirectLighting;
use render_core::scene::Scene;
use selection::{PowerSelection, UniformSelection};
use serde::{Deserialize, Serialize};
use tree_selection::{PowerUnits, TreeMode, TreeSelection};

/// Knobs of the strategies, each with its default; strategies ignore the ones they do not use.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default)]
pub struct StrategyOptions {
    /// Splitting threshold τ of adaptive tree splitting (Conty Estevez & Kulla); `None`: the
    /// mode's default, [`DEFAULT_TAU`] for our unit-free cut, [`AUTHORS_TAU`] under `reproduce`.
    pub tau: Option<f32>,
    /// Most clusters in an adaptive cut (the E&K cut and the BRDF-oriented cut).
    pub max_cut: usize,
    /// BRDF-oriented cut: split a node when its cap integral exceeds δ (authors: 0.5).
    pub delta: f32,
    /// Most BRDF-aware samples beyond the forced two (authors: 50).
    pub n_max: u32,
    /// Weight λ of a BRDF-sampling hit in P(BO) (authors: 10).
    pub lambda: f32,
    /// Cap-integral approximation behind BO.
    pub brdf_integral: brdf_oriented::BrdfIntegral,
    /// The node importance of BO's cluster choice and descent in the `mis3` strategies: the
    /// cap integrals' I_BO (default) or the SG importance (issue 24); the BO cut and UB keep
    /// the cap integrals either way.
    pub bo_importance: brdf_oriented::BoImportance,
    /// Every behaviour of the authors' code, for every tree strategy: their power units
    /// (`LeWithArea`), their E&K σ (scene units, `V[e]` = 0 from three lights on), no cap on
    /// either cut; for the method also the nearest SPTD lookup, Oat–Sander cap ∩ cap,
    /// glossy-only importance, their random-number use and the in-sample allocation.
    pub reproduce: bool,
    /// Sample points on sphere lights by the pivot-transformed lobe (mixed with cone sampling).
    pub pivot_sphere: bool,
    /// Heuristic 1: N = floor(N_max·UB); off: N = N_max/2.
    pub adaptive_total: bool,
    /// Heuristic 1 with UB times the glossy lobe's weight (Ks·F at θo), so that N follows the
    /// lobe's actual strength (off by default: see README, "weighted UB").
    pub weighted_ub: bool,
    /// Heuristic 1's N_max chosen after each pass, from the render's samples so far, by
    /// variance × cost ([`brdf_oriented::allocation::EfficiencyTally`]); off (and always under
    /// `reproduce`): the constant `n_max`, as the paper.
    pub efficient_total: bool,
    /// In `mis3-adaptive` (fixed counts), the BRDF-aware samples of a shading point as one
    /// stratified set per technique (each sample still uniform on its own); off: independent.
    pub stratified: bool,
    /// In `mis3-*`, the LS technique at glossy points (where BO runs) keeps the E&K cut, as the
    /// paper does (and `reproduce`); off (our default): one descent from the root there, the
    /// cut stays at diffuse points.
    pub split_ls_at_glossy: bool,
    /// BO descends below its cut one binary level at a time, as the paper, instead of the
    /// tree's four-wide descent (`reproduce` and `--bo-importance sg` imply it).
    pub binary_bo_descent: bool,
    /// With `efficient_total`, N_max is learnt from a pilot before the first pass (a few
    /// samples on one pixel in 16, not in the image); off: `n_max` until two passes are done.
    pub pilot: bool,
    /// Heuristic 2: P(BO) from BRDF-sampling hits and misses; off: 1/2.
    pub adaptive_split: bool,
    /// The learned selection's parameters (`learned`, `learned+bsdf`, `mis3-adaptive-learned`).
    pub learned: learned::LearnedConfig,
}

/// Our default τ for the unit-free E&K cut, chosen by the equal-time sweep of
/// `experiments/tau.toml` (results/tau/table.md): near-best for E&K and for the method alike.
pub const DEFAULT_TAU: f32 = 0.35;
/// The authors' τ (bisml's `LightTreeSampler`), used under `reproduce`.
pub const AUTHORS_TAU: f32 = 0.85;

impl StrategyOptions {
    /// τ in effect: the one given, else the mode's default.
    pub fn tau(&self) -> f32 {
        self.tau.unwrap_or(if self.reproduce {
            AUTHORS_TAU
        } else {
            DEFAULT_TAU
        })
    }

    /// The E&K cut's parameters: the authors' σ in scene units and no cap under `reproduce`,
    /// our unit-free σ and `max_cut` otherwise.
    pub fn split_params(&self) -> SplitParams {
        if self.reproduce {
            SplitParams {
                tau: self.tau(),
                max_size: usize::MAX,
                criterion: SplitCriterion::Authors,
            }
        } else {
            SplitParams {
                tau: self.tau(),
                max_size: self.max_cut,
                criterion: SplitCriterion::UnitFree,
            }
        }
    }

    /// The light tree's power units: the authors' `LeWithArea` under `reproduce`.
    pub fn power_units(&self) -> PowerUnits {
        if self.reproduce {
            PowerUnits::Authors
        } else {
            PowerUnits::Watts
        }
    }
}

impl Default for StrategyOptions {
    fn default() -> Self {
        StrategyOptions {
            tau: None,
            max_cut: 64,
            delta: 0.5,
            n_max: 50,
            lambda: 10.0,
            brdf_integral: brdf_oriented::BrdfIntegral::Sptd,
            bo_importance: brdf_oriented::BoImportance::Cap,
            reproduce: false,
            pivot_sphere: false,
            adaptive_total: true,
            weighted_ub: false,
            efficient_total: true,
            stratified: true,
            split_ls_at_glossy: false,
            binary_bo_descent: false,
            pilot: true,
            adaptive_split: true,
            learned: learned::LearnedConfig::default(),
        }
    }
}

/// Why [`create`] cannot build a strategy.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum StrategyError {
    /// No strategy of that name.
    #[error("unknown strategy `{name}` (known: {known})")]
    Unknown {
        /// The name asked for.
        name: String,
        /// The registered names, comma-separated.
        known: String,
    },
    /// An option out of range for the strategy.
    #[error("bad strategy option: {0}")]
    BadOption(String),
}

/// A strategy's name and what it does.
pub struct StrategyInfo {
    /// The name [`create`] takes.
    pub name: &'static str,
    /// One line on what it does.
    pub description: &'static str,
}

/// Every registered strategy.
pub fn strategies() -> Vec<StrategyInfo> {
    let s = |name, description| StrategyInfo { name, description };
    vec![
        s(
            "uniform",
            "one light chosen uniformly, sampled by its shape",
        ),
        s(
            "power",
            "one light chosen by power (alias table), sampled by its shape",
        ),
        s("bsdf", "BSDF sampling only (misses delta lights)"),
        s(
            "power+bsdf",
            "power light sampling and BSDF sampling, power-heuristic MIS",
        ),
        s(
            "tree",
            "light tree, single descent (Conty Estevez & Kulla 2018)",
        ),
        s("tree-split", "light tree with adaptive splitting"),
        s(
            "tree+bsdf",
            "light tree single descent + BSDF sampling, MIS",
        ),
        s(
            "tree-split+bsdf",
            "adaptive tree splitting + BSDF sampling, MIS (the paper's E&K baseline)",
        ),
        s(
            "sg-tree",
            "light tree, single descent by spherical-Gaussian BRDF-aware importance (Tokuyoshi et al. 2024)",
        ),
        s("sg-tree+bsdf", "sg-tree + BSDF sampling, MIS"),
        s(
            "brdf-oriented",
            "BRDF-oriented light sampling alone (not complete: see docs)",
        ),
        s(
            "mis3-equal",
            "tree splitting + BRDF-oriented + BSDF sampling, equal counts",
        ),
        s(
            "mis3-adaptive",
            "Liu et al. 2019: three-technique MIS with adaptive allocation",
        ),
        s(
            "mis3-adaptive-learned",
            "mis3-adaptive with the learned cluster selection (issue 25) as its LS technique at every point",
        ),
        s(
            "learned",
            "learned cluster selection (issue 25): a fixed 32-cluster cut, each cluster weighed by the tree importance × its contribution (or visibility) learnt per region in earlier passes (+20 % the tree importance alone), then the tree's descent",
        ),
        s("learned+bsdf", "learned + BSDF sampling, MIS"),
        s(
            "learned-descent",
            "learned descent (issue 25): the tree's descent with a factor per node of its top levels (all of them up to 4,096 sibling pairs per region), its contribution over its importance learnt per region in earlier passes (+20 % the plain descent)",
        ),
        s(
            "learned-descent+bsdf",
            "learned-descent + BSDF sampling, MIS",
        ),
        s(
            "oracle",
            "every light's unshadowed contribution per point, one light chosen ∝ it (+5 % power), + BSDF sampling, MIS: a floor, O(lights) per point",
        ),
        s(
            "oracle-shadowed",
            "oracle with a shadow ray to each of its points per light: a visibility-exact floor (issue 25's bound), O(lights) rays per point",
        ),
        s(
            "ris",
            "resampled importance sampling: 8 light-tree + BO candidates, one kept, + BSDF sampling, MIS (ris-N: N candidates)",
        ),
        s("ris-4", "ris with 4 candidates"),
        s("ris-32", "ris with 32 candidates"),
        s(
            "ris-adaptive",
            "ris with 4 + round(28·UB) candidates (UB of the BO cut, the paper's heuristic 1)",
        ),
    ]
}

/// The options every strategy refuses: negative δ or λ, an empty cut, τ outside [0, 1].
pub(crate) fn check_options(opts: &StrategyOptions) -> Result<(), StrategyError> {
    if !(opts.delta >= 0.0) || !(opts.lambda >= 0.0) {
        return Err(StrategyError::BadOption(format!(
            "need δ ≥ 0 and λ ≥ 0, got δ = {}, λ = {}",
            opts.delta, opts.lambda
        )));
    }
    if opts.max_cut == 0 || !(opts.tau() >= 0.0 && opts.tau() <= 1.0) {
        return Err(StrategyError::BadOption(format!(
            "need max_cut ≥ 1 and τ in [0, 1], got max_cut = {}, τ = {}",
            opts.max_cut,
            opts.tau()
        )));
    }
    Ok(())
}

/// Builds the strategy called `name` for `scene` (its parameters: [`resolve::resolved_parameters`]).
pub fn create(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    check_options(opts)?;
    let units = opts.power_units();
    let tree = |mode: TreeMode,
                with_bsdf: bool|
     -> Result<Box<dyn DirectLighting>, StrategyError> {
        let parameters = match mode {
            TreeMode::Single => serde_json::json!({ "reproduce": opts.reproduce }),
            TreeMode::Split(p) => serde_json::json!({
                "tau": p.tau,
                "max_cut": opts.max_cut,
                "split_criterion": format!("{:?}", p.criterion).to_lowercase(),
                "reproduce": opts.reproduce,
            }),
        };
        let selection = TreeSelection::new(scene, mode, units).map_err(StrategyError::BadOption)?;
        Ok(Box::new(LightStrategy {
            name: name.into(),
            selection,
            with_bsdf,
            parameters,
        }))
    };
    let split = TreeMode::Split(opts.split_params());
    Ok(match name {
        "tree" => tree(TreeMode::Single, false)?,
        "tree+bsdf" => tree(TreeMode::Single, true)?,
        "tree-split" => tree(split, false)?,
        "tree-split+bsdf" => tree(split, true)?,
        "sg-tree" | "sg-tree+bsdf" => Box::new(LightStrategy {
            name: name.into(),
            selection: sg::SgTreeSelection::new(scene, units).map_err(StrategyError::BadOption)?,
            with_bsdf: name == "sg-tree+bsdf",
            parameters: serde_json::json!({
                "reproduce": opts.reproduce,
                "floor": sg::importance::FLOOR,
            }),
        }),
        "uniform" => Box::new(LightStrategy {
            name: name.into(),
            selection: UniformSelection::new(scene),
            with_bsdf: false,
            parameters: serde_json::Value::Null,
        }),
        "power" => Box::new(LightStrategy {
            name: name.into(),
            selection: PowerSelection::new(scene),
            with_bsdf: false,
            parameters: serde_json::Value::Null,
        }),
        "power+bsdf" => Box::new(LightStrategy {
            name: name.into(),
            selection: PowerSelection::new(scene),
            with_bsdf: true,
            parameters: serde_json::Value::Null,
        }),
        "bsdf" => Box::new(BsdfStrategy),
        "brdf-oriented" | "mis3-equal" | "mis3-adaptive" | "mis3-adaptive-learned" => {
            mis3(name, scene, opts)?
        }
        "learned" | "learned+bsdf" => Box::new(learned::strategy::LearnedStrategy {
            name: name.into(),
            selection: learned::selection::LearnedSelection::new(scene, units, opts.learned)
                .map_err(StrategyError::BadOption)?,
            with_bsdf: name == "learned+bsdf",
            light_samples: opts.learned.light_samples,
            pass_weights: learned::PassWeights::Equal,
        }),
        "learned-descent" | "learned-descent+bsdf" => {
            Box::new(learned::strategy::LearnedStrategy {
                name: name.into(),
                selection: learned::descent::DescentSelection::new(scene, units, opts.learned)
                    .map_err(StrategyError::BadOption)?,
                with_bsdf: name == "learned-descent+bsdf",
                light_samples: opts.learned.light_samples,
                pass_weights: opts.learned.pass_weights,
            })
        }
        "oracle" | "oracle-shadowed" => Box::new(LightStrategy {
            name: name.into(),
            selection: if name == "oracle" {
                oracle::OracleSelection::new(scene)
            } else {
                oracle::OracleSelection::shadowed(scene)
            },
            with_bsdf: true,
            parameters: resolve::resolved_parameters(name, opts)?,
        }),
        other if ris_count(other).is_some() => ris(name, ris_count(other).unwrap(), scene, opts)?,
        other => {
            return Err(StrategyError::Unknown {
                name: other.into(),
                known: strategies()
                    .iter()
                    .map(|s| s.name)
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
    })
}

/// The strategies of Liu, Xu & Yan 2019 (see [`brdf_oriented`]).
fn mis3(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    use brdf_oriented::BrdfIntegral;
    use brdf_oriented::mis3::{Mis3, Mis3Mode};
    let mode = match name {
        "brdf-oriented" => Mis3Mode::BoOnly,
        "mis3-equal" => Mis3Mode::Equal,
        _ => Mis3Mode::Adaptive,
    };
    let ls = TreeSelection::new(
        scene,
        TreeMode::Split(opts.split_params()),
        opts.power_units(),
    )
    .map_err(StrategyError::BadOption)?;
    let config = resolve::bo_config(opts);
    let learned = if name == "mis3-adaptive-learned" {
        Some(
            learned::selection::LearnedSelection::new(scene, opts.power_units(), opts.learned)
                .map_err(StrategyError::BadOption)?,
        )
    } else {
        None
    };
    let sg_nodes = match (opts.bo_importance, &ls.tree) {
        (brdf_oriented::BoImportance::Sg, Some(tree)) => Some(
            light_tree::SgNodes::build(tree, &sg::sg_emitters(scene))
                .map_err(|e| StrategyError::BadOption(format!("SG lights: {e}")))?,
        ),
        _ => None,
    };
    Ok(match opts.brdf_integral {
        BrdfIntegral::Sptd => Box::new(Mis3 {
            sg_nodes,
            learned,
            ..Mis3::new(name.into(), mode, ls, resolve::sptd(opts), config)
        }),
        BrdfIntegral::Ltc => {
            use brdf_integrals::CapIntegral;
            let integral = resolve::ltc(opts);
            // Sanity check of the table (a placeholder build would integrate to 0).
            let probe = integral.hemisphere(render_core::Vec3::new(0.6, 0.0, 0.8), 0.1);
            if !(probe > 0.0) {
                return Err(StrategyError::BadOption(
                    "--brdf-integral ltc: the LTC table integrates to 0".into(),
                ));
            }
            Box::new(Mis3 {
                sg_nodes,
                learned,
                ..Mis3::new(name.into(), mode, ls, integral, config)
            })
        }
    })
}

/// Candidate count of a `ris` strategy name: `ris` (8), `ris-N` (1 ≤ N ≤ 1024), `ris-adaptive`.
pub(crate) fn ris_count(name: &str) -> Option<ris::CandidateCount> {
    use ris::CandidateCount;
    match name {
        "ris" => Some(CandidateCount::Fixed(8)),
        "ris-adaptive" => Some(CandidateCount::Adaptive { min: 4, max: 32 }),
        _ => {
            let m: u32 = name.strip_prefix("ris-")?.parse().ok()?;
            (1..=1024).contains(&m).then_some(CandidateCount::Fixed(m))
        }
    }
}

/// The RIS strategies (see [`ris`]); the BO candidates use the BO cut of `mis3` with its options.
fn ris(
    name: &str,
    count: ris::CandidateCount,
    scene: &Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    use brdf_oriented::BrdfIntegral;
    let tree = TreeSelection::new(scene, TreeMode::Single, opts.power_units())
        .map_err(StrategyError::BadOption)?
        .tree;
    Ok(match opts.brdf_integral {
        BrdfIntegral::Sptd => Box::new(ris::strategy::Ris {
            name: name.into(),
            tree,
            integral: brdf_integrals::Sptd::default(),
            count,
            delta: opts.delta,
            max_cut: opts.max_cut,
        }),
        BrdfIntegral::Ltc => Box::new(ris::strategy::Ris {
            name: name.into(),
            tree,
            integral: brdf_integrals::Ltc::default(),
            count,
            delta: opts.delta,
            max_cut: opts.max_cut,
        }),
    })
}
