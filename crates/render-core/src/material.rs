//! Materials (glTF metallic-roughness, or pbrt-v3's `plastic`), reduced at a hit to the
//! parameters of [`crate::bsdf::Bsdf`].
use crate::fresnel;
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
    /// The reflection model; the glTF fields above describe it unless it says otherwise.
    pub model: Model,
}

/// Which reflection model a material follows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Model {
    /// glTF metallic-roughness: Lambert + GGX with Schlick Fresnel (the fields of [`Material`]).
    #[default]
    MetallicRoughness,
    /// pbrt-v3 `plastic` (see [`crate::plastic`]): Lambert Kd = the base colour, plus Ks × a
    /// Trowbridge–Reitz lobe of width `alpha` with pbrt-v3's dielectric Fresnel.
    PbrtPlastic { ks: Vec3, alpha: f32 },
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

/// The BSDF parameters of a material at one surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfParams {
    /// Lambert albedo: baseColor · (1 − metallic), or pbrt's Kd.
    pub diffuse: Vec3,
    /// The glossy lobe's weight and Fresnel.
    pub specular: Specular,
    /// GGX (Trowbridge–Reitz) α: roughness² for glTF, pbrt's α as given.
    pub alpha: f32,
}

/// What multiplies the un-Fresnelled GGX lobe D·G/(4 cos θo cos θi).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Specular {
    /// No glossy lobe: pure Lambert (BRDF-oriented sampling is skipped there).
    None,
    /// glTF: Schlick Fresnel from the normal-incidence reflectance
    /// f0 = mix(0.04·specular, baseColor, metallic).
    Schlick { f0: Vec3 },
    /// pbrt-v3 `plastic`: Ks × pbrt-v3's `FresnelDielectric(1.5, 1)` (see [`fresnel::dielectric`]).
    PbrtPlastic { ks: Vec3 },
}

impl Specular {
    /// The lobe's weight for light arriving at cos θ = `cos_ih` to the half vector.
    #[inline]
    pub fn weight(&self, cos_ih: f32) -> Vec3 {
        match *self {
            Specular::None => Vec3::ZERO,
            Specular::Schlick { f0 } => fresnel::schlick(f0, cos_ih),
            Specular::PbrtPlastic { ks } => ks * fresnel::dielectric(cos_ih, 1.5, 1.0),
        }
    }

    /// The lobe's colour without its Fresnel factor: pbrt's Ks (what pbrt-v3's
    /// `MicrofacetReflection` reports as R), 1 for the glTF lobe, whose only weight is Fresnel.
    pub fn tint(&self) -> Vec3 {
        match *self {
            Specular::None => Vec3::ZERO,
            Specular::Schlick { .. } => Vec3::ONE,
            Specular::PbrtPlastic { ks } => ks,
        }
    }

    pub fn is_none(&self) -> bool {
        match *self {
            Specular::None => true,
            Specular::Schlick { f0 } => f0.max_element() <= 0.0,
            Specular::PbrtPlastic { ks } => ks.max_element() <= 0.0,
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
        if let Model::PbrtPlastic { ks, alpha } = self.model {
            return BsdfParams {
                diffuse: base,
                specular: if ks.max_element() > 0.0 {
                    Specular::PbrtPlastic { ks }
                } else {
                    Specular::None
                },
                alpha: alpha.clamp(MIN_ALPHA, 1.0),
            };
        }
        let metallic = metallic.clamp(0.0, 1.0);
        let diffuse = base * (1.0 - metallic);
        let f0 = Vec3::splat(0.04 * self.specular.max(0.0)).lerp(base, metallic);
        BsdfParams {
            diffuse,
            specular: if f0.max_element() > 0.0 {
                Specular::Schlick { f0 }
            } else {
                Specular::None
            },
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
