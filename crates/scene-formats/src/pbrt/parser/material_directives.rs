//! Materials and textures: `Texture` (constant ones are evaluated), `Material`,
//! `MakeNamedMaterial`, `NamedMaterial`, and the builder material of a (material, area light)
//! pair, made once. The pbrt → [`render_core::material::Material`] mapping itself is in
//! [`crate::pbrt::materials`].
use super::Parser;
use crate::pbrt::materials::{self, Context, TextureValue};
use crate::pbrt::params::ParamList;
use render_core::error::SceneError;
use std::sync::Arc;

impl Parser<'_> {
    /// `Texture "name" "type" "class" params`.
    pub(super) fn texture_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let name = self.string_arg("Texture", line)?;
        let _ty = self.string_arg("Texture", line)?;
        let class = self.string_arg("Texture", line)?;
        let p = self.params()?;
        let mut warnings = Vec::new();
        let mut ctx = Context {
            textures: &self.textures,
            warnings: &mut warnings,
        };
        let t = materials::texture(&class, &p, &mut ctx).map_err(|m| self.err(line, m))?;
        for w in warnings {
            self.warn(line, format!("Texture \"{name}\": {w}"));
        }
        if let TextureValue::Unsupported(c) = &t {
            self.warn(line, format!("Texture \"{name}\": class \"{c}\" is not supported (materials using it take their default)"));
        } else {
            self.unused(&format!("Texture \"{name}\""), &p, &[]);
        }
        self.textures.insert(name, t);
        Ok(())
    }

    /// A material from its type and parameters (`None`: `interface`), kept for later shapes.
    fn make_material(
        &mut self,
        name: &str,
        ty: &str,
        p: &ParamList,
        line: usize,
    ) -> Result<Option<usize>, SceneError> {
        let mut warnings = Vec::new();
        let mut ctx = Context {
            textures: &self.textures,
            warnings: &mut warnings,
        };
        let m = materials::material(name, ty, p, &mut ctx).map_err(|m| self.err(line, m))?;
        for w in warnings {
            self.warn(line, format!("material \"{ty}\": {w}"));
        }
        self.unused(&format!("material \"{ty}\""), p, &[]);
        Ok(m.map(|m| {
            self.materials.push(m);
            self.materials.len() - 1
        }))
    }

    /// `Material "type" params`: an anonymous material becomes current.
    pub(super) fn material_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let ty = self.string_arg("Material", line)?;
        let p = self.params()?;
        self.state.material =
            self.make_material(&format!("material at {}", self.here(line)), &ty, &p, line)?;
        Ok(())
    }

    /// `MakeNamedMaterial "name" "string type" … params`.
    pub(super) fn make_named_material(&mut self, line: usize) -> Result<(), SceneError> {
        let name = self.string_arg("MakeNamedMaterial", line)?;
        let p = self.params()?;
        let ty = p
            .string("type")
            .map_err(|m| self.err(line, m))?
            .unwrap_or("")
            .to_string();
        if ty.is_empty() {
            return Err(self.err(
                line,
                format!("MakeNamedMaterial \"{name}\" without \"string type\""),
            ));
        }
        let m = self.make_material(&name, &ty, &p, line)?;
        self.named_materials.insert(name, m);
        Ok(())
    }

    /// `NamedMaterial "name"`: a material made before becomes current.
    pub(super) fn named_material(&mut self, line: usize) -> Result<(), SceneError> {
        let name = self.string_arg("NamedMaterial", line)?;
        match self.named_materials.get(&name) {
            Some(m) => self.state.material = *m,
            None => {
                return Err(self.err(line, format!("NamedMaterial \"{name}\" is not defined")));
            }
        }
        Ok(())
    }

    /// The builder material for the current material and area light.
    pub(super) fn builder_material(&mut self) -> Result<Option<u32>, SceneError> {
        let Some(m) = self.state.material else {
            return Ok(None);
        };
        let light_key = self
            .state
            .area_light
            .as_ref()
            .map_or(0, |a| Arc::as_ptr(a) as usize);
        if let Some(&id) = self.built.get(&(m, light_key)) {
            return Ok(Some(id));
        }
        let mut mat = self.materials[m].clone();
        if let Some(a) = &self.state.area_light {
            mat.emission = a.radiance;
            mat.double_sided = a.two_sided;
            mat.name = format!("{} (emitting)", mat.name);
        }
        let id = self.builder.add_material(mat)?;
        self.built.insert((m, light_key), id);
        Ok(Some(id))
    }
}
