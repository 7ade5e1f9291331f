//! The knobs every strategy reads its parameters from ([`StrategyOptions`]), their defaults and
//! the checks every strategy applies to them. Each knob's flag and help are in [`crate::knobs`].
use crate::{brdf_oriented, learned};
use light_tree::{SplitCriterion, SplitParams};
use serde::{Deserialize, Serialize};

/// The unit of the power the tree aggregates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PowerUnits {
    /// Watts, one unit for every kind of light ([`render_core::light::Light::power`]).
    #[default]
    Watts,
    /// The authors' `LeWithArea` (`--reproduce`): luminance × area for area lights (no π,
    /// one side), the intensity's luminance for point and spot lights.
    Authors,
}

/// Stochastic lightcuts' cut size K in its paper's tables.
pub const DEFAULT_CUT_SIZE: usize = 32;

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
    /// Sample points on triangle lights by the glossy lobe's LTC (BO at glossy points; mixed
    /// with the render's point sampler).
    pub ltc_triangles: bool,
    /// Heuristic 1: N = floor(N_max·UB); off: N = N_max/2.
    pub adaptive_total: bool,
    /// Heuristic 1 with UB times the glossy lobe's weight (Ks·F at θo), so that N follows the
    /// lobe's actual strength (off by default: see docs/notes/ablations.md, "weighted UB").
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
    /// Stochastic lightcuts: most nodes in a cut (K), one shadow ray each (the paper's 32).
    pub slc_cut_size: usize,
    /// Stochastic lightcuts: how a cut node's light is drawn down its subtree.
    pub slc_descent: crate::rivals::slc_minmax::SlcDescent,
    /// The resampled hierarchical tree: its split threshold, resampled picks and traversal
    /// probability ([`crate::rivals::rht`]).
    pub rht: crate::rivals::rht_options::RhtOptions,
    /// Learning to cluster: the regions' cuts and the defensive share ([`crate::rivals::varl`]).
    pub varl: crate::rivals::varl_options::VarlOptions,
    /// The learned selection's parameters (`learned`, `learned+bsdf`, `mis3-adaptive-learned`).
    pub learned: learned::LearnedConfig,
    /// The reuse strategies' parameters (`restir`, `restir-biased`).
    pub reuse: crate::reuse::ReuseConfig,
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
            ltc_triangles: false,
            adaptive_total: true,
            weighted_ub: false,
            efficient_total: true,
            stratified: true,
            split_ls_at_glossy: false,
            binary_bo_descent: false,
            pilot: true,
            adaptive_split: true,
            slc_cut_size: DEFAULT_CUT_SIZE,
            slc_descent: Default::default(),
            rht: Default::default(),
            varl: Default::default(),
            learned: learned::LearnedConfig::default(),
            reuse: Default::default(),
        }
    }
}

/// Why [`create`] cannot build a strategy.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum StrategyError {
    /// No strategy of that name.
    #[error("unknown strategy `{name}`{suggestion} (known: {known})")]
    Unknown {
        /// The name asked for.
        name: String,
        /// `; did you mean …?` with the closest known name, or empty.
        suggestion: String,
        /// The registered names, comma-separated.
        known: String,
    },
    /// An option out of range for the strategy.
    #[error("bad strategy option: {0}")]
    BadOption(String),
    /// The scene's lights cannot make what the strategy is built on (its light tree).
    #[error("cannot build the strategy for this scene: {0}")]
    Scene(String),
}

/// The options every strategy refuses: negative δ or λ, an empty cut, τ outside [0, 1].
pub fn check_options(opts: &StrategyOptions) -> Result<(), StrategyError> {
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
