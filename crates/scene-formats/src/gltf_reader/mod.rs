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
pub mod pbrt_extras;

use glam::{Mat4, Vec2, Vec3, Vec4};
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::light::SpotCone;
use render_core::material::Material;
use render_core::scene::{Scene, SceneBuilder};
use render_core::texture::{Texture, srgb_to_linear};
use std::collections::HashMap;
use std::f32::consts::PI;
use std::path::Path;
use std::sync::Arc;

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
            return Err(SceneError::Empty);
        }
        return Err(gltf_err(
            path,
            format!(
                "no triangles (only {} punctual lights): nothing to shade",
                report.punctual_lights()
            ),
        ));
    }
    let mut scene = builder.build()?;
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
    let uris = (json.buffers.iter().filter_map(|b| b.uri.as_deref()))
        .chain(json.images.iter().filter_map(|i| i.uri.as_deref()));
    for uri in uris {
        // (a missing file is left to the gltf crate, whose message names the buffer)
        if let Some(file) = external_file(base, uri).map_err(|e| gltf_err(path, e))?
            && file.exists()
        {
            regular_file(&file).map_err(|e| gltf_err(path, e))?;
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
        Ok(Err(e)) => Err(e),
        Err(_) => Err(gltf_err(
            path,
            "the file could not be read (malformed data)",
        )),
    }
}

/// An error unless `path` is a regular file (reading a device or a pipe whole never ends).
pub(crate) fn regular_file(path: &Path) -> Result<(), String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if meta.is_file() {
        Ok(())
    } else {
        Err(format!("{} is not a regular file", path.display()))
    }
}

/// The file an external glTF URI names (None for data URIs and unsupported schemes, which the
/// gltf crate refuses itself); relative URIs are percent-decoded and must be UTF-8.
fn external_file(base: &Path, uri: &str) -> Result<Option<std::path::PathBuf>, String> {
    if uri.contains(':') {
        let file = uri
            .strip_prefix("file://")
            .or_else(|| uri.strip_prefix("file:"));
        return Ok(file.map(std::path::PathBuf::from));
    }
    let mut bytes = Vec::with_capacity(uri.len());
    let mut rest = uri.as_bytes();
    while let Some((&c, tail)) = rest.split_first() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (c, tail) {
            (b'%', [h, l, more @ ..]) if hex(*h).is_some() && hex(*l).is_some() => {
                bytes.push((hex(*h).unwrap_or(0) * 16 + hex(*l).unwrap_or(0)) as u8);
                rest = more;
            }
            _ => {
                bytes.push(c);
                rest = tail;
            }
        }
    }
    let decoded =
        String::from_utf8(bytes).map_err(|_| format!("URI `{uri}` does not decode to UTF-8"))?;
    Ok(Some(base.join(decoded)))
}

#[derive(Clone, Copy, Debug)]
struct UvSpec {
    set: u32,
    /// KHR_texture_transform: uv' = offset + R(rotation)·(scale ⊙ uv).
    transform: Option<([f32; 2], f32, [f32; 2])>,
}

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

/// Reads a number from a node's or light's `extras` JSON object.
fn extras_number(extras: &gltf::json::Extras, key: &str) -> Option<Result<f32, String>> {
    let raw = extras.as_ref()?;
    let v: serde_json::Value = match serde_json::from_str(raw.get()) {
        Ok(v) => v,
        Err(e) => return Some(Err(format!("unreadable extras: {e}"))),
    };
    let x = v.get(key)?;
    Some(
        x.as_f64()
            .map(|f| f as f32)
            .ok_or_else(|| format!("extras.{key} is not a number: {x}")),
    )
}

