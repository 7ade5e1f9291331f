//! Scene composition files (TOML): real glTF (or pbrt, `.pbrt`) assets placed in a studio with a ground, material
//! overrides where a study needs glossiness, light layouts of many small spheres or quads, and
//! a camera. Paths are relative to the composition file.
//!
//! ```toml
//! name = "toycar"
//! [[gltf]]
//! path = "../../../shared/scenes/car_toycar/ToyCar.glb"
//! fit_size = 4.0            # scale so the largest extent is 4, centred on the origin, resting on y = 0
//! rotate_y_deg = 30
//! [[gltf.override]]         # every material whose name contains `name` (all when absent)
//! roughness = 0.15
//! [ground]
//! size = 30.0
//! roughness = 0.2
//! [[lights]]
//! layout = "grid"           # grid | random | ring
//! shape = "sphere"          # sphere | quad (one-sided, facing down)
//! count = 4096
//! center = [0.0, 4.0, 0.0]
//! extent = [12.0, 0.0, 12.0]
//! size = 0.01               # sphere radius or quad half-size
//! power = 2000.0            # total emitted power in W, shared equally
//! [camera]
//! eye = [6.0, 3.0, 8.0]
//! target = [0.0, 0.8, 0.0]
//! ```
mod checks;

use crate::builtin::mesh::Mesh;
use crate::gltf_reader::add_gltf;
use glam::{Mat4, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg32;
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::{Scene, SceneBuilder};
use serde::Deserialize;
use std::f32::consts::PI;
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Composition {
    name: Option<String>,
    #[serde(default)]
    gltf: Vec<GltfPart>,
    ground: Option<Ground>,
    #[serde(default)]
    lights: Vec<LightLayout>,
    camera: Option<CameraSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GltfPart {
    path: String,
    /// Uniform scale so the largest extent equals this, centred on `translate`, resting on its y.
    fit_size: Option<f32>,
    #[serde(default)]
    scale: Option<f32>,
    #[serde(default)]
    translate: [f32; 3],
    #[serde(default)]
    rotate_y_deg: f32,
    /// Keep the file's own cameras (they are in the file's frame, so only without fit/scale).
    #[serde(default)]
    keep_cameras: bool,
    #[serde(default, rename = "override")]
    overrides: Vec<MaterialOverride>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialOverride {
    /// Substring of the material name; every material of the part when absent.
    name: Option<String>,
    base_color: Option<[f32; 3]>,
    metallic: Option<f32>,
    roughness: Option<f32>,
    specular: Option<f32>,
    /// Drop base colour and metallic-roughness textures so the factors rule.
    #[serde(default)]
    drop_textures: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Ground {
    #[serde(default)]
    y: f32,
    size: f32,
    #[serde(default = "grey")]
    base_color: [f32; 3],
    #[serde(default = "one")]
    roughness: f32,
    #[serde(default)]
    metallic: f32,
}

fn grey() -> [f32; 3] {
    [0.5; 3]
}

fn one() -> f32 {
    1.0
}

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "lowercase")]
enum Layout {
    Grid,
    Random,
    Ring,
}

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "lowercase")]
enum Shape {
    Sphere,
    Quad,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightLayout {
    layout: Layout,
    shape: Shape,
    count: usize,
    center: [f32; 3],
    /// Grid and random: the box the lights fill; ring: x is the ring radius (in the xz plane).
    extent: [f32; 3],
    /// Sphere radius or quad half-size.
    size: f32,
    /// Total emitted power (W), shared equally.
    power: f32,
    #[serde(default = "white")]
    color: [f32; 3],
    #[serde(default)]
    seed: u64,
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    eye: [f32; 3],
    target: [f32; 3],
    #[serde(default = "fov")]
    yfov_deg: f32,
    #[serde(default = "width")]
    width: u32,
    #[serde(default = "height")]
    height: u32,
}

fn fov() -> f32 {
    40.0
}

fn width() -> u32 {
    320
}

fn height() -> u32 {
    240
}

fn bad(path: &Path, message: impl Into<String>) -> SceneError {
    SceneError::Composition {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// Loads a composition file.
pub fn load_composition(path: &Path) -> Result<Scene, SceneError> {
    let io = |message: String| SceneError::Io {
        path: path.display().to_string(),
        message,
    };
    crate::gltf_reader::regular_file(path).map_err(io)?;
    let text = std::fs::read_to_string(path).map_err(|e| io(e.to_string()))?;
    let comp: Composition = toml::from_str(&text).map_err(|e| {
        // toml's message spans several lines (location, excerpt, reason): keep it on one.
        let text = e.to_string();
        let parts: Vec<&str> = text
            .lines()
            .map(str::trim)
            .filter(|l| {
                !l.is_empty() && !l.starts_with('|') && !l.chars().all(|c| c == '^' || c == ' ')
            })
            .collect();
        bad(path, parts.join(": "))
    })?;
    checks::check(&comp).map_err(|m| bad(path, m))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut b = SceneBuilder::new(comp.name.as_deref().unwrap_or(&path.display().to_string()));
    for part in &comp.gltf {
        add_part(&mut b, dir, part)?;
    }
    if let Some(g) = &comp.ground {
        let m = b.add_material(Material::simple(
            "ground",
            Vec3::from(g.base_color),
            g.metallic,
            g.roughness,
        ))?;
        Mesh::plane(Vec3::new(0.0, g.y, 0.0), g.size, g.size).add_to(&mut b, "ground", m)?;
    }
    for (k, l) in comp.lights.iter().enumerate() {
        add_lights(&mut b, l).map_err(|e| match e {
            SceneError::BadLight { message, .. } => bad(path, format!("lights[{k}]: {message}")),
            other => other.in_file(path),
        })?;
    }
    if let Some(c) = &comp.camera {
        let camera = Camera::look_at(
            "main",
            Vec3::from(c.eye),
            Vec3::from(c.target),
            Vec3::Y,
            c.yfov_deg.to_radians(),
            c.width,
            c.height,
        )
        .map_err(|e| bad(path, format!("[camera]: {e}")))?;
        b.add_camera(camera);
    }
    b.build().map_err(|e| e.in_file(path))
}

/// A glTF file, or a pbrt scene (`.pbrt`) placed the same way.
fn add_asset(b: &mut SceneBuilder, file: &Path, transform: Mat4) -> Result<(), SceneError> {
    match crate::FileFormat::of(file)? {
        crate::FileFormat::Pbrt => crate::pbrt::add_pbrt(b, file, transform).map(|_| ()),
        crate::FileFormat::Gltf => add_gltf(b, file, transform).map(|_| ()),
        crate::FileFormat::Composition => Err(bad(
            file,
            "a composition cannot place another composition (place a .gltf, .glb or .pbrt)",
        )),
    }
}

fn add_part(b: &mut SceneBuilder, dir: &Path, part: &GltfPart) -> Result<(), SceneError> {
    let file = dir.join(&part.path);
    let rotation = Mat4::from_rotation_y(part.rotate_y_deg.to_radians());
    let mut transform = Mat4::from_translation(Vec3::from(part.translate))
        * rotation
        * Mat4::from_scale(Vec3::splat(part.scale.unwrap_or(1.0)));
    if let Some(size) = part.fit_size {
        // Measure the asset alone, then scale it to `size`, centred, resting on y = translate.y.
        let mut probe = SceneBuilder::new("probe");
        add_asset(&mut probe, &file, rotation)?;
        let (lo, hi) = probe
            .bounds()
            .ok_or_else(|| bad(&file, "nothing to place"))?;
        let s = size / (hi - lo).max_element().max(1e-12);
        let base = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
        transform = Mat4::from_translation(Vec3::from(part.translate))
            * Mat4::from_scale(Vec3::splat(s))
            * Mat4::from_translation(-base)
            * rotation;
    }
    let first_material = b.material_count();
    add_asset(b, &file, transform)?;
    if !part.keep_cameras {
        b.clear_cameras();
    }
    for m in &mut b.materials_mut()[first_material..] {
        for o in &part.overrides {
            if o.name
                .as_ref()
                .is_some_and(|n| !m.name.contains(n.as_str()))
            {
                continue;
            }
            if let Some(c) = o.base_color {
                m.base_color = Vec3::from(c);
            }
            if let Some(v) = o.metallic {
                m.metallic = v;
            }
            if let Some(v) = o.roughness {
                m.roughness = v;
            }
            if let Some(v) = o.specular {
                m.specular = v;
            }
            if o.drop_textures {
                m.base_color_texture = None;
                m.metallic_roughness_texture = None;
            }
        }
    }
    Ok(())
}

/// The most lights one layout places: four times the largest built-in grid (10⁶), and few
/// enough to build in seconds, so a mistyped count is an error, not an hour-long load.
const MAX_LAYOUT_LIGHTS: usize = 1 << 22;

fn add_lights(b: &mut SceneBuilder, l: &LightLayout) -> Result<(), SceneError> {
    let err = |m: String| SceneError::BadLight {
        what: "layout".into(),
        message: m,
    };
    if l.count == 0
        || !(l.size > 0.0)
        || !l.size.is_finite()
        || !(l.power > 0.0)
        || !l.power.is_finite()
    {
        return Err(err(format!(
            "count {}, size {}, power {} must be positive (and size and power finite)",
            l.count, l.size, l.power
        )));
    }
    if l.count > MAX_LAYOUT_LIGHTS {
        return Err(err(format!(
            "count {} is more than the {MAX_LAYOUT_LIGHTS} lights a layout may place",
            l.count
        )));
    }
    let mut rng = Pcg32::seed_from_u64(l.seed);
    let c = Vec3::from(l.center);
    let e = Vec3::from(l.extent);
    let per_light = l.power / l.count as f32;
    let lum = render_core::colour::luminance(Vec3::from(l.color)).max(1e-6);
    let color = Vec3::from(l.color) / lum;
    let side = (l.count as f32).sqrt().ceil() as usize;
    let quad_material = if l.shape == Shape::Quad {
        // Φ = π L A for a one-sided quad of area (2·size)².
        let radiance = per_light / (PI * 4.0 * l.size * l.size);
        Some(b.add_material(Material {
            emission: color * radiance,
            double_sided: false,
            ..Material::diffuse("layout-quad", Vec3::ZERO)
        })?)
    } else {
        None
    };
    for i in 0..l.count {
        let p = match l.layout {
            Layout::Grid => {
                let (gx, gz) = (i % side, i / side);
                let f = |g: usize| {
                    if side > 1 {
                        g as f32 / (side - 1) as f32 - 0.5
                    } else {
                        0.0
                    }
                };
                c + Vec3::new(f(gx) * e.x, 0.0, f(gz) * e.z)
            }
            Layout::Random => {
                c + (Vec3::new(
                    rng.random::<f32>(),
                    rng.random::<f32>(),
                    rng.random::<f32>(),
                ) - 0.5)
                    * e
            }
            Layout::Ring => {
                let a = 2.0 * PI * i as f32 / l.count as f32;
                c + Vec3::new(a.cos() * e.x, 0.0, a.sin() * e.x)
            }
        };
        match quad_material {
            // Φ = π L · 4π r² for a sphere.
            None => b.add_sphere_light(
                p,
                l.size,
                color * (per_light / (4.0 * PI * PI * l.size * l.size)),
                None,
            )?,
            Some(m) => Mesh::quad(p, Vec3::new(l.size, 0.0, 0.0), Vec3::new(0.0, 0.0, l.size))
                .add_to(b, "layout-quad", m)?,
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
