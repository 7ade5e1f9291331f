//! `grid`: N sphere lights on a square grid (cells row by row, jittered by the seed) 2 units
//! above a 12 × 12 glossy plane with a diffuse sphere and a glossy box, for scaling studies
//! from 10² to 10⁶ lights. The grid spans 10 × 10 whatever N, so the spacing is 10/⌈√N⌉;
//! the default radius is 0.05 × spacing (0.005 at N = 10⁴).
use super::mesh::Mesh;
use super::{Params, light_color, sphere_radiance, uniform};
use glam::Vec3;
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;

const TOTAL_POWER: f32 = 200.0;
const SIZE: f32 = 10.0;
const HEIGHT: f32 = 2.0;

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let (n, roughness) = (p.lights()?, p.roughness()?);
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let plane = b.add_material(Material::simple(
        "glossy plane",
        Vec3::splat(0.4),
        0.0,
        roughness,
    ))?;
    let white = b.add_material(Material::diffuse("diffuse sphere", Vec3::splat(0.75)))?;
    let copper = b.add_material(Material::simple(
        "copper box",
        Vec3::new(0.95, 0.64, 0.54),
        1.0,
        roughness,
    ))?;
    Mesh::plane(Vec3::ZERO, 12.0, 12.0).add_to(&mut b, "plane", plane)?;
    Mesh::uv_sphere(Vec3::new(-0.9, 0.6, 0.0), 0.6, 64, 32).add_to(&mut b, "sphere", white)?;
    Mesh::rounded_box(Vec3::new(0.9, 0.45, -0.4), Vec3::splat(0.45), 0.1, 4)
        .add_to(&mut b, "box", copper)?;

    let side = (n as f64).sqrt().ceil() as usize;
    let spacing = SIZE / side as f32;
    // By default the radius follows the spacing, so the lights cover (and shadow) the same
    // fraction of the grid whatever N.
    let radius = p.radius_or_auto()?.unwrap_or(0.05 * spacing);
    let l = sphere_radiance(TOTAL_POWER, n, radius);
    for i in 0..n {
        let (row, col) = (i / side, i % side);
        let jx = uniform(&mut rng, -0.25, 0.25);
        let jz = uniform(&mut rng, -0.25, 0.25);
        let c = Vec3::new(
            -0.5 * SIZE + (col as f32 + 0.5 + jx) * spacing,
            HEIGHT,
            -0.5 * SIZE + (row as f32 + 0.5 + jz) * spacing,
        );
        b.add_sphere_light(c, radius, light_color(&mut rng) * l, None)?;
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        Vec3::new(0.0, 1.3, 6.5),
        Vec3::new(0.0, 0.3, 0.0),
        Vec3::Y,
        40f32.to_radians(),
        320,
        240,
    ))?);
    Ok(b)
}
