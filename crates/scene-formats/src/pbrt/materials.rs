//! pbrt materials and constant textures → our [`Material`]s.
//!
//! | pbrt | here |
//! |---|---|
//! | `matte` (v3), `diffuse` (v4): `Kd` / `reflectance` | pure Lambert (no BRDF-oriented sampling there) |
//! | `plastic` (v3): `Kd`, `Ks`, `roughness`, `remaproughness` | pbrt-v3's plastic ([`render_core::bsdf::plastic`]) |
//! | `coateddiffuse` (v4): `reflectance`, `roughness`, `remaproughness` | the glTF dielectric (Lambert + GGX, Schlick F0 = 0.04, α = √roughness as v4 remaps), with a warning |
//! | `conductor` (v4), `metal` (v3): `reflectance`, or `eta` + `k`, `roughness`, `remaproughness` | the glTF metal, F0 = reflectance or the normal-incidence Fresnel of η + ik; α = √roughness (`conductor`, v4's remap) or pbrt-v3's polynomial (`metal`) |
//! | `dielectric` (v4), `glass` (v3): `eta` (`index`), `roughness` or `uroughness`/`vroughness`, `remaproughness`; v3's `Kt` | the rough dielectric ([`render_core::bsdf::dielectric`]): ior = η, α = √roughness (v4's remap) or pbrt-v3's polynomial (`glass`), tint = `Kt` |
//! | `thindielectric` (v4): `eta` | an opaque black dielectric coat (F0 = ((η−1)/(η+1))²), with a warning |
//! | anything else | `matte` 0.5, with a warning |
//!
//! Parameters may name a texture; constant textures are used as their value, any other
//! texture as the parameter's default, with a warning.
use glam::Vec3;
use render_core::bsdf::{dielectric, plastic};
use render_core::material::Material;
use std::collections::HashMap;

use super::params::ParamList;

/// A texture's value where it is constant.
#[derive(Clone, Debug)]
pub enum TextureValue {
    Constant(Vec3),
    /// A texture we do not evaluate: its class.
    Unsupported(String),
}

/// What a material lookup needs besides its parameters.
pub struct Context<'a> {
    pub textures: &'a HashMap<String, TextureValue>,
    pub warnings: &'a mut Vec<String>,
}

impl Context<'_> {
    /// A colour (or grey) parameter: `rgb`/`color`, `float`, a `spectrum` (its mean, with a
    /// warning), a `blackbody` (white, with a warning) or a `texture` reference.
    pub fn colour(&mut self, p: &ParamList, name: &str, default: Vec3) -> Result<Vec3, String> {
        let Some(ty) = p.type_of(name).map(str::to_string) else {
            return Ok(default);
        };
        match ty.as_str() {
            "texture" => {
                let tex = p.string(name)?.unwrap_or_default().to_string();
                match self.textures.get(&tex) {
                    Some(TextureValue::Constant(c)) => Ok(*c),
                    Some(TextureValue::Unsupported(class)) => {
                        self.warnings.push(format!(
                            "texture `{tex}` ({class}) is not constant: `{name}` uses its default {default}"
                        ));
                        Ok(default)
                    }
                    None => Err(format!("parameter `{name}`: no texture named `{tex}`")),
                }
            }
            "float" => Ok(Vec3::splat(p.float(name, 0.0)?)),
            "rgb" | "color" => match p.nums(name)? {
                Some([r, g, b]) => Ok(Vec3::new(*r as f32, *g as f32, *b as f32)),
                Some(v) => Err(format!(
                    "parameter `{name}`: want 3 values, got {}",
                    v.len()
                )),
                None => Ok(default),
            },
            "spectrum" => {
                // (λ, value) pairs, or a named spectrum
                let values = match p.nums(name) {
                    Ok(Some(v)) => v.chunks_exact(2).map(|c| c[1]).collect::<Vec<_>>(),
                    _ => Vec::new(),
                };
                if values.is_empty() {
                    let spec = p.string(name)?.unwrap_or_default().to_string();
                    self.warnings.push(format!(
                        "named spectrum `{spec}` for `{name}` is not modelled: {default} used"
                    ));
                    return Ok(default);
                }
                let mean = values.iter().sum::<f64>() / values.len() as f64;
                self.warnings.push(format!(
                    "spectrum `{name}` read as its mean value {mean:.4} (grey)"
                ));
                Ok(Vec3::splat(mean as f32))
            }
            "blackbody" => {
                p.touch(name);
                self.warnings.push(format!(
                    "blackbody `{name}` read as white (no spectral model)"
                ));
                Ok(Vec3::ONE)
            }
            other => Err(format!("parameter `{name}`: a `{other}` is not a colour")),
        }
    }

    pub fn float(&mut self, p: &ParamList, name: &str, default: f32) -> Result<f32, String> {
        Ok(self.colour(p, name, Vec3::splat(default))?.x)
    }
}

