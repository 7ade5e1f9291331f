//! glTF materials → [`Material`]s: metallic-roughness factors and textures, the specular and
//! emissive-strength extensions, transmission (with `KHR_materials_ior`) as the rough
//! dielectric, and a material's `extras.pbrt`; what is not modelled is a warning.
use super::{Loader, UvSpec};
use glam::Vec3;
use render_core::bsdf::dielectric;
use render_core::bsdf::microfacet::MIN_ALPHA;
use render_core::error::SceneError;
use render_core::material::{Material, Model};

impl Loader<'_> {
    /// The builder material of a glTF material, created on first use.
    pub(super) fn material(&mut self, m: gltf::Material) -> Result<(u32, UvSpec), SceneError> {
        if let Some(&v) = self.materials.get(&m.index()) {
            return Ok(v);
        }
        let mut uv = UvSpec {
            set: 0,
            transform: None,
        };
        let mat = match m.index() {
            None => Material::default(),
            Some(i) => {
                let name = m
                    .name()
                    .map(str::to_string)
                    .unwrap_or_else(|| format!("material {i}"));
                let pbr = m.pbr_metallic_roughness();
                // One uv set and transform per material: those of the first texture that has one.
                let infos = [
                    pbr.base_color_texture(),
                    m.emissive_texture(),
                    pbr.metallic_roughness_texture(),
                ];
                if let Some(info) = infos.iter().flatten().next() {
                    uv.set = info.tex_coord();
                    if let Some(t) = info.texture_transform() {
                        uv.set = t.tex_coord().unwrap_or(uv.set);
                        uv.transform = Some((t.offset(), t.rotation(), t.scale()));
                    }
                }
                if infos.iter().flatten().any(|t| t.tex_coord() != uv.set) {
                    self.report.warn(format!(
                        "material `{name}`: textures on different uv sets; all use TEXCOORD_{}",
                        uv.set
                    ));
                }
                let base_color_texture = pbr
                    .base_color_texture()
                    .map(|t| self.texture(&t.texture(), true))
                    .transpose()?;
                let metallic_roughness_texture = pbr
                    .metallic_roughness_texture()
                    .map(|t| self.texture(&t.texture(), false))
                    .transpose()?;
                let emission_texture = m
                    .emissive_texture()
                    .map(|t| self.texture(&t.texture(), true))
                    .transpose()?;
                let bc = self.unit_factor(&name, "baseColorFactor", &pbr.base_color_factor()[..3]);
                let metallic = self.unit_factor(&name, "metallicFactor", &[pbr.metallic_factor()]);
                let roughness =
                    self.unit_factor(&name, "roughnessFactor", &[pbr.roughness_factor()]);
                let strength = m.emissive_strength().unwrap_or(1.0);
                let emission = Vec3::from(m.emissive_factor()) * strength;
                if !emission.is_finite() || emission.min_element() < 0.0 {
                    return Err(SceneError::BadEmission {
                        what: format!("material `{name}` (emissiveFactor × emissive strength)"),
                        value: format!("{:?}", emission.to_array()),
                    });
                }
                for (ext, what) in [
                    ("KHR_materials_clearcoat", "clearcoat"),
                    ("KHR_materials_sheen", "sheen"),
                    ("KHR_materials_volume", "volume"),
                    ("KHR_materials_pbrSpecularGlossiness", "specular-glossiness"),
                ] {
                    if m.extension_value(ext).is_some() {
                        self.report.warn(format!(
                            "material `{name}`: {what} ignored (read as opaque metallic-roughness)"
                        ));
                    }
                }
                if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
                    self.report
                        .warn(format!("material `{name}`: alpha mode ignored (opaque)"));
                }
                let specular = m.specular();
                if specular.as_ref().is_some_and(|s| {
                    s.specular_texture().is_some() || s.specular_color_factor() != [1.0; 3]
                }) {
                    self.report.warn(format!(
                        "material `{name}`: specular texture and colour ignored (factor used)"
                    ));
                }
                let model = self.transmission_model(&m, &name, roughness[0])?;
                let gltf_material = Material {
                    name,
                    base_color: Vec3::from_slice(&bc),
                    base_color_texture,
                    metallic: metallic[0],
                    roughness: roughness[0],
                    metallic_roughness_texture,
                    specular: specular.map_or(1.0, |s| s.specular_factor()),
                    double_sided: m.double_sided(),
                    emission,
                    emission_texture,
                    model,
                };
                match crate::gltf_reader::pbrt_extras::material(gltf_material, m.extras()) {
                    Ok(mat) => mat,
                    Err((mat, warning)) => {
                        self.report.warn(warning);
                        mat
                    }
                }
            }
        };
        let id = self.builder.add_material(mat)?;
        self.materials.insert(m.index(), (id, uv));
        Ok((id, uv))
    }

    /// A factor glTF 2.0 limits to [0, 1], clamped there, with a warning naming the file and
    /// the material where it was not.
    fn unit_factor(&mut self, material: &str, field: &str, values: &[f32]) -> Vec<f32> {
        let clamped: Vec<f32> = values.iter().map(|v| v.clamp(0.0, 1.0)).collect();
        if clamped.as_slice() != values {
            self.report.warn(format!(
                "{}: material `{material}`: {field} {values:?} is outside [0, 1] (glTF 2.0's range): {clamped:?} used",
                self.path.display()
            ));
        }
        clamped
    }

    /// `KHR_materials_transmission` with a factor above 0 makes the rough dielectric: ior from
    /// `KHR_materials_ior` (1.5 by default), α = roughness², the base colour as the tint. A
    /// partial factor, a transmission texture, metalness and `KHR_materials_volume` (a thick
    /// medium) are not modelled: a warning each, and the surface is one thin interface.
    fn transmission_model(
        &mut self,
        m: &gltf::Material,
        name: &str,
        roughness: f32,
    ) -> Result<Model, SceneError> {
        let volume = m.extension_value("KHR_materials_volume").is_some();
        let Some(t) = m.transmission().filter(|t| t.transmission_factor() > 0.0) else {
            if volume {
                self.report.warn(format!(
                    "material `{name}`: volume ignored (no transmission)"
                ));
            }
            return Ok(Model::MetallicRoughness);
        };
        let mut ignored = Vec::new();
        if t.transmission_factor() < 1.0 {
            ignored.push(format!(
                "transmission factor {} (read as 1)",
                t.transmission_factor()
            ));
        }
        if t.transmission_texture().is_some() {
            ignored.push("transmission texture".into());
        }
        let pbr = m.pbr_metallic_roughness();
        if pbr.metallic_factor() > 0.0 || pbr.metallic_roughness_texture().is_some() {
            ignored.push("metalness and the metallic-roughness texture".into());
        }
        if volume {
            ignored.push("volume (read as a thin interface)".into());
        }
        if !ignored.is_empty() {
            self.report.warn(format!(
                "material `{name}`: transmission as a rough dielectric; ignored: {}",
                ignored.join(", ")
            ));
        }
        let ior = m.ior().unwrap_or(1.5);
        dielectric::check_ior(ior).map_err(|message| SceneError::BadMaterial {
            name: name.into(),
            message,
        })?;
        let r = roughness;
        Ok(Model::Dielectric {
            ior,
            alpha: (r * r).clamp(MIN_ALPHA, 1.0),
        })
    }
}
