//! `diffuse-quads`: many small one-sided emissive quads facing down, 2.5 to 3.5 units above a
//! 12 × 12 region, over purely diffuse (Lambert, no specular lobe) floor, boxes and spheres.
use super::mesh::Mesh;
use super::{Params, area_radiance, emitter, light_color, pick, uniform};
use glam::{Quat, Vec3};
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;
use std::f32::consts::TAU;

/// Total emitted power: irradiance about 2 under the quads (P / A for one-sided emitters).
const TOTAL_POWER: f32 = 300.0;
/// Colours of the quads: one emitter material each.
const COLORS: usize = 6;

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let n = p.lights()?;
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let floor = b.add_material(Material::diffuse("floor", Vec3::new(0.6, 0.58, 0.55)))?;
    let wall = b.add_material(Material::diffuse("back wall", Vec3::new(0.5, 0.55, 0.6)))?;
    let red = b.add_material(Material::diffuse("red", Vec3::new(0.65, 0.12, 0.1)))?;
    let green = b.add_material(Material::diffuse("green", Vec3::new(0.15, 0.5, 0.15)))?;
    let white = b.add_material(Material::diffuse("white", Vec3::splat(0.8)))?;

    Mesh::plane(Vec3::ZERO, 16.0, 16.0).add_to(&mut b, "floor", floor)?;
    Mesh::quad(
        Vec3::new(0.0, 2.5, -6.0),
        Vec3::new(8.0, 0.0, 0.0),
        Vec3::new(0.0, 2.5, 0.0),
    )
    .add_to(&mut b, "back wall", wall)?;
    Mesh::cuboid(Vec3::new(-2.6, 0.0, -1.5), Vec3::new(-1.2, 1.6, -0.3))
        .add_to(&mut b, "red box", red)?;
    Mesh::cuboid(Vec3::new(1.0, 0.0, -2.5), Vec3::new(2.2, 0.8, -1.3)).add_to(
        &mut b,
        "green box",
        green,
    )?;
    Mesh::uv_sphere(Vec3::new(0.0, 0.6, 0.6), 0.6, 64, 32).add_to(&mut b, "white sphere", white)?;
    Mesh::uv_sphere(Vec3::new(2.4, 0.35, 1.2), 0.35, 48, 24).add_to(
        &mut b,
        "green sphere",
        green,
    )?;

    // Quad side shrinks with the count so the lit fraction of the ceiling stays about 10 %.
    let side = (0.12 * (1024.0 / n as f32).sqrt()).clamp(0.004, 0.6);
    let l = area_radiance(TOTAL_POWER, n, side * side);
    let mut mats = Vec::with_capacity(COLORS);
    for i in 0..COLORS {
        mats.push(b.add_material(emitter(
            &format!("lamp {i}"),
            light_color(&mut rng) * l,
            false,
        ))?);
    }
    let mut lamps = vec![Mesh::default(); COLORS];
    for _ in 0..n {
        let c = Vec3::new(
            uniform(&mut rng, -6.0, 6.0),
            uniform(&mut rng, 2.5, 3.5),
            uniform(&mut rng, -5.8, 6.0),
        );
        let rot = Quat::from_rotation_y(uniform(&mut rng, 0.0, TAU));
        let k = pick(&mut rng, COLORS);
        // u × v = −y: the front face looks down.
        lamps[k].append(&Mesh::quad(
            c,
            rot * Vec3::X * (0.5 * side),
            rot * Vec3::Z * (0.5 * side),
        ));
    }
    for (k, m) in lamps.iter().enumerate() {
        m.add_to(&mut b, &format!("lamps {k}"), mats[k])?;
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        Vec3::new(0.0, 2.0, 9.0),
        Vec3::new(0.0, 0.8, 0.0),
        Vec3::Y,
        45f32.to_radians(),
        320,
        240,
    ))?);
    Ok(b)
}
