//! Writes a loaded [`Scene`] as a binary glTF (`.glb`), so that a scene read from another
//! format (pbrt) can be inspected in any glTF viewer and loaded back by [`crate::gltf_reader`]:
//! - triangles in world space, one primitive per material (positions, normals, uvs);
//! - materials as metallic-roughness, emission as emissiveFactor × `KHR_materials_emissive_strength`,
//!   `KHR_materials_specular` where the specular factor is not 1, and `extras.pbrt` where glTF
//!   cannot say the model: `{"type": "matte", "Kd"}` for pure Lambert, `{"type": "plastic", "Kd",
//!   "Ks", "roughness", "remaproughness": false}` for pbrt-v3 plastic; a rough dielectric as
//!   `KHR_materials_transmission` (factor 1) with `KHR_materials_ior`, its tint the base colour;
//! - sphere lights as `KHR_lights_punctual` point lights with `extras.radius` (intensity =
//!   L·π·r², the convention of `../shared/scenes/bisml_cornell`), point, spot and directional
//!   lights as themselves;
//! - cameras (a mirrored camera cannot be said in glTF: written unmirrored, with a warning).
//!
//! Textures are not written (a warning names the materials that had one).
use glam::{Mat3, Quat, Vec3};
use render_core::error::SceneError;
use render_core::light::LightShape;
use render_core::material::{Material, Model};
use render_core::scene::Scene;
use serde_json::{Value, json};
use std::f32::consts::PI;
use std::path::Path;

fn colour_and_strength(c: Vec3) -> (Vec3, f32) {
    let m = c.max_element();
    if m > 0.0 {
        (c / m, m)
    } else {
        (Vec3::ZERO, 0.0)
    }
}

fn pbrt_extras(m: &Material) -> Option<Value> {
    match m.model {
        Model::PbrtPlastic { ks, alpha } => Some(json!({ "pbrt": {
            "type": "plastic", "Kd": m.base_color.to_array(), "Ks": ks.to_array(),
            "roughness": alpha, "remaproughness": false } })),
        Model::MetallicRoughness if m.specular <= 0.0 && m.metallic <= 0.0 => {
            Some(json!({ "pbrt": { "type": "matte", "Kd": m.base_color.to_array() } }))
        }
        _ => None,
    }
}

fn material_json(m: &Material) -> Value {
    let (metallic, roughness) = match m.model {
        Model::PbrtPlastic { alpha, .. } | Model::Dielectric { alpha, .. } => {
            (0.0, alpha.max(0.0).sqrt())
        }
        Model::MetallicRoughness => (m.metallic, m.roughness),
    };
    let b = m.base_color;
    let mut v = json!({
        "name": m.name,
        "pbrMetallicRoughness": { "baseColorFactor": [b.x, b.y, b.z, 1.0],
                                  "metallicFactor": metallic, "roughnessFactor": roughness },
        "doubleSided": m.double_sided,
    });
    let mut ext = serde_json::Map::new();
    if m.is_emissive() {
        let (c, s) = colour_and_strength(m.emission);
        v["emissiveFactor"] = json!(c.to_array());
        if s != 1.0 {
            ext.insert(
                "KHR_materials_emissive_strength".into(),
                json!({ "emissiveStrength": s }),
            );
        }
    }
    if m.model == Model::MetallicRoughness && m.specular != 1.0 {
        ext.insert(
            "KHR_materials_specular".into(),
            json!({ "specularFactor": m.specular }),
        );
    }
    if let Model::Dielectric { ior, .. } = m.model {
        ext.insert(
            "KHR_materials_transmission".into(),
            json!({ "transmissionFactor": 1.0 }),
        );
        ext.insert("KHR_materials_ior".into(), json!({ "ior": ior }));
    }
    if !ext.is_empty() {
        v["extensions"] = Value::Object(ext);
    }
    if let Some(e) = pbrt_extras(m) {
        v["extras"] = e;
    }
    v
}

/// Rotation taking −Z to `dir` (and +Y as close to `up` as it can).
fn rotation_towards(dir: Vec3, up: Vec3) -> Quat {
    let back = -dir.normalize();
    let up = if up.cross(back).length_squared() < 1e-8 {
        back.any_orthonormal_vector()
    } else {
        up
    };
    let right = up.cross(back).normalize();
    let up = back.cross(right);
    Quat::from_mat3(&Mat3::from_cols(right, up, back)).normalize()
}

