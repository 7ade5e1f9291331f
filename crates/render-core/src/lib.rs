//! `render-core`: what every strategy and tool of the manylights renderer stands on.
//!
//! It owns the scene (geometry, materials, lights, cameras), ray casting through an obvhs
//! CWBVH, the BSDF of a hit, the per-sample random numbers, the render loop and image output.
//! Light-sampling strategies live in the `samplers` crate and plug in through
//! [`estimator::DirectLighting`]; scene files and the built-in scenes are read by the
//! `scene-formats` crate, which builds scenes through [`scene::SceneBuilder`].

// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod bsdf;
pub mod camera;
pub mod colour;
pub mod error;
pub mod estimator;
pub mod filter;
pub mod frame;
mod hash;
pub mod light;
pub mod material;
pub mod metrics;
pub mod output;
pub mod render;
pub mod rng;
pub mod sampler;
pub mod sampling;
pub mod scene;
pub mod scene_hash;
pub mod scene_hints;
pub mod stats;
pub mod texture;
pub mod zsobol;

pub use error::SceneError;
pub use glam::{Vec2, Vec3};
