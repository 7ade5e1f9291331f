//! Lights: `LightSource` (point, spot, distant; others are skipped with a warning) and
//! `AreaLightSource "diffuse"`, which makes the shapes after it in its block emit.
use super::Parser;
use super::records::AreaLight;
use crate::pbrt::materials::Context;
use glam::Vec3;
use render_core::error::SceneError;
use render_core::light::SpotCone;
use std::sync::Arc;

impl Parser<'_> {
    /// `LightSource "type" params`.
    pub(super) fn light_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let ty = self.string_arg("LightSource", line)?;
        let p = self.params()?;
        let what = format!("LightSource \"{ty}\"");
        let e = |this: &Self, m: String| this.err(line, format!("{what}: {m}"));
        let m = self.root * self.state.ctm;
        let mut warnings = Vec::new();
        let mut ctx = Context {
            textures: &self.textures,
            warnings: &mut warnings,
        };
        let scale = p.float("scale", 1.0).map_err(|m| e(self, m))?;
        let result = match ty.as_str() {
            "point" | "spot" => {
                let i = ctx.colour(&p, "I", Vec3::ONE).map_err(|m| e(self, m))? * scale;
                let from = p.point("from", Vec3::ZERO).map_err(|m| e(self, m))?;
                let position = m.transform_point3(from.as_dvec3()).as_vec3();
                let spot = if ty == "spot" {
                    let to = p.point("to", Vec3::Z).map_err(|m| e(self, m))?;
                    let cone = p.float("coneangle", 30.0).map_err(|m| e(self, m))?;
                    let delta = p.float("conedelta", 5.0).map_err(|m| e(self, m))?;
                    let dir = m
                        .transform_vector3((to - from).as_dvec3())
                        .normalize()
                        .as_vec3();
                    if !dir.is_finite() {
                        return Err(e(self, "\"from\" and \"to\" coincide".into()));
                    }
                    let outer = cone.clamp(0.0, 90.0).to_radians();
                    let inner = (cone - delta)
                        .clamp(0.0, cone.clamp(0.0, 90.0))
                        .to_radians();
                    Some(SpotCone {
                        direction: dir,
                        cos_inner: inner.cos(),
                        cos_outer: outer.cos(),
                    })
                } else {
                    None
                };
                if p.touch("power") {
                    warnings.push("\"power\" is not supported (I × scale is used)".into());
                }
                if spot.is_some() {
                    warnings.push(
                        "the spot falloff follows glTF's smooth curve between the cone angles"
                            .into(),
                    );
                    self.report.spot_lights += 1;
                } else {
                    self.report.point_lights += 1;
                }
                self.builder.add_point_light(position, i, spot)
            }
            "distant" => {
                let l = ctx.colour(&p, "L", Vec3::ONE).map_err(|m| e(self, m))? * scale;
                let from = p.point("from", Vec3::ZERO).map_err(|m| e(self, m))?;
                let to = p.point("to", Vec3::Z).map_err(|m| e(self, m))?;
                let dir = m.transform_vector3((from - to).as_dvec3()).as_vec3();
                if p.touch("illuminance") {
                    warnings.push("\"illuminance\" is not supported (L × scale is used)".into());
                }
                self.report.distant_lights += 1;
                self.builder.add_distant_light(dir, l)
            }
            other => {
                for q in &p.params {
                    p.touch(&q.name);
                }
                self.warn(
                    line,
                    format!("LightSource \"{other}\" is not supported (skipped)"),
                );
                return Ok(());
            }
        };
        for w in warnings {
            self.warn(line, format!("{what}: {w}"));
        }
        self.unused(&what, &p, &[]);
        result.map_err(|err| self.err(line, err.to_string()))
    }

    /// `AreaLightSource "diffuse" params`: the emission of the shapes that follow.
    pub(super) fn area_light_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let ty = self.string_arg("AreaLightSource", line)?;
        let p = self.params()?;
        if ty != "diffuse" {
            self.warn(
                line,
                format!("AreaLightSource \"{ty}\" is not supported (no emission)"),
            );
            self.state.area_light = None;
            return Ok(());
        }
        let mut warnings = Vec::new();
        let mut ctx = Context {
            textures: &self.textures,
            warnings: &mut warnings,
        };
        let l = ctx
            .colour(&p, "L", Vec3::ONE)
            .map_err(|m| self.err(line, m))?;
        let scale = p.float("scale", 1.0).map_err(|m| self.err(line, m))?;
        let two_sided = p.bool("twosided", false).map_err(|m| self.err(line, m))?;
        for w in warnings {
            self.warn(line, format!("AreaLightSource: {w}"));
        }
        self.unused("AreaLightSource \"diffuse\"", &p, &[]);
        let radiance = l * scale;
        if !radiance.is_finite() || radiance.min_element() < 0.0 {
            return Err(self.err(
                line,
                format!("AreaLightSource: L × scale = {radiance} must be finite and non-negative"),
            ));
        }
        self.state.area_light = Some(Arc::new(AreaLight {
            radiance,
            two_sided,
        }));
        Ok(())
    }
}
