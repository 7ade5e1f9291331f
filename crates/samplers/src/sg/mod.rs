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
