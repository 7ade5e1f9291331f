//! The baselines every comparison needs: one light chosen uniformly or by power
//! ([`selection`]), the light tree of Conty Estevez & Kulla 2018 by one descent or an adaptive
//! cut ([`tree_selection`]), the spherical-Gaussian light tree of Tokuyoshi et al. 2024 ([`sg`]),
//! BSDF sampling alone, and the oracle floors ([`oracle`]); each as a strategy through
//! [`light_strategy::LightStrategy`] (a selection, with or without BSDF sampling by MIS).
mod light_batch;
pub mod light_strategy;
pub mod oracle;
pub mod selection;
pub mod sg;
pub mod tree_selection;
