//! `car`: a glossy car-like body (rounded boxes, torus tyres, chrome hubs) on a dark glossy
//! ground, under a ceiling of small sphere lights 4.3 to 4.5 units up and three large
//! emissive panels above them.
use super::mesh::Mesh;
use super::{Params, area_radiance, emitter, light_color, sphere_radiance, uniform};
use glam::{Mat4, Vec3};
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;

/// Power of the ceiling's sphere lights together, and of the three panels together.
const SPHERES_POWER: f32 = 2000.0;
const PANELS_POWER: f32 = 1200.0;

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let (n, radius, roughness) = (p.lights()?, p.radius()?, p.roughness()?);
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let ground = b.add_material(Material::simple(
        "glossy ground",
        Vec3::new(0.05, 0.05, 0.055),
        0.0,
        roughness,
    ))?;
    let paint = b.add_material(Material::simple(
        "car paint",
        Vec3::new(0.7, 0.06, 0.05),
        0.6,
        roughness,
    ))?;
    let glass = b.add_material(Material::simple(
        "windows",
        Vec3::new(0.02, 0.02, 0.025),
        0.0,
        roughness,
    ))?;
    let rubber = b.add_material(Material::simple("tyres", Vec3::splat(0.03), 0.0, 0.7))?;
    let chrome = b.add_material(Material::simple("chrome", Vec3::splat(0.9), 1.0, roughness))?;
    let lamp_glass = b.add_material(Material::diffuse("light covers", Vec3::splat(0.85)))?;

    Mesh::plane(Vec3::ZERO, 30.0, 30.0).add_to(&mut b, "ground", ground)?;
    Mesh::rounded_box(Vec3::new(0.0, 0.72, 0.0), Vec3::new(2.1, 0.38, 0.9), 0.3, 6)
        .add_to(&mut b, "body", paint)?;
    Mesh::rounded_box(
        Vec3::new(-0.25, 1.3, 0.0),
        Vec3::new(1.15, 0.3, 0.78),
        0.28,
        6,
    )
    .add_to(&mut b, "cabin", glass)?;
    for (x, z) in [(-1.35, 0.86), (1.35, 0.86), (-1.35, -0.86), (1.35, -0.86)] {
        let hub = Vec3::new(x, 0.38, z);
        // The torus lies around y: turn its axis onto z.
        let tyre = Mesh::torus(Vec3::ZERO, 0.26, 0.12, 64, 24).transformed(
            Mat4::from_translation(hub) * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
        );
        tyre.add_to(&mut b, "tyre", rubber)?;
        Mesh::cylinder(
            hub - Vec3::new(0.0, 0.0, 0.08),
            Vec3::Z,
            0.2,
            0.16,
            48,
            true,
        )
        .add_to(&mut b, "hub", chrome)?;
    }
    for z in [-0.55, 0.55] {
        Mesh::uv_sphere(Vec3::new(2.05, 0.8, z), 0.12, 32, 16).add_to(
            &mut b,
            "headlight",
            lamp_glass,
        )?;
    }

    let l = sphere_radiance(SPHERES_POWER, n, radius);
    for _ in 0..n {
        let c = Vec3::new(
            uniform(&mut rng, -7.0, 7.0),
            uniform(&mut rng, 4.3, 4.5),
            uniform(&mut rng, -7.0, 7.0),
        );
        b.add_sphere_light(c, radius, light_color(&mut rng) * l, None)?;
    }
    // Three 3 × 0.8 panels facing down, above the sphere lights.
    let panel_l = area_radiance(PANELS_POWER, 3, 3.0 * 0.8);
    let panel = b.add_material(emitter(
        "panel",
        Vec3::new(1.0, 0.97, 0.92) * panel_l,
        false,
    ))?;
    for z in [-2.5, 0.0, 2.5] {
        Mesh::quad(
            Vec3::new(0.0, 4.8, z),
            Vec3::new(1.5, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 0.4),
        )
        .add_to(&mut b, "panel", panel)?;
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        Vec3::new(5.5, 2.0, 6.5),
        Vec3::new(0.0, 0.75, 0.0),
        Vec3::Y,
        40f32.to_radians(),
        320,
        240,
    ))?);
    Ok(b)
}
