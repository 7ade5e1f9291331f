//! `render-core`: what every strategy and tool of the manylights renderer stands on.
//!
//! It owns the scene (geometry, materials, lights, cameras), ray casting through an obvhs
//! CWBVH, the BSDF of a hit, the per-sample random numbers, the render loop and image output.
//! Light-sampling strategies live in the `samplers` crate and plug in through
//! [`estimator::DirectLighting`].

// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod bsdf;
pub mod builtin;
pub mod camera;
pub mod colour;
pub mod composition;
pub mod error;
pub mod estimator;
pub mod frame;
pub mod fresnel;
pub mod gltf_loader;
pub mod gltf_writer;
pub mod light;
pub mod material;
pub mod metrics;
pub mod microfacet;
pub mod output;
pub mod pbrt;
pub mod pbrt_extras;
pub mod plastic;
pub mod render;
pub mod rng;
pub mod sampling;
pub mod scene;
pub mod stats;
pub mod texture;

pub use error::SceneError;
pub use glam::{Vec2, Vec3};

/// Loads a scene named on the command line: `builtin:NAME?key=value&…`, a composition file
/// (`.toml`, see [`composition`]), a pbrt scene (`.pbrt`, see [`pbrt`]) or a glTF path.
pub fn load_scene(spec: &str, camera: Option<&str>) -> Result<scene::Scene, SceneError> {
    if spec.starts_with("builtin:") {
        let mut scene = builtin::load_builtin(spec)?;
        gltf_loader::select_camera(&mut scene, camera)?;
        Ok(scene)
    } else if spec.ends_with(".toml") {
        let mut scene = composition::load_composition(std::path::Path::new(spec))?;
        gltf_loader::select_camera(&mut scene, camera)?;
        Ok(scene)
    } else if spec.ends_with(".pbrt") {
        pbrt::load_pbrt(std::path::Path::new(spec), camera)
    } else {
        gltf_loader::load_gltf(std::path::Path::new(spec), camera)
    }
}
