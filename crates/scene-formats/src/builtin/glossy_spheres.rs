//! `glossy-spheres`: N small sphere lights spread over a wide region (30 × 30 units, 3 to 5
//! units up) above a glossy ground, with glossy and diffuse spheres and boxes. Most lights
//! are far from any given shading point, so a light tree clearly beats power sampling.
use super::mesh::Mesh;
use super::{Params, light_color, sphere_radiance, uniform};
use glam::Vec3;
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;

/// Total emitted power: the irradiance under the light field is about 2 (P / 2A).
const TOTAL_POWER: f32 = 3600.0;

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let (n, radius, roughness) = (p.lights()?, p.radius()?, p.roughness()?);
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let ground = b.add_material(Material::simple(
        "glossy ground",
        Vec3::new(0.35, 0.35, 0.38),
        0.6,
        roughness,
    ))?;
    let gold = b.add_material(Material::simple(
        "gold",
        Vec3::new(1.0, 0.78, 0.34),
        1.0,
        roughness,
    ))?;
    let red = b.add_material(Material::simple(
        "red plastic",
        Vec3::new(0.7, 0.08, 0.06),
        0.0,
        roughness,
    ))?;
    let white = b.add_material(Material::diffuse("white diffuse", Vec3::splat(0.8)))?;
    let blue = b.add_material(Material::diffuse(
        "blue diffuse",
        Vec3::new(0.15, 0.25, 0.6),
    ))?;
    let steel = b.add_material(Material::simple(
        "steel",
        Vec3::new(0.6, 0.6, 0.62),
        1.0,
        (roughness * 1.5).min(1.0),
    ))?;

    Mesh::plane(Vec3::ZERO, 40.0, 40.0).add_to(&mut b, "ground", ground)?;
    Mesh::uv_sphere(Vec3::new(-1.4, 0.7, 0.0), 0.7, 96, 48).add_to(&mut b, "gold sphere", gold)?;
    Mesh::uv_sphere(Vec3::new(0.3, 0.5, 1.0), 0.5, 96, 48).add_to(&mut b, "red sphere", red)?;
    Mesh::uv_sphere(Vec3::new(1.6, 0.6, -0.3), 0.6, 64, 32).add_to(
        &mut b,
        "white sphere",
        white,
    )?;
    Mesh::cuboid(Vec3::new(-3.4, 0.0, -1.6), Vec3::new(-2.4, 1.0, -0.6))
        .add_to(&mut b, "blue box", blue)?;
    Mesh::rounded_box(
        Vec3::new(3.2, 0.45, 0.6),
        Vec3::new(0.45, 0.45, 0.45),
        0.12,
        4,
    )
    .add_to(&mut b, "steel box", steel)?;

    let l = sphere_radiance(TOTAL_POWER, n, radius);
    for _ in 0..n {
        let c = Vec3::new(
            uniform(&mut rng, -15.0, 15.0),
            uniform(&mut rng, 3.0, 5.0),
            uniform(&mut rng, -20.0, 10.0),
        );
        let color = light_color(&mut rng);
        b.add_sphere_light(c, radius, color * l, None)?;
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        Vec3::new(0.0, 2.2, 8.0),
        Vec3::new(0.0, 0.5, -1.0),
        Vec3::Y,
        40f32.to_radians(),
        320,
        240,
    ))?);
    Ok(b)
}
