//! `render-core`: what every strategy and tool of the manylights renderer stands on.
//!
//! It owns the scene (geometry, materials, lights, cameras), ray casting through an obvhs
//! CWBVH, the BSDF of a hit, the render loop and image output; the per-sample random numbers, samplers
//! and pixel filters come from `pixel-samples` (re-exported as `rng`, `sampler`, `filter`).
//! Light-sampling strategies live in the `samplers` crate and plug in through
//! [`estimator::DirectLighting`]; scene files and the built-in scenes are read by the
//! `scene-formats` crate, which builds scenes through [`scene::SceneBuilder`].

// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod batch;
pub mod bsdf;
pub mod camera;
pub mod colour;
pub mod derived;
pub mod emission_rays;
pub mod error;
pub mod estimator;
pub mod frame;
pub mod image_space;
pub mod light;
pub mod light_points;
pub mod material;
pub mod metrics;
pub mod output;
pub mod pilot;
mod ray_streams;
pub mod render;
pub mod sampling;
pub mod scene;
mod scene_builder;
pub mod scene_hash;
pub mod scene_hints;
pub mod shading_point;
pub mod spherical_triangle;
pub mod splat;
pub mod stats;
pub mod suggest;
pub mod texture;

pub use pixel_samples::{filter, rng, sampler, zsobol};

pub use error::SceneError;
pub use glam::{Vec2, Vec3};
