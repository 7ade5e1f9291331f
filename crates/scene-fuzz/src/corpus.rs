//! The valid inputs every case starts from: small glTF scenes built here (as `.gltf` with a
//! base64 buffer and as `.glb`), the small real files of `../shared/scenes/` when present, and
//! composition TOMLs that place a glTF file of the case's directory.
use serde_json::{Value, json};

/// What a case's file is read as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Gltf,
    Glb,
    Toml,
}

impl Kind {
    pub fn extension(self) -> &'static str {
        match self {
            Kind::Gltf => "gltf",
            Kind::Glb => "glb",
            Kind::Toml => "toml",
        }
    }
}

/// A glTF document and its binary buffer 0 (the GLB BIN chunk, or a base64 data URI).
#[derive(Clone, Debug)]
pub struct GltfSeed {
    pub doc: Value,
    pub bin: Vec<u8>,
}

/// One valid input.
#[derive(Clone, Debug)]
pub enum Seed {
    Gltf { name: String, gltf: GltfSeed },
    Glb { name: String, gltf: GltfSeed },
    Toml { name: String, text: String },
}

impl Seed {
    pub fn name(&self) -> &str {
        match self {
            Seed::Gltf { name, .. } | Seed::Glb { name, .. } | Seed::Toml { name, .. } => name,
        }
    }

    pub fn kind(&self) -> Kind {
        match self {
            Seed::Gltf { .. } => Kind::Gltf,
            Seed::Glb { .. } => Kind::Glb,
            Seed::Toml { .. } => Kind::Toml,
        }
    }
}

/// The glTF file every composition seed places (written into the case directory once).
pub const PLACED_GLB: &str = "placed.glb";

/// Shared files small enough to load thousands of times (path under `../shared/scenes/`).
const SHARED: [&str; 2] = [
    "cornell_box/cornell_box.glb",
    "emissive_strength_test/EmissiveStrengthTest.glb",
];

/// Every seed; the shared ones only where `shared_scenes` holds them (notices say which are
/// absent).
pub fn seeds(shared_scenes: Option<&std::path::Path>, notices: &mut Vec<String>) -> Vec<Seed> {
    let studio = studio();
    let mut seeds = vec![
        Seed::Gltf {
            name: "studio.gltf".into(),
            gltf: studio.clone(),
        },
        Seed::Glb {
            name: "studio.glb".into(),
            gltf: studio,
        },
        Seed::Gltf {
            name: "textured.gltf".into(),
            gltf: textured(),
        },
    ];
    for (name, text) in compositions() {
        seeds.push(Seed::Toml {
            name: name.into(),
            text: text.into(),
        });
    }
    for rel in SHARED {
        let Some(dir) = shared_scenes else {
            notices.push(format!("skipped seed {rel}: ../shared/scenes is absent"));
            continue;
        };
        match std::fs::read(dir.join(rel))
            .ok()
            .and_then(|b| parse_glb(&b))
        {
            Some(gltf) => seeds.push(Seed::Glb {
                name: rel.into(),
                gltf,
            }),
            None => notices.push(format!("skipped seed {rel}: absent or not a plain GLB")),
        }
    }
    seeds
}

/// The bytes of `gltf` as a `.gltf` (buffer 0 a base64 data URI) or a `.glb`.
pub fn encode(gltf: &GltfSeed, kind: Kind) -> Vec<u8> {
    let mut doc = gltf.doc.clone();
    match kind {
        Kind::Glb => {
            if let Some(b) = doc.pointer_mut("/buffers/0").and_then(Value::as_object_mut) {
                b.remove("uri");
            }
            glb(&serde_json::to_vec(&doc).unwrap_or_default(), &gltf.bin)
        }
        _ => {
            if let Some(b) = doc.pointer_mut("/buffers/0").and_then(Value::as_object_mut) {
                b.insert(
                    "uri".into(),
                    format!(
                        "data:application/octet-stream;base64,{}",
                        base64::encode(&gltf.bin)
                    )
                    .into(),
                );
            }
            serde_json::to_vec(&doc).unwrap_or_default()
        }
    }
}