impl Loader<'_> {
    fn err(&self, message: impl Into<String>) -> SceneError {
        gltf_err(self.path, message)
    }

    fn load(&mut self, root: Mat4) -> Result<(), SceneError> {
        let doc = self.doc;
        let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(scene) => scene.nodes().collect(),
            None => {
                // No scene at all: every node that is nobody's child.
                let mut is_child = vec![false; doc.nodes().len()];
                for n in doc.nodes() {
                    for c in n.children() {
                        is_child[c.index()] = true;
                    }
                }
                doc.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };
        let max_depth = doc.nodes().len();
        let mut stack: Vec<(gltf::Node, Mat4, usize)> =
            roots.into_iter().rev().map(|n| (n, root, 0)).collect();
        while let Some((node, parent, depth)) = stack.pop() {
            if depth > max_depth {
                return Err(self.err("the node hierarchy has a cycle"));
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            let world = parent * local;
            if let Some(mesh) = node.mesh() {
                self.add_mesh(&node, &mesh, world)?;
            }
            if let Some(light) = node.light() {
                self.add_light(&node, &light, world)?;
            }
            if let Some(camera) = node.camera() {
                self.add_camera(&node, &camera, world)?;
            }
            if node.skin().is_some() {
                self.report
                    .warn("skins are ignored (meshes are read in their bind pose)".into());
            }
            let children: Vec<gltf::Node> = node.children().collect();
            for c in children.into_iter().rev() {
                stack.push((c, world, depth + 1));
            }
        }
        Ok(())
    }

    fn add_mesh(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: Mat4,
    ) -> Result<(), SceneError> {
        let mesh_name = mesh
            .name()
            .or(node.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("mesh {}", mesh.index()));
        for prim in mesh.primitives() {
            use gltf::mesh::Mode;
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.report.skipped_primitives += 1;
                self.builder.count_skipped_primitives(1);
                continue;
            }
            if prim.get(&gltf::Semantic::Positions).is_none() {
                self.report.skipped_primitives += 1;
                self.builder.count_skipped_primitives(1);
                continue;
            }
            let (material, uv_spec) = self.material(prim.material())?;
            if prim.get(&gltf::Semantic::Colors(0)).is_some() {
                self.report.warn("vertex colours (COLOR_0) ignored".into());
            }
            check_accessor_types(&prim)
                .map_err(|e| self.err(format!("mesh `{mesh_name}`: {e}")))?;
            let buffers = self.buffers;
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let positions: Vec<Vec3> = match reader.read_positions() {
                Some(it) => it.map(Vec3::from).collect(),
                None => {
                    return Err(self.err(format!(
                        "mesh `{mesh_name}`: POSITION accessor lies outside its buffer"
                    )));
                }
            };
            let normals: Option<Vec<Vec3>> = reader
                .read_normals()
                .map(|it| it.map(Vec3::from).collect::<Vec<_>>())
                .filter(|n| n.len() == positions.len());
            let mut uvs: Option<Vec<Vec2>> = reader
                .read_tex_coords(uv_spec.set)
                .map(|t| t.into_f32().map(Vec2::from).collect::<Vec<_>>())
                .filter(|t| t.len() == positions.len());
            if let (Some(uvs), Some((offset, rotation, scale))) = (uvs.as_mut(), uv_spec.transform)
            {
                let (s, c) = rotation.sin_cos();
                for uv in uvs.iter_mut() {
                    let (x, y) = (uv.x * scale[0], uv.y * scale[1]);
                    *uv = Vec2::new(c * x + s * y + offset[0], -s * x + c * y + offset[1]);
                }
            }
            let raw: Vec<u32> = match prim.indices() {
                Some(_) => match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => {
                        return Err(self.err(format!(
                            "mesh `{mesh_name}`: index accessor lies outside its buffer"
                        )));
                    }
                },
                None => (0..positions.len() as u32).collect(),
            };
            let indices = triangle_list(mode, &raw);
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(self.err(format!(
                    "mesh `{mesh_name}`: index {bad} is past its {} vertices",
                    positions.len()
                )));
            }
            self.report.primitives += 1;
            self.report.triangles += indices.len() / 3;
            self.builder.add_mesh(
                &mesh_name,
                &positions,
                normals.as_deref(),
                uvs.as_deref(),
                &indices,
                world,
                material,
            )?;
        }
        Ok(())
    }

    /// The builder material of a glTF material, created on first use.
    fn material(&mut self, m: gltf::Material) -> Result<(u32, UvSpec), SceneError> {
        if let Some(&v) = self.materials.get(&m.index()) {
            return Ok(v);
        }
        let mut uv = UvSpec {
            set: 0,
            transform: None,
        };
        let mat = match m.index() {
            None => Material::default(),
            Some(i) => {
                let name = m
                    .name()
                    .map(str::to_string)
                    .unwrap_or_else(|| format!("material {i}"));
                let pbr = m.pbr_metallic_roughness();
                // One uv set and transform per material: those of the first texture that has one.
                let infos = [
                    pbr.base_color_texture(),
                    m.emissive_texture(),
                    pbr.metallic_roughness_texture(),
                ];
                if let Some(info) = infos.iter().flatten().next() {
                    uv.set = info.tex_coord();
                    if let Some(t) = info.texture_transform() {
                        uv.set = t.tex_coord().unwrap_or(uv.set);
                        uv.transform = Some((t.offset(), t.rotation(), t.scale()));
                    }
                }
                if infos.iter().flatten().any(|t| t.tex_coord() != uv.set) {
                    self.report.warn(format!(
                        "material `{name}`: textures on different uv sets; all use TEXCOORD_{}",
                        uv.set
                    ));
                }
                let base_color_texture = pbr
                    .base_color_texture()
                    .map(|t| self.texture(&t.texture(), true))
                    .transpose()?;
                let metallic_roughness_texture = pbr
                    .metallic_roughness_texture()
                    .map(|t| self.texture(&t.texture(), false))
                    .transpose()?;
                let emission_texture = m
                    .emissive_texture()
                    .map(|t| self.texture(&t.texture(), true))
                    .transpose()?;
                let bc = pbr.base_color_factor();
                let strength = m.emissive_strength().unwrap_or(1.0);
                let emission = Vec3::from(m.emissive_factor()) * strength;
                if !emission.is_finite() || emission.min_element() < 0.0 {
                    return Err(SceneError::BadEmission {
                        what: format!("material `{name}` (emissiveFactor × emissive strength)"),
                        value: format!("{:?}", emission.to_array()),
                    });
                }
                for (ext, what) in [
                    ("KHR_materials_transmission", "transmission"),
                    ("KHR_materials_clearcoat", "clearcoat"),
                    ("KHR_materials_sheen", "sheen"),
                    ("KHR_materials_volume", "volume"),
                    ("KHR_materials_pbrSpecularGlossiness", "specular-glossiness"),
                ] {
                    if m.extension_value(ext).is_some()
                        || (ext == "KHR_materials_transmission" && m.transmission().is_some())
                    {
                        self.report.warn(format!(
                            "material `{name}`: {what} ignored (read as opaque metallic-roughness)"
                        ));
                    }
                }
                if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
                    self.report
                        .warn(format!("material `{name}`: alpha mode ignored (opaque)"));
                }
                let specular = m.specular();
                if specular.as_ref().is_some_and(|s| {
                    s.specular_texture().is_some() || s.specular_color_factor() != [1.0; 3]
                }) {
                    self.report.warn(format!(
                        "material `{name}`: specular texture and colour ignored (factor used)"
                    ));
                }
                let gltf_material = Material {
                    name,
                    base_color: Vec3::new(bc[0], bc[1], bc[2]),
                    base_color_texture,
                    metallic: pbr.metallic_factor(),
                    roughness: pbr.roughness_factor(),
                    metallic_roughness_texture,
                    specular: specular.map_or(1.0, |s| s.specular_factor()),
                    double_sided: m.double_sided(),
                    emission,
                    emission_texture,
                    model: Default::default(),
                };
                match crate::gltf_reader::pbrt_extras::material(gltf_material, m.extras()) {
                    Ok(mat) => mat,
                    Err((mat, warning)) => {
                        self.report.warn(warning);
                        mat
                    }
                }
            }
        };
        let id = self.builder.add_material(mat)?;
        self.materials.insert(m.index(), (id, uv));
        Ok((id, uv))
    }

    fn texture(&mut self, tex: &gltf::Texture, srgb: bool) -> Result<Arc<Texture>, SceneError> {
        let image = tex.source();
        let key = (image.index(), srgb);
        let sampler = tex.sampler();
        let repeat = gltf::texture::WrappingMode::Repeat;
        if sampler.wrap_s() != repeat || sampler.wrap_t() != repeat {
            self.report
                .warn("texture wrap modes other than repeat read as repeat".into());
        }
        if let Some(t) = self.textures.get(&key) {
            return Ok(t.clone());
        }
        self.check_image_source(image.index())
            .map_err(|e| self.err(format!("image {}: {e}", image.index())))?;
        let data = gltf::image::Data::from_source(image.source(), Some(self.base), self.buffers)
            .map_err(|e| self.err(format!("image {}: {e}", image.index())))?;
        let t = Arc::new(
            convert_image(&data, srgb)
                .map_err(|e| self.err(format!("image {}: {e}", image.index())))?,
        );
        self.textures.insert(key, t.clone());
        Ok(t)
    }

    /// What the gltf crate's image reading assumes unchecked (it panics otherwise): a buffer
    /// view image has a MIME type and lies inside its buffer; any other has a URI.
    fn check_image_source(&self, index: usize) -> Result<(), String> {
        let json = self.doc.as_json();
        let img = json.images.get(index).ok_or("does not exist")?;
        match &img.buffer_view {
            Some(v) => {
                if img.mime_type.is_none() {
                    return Err("a buffer view image needs a mimeType".into());
                }
                let view = json
                    .buffer_views
                    .get(v.value())
                    .ok_or("its buffer view does not exist")?;
                let data = self
                    .buffers
                    .get(view.buffer.value())
                    .ok_or("its buffer does not exist")?;
                let end = (view.byte_offset.map_or(0, |o| o.0) as usize)
                    .checked_add(view.byte_length.0 as usize);
                if end.is_none_or(|e| e > data.0.len()) {
                    return Err("its buffer view runs past its buffer".into());
                }
                Ok(())
            }
            None if img.uri.is_none() => Err("has neither a uri nor a bufferView".into()),
            None => Ok(()),
        }
    }

    fn add_light(
        &mut self,
        node: &gltf::Node,
        light: &gltf::khr_lights_punctual::Light,
        world: Mat4,
    ) -> Result<(), SceneError> {
        use gltf::khr_lights_punctual::Kind;
        let name = light
            .name()
            .or(node.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("light {}", light.index()));
        let power = Vec3::from(light.color()) * light.intensity();
        if !power.is_finite() || power.min_element() < 0.0 {
            return Err(SceneError::BadEmission {
                what: format!("light `{name}` (color × intensity)"),
                value: format!("{:?}", power.to_array()),
            });
        }
        let radius = match extras_number(node.extras(), "radius")
            .or_else(|| extras_number(light.extras(), "radius"))
        {
            None => 0.0,
            Some(Ok(r)) if r.is_finite() && r >= 0.0 => r,
            Some(Ok(r)) => {
                return Err(SceneError::BadLight {
                    what: name,
                    message: format!("radius {r} (must be finite and >= 0)"),
                });
            }
            Some(Err(e)) => {
                return Err(SceneError::BadLight {
                    what: name,
                    message: e,
                });
            }
        };
        if light.range().is_some() {
            self.report
                .warn("punctual light `range` ignored (inverse-square falloff everywhere)".into());
        }
        let position = world.transform_point3(Vec3::ZERO);
        let axis = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let spot = match light.kind() {
            Kind::Directional => {
                self.builder.add_distant_light(-axis, power)?;
                self.report.distant_lights += 1;
                return Ok(());
            }
            Kind::Point => None,
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                if axis == Vec3::ZERO || !axis.is_finite() {
                    return Err(SceneError::BadLight {
                        what: name,
                        message: "spot light with a degenerate node transform".into(),
                    });
                }
                let outer = outer_cone_angle.clamp(0.0, PI / 2.0);
                let inner = inner_cone_angle.clamp(0.0, outer);
                Some(SpotCone {
                    direction: axis,
                    cos_inner: inner.cos(),
                    cos_outer: outer.cos(),
                })
            }
        };
        if radius > 0.0 {
            self.builder.add_sphere_light(
                position,
                radius,
                power / (PI * radius * radius),
                spot,
            )?;
            self.report.sphere_lights += 1;
        } else {
            self.builder.add_point_light(position, power, spot)?;
            if spot.is_some() {
                self.report.spot_lights += 1;
            } else {
                self.report.point_lights += 1;
            }
        }
        Ok(())
    }

    fn add_camera(
        &mut self,
        node: &gltf::Node,
        camera: &gltf::Camera,
        world: Mat4,
    ) -> Result<(), SceneError> {
        let name = camera
            .name()
            .or(node.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("camera {}", camera.index()));
        let gltf::camera::Projection::Perspective(p) = camera.projection() else {
            self.report
                .warn(format!("orthographic camera `{name}` ignored"));
            return Ok(());
        };
        let yfov = p.yfov();
        if !(yfov > 0.0 && yfov < PI) {
            return Err(self.err(format!("camera `{name}`: yfov {yfov} is not in (0, π)")));
        }
        let aspect = p
            .aspect_ratio()
            .filter(|a| a.is_finite() && *a > 0.0)
            .unwrap_or(1.0);
        let height = DEFAULT_CAMERA_HEIGHT;
        let width = ((height as f32 * aspect).round() as u32).clamp(1, 16384);
        let eye = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        if !eye.is_finite() || forward == Vec3::ZERO || forward.cross(up).length_squared() < 1e-12 {
            return Err(self.err(format!("camera `{name}`: degenerate node transform")));
        }
        self.builder.add_camera(Camera::look_at(
            &name,
            eye,
            eye + forward,
            up,
            yfov,
            width,
            height,
        ));
        self.report.cameras += 1;
        Ok(())
    }
}

