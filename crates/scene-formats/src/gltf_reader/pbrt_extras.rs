//! A glTF material's `extras.pbrt`: the material's pbrt description, e.g.
//! `{"pbrt": {"type": "plastic", "Kd": [0.3, 0.1, 0.2], "Ks": [0.7, 0.7, 0.7], "roughness": 0.008,
//! "remaproughness": false}}`. It says what glTF cannot, so it replaces the glTF reflection model:
//! - `matte` (or pbrt-v4 `diffuse`): pure Lambert with albedo `Kd` (or `reflectance`; the glTF
//!   base colour when absent), so BRDF-oriented sampling is skipped there;
//! - `plastic`: pbrt-v3's plastic ([`render_core::bsdf::plastic`]), pbrt-v3's defaults for absent values.
//!
//! Any other type, or a value of the wrong kind, is a warning and the glTF material is kept.
use glam::Vec3;
use render_core::bsdf::plastic;
use render_core::material::{Material, Model};
use serde_json::Value;

/// `Ok` with the material `extras.pbrt` describes (or `gltf` unchanged when there is none), or
/// `Err` with the glTF material and the warning saying why it was kept.
pub fn material(
    gltf: Material,
    extras: &gltf::json::Extras,
) -> Result<Material, (Material, String)> {
    let Some(raw) = extras.as_ref() else {
        return Ok(gltf);
    };
    let name = gltf.name.clone();
    let warn = |gltf: Material, why: String| {
        Err((
            gltf,
            format!("material `{name}`: extras.pbrt {why}; the glTF material is used"),
        ))
    };
    let v: Value = match serde_json::from_str(raw.get()) {
        Ok(v) => v,
        Err(e) => return warn(gltf, format!("unreadable ({e})")),
    };
    let Some(pbrt) = v.get("pbrt") else {
        return Ok(gltf);
    };
    let Some(kind) = pbrt.get("type").and_then(Value::as_str) else {
        return warn(gltf, "has no string `type`".into());
    };
    match from_description(gltf.clone(), kind, pbrt) {
        Ok(m) => Ok(m),
        Err(why) => warn(gltf, why),
    }
}

fn from_description(base: Material, kind: &str, p: &Value) -> Result<Material, String> {
    let kd_default = base.base_color;
    match kind {
        "matte" | "diffuse" => {
            let kd = colour(p, "Kd")?
                .or(colour(p, "reflectance")?)
                .unwrap_or(kd_default);
            if number(p, "sigma")?.is_some_and(|s| s != 0.0) {
                return Err("matte `sigma` (Oren–Nayar) is not modelled".into());
            }
            let mut m = Material::diffuse(&base.name, kd);
            keep_surface(&mut m, base);
            Ok(m)
        }
        "plastic" => {
            let kd = colour(p, "Kd")?.unwrap_or(Vec3::splat(plastic::DEFAULT_KD));
            let ks = colour(p, "Ks")?.unwrap_or(Vec3::splat(plastic::DEFAULT_KS));
            let roughness = number(p, "roughness")?.unwrap_or(plastic::DEFAULT_ROUGHNESS);
            let remap = match p.get("remaproughness") {
                None => true,
                Some(Value::Bool(b)) => *b,
                Some(Value::String(s)) if s == "true" || s == "false" => s == "true",
                Some(x) => return Err(format!("`remaproughness` is not a bool: {x}")),
            };
            let mut m = plastic::material(&base.name, kd, ks, roughness, remap);
            keep_surface(&mut m, base);
            debug_assert!(matches!(m.model, Model::PbrtPlastic { .. }));
            Ok(m)
        }
        other => Err(format!("type `{other}` is not modelled")),
    }
}

/// What the pbrt description does not speak about: sidedness and emission.
fn keep_surface(m: &mut Material, base: Material) {
    m.double_sided = base.double_sided;
    m.emission = base.emission;
    m.emission_texture = base.emission_texture;
}

fn number(p: &Value, key: &str) -> Result<Option<f32>, String> {
    match p.get(key) {
        None => Ok(None),
        Some(x) => {
            let x = match x {
                Value::Array(a) if a.len() == 1 => &a[0],
                x => x,
            };
            x.as_f64()
                .filter(|f| f.is_finite())
                .map(|f| Some(f as f32))
                .ok_or_else(|| format!("`{key}` is not a number: {x}"))
        }
    }
}

/// An RGB triple or one grey value; negative or non-finite values are refused.
fn colour(p: &Value, key: &str) -> Result<Option<Vec3>, String> {
    let Some(x) = p.get(key) else {
        return Ok(None);
    };
    let nums: Option<Vec<f64>> = match x {
        Value::Array(a) => a.iter().map(Value::as_f64).collect(),
        Value::Number(n) => n.as_f64().map(|f| vec![f]),
        _ => None,
    };
    let c = match nums.as_deref() {
        Some([g]) => Vec3::splat(*g as f32),
        Some([r, g, b]) => Vec3::new(*r as f32, *g as f32, *b as f32),
        _ => return Err(format!("`{key}` is not an RGB triple: {x}")),
    };
    if !c.is_finite() || c.min_element() < 0.0 {
        return Err(format!("`{key}` is negative or not finite: {x}"));
    }
    Ok(Some(c))
}
