//! glTF metallic-roughness materials, reduced at a hit to the parameters of [`crate::bsdf::Bsdf`].
use crate::microfacet::MIN_ALPHA;
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
        }
    }
}

/// The BSDF parameters of a material at one surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfParams {
    /// Lambert albedo: baseColor · (1 − metallic).
    pub diffuse: Vec3,
    /// Normal-incidence reflectance of the GGX lobe: mix(0.04·specular, baseColor, metallic).
    pub f0: Vec3,
    /// GGX α = roughness².
    pub alpha: f32,
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

    pub fn params_at(&self, uv: Vec2) -> BsdfParams {
        let mut base = self.base_color;
        if let Some(t) = &self.base_color_texture {
            base *= t.sample(uv).truncate();
        }
        let (mut metallic, mut roughness) = (self.metallic, self.roughness);
        if let Some(t) = &self.metallic_roughness_texture {
            let s = t.sample(uv);
            roughness *= s.y;
            metallic *= s.z;
        }
        let metallic = metallic.clamp(0.0, 1.0);
        let diffuse = base * (1.0 - metallic);
        let f0 = Vec3::splat(0.04 * self.specular.max(0.0)).lerp(base, metallic);
        BsdfParams {
            diffuse,
            f0,
            alpha: (roughness * roughness).clamp(MIN_ALPHA, 1.0),
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