/// A `Texture "name" "spectrum"|"float" "class" …` directive.
pub fn texture(class: &str, p: &ParamList, ctx: &mut Context) -> Result<TextureValue, String> {
    match class {
        "constant" => Ok(TextureValue::Constant(ctx.colour(p, "value", Vec3::ONE)?)),
        "scale" => {
            let a = ctx.colour(p, "tex", Vec3::ONE)?;
            let b = ctx.colour(p, "scale", Vec3::ONE)?;
            Ok(TextureValue::Constant(a * b))
        }
        other => {
            for q in &p.params {
                p.touch(&q.name);
            }
            Ok(TextureValue::Unsupported(other.into()))
        }
    }
}

/// pbrt-v3's roughness parameters: `roughness` (or the mean of `uroughness`/`vroughness`),
/// remapped by pbrt-v3's `RoughnessToAlpha` (a polynomial in ln r) when `remaproughness`
/// (default true). For v3's materials (`metal`, `glass`) only.
fn v3_alpha(p: &ParamList, ctx: &mut Context, default: f32) -> Result<f32, String> {
    alpha_remapped(p, ctx, default, plastic::roughness_to_alpha)
}

/// pbrt-v4's: the same parameters remapped by v4's `RoughnessToAlpha`, √r. For v4's
/// materials (`conductor`, `coateddiffuse`, `dielectric`, `thindielectric`).
fn v4_alpha(p: &ParamList, ctx: &mut Context, default: f32) -> Result<f32, String> {
    alpha_remapped(p, ctx, default, v4_roughness_to_alpha)
}

/// pbrt-v4's `RoughnessToAlpha`: √roughness.
fn v4_roughness_to_alpha(roughness: f32) -> f32 {
    roughness.max(0.0).sqrt()
}

/// [`alpha`] with the remapping `remap` (pbrt-v3's and pbrt-v4's differ).
fn alpha_remapped(
    p: &ParamList,
    ctx: &mut Context,
    default: f32,
    remap: fn(f32) -> f32,
) -> Result<f32, String> {
    let r = if p.has("roughness") {
        ctx.float(p, "roughness", default)?
    } else if p.has("uroughness") || p.has("vroughness") {
        let u = ctx.float(p, "uroughness", default)?;
        let v = ctx.float(p, "vroughness", default)?;
        if u != v {
            ctx.warnings
                .push("anisotropic roughness read as its mean (isotropic GGX)".into());
        }
        0.5 * (u + v)
    } else {
        default
    };
    Ok(if p.bool("remaproughness", true)? {
        remap(r)
    } else {
        r
    })
}

/// A glTF-style material with GGX α `alpha` (roughness = √α).
fn gltf_like(name: &str, base: Vec3, metallic: f32, alpha: f32, specular: f32) -> Material {
    Material {
        specular,
        ..Material::simple(name, base, metallic, alpha.max(0.0).sqrt())
    }
}

