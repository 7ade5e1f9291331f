//! `scene-formats`: every way a scene reaches the manylights renderer, and the one way out.
//!
//! Readers build a [`render_core::scene::Scene`] through its `SceneBuilder`: glTF 2.0 files
//! ([`gltf_reader`]), pbrt-v4 and pbrt-v3 scene files ([`pbrt`]), TOML compositions placing
//! real assets with overrides and light layouts ([`composition`]) and the procedural
//! `builtin:` scenes ([`builtin`]). [`gltf_writer`] writes a loaded scene back as `.glb`.
//! [`load_scene`] picks the reader from the name given on the command line.

// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod builtin;
pub mod composition;
pub mod gltf_reader;
pub mod gltf_writer;
pub mod pbrt;
#[cfg(test)]
mod scratch;
#[cfg(test)]
mod test_notice;

use render_core::SceneError;
use render_core::scene::Scene;
use std::path::Path;

/// Loads a scene named on the command line: `builtin:NAME?key=value&…`, a composition file
/// (`.toml`, see [`composition`]), a pbrt scene (`.pbrt`, see [`pbrt`]) or a glTF path, and
/// makes the camera called `camera` its first one.
pub fn load_scene(spec: &str, camera: Option<&str>) -> Result<Scene, SceneError> {
    if spec.starts_with("builtin:") {
        let mut scene = builtin::load_builtin(spec)?;
        scene.select_camera(camera)?;
        Ok(scene)
    } else if spec.ends_with(".toml") {
        let mut scene = composition::load_composition(Path::new(spec))?;
        scene.select_camera(camera)?;
        Ok(scene)
    } else if spec.ends_with(".pbrt") {
        pbrt::load_pbrt(Path::new(spec), camera)
    } else {
        gltf_reader::load_gltf(Path::new(spec), camera)
    }
}
