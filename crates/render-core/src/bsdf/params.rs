//! The material → BSDF step: what a [`Material`] is at one surface point, as the parameters
//! [`super::Bsdf`] evaluates and samples.
use super::fresnel;
use super::microfacet::MIN_ALPHA;
use crate::material::{Material, Model};
use glam::{Vec2, Vec3};

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
    /// A rough dielectric that reflects and transmits ([`super::dielectric`]): the Fresnel
    /// reflectance of index `ior` (inside, behind the geometric normal, over outside), and
    /// `tint` on the transmitted light.
    Dielectric { tint: Vec3, ior: f32 },
}

impl Specular {
    /// The lobe's weight for light arriving at cos θ = `cos_ih` to the half vector.
    #[inline]
    pub fn weight(&self, cos_ih: f32) -> Vec3 {
        match *self {
            Specular::None => Vec3::ZERO,
            Specular::Schlick { f0 } => fresnel::schlick(f0, cos_ih),
            Specular::PbrtPlastic { ks } => ks * fresnel::dielectric(cos_ih, 1.5, 1.0),
            // seen from outside; the BSDF itself knows which side the viewer is on
            Specular::Dielectric { ior, .. } => Vec3::splat(fresnel::dielectric(cos_ih, 1.0, ior)),
        }
    }

    /// The lobe's colour without its Fresnel factor: pbrt's Ks (what pbrt-v3's
    /// `MicrofacetReflection` reports as R), 1 for the glTF lobe, whose only weight is Fresnel.
    pub fn tint(&self) -> Vec3 {
        match *self {
            Specular::None => Vec3::ZERO,
            Specular::Schlick { .. } => Vec3::ONE,
            Specular::PbrtPlastic { ks } => ks,
            Specular::Dielectric { tint, .. } => tint,
        }
    }

    pub fn is_none(&self) -> bool {
        match *self {
            Specular::None => true,
            Specular::Schlick { f0 } => f0.max_element() <= 0.0,
            Specular::PbrtPlastic { ks } => ks.max_element() <= 0.0,
            // reflects even when its tint blocks all transmission
            Specular::Dielectric { .. } => false,
        }
    }
}

impl Material {
    /// The BSDF parameters at texture coordinate `uv`.
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
        if let Model::Dielectric { ior, alpha } = self.model {
            return BsdfParams {
                diffuse: Vec3::ZERO,
                specular: Specular::Dielectric { tint: base, ior },
                alpha: alpha.clamp(MIN_ALPHA, 1.0),
            };
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
}
