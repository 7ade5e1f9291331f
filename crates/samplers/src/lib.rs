//! `samplers`: light-sampling techniques and the direct-lighting strategies built from them.
//!
//! A strategy is a [`render_core::estimator::DirectLighting`]; [`create`] builds one by name.
//! Every technique can both sample a light point and evaluate the density of any light point,
//! so strategies combine them by multiple importance sampling.
//!
//! **Layout.** One folder per family: [`baselines`] (uniform, power, BSDF, the light trees, the
//! oracles), [`brdf_oriented`] (the paper's method), [`learned`] (the learned selections),
//! [`ris`] (per-pixel resampling) and [`rivals`] (this round's tree rivals). At the root: the
//! [`registry`] of every [`Strategy`], the [`knobs`] they read from [`StrategyOptions`], and the
//! pieces several families share (MIS weights, BSDF sampling, the work counters).
//!
//! **Embedding BRDF-oriented sampling elsewhere.** The BO technique runs from raw inputs: a
//! [`light_tree::LightTree`] built from the host's light bounds, a
//! [`brdf_oriented::importance::BoRecord::from_parts`] (position, frame, GGX lobe from
//! `brdf-integrals`, lobe weights), [`brdf_oriented::technique::BoState::select_from`] with any
//! source of uniform numbers and `selection_pmf` for MIS; the `embedding-example` crate
//! (crates/embedding-example, `cargo run --release -p embedding-example`) does it, and its
//! samples pass the chi-square test in its tests. The crate still depends on
//! `render-core` for `Frame`, `Vec3` and, in the strategies, scenes, lights and `SampleStream`:
//! splitting the renderer-agnostic techniques into a crate of their own needs `Frame` moved
//! down (to `light-tree` or a small geometry crate), a point-on-light callback in place of
//! `BoState::sample_point`'s `Light`, and the three-technique MIS and allocation written
//! against a trait for "trace a BSDF direction, report the light hit".

// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]

pub mod alias;
pub mod baselines;
pub mod brdf_oriented;
pub mod bsdf_sampling;
pub mod convergence;
pub mod knobs;
pub mod learned;
mod memo;
pub mod mis;
mod options;
pub mod point_sets;
pub mod registry;
pub mod resolve;
pub mod reuse;
pub mod ris;
pub mod rivals;
mod scratch;
pub mod shared_tree;
pub mod strategy;
pub mod work_counters;

/// The baselines' modules, by their short paths.
pub use baselines::{light_strategy, oracle, selection, sg, tree_selection};
pub use options::{AUTHORS_TAU, DEFAULT_TAU, StrategyError, StrategyOptions, check_options};
use render_core::estimator::DirectLighting;
use render_core::scene::Scene;
pub use strategy::Strategy;

/// Every registered strategy ([`registry::STRATEGIES`]).
pub fn strategies() -> &'static [&'static Strategy] {
    registry::STRATEGIES
}

/// Builds the strategy called `name` for `scene` (its parameters: [`registry::resolved_parameters`]).
pub fn create(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    check_options(opts)?;
    (registry::find(name)?.build)(name, scene, opts)
}
