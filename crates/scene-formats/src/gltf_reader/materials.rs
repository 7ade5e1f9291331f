//! glTF materials → [`Material`]s: metallic-roughness factors and textures, the specular and
//! emissive-strength extensions, and a material's `extras.pbrt`; what is not modelled is a
//! warning.
use super::{Loader, UvSpec};
use glam::Vec3;
use render_core::error::SceneError;
use render_core::material::Material;

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
                let bc = pbr.base_color_factor();
                let strength = m.emissive_strength().unwrap_or(1.0);
                let emission = Vec3::from(m.emissive_factor()) * strength;
                if !emission.is_finite() || emission.min_element() < 0.0 {
                    return Err(SceneError::BadEmission {
                        what: format!("material `{name}` (emissiveFactor × emissive strength)"),
                        value: format!("{:?}", emission.to_array()),
                    });
                }
                for (ext, what) in [
                    ("KHR_materials_transmission", "transmission"),
                    ("KHR_materials_clearcoat", "clearcoat"),
                    ("KHR_materials_sheen", "sheen"),
                    ("KHR_materials_volume", "volume"),
                    ("KHR_materials_pbrSpecularGlossiness", "specular-glossiness"),
                ] {
                    if m.extension_value(ext).is_some()
                        || (ext == "KHR_materials_transmission" && m.transmission().is_some())
                    {
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
                let gltf_material = Material {
                    name,
                    base_color: Vec3::new(bc[0], bc[1], bc[2]),
                    base_color_texture,
                    metallic: pbr.metallic_factor(),
                    roughness: pbr.roughness_factor(),
                    metallic_roughness_texture,
                    specular: specular.map_or(1.0, |s| s.specular_factor()),
                    double_sided: m.double_sided(),
                    emission,
                    emission_texture,
                    model: Default::default(),
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
}