/// A GLB container: 12-byte header, JSON chunk, BIN chunk (each padded to 4 bytes).
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |n: usize| n.div_ceil(4) * 4;
    let (jl, bl) = (pad(json.len()), pad(bin.len()));
    let total = 12 + 8 + jl + if bin.is_empty() { 0 } else { 8 + bl };
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((jl as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.resize(20 + jl, b' ');
    if !bin.is_empty() {
        out.extend((bl as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
        out.resize(total, 0);
    }
    out
}

/// The JSON and BIN chunks of a GLB without external buffers.
fn parse_glb(b: &[u8]) -> Option<GltfSeed> {
    let u32_at = |i: usize| Some(u32::from_le_bytes(b.get(i..i + 4)?.try_into().ok()?) as usize);
    if b.get(0..4)? != b"glTF" {
        return None;
    }
    let jl = u32_at(12)?;
    let doc: Value = serde_json::from_slice(b.get(20..20 + jl)?).ok()?;
    let bin = match u32_at(20 + jl) {
        Some(bl) => b.get(28 + jl..28 + jl + bl)?.to_vec(),
        None => Vec::new(),
    };
    let external = doc["buffers"]
        .as_array()
        .is_some_and(|bs| bs.iter().any(|x| x.get("uri").is_some()));
    (!external).then_some(GltfSeed { doc, bin })
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A floor quad, a glossy box-ish panel, an emissive triangle, a node hierarchy with matrix and
/// TRS transforms, a perspective camera and three punctual lights (sphere, point, spot), with
/// u16 indices, normals and UVs.
// The quaternion is spelt to seven digits, as an exporter writes it into a file.
#[allow(clippy::approx_constant)]
pub fn studio() -> GltfSeed {
    // accessor 0: floor positions (4), 1: floor normals, 2: floor uvs, 3: floor indices (u16),
    // 4: emitter positions (3), 5: emitter indices (u32)
    let mut bin = f32_bytes(&[
        -2.0, 0.0, -2.0, 2.0, 0.0, -2.0, 2.0, 0.0, 2.0, -2.0, 0.0, 2.0,
    ]); // 0..48
    bin.extend(f32_bytes(&[0.0, 1.0, 0.0].repeat(4))); // 48..96
    bin.extend(f32_bytes(&[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0])); // 96..128
    bin.extend([0u16, 2, 1, 0, 3, 2].iter().flat_map(|i| i.to_le_bytes())); // 128..140
    bin.extend([0u8; 4]); // 140..144
    bin.extend(f32_bytes(&[-0.3, 1.5, 0.0, 0.3, 1.5, 0.0, 0.0, 1.5, 0.4])); // 144..180
    bin.extend([0u32, 2, 1].iter().flat_map(|i| i.to_le_bytes())); // 180..192
    let doc = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
        "extensions": { "KHR_lights_punctual": { "lights": [
            { "type": "point", "color": [1.0, 0.9, 0.8], "intensity": 5.0 },
            { "type": "spot", "intensity": 8.0, "range": 10.0,
              "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } },
            { "type": "directional", "intensity": 0.5 }
        ] } },
        "scene": 0,
        "scenes": [{ "nodes": [0, 3, 4, 5, 6] }],
        "nodes": [
            { "name": "floor", "mesh": 0, "children": [1] },
            { "name": "emitter", "mesh": 1, "translation": [0.0, 0.2, 0.0],
              "rotation": [0.0, 0.0, 0.0, 1.0], "scale": [1.0, 1.0, 1.0], "children": [2] },
            { "name": "panel", "mesh": 2,
              "matrix": [0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0.5, 0.5, -1.0, 1] },
            { "name": "cam", "camera": 0, "translation": [0.0, 1.0, 4.0] },
            { "name": "bulb", "translation": [1.0, 2.0, 0.0], "extras": { "radius": 0.05 },
              "extensions": { "KHR_lights_punctual": { "light": 0 } } },
            { "name": "spot", "translation": [-1.0, 2.0, 0.0],
              "rotation": [-0.7071068, 0.0, 0.0, 0.7071068],
              "extensions": { "KHR_lights_punctual": { "light": 1 } } },
            { "name": "sun", "rotation": [-0.5, 0.0, 0.0, 0.8660254],
              "extensions": { "KHR_lights_punctual": { "light": 2 } } }
        ],
        "cameras": [{ "name": "main", "type": "perspective",
                      "perspective": { "yfov": 0.8, "znear": 0.01, "zfar": 100.0, "aspectRatio": 1.5 } }],
        "meshes": [
            { "name": "floor", "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 },
                                                "indices": 3, "material": 0 }] },
            { "name": "emitter", "primitives": [{ "attributes": { "POSITION": 4 }, "indices": 5, "material": 1 }] },
            { "name": "panel", "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1 }, "indices": 3,
                                                "material": 2, "mode": 4 }] }
        ],
        "materials": [
            { "name": "floor", "pbrMetallicRoughness": { "baseColorFactor": [0.6, 0.6, 0.6, 1.0],
                                                          "metallicFactor": 0.0, "roughnessFactor": 0.4 } },
            { "name": "lamp", "emissiveFactor": [1.0, 0.8, 0.6], "doubleSided": true,
              "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } } },
            { "name": "metal", "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.7, 0.5, 1.0],
                                                          "metallicFactor": 1.0, "roughnessFactor": 0.1 } }
        ],
        "buffers": [{ "byteLength": bin.len() }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48, "byteStride": 12 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 96, "byteLength": 32 },
            { "buffer": 0, "byteOffset": 128, "byteLength": 12 },
            { "buffer": 0, "byteOffset": 144, "byteLength": 36 },
            { "buffer": 0, "byteOffset": 180, "byteLength": 12 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [-2.0, 0.0, -2.0], "max": [2.0, 0.0, 2.0] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" },
            { "bufferView": 4, "componentType": 5126, "count": 3, "type": "VEC3",
              "min": [-0.3, 1.5, 0.0], "max": [0.3, 1.5, 0.4] },
            { "bufferView": 5, "componentType": 5125, "count": 3, "type": "SCALAR" }
        ]
    });
    GltfSeed { doc, bin }
}

