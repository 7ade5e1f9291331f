//! Materials as scenes describe them (glTF metallic-roughness, pbrt-v3's `plastic`, or a rough
//! dielectric);
//! [`crate::bsdf::BsdfParams`] is what one becomes at a hit.
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    /// Linear base colour factor.
    pub base_color: Vec3,
    /// Linear (already sRGB-decoded) base colour texture, multiplied with the factor.
    pub base_color_texture: Option<Arc<Texture>>,
    pub metallic: f32,
    pub roughness: f32,
    /// glTF metallicRoughness texture: G = roughness, B = metallic, multiplied with the factors.
    pub metallic_roughness_texture: Option<Arc<Texture>>,
    /// KHR_materials_specular factor: 0 turns the dielectric specular lobe off (pure Lambert).
    pub specular: f32,
    pub double_sided: bool,
    /// Emitted radiance factor (emissiveFactor × emissive strength).
    pub emission: Vec3,
    /// Linear emissive texture, multiplied with `emission`.
    pub emission_texture: Option<Arc<Texture>>,
    /// The reflection model; the glTF fields above describe it unless it says otherwise.
    pub model: Model,
}

/// Which reflection model a material follows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Model {
    /// glTF metallic-roughness: Lambert + GGX with Schlick Fresnel (the fields of [`Material`]).
    #[default]
    MetallicRoughness,
    /// pbrt-v3 `plastic` (see [`crate::bsdf::plastic`]): Lambert Kd = the base colour, plus Ks × a
    /// Trowbridge–Reitz lobe of width `alpha` with pbrt-v3's dielectric Fresnel.
    PbrtPlastic { ks: Vec3, alpha: f32 },
    /// A rough dielectric that transmits (see [`crate::bsdf::dielectric`]): index of
    /// refraction `ior` behind the geometric normal (1 in front), GGX width `alpha`, and the
    /// base colour (× its texture) as the transmission tint.
    Dielectric { ior: f32, alpha: f32 },
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            base_color: Vec3::splat(0.8),
            base_color_texture: None,
            metallic: 0.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            specular: 1.0,
            double_sided: true,
            emission: Vec3::ZERO,
            emission_texture: None,
            model: Model::MetallicRoughness,
        }
    }
}

impl Material {
    /// A glossy or diffuse material with plain factors (used by the built-in scenes).
    pub fn simple(name: &str, base_color: Vec3, metallic: f32, roughness: f32) -> Material {
        Material {
            name: name.into(),
            base_color,
            metallic,
            roughness,
            ..Default::default()
        }
    }

    /// Lambert only: no specular lobe.
    pub fn diffuse(name: &str, base_color: Vec3) -> Material {
        Material {
            specular: 0.0,
            ..Material::simple(name, base_color, 0.0, 1.0)
        }
    }

    pub fn emission_at(&self, uv: Vec2) -> Vec3 {
        match &self.emission_texture {
            Some(t) => self.emission * t.sample(uv).truncate(),
            None => self.emission,
        }
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
