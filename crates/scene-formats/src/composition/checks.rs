//! The ranges of a composition's numbers, checked before anything is loaded: each refusal
//! names the field (`gltf[0].fit_size`) and what would be accepted. The camera is checked
//! where it is made ([`render_core::camera::Camera::look_at`]).
use super::{Composition, GltfPart, Ground, LightLayout, MaterialOverride};

/// The largest image side a composition's camera may ask for (as pbrt's `Film`).
const MAX_IMAGE_SIDE: u32 = 65536;

/// Every field of `c` within its range, or the first that is not.
pub(super) fn check(c: &Composition) -> Result<(), String> {
    for (k, part) in c.gltf.iter().enumerate() {
        check_part(part).map_err(|m| format!("gltf[{k}].{m}"))?;
    }
    if let Some(g) = &c.ground {
        check_ground(g).map_err(|m| format!("ground.{m}"))?;
    }
    for (k, l) in c.lights.iter().enumerate() {
        check_lights(l).map_err(|m| format!("lights[{k}].{m}"))?;
    }
    if let Some(cam) = &c.camera
        && (cam.width > MAX_IMAGE_SIDE || cam.height > MAX_IMAGE_SIDE)
    {
        return Err(format!(
            "camera: image size {} × {} is larger than {MAX_IMAGE_SIDE} × {MAX_IMAGE_SIDE}",
            cam.width, cam.height
        ));
    }
    Ok(())
}

fn check_part(p: &GltfPart) -> Result<(), String> {
    if let Some(s) = p.fit_size {
        positive("fit_size", s)?;
    }
    if let Some(s) = p.scale {
        positive("scale", s)?;
    }
    finite3("translate", p.translate)?;
    finite("rotate_y_deg", p.rotate_y_deg)?;
    for (k, o) in p.overrides.iter().enumerate() {
        check_override(o).map_err(|m| format!("override[{k}].{m}"))?;
    }
    Ok(())
}

fn check_override(o: &MaterialOverride) -> Result<(), String> {
    if let Some(c) = o.base_color {
        unit3("base_color", c)?;
    }
    for (name, v) in [
        ("metallic", o.metallic),
        ("roughness", o.roughness),
        ("specular", o.specular),
    ] {
        if let Some(v) = v {
            unit(name, v)?;
        }
    }
    Ok(())
}

fn check_ground(g: &Ground) -> Result<(), String> {
    finite("y", g.y)?;
    positive("size", g.size)?;
    unit3("base_color", g.base_color)?;
    unit("roughness", g.roughness)?;
    unit("metallic", g.metallic)
}

/// What `add_lights` does not check itself (count, size and power it does).
fn check_lights(l: &LightLayout) -> Result<(), String> {
    finite3("center", l.center)?;
    finite3("extent", l.extent)?;
    let c = glam::Vec3::from(l.color);
    if !c.is_finite() || c.min_element() < 0.0 || !(render_core::colour::luminance(c) > 0.0) {
        return Err(format!(
            "color {:?} must be finite and non-negative, with some light (luminance above 0)",
            l.color
        ));
    }
    Ok(())
}

fn finite(name: &str, v: f32) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{name} {v} must be finite"))
    }
}

fn finite3(name: &str, v: [f32; 3]) -> Result<(), String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("{name} {v:?} must be finite"))
    }
}

fn positive(name: &str, v: f32) -> Result<(), String> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(format!("{name} {v} must be positive and finite"))
    }
}

fn unit(name: &str, v: f32) -> Result<(), String> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(format!("{name} {v} must be in [0, 1]"))
    }
}

fn unit3(name: &str, v: [f32; 3]) -> Result<(), String> {
    if v.iter().all(|x| (0.0..=1.0).contains(x)) {
        Ok(())
    } else {
        Err(format!("{name} {v:?} must be in [0, 1] in each channel"))
    }
}
