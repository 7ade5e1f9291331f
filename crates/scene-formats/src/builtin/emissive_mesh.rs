//! `emissive-mesh`: a cloud of small emissive icospheres (each 20·4^s one-sided triangle
//! lights facing outward) over a metal ground, with a diffuse sphere and a glossy box. The
//! scene users bring most often: every light is a triangle of an emissive mesh, tens of
//! thousands of them, and nearby triangles of one sphere face every way.
use super::mesh::Mesh;
use super::{Params, area_radiance, emitter, light_color, pick, uniform};
use glam::Vec3;
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;

/// Total emitted power: irradiance of a few units on the ground under the cloud.
const TOTAL_POWER: f32 = 400.0;
/// Colours of the spheres: one emitter material each.
const COLORS: usize = 6;
/// Centre and radius of the diffuse sphere, centre and half-size of the glossy box: lights keep out of them.
const SPHERE: (Vec3, f32) = (Vec3::new(-0.9, 0.6, -0.8), 0.6);
const BOX: (Vec3, Vec3) = (Vec3::new(1.0, 0.45, -0.4), Vec3::new(0.45, 0.45, 0.45));

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let (n, radius, roughness) = (p.lights()?, p.radius()?, p.roughness()?);
    let subdivisions = p.count("subdivisions", 0, 3)? as u32;
    let per_sphere = 20 * 4usize.pow(subdivisions);
    if n * per_sphere > super::MAX_LIGHTS {
        return Err(SceneError::BadBuiltinParam {
            scene: "emissive-mesh".into(),
            key: "lights".into(),
            message: format!(
                "{n} spheres × {per_sphere} triangles is over {} lights",
                super::MAX_LIGHTS
            ),
        });
    }
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let ground = b.add_material(Material::simple(
        "metal ground",
        Vec3::new(0.62, 0.6, 0.58),
        1.0,
        roughness,
    ))?;
    let white = b.add_material(Material::diffuse("diffuse sphere", Vec3::splat(0.75)))?;
    let glossy = b.add_material(Material::simple(
        "glossy box",
        Vec3::new(0.1, 0.25, 0.6),
        0.0,
        roughness,
    ))?;
    Mesh::plane(Vec3::ZERO, 30.0, 30.0).add_to(&mut b, "ground", ground)?;
    Mesh::uv_sphere(SPHERE.0, SPHERE.1, 96, 48).add_to(&mut b, "diffuse sphere", white)?;
    Mesh::rounded_box(BOX.0, BOX.1, 0.08, 4).add_to(&mut b, "glossy box", glossy)?;

    // One radiance for every triangle: the spheres' total area emits TOTAL_POWER (one-sided).
    let unit = Mesh::icosphere(Vec3::ZERO, radius, subdivisions);
    let area: f32 = unit
        .indices
        .chunks_exact(3)
        .map(|t| {
            let q = [0, 1, 2].map(|k| unit.positions[t[k] as usize]);
            0.5 * (q[1] - q[0]).cross(q[2] - q[0]).length()
        })
        .sum();
    let l = area_radiance(TOTAL_POWER, n, area);
    let mut mats = Vec::with_capacity(COLORS);
    for i in 0..COLORS {
        mats.push(b.add_material(emitter(
            &format!("emitter {i}"),
            light_color(&mut rng) * l,
            false,
        ))?);
    }
    let mut spheres = vec![Mesh::default(); COLORS];
    let clearance = 2.0 * radius;
    for _ in 0..n {
        // Draw until the sphere clears the objects (a few tries at most: they fill little of the volume).
        let center = loop {
            let c = Vec3::new(
                uniform(&mut rng, -3.5, 3.5),
                uniform(&mut rng, 0.1 + radius, 2.6),
                uniform(&mut rng, -4.5, 1.5),
            );
            let off_sphere = c.distance(SPHERE.0) > SPHERE.1 + clearance;
            let off_box = ((c - BOX.0).abs() - BOX.1).max_element() > clearance;
            if off_sphere && off_box {
                break c;
            }
        };
        let mut sphere = unit.clone();
        for q in &mut sphere.positions {
            *q += center;
        }
        spheres[pick(&mut rng, COLORS)].append(&sphere);
    }
    for (k, m) in spheres.iter().enumerate() {
        m.add_to(&mut b, &format!("emissive icospheres {k}"), mats[k])?;
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        Vec3::new(0.0, 1.6, 5.5),
        Vec3::new(0.0, 0.7, -1.0),
        Vec3::Y,
        45f32.to_radians(),
        256,
        256,
    ))?);
    Ok(b)
}
