//! The glTF reader's tests: small files written here, and the shared scenes where present.
use super::meshes::triangle_list;
use super::*;
use crate::scratch::Scratch;
use glam::{Vec2, Vec3};
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

/// Writes `doc` as a .gltf whose buffer 0 holds `bin` as a base64 data URI, in `tmp`.
fn write_gltf(tmp: &Scratch, name: &str, mut doc: Value, bin: &[u8]) -> PathBuf {
    if !bin.is_empty() {
        doc["buffers"] = json!([{ "byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", base64::encode(bin)) }]);
    }
    let path = tmp.path(name);
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
    let tmp = Scratch::new("gltf-tests");
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
    let path = write_gltf(&tmp, "hierarchy.gltf", doc, &bin);
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
    let tmp = Scratch::new("gltf-tests");
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
    let path = write_gltf(&tmp, "lights.gltf", doc, &bin);
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
    let tmp = Scratch::new("gltf-tests");
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
    let path = write_gltf(&tmp, "emissive.gltf", doc, &bin);
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
    let tmp = Scratch::new("gltf-tests");
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
    let path = write_gltf(&tmp, "cameras.gltf", doc, &bin);
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
    let e = err(load_gltf(&path, Some("side veiw")));
    assert!(
        matches!(e.cause(), SceneError::CameraNotFound { .. }),
        "{e}"
    );
    let text = e.to_string();
    assert!(text.contains("did you mean `side view`?"), "{text}");
    assert!(text.contains("its cameras: "), "{text}");
}