/// The studio's floor with a 2×2 PNG base colour and emissive texture (image in buffer 0),
/// a texture transform and a sampler.
pub fn textured() -> GltfSeed {
    let mut base = studio();
    let mut png = Vec::new();
    let img = image::RgbaImage::from_raw(
        2,
        2,
        vec![
            255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128,
        ],
    )
    .expect("2×2 RGBA");
    image::DynamicImage::ImageRgba8(img)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("PNG encoding of a 2×2 image");
    let offset = base.bin.len();
    base.bin.extend(&png);
    base.bin.resize(base.bin.len().div_ceil(4) * 4, 0);
    let doc = &mut base.doc;
    doc["buffers"][0]["byteLength"] = base.bin.len().into();
    doc["bufferViews"]
        .as_array_mut()
        .expect("bufferViews")
        .push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": png.len() }));
    doc["images"] = json!([{ "bufferView": 6, "mimeType": "image/png" }]);
    doc["samplers"] =
        json!([{ "magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 33648 }]);
    doc["textures"] = json!([{ "source": 0, "sampler": 0 }]);
    doc["extensionsUsed"]
        .as_array_mut()
        .expect("extensionsUsed")
        .push("KHR_texture_transform".into());
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({
        "index": 0,
        "extensions": { "KHR_texture_transform": { "offset": [0.5, 0.0], "rotation": 0.3, "scale": [2.0, 2.0] } }
    });
    doc["materials"][1]["emissiveTexture"] = json!({ "index": 0, "texCoord": 0 });
    // The emitter's 3 vertices read the floor's first 3 uvs (accessor 6).
    doc["accessors"]
        .as_array_mut()
        .expect("accessors")
        .push(json!({ "bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2" }));
    doc["meshes"][1]["primitives"][0]["attributes"]["TEXCOORD_0"] = 6.into();
    base
}

/// Composition seeds, each placing [`PLACED_GLB`]: every layout and shape, overrides, a
/// ground and a camera.
fn compositions() -> Vec<(&'static str, &'static str)> {
    vec![
        (
            "grid-spheres.toml",
            r#"name = "fuzz-grid"
[[gltf]]
path = "placed.glb"
fit_size = 2.0
rotate_y_deg = 30.0
[[gltf.override]]
name = "floor"
base_color = [0.7, 0.6, 0.5]
metallic = 0.0
roughness = 0.2
specular = 0.5
drop_textures = true
[ground]
y = -0.01
size = 8.0
base_color = [0.4, 0.4, 0.4]
roughness = 0.3
metallic = 0.0
[[lights]]
layout = "grid"
shape = "sphere"
count = 16
center = [0.0, 3.0, 0.0]
extent = [4.0, 0.0, 4.0]
size = 0.02
power = 100.0
[camera]
eye = [3.0, 2.0, 4.0]
target = [0.0, 0.5, 0.0]
yfov_deg = 40.0
width = 64
height = 48
"#,
        ),
        (
            "random-quads.toml",
            r#"[[gltf]]
path = "placed.glb"
scale = 0.5
translate = [0.0, 0.0, 1.0]
keep_cameras = true
[[lights]]
layout = "random"
shape = "quad"
count = 8
center = [0.0, 2.5, 0.0]
extent = [3.0, 0.5, 3.0]
size = 0.05
power = 50.0
color = [1.0, 0.9, 0.8]
seed = 3
[[lights]]
layout = "ring"
shape = "sphere"
count = 12
center = [0.0, 1.0, 0.0]
extent = [2.0, 0.0, 0.0]
size = 0.01
power = 20.0
"#,
        ),
    ]
}