/// Writes `scene` to `path` as a `.glb`; returns the warnings.
pub fn write_glb(scene: &Scene, path: &Path) -> Result<Vec<String>, SceneError> {
    let mut warnings = Vec::new();
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut push = |bin: &mut Vec<u8>, data: &[f32], n: usize, ty: &str, minmax: bool| -> usize {
        let offset = bin.len();
        bin.extend(data.iter().flat_map(|x| x.to_le_bytes()));
        views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": data.len() * 4 }));
        let mut a =
            json!({ "bufferView": views.len() - 1, "componentType": 5126, "count": n, "type": ty });
        if minmax {
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for p in data.chunks_exact(3) {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        accessors.push(a);
        accessors.len() - 1
    };

    // one primitive per material, non-indexed
    let mut by_material: Vec<Vec<usize>> = vec![Vec::new(); scene.materials.len()];
    for (i, t) in scene.triangles.iter().enumerate() {
        by_material[t.material as usize].push(i);
    }
    let mut primitives = Vec::new();
    for (m, tris) in by_material.iter().enumerate() {
        if tris.is_empty() {
            continue;
        }
        let (mut p, mut n, mut uv) = (Vec::new(), Vec::new(), Vec::new());
        for &i in tris {
            let t = &scene.triangles[i];
            for k in 0..3 {
                p.extend(t.p[k].to_array());
                n.extend(t.n[k].to_array());
                uv.extend(t.uv[k].to_array());
            }
        }
        let count = tris.len() * 3;
        let ap = push(&mut bin, &p, count, "VEC3", true);
        let an = push(&mut bin, &n, count, "VEC3", false);
        let auv = push(&mut bin, &uv, count, "VEC2", false);
        primitives.push(json!({ "attributes": { "POSITION": ap, "NORMAL": an, "TEXCOORD_0": auv }, "material": m }));
    }
    let materials: Vec<Value> = scene.materials.iter().map(material_json).collect();
    for m in &scene.materials {
        if m.base_color_texture.is_some()
            || m.metallic_roughness_texture.is_some()
            || m.emission_texture.is_some()
        {
            warnings.push(format!("material `{}`: textures are not written", m.name));
        }
    }

    let mut nodes = Vec::new();
    let mut root_nodes = Vec::new();
    let mut meshes = Vec::new();
    if !primitives.is_empty() {
        meshes.push(json!({ "name": scene.name, "primitives": primitives }));
        nodes.push(json!({ "name": "geometry", "mesh": 0 }));
        root_nodes.push(nodes.len() - 1);
    }
    let mut lights = Vec::new();
    for (i, l) in scene.lights.iter().enumerate() {
        let (light, node) = match l.shape {
            LightShape::Triangle { .. } => continue, // written as emissive material
            LightShape::Sphere { center, radius } => {
                let (c, s) = colour_and_strength(l.emission * (PI * radius * radius));
                (
                    json!({ "type": "point", "color": c.to_array(), "intensity": s }),
                    json!({ "name": format!("sphere light {i}"), "translation": center.to_array(),
                            "extras": { "radius": radius, "radiance": l.emission.to_array() } }),
                )
            }
            LightShape::Point { position } => {
                let (c, s) = colour_and_strength(l.emission);
                match l.spot {
                    None => (
                        json!({ "type": "point", "color": c.to_array(), "intensity": s }),
                        json!({ "name": format!("point light {i}"), "translation": position.to_array() }),
                    ),
                    Some(spot) => (
                        json!({ "type": "spot", "color": c.to_array(), "intensity": s,
                                "spot": { "innerConeAngle": spot.cos_inner.clamp(-1.0, 1.0).acos(),
                                          "outerConeAngle": spot.cos_outer.clamp(-1.0, 1.0).acos() } }),
                        json!({ "name": format!("spot light {i}"), "translation": position.to_array(),
                                "rotation": rotation_towards(spot.direction, Vec3::Y).to_array() }),
                    ),
                }
            }
        };
        if matches!(l.shape, LightShape::Sphere { .. }) && l.spot.is_some() {
            warnings.push("a sphere spot light is written without its cone".into());
        }
        lights.push(light);
        let mut node = node;
        node["extensions"] = json!({ "KHR_lights_punctual": { "light": lights.len() - 1 } });
        nodes.push(node);
        root_nodes.push(nodes.len() - 1);
    }
    for (i, d) in scene.distant_lights.iter().enumerate() {
        let (c, s) = colour_and_strength(d.irradiance);
        lights.push(json!({ "type": "directional", "color": c.to_array(), "intensity": s }));
        nodes.push(json!({ "name": format!("directional light {i}"),
                           "rotation": rotation_towards(-d.direction, Vec3::Y).to_array(),
                           "extensions": { "KHR_lights_punctual": { "light": lights.len() - 1 } } }));
        root_nodes.push(nodes.len() - 1);
    }
    let mut cameras = Vec::new();
    for c in &scene.cameras {
        if c.mirrored {
            warnings.push(format!(
                "camera `{}` is mirrored (a left-handed frame), which glTF cannot say: written unmirrored",
                c.name
            ));
        }
        cameras.push(json!({ "name": c.name, "type": "perspective",
            "perspective": { "yfov": c.yfov, "aspectRatio": c.width as f32 / c.height as f32, "znear": 1e-3 } }));
        nodes.push(json!({ "name": c.name, "camera": cameras.len() - 1,
                           "translation": c.position.to_array(),
                           "rotation": rotation_towards(c.forward, c.up).to_array() }));
        root_nodes.push(nodes.len() - 1);
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let mut used = vec!["KHR_materials_emissive_strength", "KHR_materials_specular"];
    if !lights.is_empty() {
        used.push("KHR_lights_punctual");
    }
    if scene
        .materials
        .iter()
        .any(|m| matches!(m.model, Model::Dielectric { .. }))
    {
        used.extend(["KHR_materials_transmission", "KHR_materials_ior"]);
    }
    let mut doc = json!({
        "asset": { "version": "2.0", "generator": "manylights convert" },
        "extensionsUsed": used,
        "scene": 0,
        "scenes": [{ "nodes": root_nodes }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{ "byteLength": bin.len() }],
    });
    if !lights.is_empty() {
        doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": lights } });
    }
    if !cameras.is_empty() {
        doc["cameras"] = Value::Array(cameras);
    }
    if let Some(c) = scene.cameras.first() {
        doc["extras"] = json!({ "film": { "width": c.width, "height": c.height } });
    }
    if let Some(pbrt) = crate::gltf_reader::hints_extras(&scene.render_hints) {
        doc["extras"]["pbrt"] = pbrt;
    }
    let mut text = serde_json::to_vec(&doc).map_err(|e| io_err(path, e.to_string()))?;
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    render_core::output::write_atomically(path, |tmp| {
        std::fs::write(tmp, &out).map_err(|e| e.to_string())
    })
    .map_err(|e| io_err(path, e))?;
    Ok(warnings)
}

fn io_err(path: &Path, message: String) -> SceneError {
    SceneError::Io {
        path: path.display().to_string(),
        message,
    }
}
