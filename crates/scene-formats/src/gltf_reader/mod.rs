//! glTF 2.0 scenes (`.gltf` / `.glb`) through the `gltf` crate.
//!
//! What is read:
//! - every triangle primitive (`TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN`; indexed or not) of
//!   every node of the default scene (else the first scene, else every root node), under the
//!   node's full world transform; `POSITION`, `NORMAL` and one `TEXCOORD_n` set;
//!   points and lines are skipped and counted in [`SceneStats`](render_core::scene::SceneStats);
//! - metallic-roughness materials: baseColor factor × texture (sRGB decoded), metallic and
//!   roughness factors × texture (linear, G = roughness, B = metallic), `KHR_materials_specular`
//!   specularFactor (1 when absent; 0 makes the material pure Lambert), doubleSided, and
//!   emission = emissiveFactor × `KHR_materials_emissive_strength` × emissiveTexture (sRGB
//!   decoded). The [`SceneBuilder`] turns emissive triangles into area lights (zero-average ones
//!   are not lights);
//! - a material's `extras.pbrt` (its pbrt description, as `manylights convert` and the
//!   bisml_cornell scene write it) replaces the reflection model: see [`crate::gltf_reader::pbrt_extras`];
//! - `KHR_lights_punctual`: see [`PunctualUnits`] below for the unit convention;
//! - perspective cameras (`yfov`, `aspectRatio`), looking down the node's −Z with +Y up.
//!
//! Not modelled (read as an opaque metallic-roughness surface, reported in
//! [`GltfReport::warnings`]): transmission, clearcoat, sheen, volume, alpha blending/masking,
//! normal and occlusion maps, the specular texture and colour, texture sampler wrap modes
//! (always repeat), orthographic cameras, punctual light `range`.
//!
//! # Punctual light units
//! glTF gives point and spot intensities in candela and directional ones in lux. The renderer
//! works in plain radiometric units, and the converted scenes of `../shared/scenes`
//! (bisml_cornell) store `color × intensity` = radiant intensity I directly. So:
//! - point / spot: I = `color × intensity` (W/sr); with a node `extras.radius` r > 0 (or the
//!   light's own `extras.radius`), a sphere light of radiance L = I / (π r²), which has the
//!   same intensity when seen from outside; the radius is not scaled by the node transform;
//! - spot: emission axis = node −Z, cone from `innerConeAngle` / `outerConeAngle`;
//! - directional: irradiance E = `color × intensity`, direction to the light = node +Z.
//!
//! No photometric (lumen → watt) conversion is applied.
//!
//! # Layout
//! This file reads and checks the file and holds the `Loader`'s state; the loader's steps are
//! modules of their own: `nodes` (the node hierarchy and its transforms), `meshes`
//! (primitives → triangles), `materials` and `textures`, `lights` (punctual lights),
//! `camera`; `files` checks external files, [`pbrt_extras`] reads a material's pbrt
//! description.
mod camera;
mod files;
mod lights;
mod materials;
mod meshes;
mod nodes;
pub mod pbrt_extras;
mod render_hints;
pub use render_hints::hints_extras;
mod textures;

#[cfg(test)]
mod tests;

use files::external_file;
use glam::Mat4;
use render_core::error::SceneError;
use render_core::scene::{Scene, SceneBuilder};
use render_core::texture::Texture;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

pub(crate) use files::regular_file;

/// The extensions a file may list in `extensionsRequired`.
pub const SUPPORTED_REQUIRED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_specular",
    "KHR_texture_transform",
];

/// Marker type documenting the light-unit convention (see the module documentation).
pub enum PunctualUnits {}

/// Default image height of a glTF camera; the width follows its aspect ratio.
pub const DEFAULT_CAMERA_HEIGHT: u32 = 512;

/// What one glTF file contributed to a [`SceneBuilder`].
#[derive(Clone, Debug, Default)]
pub struct GltfReport {
    /// Triangle primitives read.
    pub primitives: usize,
    /// Triangles handed to the builder (degenerate ones are then skipped by the builder).
    pub triangles: usize,
    /// Point and line primitives, and primitives without positions: not loaded.
    pub skipped_primitives: usize,
    pub sphere_lights: usize,
    pub point_lights: usize,
    pub spot_lights: usize,
    pub distant_lights: usize,
    pub cameras: usize,
    /// Features of the file that were ignored, each once.
    pub warnings: Vec<String>,
}

impl GltfReport {
    fn warn(&mut self, w: String) {
        if !self.warnings.contains(&w) {
            self.warnings.push(w);
        }
    }

    fn punctual_lights(&self) -> usize {
        self.sphere_lights + self.point_lights + self.spot_lights + self.distant_lights
    }
}

/// Loads a glTF file as a scene. With `camera = Some(name)`, the camera of that name (glTF
/// camera name, else its node's name) becomes the scene's first camera, so
/// `Scene::camera(None)` returns it; an unknown name is an error. A file without cameras gets
/// `Camera::framing` of its bounds from `Scene::camera(None)`.
pub fn load_gltf(path: &Path, camera: Option<&str>) -> Result<Scene, SceneError> {
    load_gltf_with_report(path, camera).map(|(scene, _)| scene)
}

