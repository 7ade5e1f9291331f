//! `samplers`: light-sampling techniques and the direct-lighting strategies built from them.
//!
//! A strategy is a [`render_core::estimator::DirectLighting`]; [`create`] builds one by name.
//! Every technique can both sample a light point and evaluate the density of any light point,
//! so strategies combine them by multiple importance sampling.

// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod alias;
pub mod bsdf_sampling;
pub mod convergence;
pub mod light_strategy;
pub mod mis;
pub mod selection;
pub mod tree_selection;

use light_strategy::{BsdfStrategy, LightStrategy};
use render_core::estimator::DirectLighting;
use render_core::scene::Scene;
use selection::{PowerSelection, UniformSelection};
use serde::{Deserialize, Serialize};
use tree_selection::{TreeMode, TreeSelection};

/// Knobs of the strategies, each with its default; strategies ignore the ones they do not use.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StrategyOptions {
    /// Splitting threshold τ of adaptive tree splitting (Conty Estevez & Kulla; the authors' code uses 0.85).
    pub tau: f32,
    /// Most clusters in an adaptive cut.
    pub max_cut: usize,
}

impl Default for StrategyOptions {
    fn default() -> Self {
        StrategyOptions {
            tau: 0.85,
            max_cut: 64,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum StrategyError {
    #[error("unknown strategy `{name}` (known: {known})")]
    Unknown { name: String, known: String },
    #[error("strategy `{0}` is not implemented yet")]
    NotImplemented(String),
    #[error("bad strategy option: {0}")]
    BadOption(String),
}

/// A strategy's name and what it does.
pub struct StrategyInfo {
    pub name: &'static str,
    pub description: &'static str,
    pub implemented: bool,
}

pub fn strategies() -> Vec<StrategyInfo> {
    let s = |name, description, implemented| StrategyInfo {
        name,
        description,
        implemented,
    };
    vec![
        s(
            "uniform",
            "one light chosen uniformly, sampled by its shape",
            true,
        ),
        s(
            "power",
            "one light chosen by power (alias table), sampled by its shape",
            true,
        ),
        s("bsdf", "BSDF sampling only (misses delta lights)", true),
        s(
            "power+bsdf",
            "power light sampling and BSDF sampling, power-heuristic MIS",
            true,
        ),
        s(
            "tree",
            "light tree, single descent (Conty Estevez & Kulla 2018)",
            true,
        ),
        s("tree-split", "light tree with adaptive splitting", true),
        s(
            "tree+bsdf",
            "light tree single descent + BSDF sampling, MIS",
            true,
        ),
        s(
            "tree-split+bsdf",
            "adaptive tree splitting + BSDF sampling, MIS (the paper's E&K baseline)",
            true,
        ),
        s(
            "brdf-oriented",
            "BRDF-oriented light sampling alone (not complete: see docs)",
            false,
        ),
        s(
            "mis3-equal",
            "tree splitting + BRDF-oriented + BSDF sampling, equal counts",
            false,
        ),
        s(
            "mis3-adaptive",
            "Liu et al. 2019: three-technique MIS with adaptive allocation",
            false,
        ),
    ]
}

/// Builds the strategy called `name` for `scene`.
pub fn create(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    if opts.max_cut == 0 || !(opts.tau >= 0.0 && opts.tau <= 1.0) {
        return Err(StrategyError::BadOption(format!(
            "need max_cut ≥ 1 and τ in [0, 1], got max_cut = {}, τ = {}",
            opts.max_cut, opts.tau
        )));
    }
    let tree =
        |mode: TreeMode, with_bsdf: bool| -> Result<Box<dyn DirectLighting>, StrategyError> {
            let parameters = match mode {
                TreeMode::Single => serde_json::Value::Null,
                TreeMode::Split { tau, max_cut } => {
                    serde_json::json!({ "tau": tau, "max_cut": max_cut })
                }
            };
            let selection = TreeSelection::new(scene, mode).map_err(StrategyError::BadOption)?;
            Ok(Box::new(LightStrategy {
                name: name.into(),
                selection,
                with_bsdf,
                parameters,
            }))
        };
    let split = TreeMode::Split {
        tau: opts.tau,
        max_cut: opts.max_cut,
    };
    Ok(match name {
        "tree" => tree(TreeMode::Single, false)?,
        "tree+bsdf" => tree(TreeMode::Single, true)?,
        "tree-split" => tree(split, false)?,
        "tree-split+bsdf" => tree(split, true)?,
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
        other => {
            let all = strategies();
            return Err(match all.iter().find(|s| s.name == other) {
                Some(_) => StrategyError::NotImplemented(other.into()),
                None => StrategyError::Unknown {
                    name: other.into(),
                    known: all.iter().map(|s| s.name).collect::<Vec<_>>().join(", "),
                },
            });
        }
    })
}