/// Triangle-list indices from a primitive's indices in its drawing mode.
fn triangle_list(mode: gltf::mesh::Mode, idx: &[u32]) -> Vec<u32> {
    use gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
            .flat_map(|i| {
                if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i + 1], idx[i], idx[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..idx.len().saturating_sub(1))
            .flat_map(|i| [idx[i], idx[i + 1], idx[0]])
            .collect(),
        _ => idx[..idx.len() / 3 * 3].to_vec(),
    }
}

/// The component types and shapes the gltf crate's readers assume of the accessors read here
/// (it panics on others): float VEC3 positions and normals, float or normalised-integer VEC2
/// uvs, unsigned-integer scalar indices.
fn check_accessor_types(prim: &gltf::Primitive) -> Result<(), String> {
    use gltf::Semantic;
    use gltf::accessor::{DataType, Dimensions};
    let check = |what: &str, a: gltf::Accessor, types: &[DataType], dims: Dimensions| {
        let element = a.data_type().size() * a.dimensions().multiplicity();
        let stride = a.view().and_then(|v| v.stride()).unwrap_or(element);
        if stride < element {
            return Err(format!(
                "{what} accessor {}: byteStride {stride} is less than its {element}-byte elements",
                a.index()
            ));
        }
        if types.contains(&a.data_type()) && a.dimensions() == dims {
            Ok(())
        } else {
            Err(format!(
                "{what} accessor {} is {:?} {:?}, not {:?} of {types:?}",
                a.index(),
                a.data_type(),
                a.dimensions(),
                dims
            ))
        }
    };
    for (semantic, a) in prim.attributes() {
        match semantic {
            Semantic::Positions => check("POSITION", a, &[DataType::F32], Dimensions::Vec3)?,
            Semantic::Normals => check("NORMAL", a, &[DataType::F32], Dimensions::Vec3)?,
            Semantic::TexCoords(_) => check(
                "TEXCOORD",
                a,
                &[DataType::F32, DataType::U8, DataType::U16],
                Dimensions::Vec2,
            )?,
            _ => {}
        }
    }
    if let Some(a) = prim.indices() {
        let unsigned = [DataType::U8, DataType::U16, DataType::U32];
        check("index", a, &unsigned, Dimensions::Scalar)?;
    }
    Ok(())
}