/// [`load_gltf`], also returning what was read and what was ignored.
pub fn load_gltf_with_report(
    path: &Path,
    camera: Option<&str>,
) -> Result<(Scene, GltfReport), SceneError> {
    let mut builder = SceneBuilder::new(&path.display().to_string());
    let report = add_gltf(&mut builder, path, Mat4::IDENTITY)?;
    if report.triangles == 0 {
        if report.punctual_lights() == 0 {
            return Err(SceneError::Empty.in_file(path));
        }
        return Err(gltf_err(
            path,
            format!(
                "no triangles (only {} punctual lights): nothing to shade",
                report.punctual_lights()
            ),
        ));
    }
    let mut scene = builder.build().map_err(|e| e.in_file(path))?;
    if scene.triangles.is_empty() {
        return Err(gltf_err(
            path,
            format!("no triangles: all {} are degenerate", report.triangles),
        ));
    }
    scene.select_camera(camera)?;
    scene.stats.warnings.extend(report.warnings.iter().cloned());
    Ok((scene, report))
}

/// A glTF error naming the file.
fn gltf_err(path: &Path, message: impl Into<String>) -> SceneError {
    SceneError::Gltf {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// Adds everything of a glTF file to `builder`, with `transform` applied on top of the file's
/// own node transforms (for scene composition). Cameras are added too.
pub fn add_gltf(
    builder: &mut SceneBuilder,
    path: &Path,
    transform: Mat4,
) -> Result<GltfReport, SceneError> {
    let io = |e: String| SceneError::Io {
        path: path.display().to_string(),
        message: e,
    };
    regular_file(path).map_err(io)?;
    let bytes = std::fs::read(path).map_err(|e| io(e.to_string()))?;
    // Check the required extensions first, so an unsupported one gets its own message
    // instead of a validation report.
    let raw = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| gltf_err(path, e.to_string()))?;
    for ext in raw.extensions_required() {
        if !SUPPORTED_REQUIRED_EXTENSIONS.contains(&ext) {
            return Err(gltf_err(
                path,
                format!("requires extension `{ext}`, which is not supported"),
            ));
        }
    }
    // gltf-json's validation indexes the accessors by a primitive's POSITION unchecked (it
    // panics on an out-of-range index): check those first.
    let json = raw.document.as_json();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(a) = prim.attributes.get(&position)
                && a.value() >= json.accessors.len()
            {
                return Err(gltf_err(
                    path,
                    format!(
                        "mesh {m} primitive {p}: POSITION accessor {} does not exist",
                        a.value()
                    ),
                ));
            }
        }
    }
    // External files are read whole by the gltf crate: each must be a regular file (not
    // /dev/zero, a pipe or a directory), and its URI must decode (the crate panics otherwise).
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    let buffers = json.buffers.iter().map(|b| ("buffers", b.uri.as_deref()));
    let images = json.images.iter().map(|i| ("images", i.uri.as_deref()));
    let mut index = HashMap::new();
    for (kind, uri) in buffers.chain(images) {
        let k = index.entry(kind).or_insert(0usize);
        *k += 1;
        let Some(uri) = uri else { continue };
        // A missing buffer is named here (the gltf crate's message names neither it nor its
        // file); a missing image is left to the texture reader, which names it.
        if let Some(file) = external_file(base, uri).map_err(|e| gltf_err(path, e))?
            && (kind == "buffers" || file.exists())
        {
            regular_file(&file).map_err(|e| {
                gltf_err(path, format!("{kind}[{}]: {}: {e}", *k - 1, file.display()))
            })?;
        }
    }
    drop(raw);
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice(&bytes).map_err(|e| gltf_err(path, e.to_string()))?;
    drop(bytes);
    let buffers = gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| gltf_err(path, format!("buffers: {e}")))?;
    let mut loader = Loader {
        path,
        doc: &document,
        base,
        buffers: &buffers,
        builder,
        textures: HashMap::new(),
        materials: HashMap::new(),
        report: GltfReport::default(),
    };
    // Reading accessors through the gltf crate is bounds-checked; a panic would still be a
    // bug in a dependency on a hostile file, so it becomes an error instead of a crash.
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| loader.load(transform)));
    let report = std::mem::take(&mut loader.report);
    match result {
        Ok(Ok(())) => Ok(report),
        Ok(Err(e)) => Err(e.in_file(path)),
        Err(_) => Err(gltf_err(
            path,
            "the file could not be read (malformed data)",
        )),
    }
}

/// A material's texture coordinates: its uv set and texture transform.
#[derive(Clone, Copy, Debug)]
pub(super) struct UvSpec {
    pub(super) set: u32,
    /// KHR_texture_transform: uv' = offset + R(rotation)·(scale ⊙ uv).
    pub(super) transform: Option<([f32; 2], f32, [f32; 2])>,
}

/// One glTF file being added to a builder: the document, its buffers, and what was made of it.
struct Loader<'a> {
    path: &'a Path,
    doc: &'a gltf::Document,
    base: &'a Path,
    buffers: &'a [gltf::buffer::Data],
    builder: &'a mut SceneBuilder,
    /// (image index, sRGB) → decoded linear texture.
    textures: HashMap<(usize, bool), Arc<Texture>>,
    /// glTF material index (None = default material) → builder material and its uv set.
    materials: HashMap<Option<usize>, (u32, UvSpec)>,
    report: GltfReport,
}
