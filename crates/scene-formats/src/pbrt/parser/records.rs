//! What the parser keeps between directives: the open sources, the graphics state and its
//! blocks, shapes recorded for instancing, and the camera as read. Plain data, so that every
//! directive module can use it without importing the parser back.
use crate::pbrt::shapes::MeshData;
use crate::pbrt::tokenizer::Tokenizer;
use glam::{DMat4, Vec3};
use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;
use std::sync::Arc;

/// One file of the include stack.
pub(super) struct Source {
    pub(super) tokens: Tokenizer<BufReader<File>>,
    /// As named (for messages) and canonical (for include cycles).
    pub(super) shown: String,
    pub(super) canonical: PathBuf,
}

/// The current `AreaLightSource "diffuse"`: what the shapes after it emit.
#[derive(Clone)]
pub(super) struct AreaLight {
    pub(super) radiance: Vec3,
    pub(super) two_sided: bool,
}

/// The graphics state that `AttributeBegin`/`End` saves and restores.
#[derive(Clone)]
pub(super) struct State {
    pub(super) ctm: DMat4,
    pub(super) reverse: bool,
    /// Index into `Parser::materials`; `None`: `interface` (no surface).
    pub(super) material: Option<usize>,
    pub(super) area_light: Option<Arc<AreaLight>>,
}

/// A shape recorded inside `ObjectBegin`/`ObjectEnd`, added once per `ObjectInstance`.
pub(super) struct Instanced {
    pub(super) mesh: Arc<MeshData>,
    pub(super) ctm: DMat4,
    pub(super) material: u32,
    pub(super) name: String,
}

/// The kind of an open block, which decides what its end restores.
pub(super) enum Block {
    Attribute,
    Transform,
    Object,
}

/// Camera directive as read; made into a [`render_core::camera::Camera`] at the end, once the
/// film is known.
pub(super) struct CameraSpec {
    pub(super) camera_from_world: DMat4,
    pub(super) fov_degrees: f64,
    /// The file of the `Camera` directive (as messages show it) and its line; line 0 for the
    /// default camera.
    pub(super) file: String,
    pub(super) line: usize,
}
