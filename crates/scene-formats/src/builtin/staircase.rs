//! `staircase`: twelve steps climbing away from the camera between two walls, above a glossy
//! floor, with small lamps along the front edge of every tread and along both walls at
//! handrail height.
use super::mesh::Mesh;
use super::{Params, pick, sphere_radiance, uniform};
use glam::Vec3;
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;

const TOTAL_POWER: f32 = 120.0;
const STEPS: usize = 12;
/// Rise and run of a step, half-width of the stair.
const RISE: f32 = 0.18;
const RUN: f32 = 0.3;
const HALF_WIDTH: f32 = 1.0;

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let (n, radius, roughness) = (p.lights()?, p.radius()?, p.roughness()?);
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let floor = b.add_material(Material::simple(
        "glossy floor",
        Vec3::new(0.15, 0.15, 0.17),
        0.3,
        roughness,
    ))?;
    let wood = b.add_material(Material::simple(
        "steps",
        Vec3::new(0.5, 0.3, 0.16),
        0.0,
        0.6,
    ))?;
    let wall = b.add_material(Material::diffuse("walls", Vec3::new(0.7, 0.68, 0.62)))?;
    let rail = b.add_material(Material::simple(
        "handrail",
        Vec3::new(0.85, 0.85, 0.88),
        1.0,
        roughness,
    ))?;

    Mesh::plane(Vec3::new(0.0, 0.0, 2.0), 2.0 * HALF_WIDTH + 0.2, 6.0)
        .add_to(&mut b, "floor", floor)?;
    for k in 0..STEPS {
        let (z0, z1) = (-(k as f32 + 1.0) * RUN, -(k as f32) * RUN);
        Mesh::cuboid(
            Vec3::new(-HALF_WIDTH, 0.0, z0),
            Vec3::new(HALF_WIDTH, (k as f32 + 1.0) * RISE, z1),
        )
        .add_to(&mut b, "step", wood)?;
    }
    let top = STEPS as f32 * RISE;
    let end = -(STEPS as f32) * RUN;
    Mesh::cuboid(
        Vec3::new(-HALF_WIDTH, 0.0, end - 2.0),
        Vec3::new(HALF_WIDTH, top, end),
    )
    .add_to(&mut b, "landing", wood)?;
    // Side walls facing inward, from behind the camera to past the landing.
    let (wz0, wz1, wh) = (end - 2.0, 5.0, top + 2.5);
    let wc = 0.5 * (wz0 + wz1);
    let (half_len, half_h) = (0.5 * (wz1 - wz0), 0.5 * wh);
    let wx = HALF_WIDTH + 0.1;
    Mesh::quad(
        Vec3::new(-wx, half_h, wc),
        Vec3::new(0.0, half_h, 0.0),
        Vec3::new(0.0, 0.0, half_len),
    )
    .add_to(&mut b, "left wall", wall)?;
    Mesh::quad(
        Vec3::new(wx, half_h, wc),
        Vec3::new(0.0, 0.0, half_len),
        Vec3::new(0.0, half_h, 0.0),
    )
    .add_to(&mut b, "right wall", wall)?;
    Mesh::quad(
        Vec3::new(0.0, top + 0.5 * (wh - top), wz0),
        Vec3::new(wx, 0.0, 0.0),
        Vec3::new(0.0, 0.5 * (wh - top), 0.0),
    )
    .add_to(&mut b, "end wall", wall)?;
    // A handrail on each wall, following the slope.
    let slope = Vec3::new(0.0, top, end).normalize();
    let rail_len = Vec3::new(0.0, top, end).length();
    for x in [-HALF_WIDTH + 0.05, HALF_WIDTH - 0.05] {
        Mesh::cylinder(Vec3::new(x, 0.9, 0.0), slope, 0.025, rail_len, 16, true)
            .add_to(&mut b, "handrail", rail)?;
    }

    // Lamps: 60 % along the tread edges, 40 % on the walls just below the handrails.
    let l = sphere_radiance(TOTAL_POWER, n, radius);
    let warm = Vec3::new(1.0, 0.8, 0.6) / render_core::colour::luminance(Vec3::new(1.0, 0.8, 0.6));
    for _ in 0..n {
        let c = if uniform(&mut rng, 0.0, 1.0) < 0.6 {
            let k = pick(&mut rng, STEPS);
            Vec3::new(
                uniform(&mut rng, -HALF_WIDTH + 0.05, HALF_WIDTH - 0.05),
                (k as f32 + 1.0) * RISE + radius + 0.002,
                -(k as f32) * RUN - 0.04,
            )
        } else {
            let side = if uniform(&mut rng, 0.0, 1.0) < 0.5 {
                -1.0
            } else {
                1.0
            };
            let t = uniform(&mut rng, 0.0, 1.0);
            Vec3::new(side * (wx - radius - 0.01), 0.75 + t * top, t * end)
        };
        b.add_sphere_light(c, radius, warm * l, None)?;
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        Vec3::new(0.5, 1.4, 4.2),
        Vec3::new(0.0, 1.1, -1.6),
        Vec3::Y,
        50f32.to_radians(),
        320,
        240,
    ))?);
    Ok(b)
}
