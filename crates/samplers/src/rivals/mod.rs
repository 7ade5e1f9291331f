//! The field's light-tree rivals beside the paper's method (issue 50), each on our light tree
//! and with our light-point sampling, BSDF sampling and MIS helpers:
//!
//! * [`slc`]: stochastic lightcuts (Yuksel, HPG 2019): a cut of at most K nodes refined by
//!   an error bound, one light per cut node drawn down its subtree, one shadow ray each.
//! * [`slc_bo`]: `slc-bo+bsdf`, its descent weighed by the paper's BRDF-oriented importance.
//! * [`slc_minmax`]: the descent of Lin & Yuksel's real-time code, as an option of `slc`.
//! * [`rht`]: the resampled hierarchical tree (Conty Estevez, Hellmuth & Lecocq 2024): a
//!   stochastic split traversal gathers candidates ([`rht_gather`], over the records of
//!   [`rht_nodes`]), one resampled to shade.
//! * [`varl`]: learning to cluster (Wang, Wu, Li & Chuang 2021): per region a cut refined and a
//!   distribution over it learnt between passes ([`varl_table`]).
//!
//! Their knobs live apart ([`rht_options`], [`varl_options`]), as leaves the shared options import.
pub mod rht;
pub mod rht_gather;
pub mod rht_nodes;
pub mod rht_options;
pub mod slc;
pub mod slc_bo;
pub mod slc_minmax;
pub mod varl;
pub mod varl_options;
pub mod varl_table;
