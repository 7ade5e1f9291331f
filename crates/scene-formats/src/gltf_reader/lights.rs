//! `KHR_lights_punctual`: point, spot and directional lights in the units of the module
//! documentation ([`super::PunctualUnits`]); an `extras.radius` makes a sphere light.
use super::Loader;
use glam::{Mat4, Vec3};
use render_core::error::SceneError;
use render_core::light::SpotCone;
use std::f32::consts::PI;

impl Loader<'_> {
    /// Adds the node's punctual light under its world transform.
    pub(super) fn add_light(
        &mut self,
        node: &gltf::Node,
        light: &gltf::khr_lights_punctual::Light,
        world: Mat4,
    ) -> Result<(), SceneError> {
        use gltf::khr_lights_punctual::Kind;
        let name = light
            .name()
            .or(node.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("light {}", light.index()));
        let power = Vec3::from(light.color()) * light.intensity();
        if !power.is_finite() || power.min_element() < 0.0 {
            return Err(SceneError::BadEmission {
                what: format!("light `{name}` (color × intensity)"),
                value: format!("{:?}", power.to_array()),
            });
        }
        let radius = match extras_number(node.extras(), "radius")
            .or_else(|| extras_number(light.extras(), "radius"))
        {
            None => 0.0,
            Some(Ok(r)) if r.is_finite() && r >= 0.0 => r,
            Some(Ok(r)) => {
                return Err(SceneError::BadLight {
                    what: name,
                    message: format!("radius {r} (must be finite and >= 0)"),
                });
            }
            Some(Err(e)) => {
                return Err(SceneError::BadLight {
                    what: name,
                    message: e,
                });
            }
        };
        if light.range().is_some() {
            self.report
                .warn("punctual light `range` ignored (inverse-square falloff everywhere)".into());
        }
        let position = world.transform_point3(Vec3::ZERO);
        let axis = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let spot = match light.kind() {
            Kind::Directional => {
                self.builder.add_distant_light(-axis, power)?;
                self.report.distant_lights += 1;
                return Ok(());
            }
            Kind::Point => None,
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                if axis == Vec3::ZERO || !axis.is_finite() {
                    return Err(SceneError::BadLight {
                        what: name,
                        message: "spot light with a degenerate node transform".into(),
                    });
                }
                let outer = outer_cone_angle.clamp(0.0, PI / 2.0);
                let inner = inner_cone_angle.clamp(0.0, outer);
                Some(SpotCone {
                    direction: axis,
                    cos_inner: inner.cos(),
                    cos_outer: outer.cos(),
                })
            }
        };
        if radius > 0.0 {
            self.builder.add_sphere_light(
                position,
                radius,
                power / (PI * radius * radius),
                spot,
            )?;
            self.report.sphere_lights += 1;
        } else {
            self.builder.add_point_light(position, power, spot)?;
            if spot.is_some() {
                self.report.spot_lights += 1;
            } else {
                self.report.point_lights += 1;
            }
        }
        Ok(())
    }
}

/// Reads a number from a node's or light's `extras` JSON object.
fn extras_number(extras: &gltf::json::Extras, key: &str) -> Option<Result<f32, String>> {
    let raw = extras.as_ref()?;
    let v: serde_json::Value = match serde_json::from_str(raw.get()) {
        Ok(v) => v,
        Err(e) => return Some(Err(format!("unreadable extras: {e}"))),
    };
    let x = v.get(key)?;
    Some(
        x.as_f64()
            .map(|f| f as f32)
            .ok_or_else(|| format!("extras.{key} is not a number: {x}")),
    )
}