/// Our material for pbrt material `kind`; `None` for `interface` (no surface: pbrt uses it for
/// medium boundaries).
pub fn material(
    name: &str,
    kind: &str,
    p: &ParamList,
    ctx: &mut Context,
) -> Result<Option<Material>, String> {
    p.touch("type");
    p.touch("normalmap");
    p.touch("displacement");
    let m = match kind {
        "" | "none" | "interface" => return Ok(None),
        "matte" | "diffuse" => {
            let kd = if p.has("Kd") {
                ctx.colour(p, "Kd", Vec3::splat(0.5))?
            } else {
                ctx.colour(p, "reflectance", Vec3::splat(0.5))?
            };
            if ctx.float(p, "sigma", 0.0)? != 0.0 {
                ctx.warnings
                    .push("matte `sigma` (Oren–Nayar) read as Lambert".into());
            }
            Material::diffuse(name, diffuse_reflectance(name, kind, kd, ctx))
        }
        "plastic" => {
            let kd = ctx.colour(p, "Kd", Vec3::splat(plastic::DEFAULT_KD))?;
            let ks = ctx.colour(p, "Ks", Vec3::splat(plastic::DEFAULT_KS))?;
            let r = ctx.float(p, "roughness", plastic::DEFAULT_ROUGHNESS)?;
            let remap = p.bool("remaproughness", true)?;
            plastic::material(name, kd, ks, r, remap)
        }
        "coateddiffuse" => {
            let kd = ctx.colour(p, "reflectance", Vec3::splat(0.5))?;
            let a = v4_alpha(p, ctx, 0.0)?;
            for k in ["thickness", "albedo", "g", "maxdepth", "nsamples", "eta"] {
                p.touch(k);
            }
            ctx.warnings.push(
                "coateddiffuse approximated by Lambert + GGX with Schlick F0 = 0.04 (no layering)"
                    .into(),
            );
            gltf_like(name, kd, 0.0, a, 1.0)
        }
        "conductor" | "metal" => {
            // `metal` is pbrt-v3's (default roughness 0.01, v3's remap), `conductor` v4's.
            let a = if kind == "metal" {
                v3_alpha(p, ctx, 0.01)?
            } else {
                v4_alpha(p, ctx, 0.0)?
            };
            let f0 = if p.has("reflectance") {
                ctx.colour(p, "reflectance", Vec3::ONE)?
            } else {
                // defaults: copper (pbrt's default metal), RGB of its measured η and k
                let eta = ctx.colour(p, "eta", Vec3::new(0.200, 0.924, 1.102))?;
                let k = ctx.colour(p, "k", Vec3::new(3.912, 2.452, 2.142))?;
                let one = Vec3::ONE;
                ((eta - one) * (eta - one) + k * k) / ((eta + one) * (eta + one) + k * k)
            };
            gltf_like(name, f0.clamp(Vec3::ZERO, Vec3::ONE), 1.0, a, 1.0)
        }
        "dielectric" | "glass" => {
            let eta = index_of_refraction(p, ctx)?;
            dielectric::check_ior(eta).map_err(|e| format!("{kind}: {e}"))?;
            let a = if kind == "glass" {
                v3_alpha(p, ctx, 0.0)?
            } else {
                v4_alpha(p, ctx, 0.0)?
            };
            let tint = ctx.colour(p, "Kt", Vec3::ONE)?;
            if ctx.colour(p, "Kr", Vec3::ONE)? != Vec3::ONE {
                ctx.warnings.push(format!(
                    "{kind} `Kr` ignored (reflection is the Fresnel term's)"
                ));
            }
            dielectric::material(name, tint, eta, a)
        }
        "thindielectric" => {
            let eta = index_of_refraction(p, ctx)?;
            let a = v4_alpha(p, ctx, 0.0)?;
            for k in ["Kr", "Kt"] {
                p.touch(k);
            }
            ctx.warnings.push(format!(
                "{kind} rendered as an opaque black surface with its Fresnel reflection (no transmission)"
            ));
            let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
            gltf_like(name, Vec3::ZERO, 0.0, a, f0 / 0.04)
        }
        other => {
            for q in &p.params {
                p.touch(&q.name);
            }
            ctx.warnings.push(format!(
                "material type `{other}` is not supported: matte 0.5 used"
            ));
            Material::diffuse(name, Vec3::splat(0.5))
        }
    };
    Ok(Some(m))
}

/// The reflectance a diffuse material uses, as the pbrt version of `kind` evaluates it:
/// pbrt-v4's `diffuse` clamps it to [0, 1], pbrt-v3's `matte` only below 0 (`Spectrum::Clamp`'s
/// default range is [0, ∞)). A clamped value is a warning.
fn diffuse_reflectance(name: &str, kind: &str, kd: Vec3, ctx: &mut Context) -> Vec3 {
    let (clamped, range) = if kind == "matte" {
        (kd.max(Vec3::ZERO), "[0, ∞) (pbrt-v3's matte)")
    } else {
        (
            kd.clamp(Vec3::ZERO, Vec3::ONE),
            "[0, 1] (pbrt-v4's diffuse)",
        )
    };
    if clamped != kd {
        ctx.warnings.push(format!(
            "material `{name}`: {kind} reflectance {:?} clamped to {range}: {:?} used",
            kd.to_array(),
            clamped.to_array()
        ));
    }
    clamped
}

/// A dielectric's `eta` (pbrt-v3's `index` where given), 1.5 by default.
fn index_of_refraction(p: &ParamList, ctx: &mut Context) -> Result<f32, String> {
    let eta = ctx.float(p, "eta", 1.5)?;
    if p.has("index") {
        ctx.float(p, "index", eta)
    } else {
        Ok(eta)
    }
}

/// The default material before any `Material` directive (pbrt's: matte 0.5).
pub fn default_material() -> Material {
    Material::diffuse("pbrt default", Vec3::splat(0.5))
}