/// A decoded glTF image as a linear RGBA texture (grey images replicate to RGB).
fn convert_image(img: &gltf::image::Data, srgb: bool) -> Result<Texture, String> {
    use gltf::image::Format;
    let (w, h) = (img.width, img.height);
    let n = w as usize * h as usize;
    if n == 0 {
        return Err("empty image".into());
    }
    let lut: Vec<f32> = (0..256)
        .map(|i| {
            if srgb {
                srgb_to_linear(i as f32 / 255.0)
            } else {
                i as f32 / 255.0
            }
        })
        .collect();
    let c8 = |v: u8| lut[v as usize];
    let c16 = |b: &[u8]| {
        let v = u16::from_ne_bytes([b[0], b[1]]) as f32 / 65535.0;
        if srgb { srgb_to_linear(v) } else { v }
    };
    let a16 = |b: &[u8]| u16::from_ne_bytes([b[0], b[1]]) as f32 / 65535.0;
    let f32c = |b: &[u8]| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
    let (channels, bytes_per) = match img.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    let stride = channels * bytes_per;
    if img.pixels.len() < n * stride {
        return Err(format!(
            "{} bytes of pixel data for {w}×{h} {:?}",
            img.pixels.len(),
            img.format
        ));
    }
    let texels = img.pixels[..n * stride]
        .chunks_exact(stride)
        .map(|p| {
            let ch = |k: usize| &p[k * bytes_per..(k + 1) * bytes_per];
            let v = |k: usize| match bytes_per {
                1 => c8(ch(k)[0]),
                2 => c16(ch(k)),
                _ => f32c(ch(k)),
            };
            let a = |k: usize| match bytes_per {
                1 => ch(k)[0] as f32 / 255.0,
                2 => a16(ch(k)),
                _ => f32c(ch(k)),
            };
            match channels {
                1 => Vec4::new(v(0), v(0), v(0), 1.0),
                2 => Vec4::new(v(0), v(0), v(0), a(1)),
                3 => Vec4::new(v(0), v(1), v(2), 1.0),
                _ => Vec4::new(v(0), v(1), v(2), a(3)),
            }
        })
        .collect();
    Ok(Texture::new(w, h, texels))
}

#[cfg(test)]
mod tests {
    use super::*;
    use render_core::light::LightShape;
    use serde_json::{Value, json};
    use std::path::PathBuf;

    fn err(r: Result<Scene, SceneError>) -> SceneError {
        match r {
            Ok(_) => panic!("expected an error"),
            Err(e) => e,
        }
    }

