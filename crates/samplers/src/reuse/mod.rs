//! Samples shared between pixels: ReSTIR DI's spatial reuse on the render loop's image-space
//! passes (`render_core::image_space`).
//!
//! * [`light_point`]: a sample as a point on a light (area measure), the target p̂ and its
//!   shadow ray.
//! * [`reservoir`]: weighted reservoir sampling and the contribution weight W.
//! * [`initial`]: a pixel's candidates (M light + one BSDF) resampled into its first reservoir.
//! * [`spatial`]: neighbours and one round of reuse, unbiased (pairwise MIS) or the paper's 1/M.
//! * [`history`]: reuse of a pixel's reservoir of the previous pass (`--restir-history`).
//! * [`sources`]: where the first candidates come from (a light selection, or the paper's
//!   BO + tree techniques).
//! * [`strategy`]: `restir`, `restir-biased`, `restir-bo`; [`config`]: their `--restir-*` parameters.
pub mod config;
pub mod history;
pub mod initial;
pub mod light_point;
pub mod reservoir;
pub mod sources;
pub mod spatial;
pub mod strategy;

pub use config::ReuseConfig;