#[test]
fn bad_input_gives_a_clear_error() {
    let tmp = Scratch::new("gltf-tests");
    let missing = tmp.path("does-not-exist.glb");
    let e = err(load_gltf(&missing, None));
    assert!(matches!(e, SceneError::Io { .. }), "{e}");
    // Each reader names a missing file once.
    for name in [
        "does-not-exist.glb",
        "does-not-exist.toml",
        "does-not-exist.pbrt",
    ] {
        let missing = tmp.path(name);
        let e = err(crate::load_scene(missing.to_str().unwrap(), None)).to_string();
        assert_eq!(e.matches(name).count(), 1, "{e}");
    }

    let garbage = tmp.path("garbage.glb");
    std::fs::write(
        &garbage,
        b"glTF\x02\x00\x00\x00 this is not a real file \xff\xfe",
    )
    .unwrap();
    let e = err(load_gltf(&garbage, None));
    assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
    let garbage_json = tmp.path("garbage.gltf");
    std::fs::write(&garbage_json, b"{ \"asset\": ").unwrap();
    assert!(matches!(
        load_gltf(&garbage_json, None),
        Err(SceneError::Gltf { .. })
    ));

    let (doc, bin) = triangle_doc([0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let e = err(load_gltf(&write_gltf(&tmp, "nan.gltf", doc, &bin), None));
    assert!(
        matches!(e.cause(), SceneError::NonFiniteVertex { .. }),
        "{e}"
    );
    assert!(
        e.to_string().contains("nan.gltf: "),
        "the file is named: {e}"
    );

    let (mut doc, bin) = triangle_doc(TRI);
    doc["materials"] = json!([{ "name": "bad", "emissiveFactor": [1.0, -1.0, 0.0] }]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let e = err(load_gltf(
        &write_gltf(&tmp, "negative.gltf", doc, &bin),
        None,
    ));
    assert!(matches!(e.cause(), SceneError::BadEmission { .. }), "{e}");
    assert!(e.to_string().contains("bad"), "{e}");
    assert!(
        e.to_string().contains("negative.gltf: "),
        "the file is named: {e}"
    );

    let (mut doc, bin) = triangle_doc(TRI);
    doc["materials"] = json!([{ "emissiveFactor": [1.0, 1.0, 1.0], "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": -2.0 } } }]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let e = err(load_gltf(
        &write_gltf(&tmp, "negative2.gltf", doc, &bin),
        None,
    ));
    assert!(matches!(e.cause(), SceneError::BadEmission { .. }), "{e}");
    assert!(e.to_string().contains("negative2.gltf: "), "{e}");

    let (mut doc, bin) = triangle_doc(TRI);
    doc["extensions"] =
        json!({ "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": -1.0 }] } });
    doc["nodes"] =
        json!([{ "mesh": 0 }, { "extensions": { "KHR_lights_punctual": { "light": 0 } } }]);
    doc["scenes"] = json!([{ "nodes": [0, 1] }]);
    let e = err(load_gltf(
        &write_gltf(&tmp, "negative3.gltf", doc, &bin),
        None,
    ));
    assert!(matches!(e.cause(), SceneError::BadEmission { .. }), "{e}");
    assert!(e.to_string().contains("negative3.gltf: "), "{e}");

    // Non-finite emission (1e39 overflows f32), bad radii, a bad camera.
    let (mut doc, bin) = triangle_doc(TRI);
    doc["materials"] = json!([{ "emissiveFactor": [1.0, 1.0, 1.0], "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 1e39 } } }]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let e = err(load_gltf(
        &write_gltf(&tmp, "infinite.gltf", doc, &bin),
        None,
    ));
    assert!(matches!(e.cause(), SceneError::BadEmission { .. }), "{e}");
    assert!(e.to_string().contains("infinite.gltf: "), "{e}");
    // finite emission, infinite power: 1e38 over the triangle's area (the audit's case)
    let (mut doc, bin) = triangle_doc(TRI.map(|x| 4.0 * x));
    doc["materials"] = json!([{ "name": "sun", "emissiveFactor": [1.0, 1.0, 1.0], "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 1e38 } } }]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let e = err(load_gltf(&write_gltf(&tmp, "sun.gltf", doc, &bin), None));
    assert!(matches!(e.cause(), SceneError::InfinitePower { .. }), "{e}");
    assert!(
        e.to_string().starts_with("sun.gltf: ") || e.to_string().contains("/sun.gltf: "),
        "{e}"
    );
    assert!(e.to_string().contains("material `sun`"), "{e}");
    for (i, extras) in [json!({ "radius": -0.5 }), json!({ "radius": "big" })]
        .into_iter()
        .enumerate()
    {
        let (mut doc, bin) = triangle_doc(TRI);
        doc["extensions"] =
            json!({ "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": 1.0 }] } });
        doc["nodes"] = json!([{ "mesh": 0 }, { "extensions": { "KHR_lights_punctual": { "light": 0 } }, "extras": extras }]);
        doc["scenes"] = json!([{ "nodes": [0, 1] }]);
        let e = err(load_gltf(
            &write_gltf(&tmp, &format!("radius{i}.gltf"), doc, &bin),
            None,
        ));
        assert!(matches!(e.cause(), SceneError::BadLight { .. }), "{e}");
        assert!(e.to_string().contains(&format!("radius{i}.gltf: ")), "{e}");
    }
    let (mut doc, bin) = triangle_doc(TRI);
    doc["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 4.0, "znear": 0.01 } }]);
    doc["nodes"] = json!([{ "mesh": 0 }, { "camera": 0 }]);
    doc["scenes"] = json!([{ "nodes": [0, 1] }]);
    let e = err(load_gltf(&write_gltf(&tmp, "camera.gltf", doc, &bin), None));
    assert!(
        matches!(e, SceneError::Gltf { .. }) && e.to_string().contains("yfov"),
        "{e}"
    );
    // a camera node that collapses the view direction
    let (mut doc, bin) = triangle_doc(TRI);
    doc["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.01 } }]);
    doc["nodes"] = json!([{ "mesh": 0 }, { "camera": 0, "scale": [1.0, 1.0, 0.0] }]);
    doc["scenes"] = json!([{ "nodes": [0, 1] }]);
    let e = err(load_gltf(&write_gltf(&tmp, "flat.gltf", doc, &bin), None)).to_string();
    assert!(
        e.contains("flat.gltf") && e.contains("camera `camera 0`"),
        "{e}"
    );

    let empty = write_gltf(
        &tmp,
        "empty.gltf",
        json!({ "asset": { "version": "2.0" }, "scenes": [{ "nodes": [] }] }),
        &[],
    );
    let e = err(load_gltf(&empty, None));
    assert!(matches!(e.cause(), SceneError::Empty), "{e}");
    assert!(e.to_string().contains("empty.gltf: "), "{e}");

    let lights_only = json!({
        "asset": { "version": "2.0" },
        "extensions": { "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": 1.0 }] } },
        "nodes": [{ "extensions": { "KHR_lights_punctual": { "light": 0 } } }],
        "scenes": [{ "nodes": [0] }]
    });
    let e = err(load_gltf(
        &write_gltf(&tmp, "lights-only.gltf", lights_only, &[]),
        None,
    ));
    assert!(e.to_string().contains("no triangles"), "{e}");

    let (mut doc, bin) = triangle_doc(TRI);
    doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let e = err(load_gltf(&write_gltf(&tmp, "draco.gltf", doc, &bin), None));
    assert!(e.to_string().contains("KHR_draco_mesh_compression"), "{e}");

    // An index past the vertex array, and an accessor past its buffer.
    let (mut doc, mut bin) = triangle_doc(TRI);
    bin[36..38].copy_from_slice(&7u16.to_le_bytes());
    doc["accessors"][1]["max"] = json!([7]);
    let e = err(load_gltf(
        &write_gltf(&tmp, "bad-index.gltf", doc, &bin),
        None,
    ));
    assert!(matches!(e, SceneError::Gltf { .. }), "{e}");
    let (mut doc, bin) = triangle_doc(TRI);
    doc["accessors"][0]["count"] = json!(300);
    let e = err(load_gltf(
        &write_gltf(&tmp, "short-buffer.gltf", doc, &bin),
        None,
    ));
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
    let tmp = Scratch::new("gltf-tests");
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
    let prim = |m: usize| json!({ "attributes": { "POSITION": 0 }, "indices": 1, "material": m });
    doc["materials"] = Value::Array(materials.to_vec());
    doc["meshes"] = json!([{ "primitives": (0..materials.len()).map(prim).collect::<Vec<_>>() }]);
    let path = write_gltf(&tmp, "extras_pbrt.gltf", doc, &bin);
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
        crate::test_notice::skipped(&format!("the checks of {rel}"));
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
    // its glass transmits
    assert!(
        scene.materials.iter().any(|m| m.name == "Glass"
            && matches!(m.model, render_core::material::Model::Dielectric { .. })),
        "{:?}",
        report.warnings
    );
}