    /// Little-endian bytes of f32s.
    fn f32_bytes(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    fn temp_path(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("scene-formats-gltf-tests-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    /// Writes `doc` as a .gltf whose buffer 0 holds `bin` as a base64 data URI.
    fn write_gltf(name: &str, mut doc: Value, bin: &[u8]) -> PathBuf {
        if !bin.is_empty() {
            doc["buffers"] = json!([{ "byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", base64::encode(bin)) }]);
        }
        let path = temp_path(name);
        std::fs::write(&path, serde_json::to_vec_pretty(&doc).unwrap()).unwrap();
        path
    }

    /// One triangle (0,0,0), (1,0,0), (0,1,0) with u16 indices, plus UVs: accessors 0
    /// (positions), 1 (indices), 2 (uvs).
    fn triangle_doc(positions: [f32; 9]) -> (Value, Vec<u8>) {
        let mut bin = f32_bytes(&positions); // 36 bytes
        bin.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes())); // 8 bytes (padded)
        bin.extend(f32_bytes(&[0.25, 0.5, 0.75, 0.5, 0.25, 0.5])); // 24 bytes
        let doc = json!({
            "asset": { "version": "2.0" },
            "scene": 0,
            "scenes": [{ "nodes": [0] }],
            "nodes": [{ "mesh": 0 }],
            "meshes": [{ "name": "tri", "primitives": [{ "attributes": { "POSITION": 0, "TEXCOORD_0": 2 }, "indices": 1 }] }],
            "bufferViews": [
                { "buffer": 0, "byteOffset": 0, "byteLength": 36 },
                { "buffer": 0, "byteOffset": 36, "byteLength": 6 },
                { "buffer": 0, "byteOffset": 44, "byteLength": 24 }
            ],
            "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
                { "bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR" },
                { "bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2" }
            ]
        });
        (doc, bin)
    }

    const TRI: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

    #[test]
    fn hierarchy_transforms_reach_world_space_and_modes_are_handled() {
        let (mut doc, bin) = triangle_doc(TRI);
        doc["scenes"] = json!([{ "nodes": [0] }]);
        doc["nodes"] = json!([
            { "name": "parent", "translation": [10, 0, 0], "children": [1] },
            { "name": "child", "scale": [2, 2, 2], "mesh": 0, "children": [2] },
            { "name": "grandchild", "translation": [0, 0, 1], "mesh": 1 }
        ]);
        // Mesh 1: the same vertices non-indexed, plus a POINTS primitive that is skipped.
        doc["meshes"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "primitives": [
            { "attributes": { "POSITION": 0 } },
            { "attributes": { "POSITION": 0 }, "mode": 0 }
        ] }));
        let path = write_gltf("hierarchy.gltf", doc, &bin);
        let (scene, report) = load_gltf_with_report(&path, None).unwrap();
        assert_eq!(scene.triangles.len(), 2);
        assert_eq!((report.primitives, report.skipped_primitives), (2, 1));
        assert_eq!(scene.stats.non_triangle_primitives_skipped, 1);
        let t0 = &scene.triangles[0];
        assert_eq!(
            t0.p,
            [
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(12.0, 0.0, 0.0),
                Vec3::new(10.0, 2.0, 0.0)
            ]
        );
        // The grandchild's translation is scaled by its parent: z = 2.
        let t1 = &scene.triangles[1];
        assert_eq!(
            t1.p,
            [
                Vec3::new(10.0, 0.0, 2.0),
                Vec3::new(12.0, 0.0, 2.0),
                Vec3::new(10.0, 2.0, 2.0)
            ]
        );
        // No normals in the file: flat shading with the geometric normal.
        assert_eq!(t0.n, [Vec3::Z; 3]);
        assert_eq!(t0.uv[1], Vec2::new(0.75, 0.5));
        // No camera: the default framing camera.
        assert_eq!(scene.camera(None).unwrap().name, "default");
    }

    #[test]
    fn strips_and_fans_become_triangle_lists() {
        use gltf::mesh::Mode;
        assert_eq!(
            triangle_list(Mode::TriangleStrip, &[0, 1, 2, 3]),
            vec![0, 1, 2, 2, 1, 3]
        );
        assert_eq!(
            triangle_list(Mode::TriangleFan, &[0, 1, 2, 3]),
            vec![1, 2, 0, 2, 3, 0]
        );
        assert_eq!(triangle_list(Mode::Triangles, &[0, 1, 2, 3]), vec![0, 1, 2]);
    }

    #[test]
    fn punctual_lights_with_radius_become_sphere_lights() {
        let (mut doc, bin) = triangle_doc(TRI);
        doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
        doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
            { "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 2.0 },
            { "type": "point", "intensity": 3.0 },
            { "type": "spot", "intensity": 1.0, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } },
            { "type": "directional", "color": [1.0, 1.0, 1.0], "intensity": 5.0 }
        ] } });
        // Rotation of −90° about x: local −Z points down (−y) and local +Z up (+y).
        let (s, c) = (-std::f32::consts::FRAC_PI_4).sin_cos();
        doc["scenes"] = json!([{ "nodes": [0, 1, 2, 3, 4] }]);
        doc["nodes"] = json!([
            { "mesh": 0 },
            { "translation": [0, 3, 0], "extensions": { "KHR_lights_punctual": { "light": 0 } }, "extras": { "radius": 0.01 } },
            { "translation": [1, 3, 0], "extensions": { "KHR_lights_punctual": { "light": 1 } } },
            { "translation": [2, 3, 0], "rotation": [s, 0, 0, c], "extensions": { "KHR_lights_punctual": { "light": 2 } } },
            { "rotation": [s, 0, 0, c], "extensions": { "KHR_lights_punctual": { "light": 3 } } }
        ]);
        let path = write_gltf("lights.gltf", doc, &bin);
        let scene = load_gltf(&path, None).unwrap();
        assert_eq!(
            (
                scene.stats.sphere_lights,
                scene.stats.point_lights,
                scene.stats.spot_lights,
                scene.stats.distant_lights
            ),
            (1, 1, 1, 1)
        );
        let sphere = scene
            .lights
            .iter()
            .find(|l| matches!(l.shape, LightShape::Sphere { .. }))
            .unwrap();
        let LightShape::Sphere { center, radius } = sphere.shape else {
            unreachable!()
        };
        assert_eq!((center, radius), (Vec3::new(0.0, 3.0, 0.0), 0.01));
        let expect = Vec3::new(2.0, 1.0, 0.5) / (std::f32::consts::PI * 1e-4);
        assert!((sphere.emission - expect).length() < 1e-3 * expect.length());
        let spot = scene.lights.iter().find_map(|l| l.spot).unwrap();
        assert!((spot.direction - Vec3::NEG_Y).length() < 1e-5);
        assert!(
            (spot.cos_inner - 0.2f32.cos()).abs() < 1e-6
                && (spot.cos_outer - 0.5f32.cos()).abs() < 1e-6
        );
        let d = scene.distant_lights[0];
        assert!((d.direction - Vec3::Y).length() < 1e-5);
        assert_eq!(d.irradiance, Vec3::splat(5.0));
    }

    #[test]
    fn emissive_materials_become_lights_and_textures_gate_them() {
        // Two triangles over a 2×1 emissive texture: black on the left, white on the right.
        let mut png = Vec::new();
        image::RgbImage::from_raw(2, 1, vec![0, 0, 0, 255, 255, 255])
            .unwrap()
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let (mut doc, mut bin) = triangle_doc(TRI);
        let png_offset = bin.len();
        bin.extend_from_slice(&png);
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        // Second uv set: the whole triangle at the black texel's centre.
        let uv2_offset = bin.len();
        bin.extend(f32_bytes(&[0.25, 0.5, 0.25, 0.5, 0.25, 0.5]));
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "buffer": 0, "byteOffset": png_offset, "byteLength": png.len() }));
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "buffer": 0, "byteOffset": uv2_offset, "byteLength": 24 }));
        doc["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "bufferView": 4, "componentType": 5126, "count": 3, "type": "VEC2" }));
        doc["images"] = json!([{ "bufferView": 3, "mimeType": "image/png" }]);
        doc["textures"] = json!([{ "source": 0 }]);
        doc["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
        doc["materials"] = json!([
            { "name": "lamp", "emissiveFactor": [1.0, 0.5, 0.0], "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } } },
            { "name": "screen", "emissiveFactor": [1.0, 1.0, 1.0], "emissiveTexture": { "index": 0 }, "doubleSided": true }
        ]);
        doc["meshes"] = json!([{ "primitives": [
            { "attributes": { "POSITION": 0 }, "indices": 1, "material": 0 },
            { "attributes": { "POSITION": 0, "TEXCOORD_0": 2 }, "indices": 1, "material": 1 },
            { "attributes": { "POSITION": 0, "TEXCOORD_0": 3 }, "indices": 1, "material": 1 }
        ] }]);
        let path = write_gltf("emissive.gltf", doc, &bin);
        let scene = load_gltf(&path, None).unwrap();
        assert_eq!(scene.triangles.len(), 3);
        assert_eq!(scene.stats.triangle_lights, 2);
        assert_eq!(scene.stats.black_emissive_triangles, 1);
        assert_eq!(scene.lights[0].emission, Vec3::new(4.0, 2.0, 0.0));
        assert!(!scene.lights[0].two_sided);
        assert!(scene.lights[1].two_sided);
        // The white texel decodes to linear 1; the triangle's uvs (0.25..0.75) straddle both texels.
        let m = scene.lights[1].mean_emission;
        assert!(m.x > 0.2 && m.x < 0.8, "{m}");
        assert_eq!(scene.triangles[2].light, render_core::scene::NO_LIGHT);
    }

    #[test]
    fn cameras_are_read_with_their_names_and_selectable() {
        let (mut doc, bin) = triangle_doc(TRI);
        doc["cameras"] = json!([
            { "name": "wide", "type": "perspective", "perspective": { "yfov": 1.0, "aspectRatio": 2.0, "znear": 0.01 } },
            { "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.01 } }
        ]);
        let (s, c) = (std::f32::consts::FRAC_PI_4).sin_cos(); // +90° about y: −Z turns to −X
        doc["scenes"] = json!([{ "nodes": [0, 1, 2] }]);
        doc["nodes"] = json!([
            { "mesh": 0 },
            { "camera": 0, "translation": [0, 0, 5] },
            { "name": "side view", "camera": 1, "translation": [5, 0, 0], "rotation": [0, s, 0, c] }
        ]);
        let path = write_gltf("cameras.gltf", doc, &bin);
        let scene = load_gltf(&path, None).unwrap();
        let cam = scene.camera(None).unwrap();
        assert_eq!(
            (cam.name.as_str(), cam.width, cam.height, cam.yfov),
            ("wide", 1024, 512, 1.0)
        );
        assert_eq!(cam.position, Vec3::new(0.0, 0.0, 5.0));
        assert!((cam.forward - Vec3::NEG_Z).length() < 1e-6 && (cam.up - Vec3::Y).length() < 1e-6);
        let scene = load_gltf(&path, Some("side view")).unwrap();
        let cam = scene.camera(None).unwrap();
        assert_eq!((cam.name.as_str(), cam.width), ("side view", 512));
        assert!(
            (cam.forward - Vec3::NEG_X).length() < 1e-5,
            "{}",
            cam.forward
        );
        assert!(matches!(
            load_gltf(&path, Some("nope")),
            Err(SceneError::CameraNotFound(_))
        ));
    }

    #[test]
    fn bad_input_gives_a_clear_error() {
        let missing = temp_path("does-not-exist.glb");
        let e = err(load_gltf(&missing, None));
        assert!(matches!(e, SceneError::Io { .. }), "{e}");

        let garbage = temp_path("garbage.glb");
        std::fs::write(
            &garbage,
            b"glTF\x02\x00\x00\x00 this is not a real file \xff\xfe",
        )
        .unwrap();
        let e = err(load_gltf(&garbage, None));
        assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
        let garbage_json = temp_path("garbage.gltf");
        std::fs::write(&garbage_json, b"{ \"asset\": ").unwrap();
        assert!(matches!(
            load_gltf(&garbage_json, None),
            Err(SceneError::Gltf { .. })
        ));

        let (doc, bin) = triangle_doc([0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 1.0, 0.0]);
        let e = err(load_gltf(&write_gltf("nan.gltf", doc, &bin), None));
        assert!(matches!(e, SceneError::NonFiniteVertex { .. }), "{e}");

        let (mut doc, bin) = triangle_doc(TRI);
        doc["materials"] = json!([{ "name": "bad", "emissiveFactor": [1.0, -1.0, 0.0] }]);
        doc["meshes"][0]["primitives"][0]["material"] = json!(0);
        let e = err(load_gltf(&write_gltf("negative.gltf", doc, &bin), None));
        assert!(matches!(e, SceneError::BadEmission { .. }), "{e}");
        assert!(e.to_string().contains("bad"), "{e}");

        let (mut doc, bin) = triangle_doc(TRI);
        doc["materials"] = json!([{ "emissiveFactor": [1.0, 1.0, 1.0], "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": -2.0 } } }]);
        doc["meshes"][0]["primitives"][0]["material"] = json!(0);
        assert!(matches!(
            load_gltf(&write_gltf("negative2.gltf", doc, &bin), None),
            Err(SceneError::BadEmission { .. })
        ));

        let (mut doc, bin) = triangle_doc(TRI);
        doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": -1.0 }] } });
        doc["nodes"] =
            json!([{ "mesh": 0 }, { "extensions": { "KHR_lights_punctual": { "light": 0 } } }]);
        doc["scenes"] = json!([{ "nodes": [0, 1] }]);
        assert!(matches!(
            load_gltf(&write_gltf("negative3.gltf", doc, &bin), None),
            Err(SceneError::BadEmission { .. })
        ));

        // Non-finite emission (1e39 overflows f32), bad radii, a bad camera.
        let (mut doc, bin) = triangle_doc(TRI);
        doc["materials"] = json!([{ "emissiveFactor": [1.0, 1.0, 1.0], "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 1e39 } } }]);
        doc["meshes"][0]["primitives"][0]["material"] = json!(0);
        let e = err(load_gltf(&write_gltf("infinite.gltf", doc, &bin), None));
        assert!(matches!(e, SceneError::BadEmission { .. }), "{e}");
        for (i, extras) in [json!({ "radius": -0.5 }), json!({ "radius": "big" })]
            .into_iter()
            .enumerate()
        {
            let (mut doc, bin) = triangle_doc(TRI);
            doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": 1.0 }] } });
            doc["nodes"] = json!([{ "mesh": 0 }, { "extensions": { "KHR_lights_punctual": { "light": 0 } }, "extras": extras }]);
            doc["scenes"] = json!([{ "nodes": [0, 1] }]);
            let e = err(load_gltf(
                &write_gltf(&format!("radius{i}.gltf"), doc, &bin),
                None,
            ));
            assert!(matches!(e, SceneError::BadLight { .. }), "{e}");
        }
        let (mut doc, bin) = triangle_doc(TRI);
        doc["cameras"] =
            json!([{ "type": "perspective", "perspective": { "yfov": 4.0, "znear": 0.01 } }]);
        doc["nodes"] = json!([{ "mesh": 0 }, { "camera": 0 }]);
        doc["scenes"] = json!([{ "nodes": [0, 1] }]);
        let e = err(load_gltf(&write_gltf("camera.gltf", doc, &bin), None));
        assert!(
            matches!(e, SceneError::Gltf { .. }) && e.to_string().contains("yfov"),
            "{e}"
        );

        let empty = write_gltf(
            "empty.gltf",
            json!({ "asset": { "version": "2.0" }, "scenes": [{ "nodes": [] }] }),
            &[],
        );
        let e = err(load_gltf(&empty, None));
        assert!(matches!(e, SceneError::Empty), "{e}");

        let lights_only = json!({
            "asset": { "version": "2.0" },
            "extensions": { "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": 1.0 }] } },
            "nodes": [{ "extensions": { "KHR_lights_punctual": { "light": 0 } } }],
            "scenes": [{ "nodes": [0] }]
        });
        let e = err(load_gltf(
            &write_gltf("lights-only.gltf", lights_only, &[]),
            None,
        ));
        assert!(e.to_string().contains("no triangles"), "{e}");

        let (mut doc, bin) = triangle_doc(TRI);
        doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
        doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
        let e = err(load_gltf(&write_gltf("draco.gltf", doc, &bin), None));
        assert!(e.to_string().contains("KHR_draco_mesh_compression"), "{e}");

        // An index past the vertex array, and an accessor past its buffer.
        let (mut doc, mut bin) = triangle_doc(TRI);
        bin[36..38].copy_from_slice(&7u16.to_le_bytes());
        doc["accessors"][1]["max"] = json!([7]);
        let e = err(load_gltf(&write_gltf("bad-index.gltf", doc, &bin), None));
        assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
        let (mut doc, bin) = triangle_doc(TRI);
        doc["accessors"][0]["count"] = json!(300);
        let e = err(load_gltf(&write_gltf("short-buffer.gltf", doc, &bin), None));
        assert!(matches!(e, SceneError::Gltf { .. }), "{e}");

        // Every message is one line.
        for p in [&missing, &garbage, &garbage_json, &empty] {
            let e = err(load_gltf(p, None));
            eprintln!("{e}");
            assert!(!e.to_string().contains('\n'), "{e}");
        }
    }

    /// `extras.pbrt` replaces the reflection model: matte → pure Lambert, plastic → pbrt-v3
    /// plastic, KHR_materials_specular factor 0 → pure Lambert, an unknown type or a bad value
    /// → a warning and the glTF material.
    #[test]
    fn extras_pbrt_materials_load_as_described() {
        use render_core::bsdf::Specular;
        use render_core::material::Model;
        let (mut doc, bin) = triangle_doc(TRI);
        let materials = [
            json!({ "name": "wall", "pbrMetallicRoughness": { "baseColorFactor": [0.1, 0.1, 0.1, 1] },
                    "extras": { "pbrt": { "type": "matte", "Kd": [0.725, 0.71, 0.68] } } }),
            json!({ "name": "bunny", "pbrMetallicRoughness": { "roughnessFactor": 0.0894427 },
                    "extras": { "pbrt": { "type": "plastic", "Kd": [0.3, 0.1, 0.2], "Ks": [0.7, 0.7, 0.7],
                                          "roughness": 0.008, "remaproughness": false } } }),
            json!({ "name": "remapped", "extras": { "pbrt": { "type": "plastic", "roughness": 0.1 } } }),
            json!({ "name": "no-spec", "pbrMetallicRoughness": { "metallicFactor": 0.0 }, "extensions": { "KHR_materials_specular": { "specularFactor": 0.0 } } }),
            json!({ "name": "glass", "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1] },
                    "extras": { "pbrt": { "type": "glass" } } }),
            json!({ "name": "bad", "extras": { "pbrt": { "type": "plastic", "Ks": "shiny" } } }),
            json!({ "name": "plain" }),
        ];
        let prim =
            |m: usize| json!({ "attributes": { "POSITION": 0 }, "indices": 1, "material": m });
        doc["materials"] = Value::Array(materials.to_vec());
        doc["meshes"] =
            json!([{ "primitives": (0..materials.len()).map(prim).collect::<Vec<_>>() }]);
        let path = write_gltf("extras_pbrt.gltf", doc, &bin);
        let (scene, report) = load_gltf_with_report(&path, None).unwrap();
        let m = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap();
        let params = |name: &str| m(name).params_at(Vec2::ZERO);

        let wall = params("wall");
        assert_eq!(wall.specular, Specular::None);
        assert_eq!(wall.diffuse, Vec3::new(0.725, 0.71, 0.68));

        let bunny = params("bunny");
        assert_eq!(
            bunny.specular,
            Specular::PbrtPlastic {
                ks: Vec3::splat(0.7)
            }
        );
        assert_eq!(bunny.diffuse, Vec3::new(0.3, 0.1, 0.2));
        assert!(
            (bunny.alpha - 0.008).abs() < 1e-7,
            "α = roughness without remapping"
        );

        // pbrt-v3's defaults: Kd = Ks = 0.25, remapped roughness
        let Model::PbrtPlastic { ks, alpha } = m("remapped").model else {
            panic!("plastic")
        };
        assert_eq!(
            (ks, m("remapped").base_color),
            (Vec3::splat(0.25), Vec3::splat(0.25))
        );
        assert!((alpha - render_core::bsdf::plastic::roughness_to_alpha(0.1)).abs() < 1e-7);

        assert_eq!(params("no-spec").specular, Specular::None);
        assert!(matches!(params("plain").specular, Specular::Schlick { .. }));
        for name in ["glass", "bad"] {
            assert_eq!(m(name).model, Model::MetallicRoughness, "{name}");
            assert!(matches!(params(name).specular, Specular::Schlick { .. }));
            assert!(
                report
                    .warnings
                    .iter()
                    .any(|w| w.contains(&format!("`{name}`")) && w.contains("extras.pbrt")),
                "{name}: {:?}",
                report.warnings
            );
        }
    }

    fn shared_scene(rel: &str) -> Option<PathBuf> {
        let p = PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/scenes/"
        ))
        .join(rel);
        if p.exists() {
            Some(p)
        } else {
            eprintln!("skipped: {} is not present", p.display());
            None
        }
    }

    #[test]
    fn bisml_cornell_loads_with_its_sphere_lights() {
        let Some(path) = shared_scene("bisml_cornell/bisml_cornell.glb") else {
            return;
        };
        let scene = load_gltf(&path, None).unwrap();
        assert_eq!(scene.stats.sphere_lights, 1494);
        assert_eq!(scene.stats.point_lights + scene.stats.triangle_lights, 0);
        assert_eq!(
            scene.triangles.len() + scene.stats.degenerate_triangles_skipped,
            119_461
        );
        assert!(scene.stats.degenerate_triangles_skipped < 10);
        for l in &scene.lights {
            let LightShape::Sphere { radius, .. } = l.shape else {
                panic!("not a sphere light")
            };
            assert_eq!(radius, 0.001);
        }
        // The right wall's 831 lights have radiance (300, 180, 225).
        let right = scene
            .lights
            .iter()
            .filter(|l| {
                (l.emission - Vec3::new(300.0, 180.0, 225.0))
                    .abs()
                    .max_element()
                    < 0.01
            })
            .count();
        assert_eq!(right, 831);
        let cam = scene.camera(None).unwrap();
        assert!((cam.position - Vec3::new(0.0, 1.0, 6.8)).length() < 1e-5);
        assert!((cam.yfov - 19.5f32.to_radians()).abs() < 1e-5);
        assert_eq!((cam.width, cam.height), (512, 512));
        // The README's camera check: this light lands at raster (82.6, 94.9) of 1024², top left.
        let d = Vec3::new(-0.999, 1.970, -0.132) - cam.position;
        let right = cam.forward.cross(cam.up);
        let tan = (0.5 * cam.yfov).tan();
        let sx = d.dot(right) / d.dot(cam.forward) / tan;
        let sy = d.dot(cam.up) / d.dot(cam.forward) / tan;
        let raster = Vec2::new((sx + 1.0) * 512.0, (1.0 - sy) * 512.0);
        assert!((raster - Vec2::new(82.6, 94.9)).length() < 0.2, "{raster}");
        // And the camera's own ray through that raster position points at the light.
        let dir = cam.ray_direction(raster / 1024.0, 1.0);
        assert!(dir.dot(d.normalize()) > 1.0 - 1e-6);
    }

    #[test]
    fn toycar_lights_only_where_its_emissive_texture_is_not_black() {
        let Some(path) = shared_scene("car_toycar/ToyCar.glb") else {
            return;
        };
        let (scene, report) = load_gltf_with_report(&path, None).unwrap();
        let s = &scene.stats;
        eprintln!("{s:?}\n{:?}", report.warnings);
        assert_eq!(
            scene.triangles.len() + s.degenerate_triangles_skipped,
            108_936
        );
        assert!(
            s.triangle_lights > 0 && s.black_emissive_triangles > 0,
            "{s:?}"
        );
        assert!(s.triangle_lights < 88_837 / 2, "{s:?}");
        assert_eq!(scene.cameras.len(), 8);
        assert_eq!(scene.stats.warnings, report.warnings);
        assert!(
            report.warnings.iter().any(|w| w.contains("transmission")),
            "{:?}",
            report.warnings
        );
    }

    #[test]
    fn every_shared_scene_loads_with_its_triangle_count() {
        // (file, triangles in the SOURCES.md table, lights expected)
        let table = [
            ("lamp_lights_punctual/LightsPunctualLamp.glb", 6_000),
            ("lamp_stained_glass/StainedGlassLamp.glb", 35_132),
            ("emissive_strength_test/EmissiveStrengthTest.glb", 90),
            ("cornell_box/cornell_box.glb", 32),
            ("staircase_wooden/staircase.glb", 262_663),
            ("staircase_modern_hall/staircase2.glb", 31_247),
            ("veach_mis/veach_mis.glb", 11_956),
            ("stanford_bunny/stanford_bunny.glb", 69_451),
            ("stanford_happy_buddha/happy_buddha_100k.glb", 100_000),
            ("stanford_dragon/stanford_dragon_100k.glb", 100_000),
        ];
        for (file, triangles) in table {
            let Some(path) = shared_scene(file) else {
                continue;
            };
            let scene = load_gltf(&path, None).unwrap_or_else(|e| panic!("{file}: {e}"));
            let s = &scene.stats;
            assert_eq!(
                scene.triangles.len() + s.degenerate_triangles_skipped,
                triangles,
                "{file}"
            );
            if file.contains("EmissiveStrength") {
                assert_eq!(s.triangle_lights, 60);
            }
            if file.contains("LightsPunctualLamp") {
                assert_eq!(s.point_lights, 5);
            }
        }
    }

    #[test]
    fn external_buffers_and_texture_transforms() {
        let (mut doc, bin) = triangle_doc(TRI);
        let bin_path = temp_path("external.bin");
        std::fs::write(&bin_path, &bin).unwrap();
        doc["buffers"] = json!([{ "byteLength": bin.len(), "uri": "external.bin" }]);
        // A 1×1 base colour texture whose transform scales uv by 2 and shifts it by (0.5, 0).
        let mut png = Vec::new();
        image::RgbImage::from_raw(1, 1, vec![255, 255, 255])
            .unwrap()
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        std::fs::write(temp_path("white.png"), &png).unwrap();
        doc["images"] = json!([{ "uri": "white.png" }]);
        doc["textures"] = json!([{ "source": 0 }]);
        doc["extensionsUsed"] = json!(["KHR_texture_transform"]);
        doc["materials"] = json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0,
            "extensions": { "KHR_texture_transform": { "scale": [2.0, 2.0], "offset": [0.5, 0.0] } } } } }]);
        doc["meshes"][0]["primitives"][0]["material"] = json!(0);
        let path = temp_path("external.gltf");
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        let scene = load_gltf(&path, None).unwrap();
        // uv (0.75, 0.5) → (2.0, 1.0)
        assert_eq!(scene.triangles[0].uv[1], Vec2::new(2.0, 1.0));
        assert!(scene.materials[0].base_color_texture.is_some());
        // Without the external buffer: an error naming the problem.
        std::fs::remove_file(&bin_path).unwrap();
        let e = err(load_gltf(&path, None));
        assert!(
            matches!(e, SceneError::Gltf { .. }) && e.to_string().contains("buffers"),
            "{e}"
        );
    }
}
