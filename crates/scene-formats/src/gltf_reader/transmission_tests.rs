//! `KHR_materials_transmission` (+ `KHR_materials_ior`) as the rough dielectric.
use super::*;
use render_core::material::Model;

/// Full transmission with an ior is the dielectric (α = roughness², base colour as tint); a
/// partial factor and a volume are read the same with a warning; a volume alone is ignored
/// with a warning; an ior of 1 is an error naming the material.
#[test]
fn transmission_loads_as_the_rough_dielectric() {
    let tmp = Scratch::new("gltf-tests");
    let (mut doc, bin) = triangle_doc([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let materials = [
        json!({ "name": "clear", "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.8, 0.7, 1], "metallicFactor": 0.0, "roughnessFactor": 0.5 },
                "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 }, "KHR_materials_ior": { "ior": 1.33 } } }),
        json!({ "name": "thick", "pbrMetallicRoughness": { "metallicFactor": 0.0 },
                "extensions": { "KHR_materials_transmission": { "transmissionFactor": 0.5 }, "KHR_materials_volume": { "thicknessFactor": 0.1 } } }),
        json!({ "name": "volume only", "extensions": { "KHR_materials_volume": { "thicknessFactor": 0.1 } } }),
    ];
    let prim = |m: usize| json!({ "attributes": { "POSITION": 0 }, "indices": 1, "material": m });
    doc["materials"] = Value::Array(materials.to_vec());
    doc["meshes"] = json!([{ "primitives": (0..materials.len()).map(prim).collect::<Vec<_>>() }]);
    doc["extensionsUsed"] = json!([
        "KHR_materials_transmission",
        "KHR_materials_ior",
        "KHR_materials_volume"
    ]);
    let path = write_gltf(&tmp, "transmission.gltf", doc.clone(), &bin);
    let (scene, report) = load_gltf_with_report(&path, None).unwrap();
    let m = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap();
    assert_eq!(
        m("clear").model,
        Model::Dielectric {
            ior: 1.33,
            alpha: 0.25
        }
    );
    assert_eq!(m("clear").base_color, Vec3::new(0.9, 0.8, 0.7));
    assert_eq!(
        m("thick").model,
        Model::Dielectric {
            ior: 1.5,
            alpha: 1.0
        }
    );
    assert_eq!(m("volume only").model, Model::MetallicRoughness);
    let warned = |name: &str, what: &str| {
        report
            .warnings
            .iter()
            .any(|w| w.contains(&format!("`{name}`")) && w.contains(what))
    };
    assert!(warned("thick", "transmission factor 0.5") && warned("thick", "volume"));
    assert!(warned("volume only", "volume ignored"));
    assert!(!warned("clear", "ignored"), "{:?}", report.warnings);

    doc["materials"][0]["extensions"]["KHR_materials_ior"]["ior"] = json!(1.0);
    let e = err(load_gltf(&write_gltf(&tmp, "ior1.gltf", doc, &bin), None)).to_string();
    assert!(e.contains("clear") && e.contains("ior"), "{e}");
}
