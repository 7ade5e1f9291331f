//! The spherical-Gaussian light tree (Tokuyoshi, Ikeda, Kulkarni & Harada, SIGGRAPH Asia
//! 2024): the light tree's single descent with a BRDF-aware node importance, the analytic
//! lighting integral of each node's SG light ([`light_tree::SgNodes`]) with the BSDF.
//!
//! * [`lobe`]: vMF integrals against the receiver's hemisphere (our own approximations);
//! * [`importance`]: the per-shading-point record and the node importance (diffuse, glossy
//!   with NDF filtering, and the floor that keeps the descent unbiased);
//! * [`selection`]: the descent as a [`crate::selection::LightSelection`], `pick` and `pmf`
//!   side by side, behind the strategies `sg-tree` and `sg-tree+bsdf`.
pub mod importance;
pub mod lobe;
pub mod selection;

pub use importance::SgShading;
pub use selection::{SgTreeSelection, sg_emitters};

use crate::light_strategy::LightStrategy;
use crate::strategy::Strategy;
use crate::{StrategyError, StrategyOptions, resolve};

fn resolve_sg(_: &str, opts: &StrategyOptions) -> serde_json::Value {
    serde_json::json!({
        "tree": "single, spherical-Gaussian importance",
        "power_units": resolve::units(opts),
        "floor": importance::FLOOR,
    })
}

fn build_sg(
    name: &str,
    scene: &render_core::scene::Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn render_core::estimator::DirectLighting>, StrategyError> {
    Ok(Box::new(LightStrategy {
        name: name.into(),
        selection: SgTreeSelection::new(scene, opts.power_units()).map_err(StrategyError::Scene)?,
        with_bsdf: name == SG_TREE_BSDF.name,
        parameters: serde_json::json!({
            "reproduce": opts.reproduce,
            "floor": importance::FLOOR,
        }),
    }))
}

/// `sg-tree`.
pub const SG_TREE: Strategy = Strategy::new(
    "sg-tree",
    "light tree, single descent by spherical-Gaussian BRDF-aware importance (Tokuyoshi et al. 2024)",
    resolve_sg,
    build_sg,
);

/// `sg-tree+bsdf`.
pub const SG_TREE_BSDF: Strategy = Strategy::new(
    "sg-tree+bsdf",
    "sg-tree + BSDF sampling, MIS",
    resolve_sg,
    build_sg,
);
