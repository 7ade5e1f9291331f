//! `statue`: a ridged (2, 3) torus-knot tube (a trefoil standing upright, facing the camera),
//! diffuse + glossy, standing in for the Buddha (fine curvature everywhere), on a diffuse
//! pedestal, lit by many sphere lights scattered on a shell around it (none in the cone
//! between the camera and the statue).
use super::mesh::Mesh;
use super::{Params, light_color, sphere_radiance, uniform};
use glam::{Mat4, Vec3};
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;
use std::f32::consts::TAU;

const TOTAL_POWER: f32 = 400.0;
const CENTER: Vec3 = Vec3::new(0.0, 1.95, 0.0);
const EYE: Vec3 = Vec3::new(0.0, 2.0, 6.0);

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let (n, radius, roughness) = (p.lights()?, p.radius()?, p.roughness()?);
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let floor = b.add_material(Material::diffuse("floor", Vec3::splat(0.4)))?;
    let marble = b.add_material(Material::diffuse("pedestal", Vec3::new(0.75, 0.74, 0.7)))?;
    let statue = b.add_material(Material::simple(
        "statue",
        Vec3::new(0.7, 0.55, 0.35),
        0.0,
        roughness,
    ))?;

    Mesh::plane(Vec3::ZERO, 20.0, 20.0).add_to(&mut b, "floor", floor)?;
    Mesh::cylinder(Vec3::ZERO, Vec3::Y, 0.9, 0.6, 96, true).add_to(&mut b, "pedestal", marble)?;
    // (2, 3) torus knot around the y axis, its tube ridged along and around; then stood up
    // (axis towards the camera) above the pedestal.
    let knot = |s: f32| {
        let phi = s * TAU;
        let q = 1.0 + 0.42 * (3.0 * phi).cos();
        Vec3::new(
            q * (2.0 * phi).cos(),
            0.42 * (3.0 * phi).sin(),
            q * (2.0 * phi).sin(),
        ) * 0.8
    };
    let ridges =
        |s: f32, a: f32| 0.13 * (1.0 + 0.08 * (60.0 * TAU * s).sin() + 0.05 * (7.0 * a).cos());
    let upright =
        Mat4::from_translation(CENTER) * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2);
    Mesh::tube(knot, ridges, 1200, 40)
        .transformed(upright)
        .add_to(&mut b, "statue", statue)?;

    // Lights on a shell of radius 2.2 to 3.2 around the statue, above the floor.
    let l = sphere_radiance(TOTAL_POWER, n, radius);
    let mut placed = 0;
    while placed < n {
        let z = uniform(&mut rng, -0.5, 1.0);
        let phi = uniform(&mut rng, 0.0, TAU);
        let dir = Vec3::new(
            (1.0 - z * z).sqrt() * phi.cos(),
            z,
            (1.0 - z * z).sqrt() * phi.sin(),
        );
        let c = CENTER + dir * uniform(&mut rng, 2.2, 3.2);
        let to_camera = (EYE - CENTER).normalize();
        if c.y < 0.2 + radius || dir.dot(to_camera) > 40f32.to_radians().cos() {
            continue;
        }
        b.add_sphere_light(c, radius, light_color(&mut rng) * l, None)?;
        placed += 1;
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        EYE,
        Vec3::new(0.0, 1.5, 0.0),
        Vec3::Y,
        40f32.to_radians(),
        320,
        240,
    ))?);
    Ok(b)
}