#[path = "transmission_tests.rs"]
mod transmission;

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
    let tmp = Scratch::new("gltf-tests");
    let (mut doc, bin) = triangle_doc(TRI);
    let bin_path = tmp.path("external.bin");
    std::fs::write(&bin_path, &bin).unwrap();
    doc["buffers"] = json!([{ "byteLength": bin.len(), "uri": "external.bin" }]);
    // A 1×1 base colour texture whose transform scales uv by 2 and shifts it by (0.5, 0).
    let mut png = Vec::new();
    image::RgbImage::from_raw(1, 1, vec![255, 255, 255])
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    std::fs::write(tmp.path("white.png"), &png).unwrap();
    doc["images"] = json!([{ "uri": "white.png" }]);
    doc["textures"] = json!([{ "source": 0 }]);
    doc["extensionsUsed"] = json!(["KHR_texture_transform"]);
    doc["materials"] = json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0,
        "extensions": { "KHR_texture_transform": { "scale": [2.0, 2.0], "offset": [0.5, 0.0] } } } } }]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let path = tmp.path("external.gltf");
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
    assert!(
        e.to_string().contains("buffers[0]: ") && e.to_string().contains("external.bin: "),
        "the missing file is named: {e}"
    );
}

/// Factors glTF 2.0 limits to [0, 1] are clamped there, with a warning naming the file and the
/// material (a base colour of 5 was used as given, a negative roughness refused).
#[test]
fn factors_beyond_their_range_are_clamped_with_a_warning() {
    let tmp = Scratch::new("gltf-clamp");
    let (mut doc, bin) = triangle_doc(TRI);
    doc["materials"] = json!([{ "name": "hot", "pbrMetallicRoughness": {
        "baseColorFactor": [5.0, 0.5, -1.0, 1.0], "metallicFactor": 2.0, "roughnessFactor": -1.0 } }]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let path = write_gltf(&tmp, "hot.gltf", doc, &bin);
    let (scene, report) = load_gltf_with_report(&path, None).unwrap();
    let m = &scene.materials[0];
    assert_eq!(
        (m.base_color, m.metallic, m.roughness),
        (Vec3::new(1.0, 0.5, 0.0), 1.0, 0.0)
    );
    let warnings: Vec<&String> = report
        .warnings
        .iter()
        .filter(|w| w.contains("hot.gltf: material `hot`: ") && w.contains("outside [0, 1]"))
        .collect();
    assert_eq!(warnings.len(), 3, "{:?}", report.warnings);
    assert_eq!(scene.stats.warnings.len(), report.warnings.len());
}
