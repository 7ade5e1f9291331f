//! `lamp`: a chandelier of many small bulbs hanging in strands below three brass rings, over
//! a glossy table with a chrome sphere, a glossy torus and a diffuse vase, in a room with a
//! diffuse floor and back wall.
use super::mesh::Mesh;
use super::{Params, sphere_radiance, uniform};
use glam::{Mat4, Vec3};
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;
use std::f32::consts::TAU;

const TOTAL_POWER: f32 = 150.0;
/// Height of the rings and their radii.
const RING_Y: f32 = 3.0;
const RINGS: [f32; 3] = [0.45, 0.8, 1.15];

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let (n, radius, roughness) = (p.lights()?, p.radius()?, p.roughness()?);
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let floor = b.add_material(Material::diffuse("floor", Vec3::new(0.45, 0.32, 0.22)))?;
    let wall = b.add_material(Material::diffuse("wall", Vec3::new(0.6, 0.58, 0.5)))?;
    let table = b.add_material(Material::simple(
        "lacquered table",
        Vec3::new(0.22, 0.1, 0.05),
        0.0,
        roughness,
    ))?;
    let legs = b.add_material(Material::diffuse("table legs", Vec3::new(0.2, 0.12, 0.07)))?;
    let brass = b.add_material(Material::simple(
        "brass",
        Vec3::new(0.9, 0.7, 0.4),
        1.0,
        roughness,
    ))?;
    let chrome = b.add_material(Material::simple("chrome", Vec3::splat(0.9), 1.0, roughness))?;
    let red = b.add_material(Material::simple(
        "red glaze",
        Vec3::new(0.6, 0.05, 0.05),
        0.0,
        roughness,
    ))?;
    let vase = b.add_material(Material::diffuse("vase", Vec3::new(0.2, 0.35, 0.6)))?;

    Mesh::plane(Vec3::ZERO, 14.0, 14.0).add_to(&mut b, "floor", floor)?;
    Mesh::quad(
        Vec3::new(0.0, 3.0, -4.0),
        Vec3::new(7.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
    )
    .add_to(&mut b, "back wall", wall)?;
    Mesh::rounded_box(
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.5, 0.05, 0.85),
        0.04,
        3,
    )
    .add_to(&mut b, "table top", table)?;
    for (x, z) in [(-1.35, -0.7), (1.35, -0.7), (-1.35, 0.7), (1.35, 0.7)] {
        Mesh::cylinder(Vec3::new(x, 0.0, z), Vec3::Y, 0.05, 0.95, 24, false).add_to(
            &mut b,
            "table leg",
            legs,
        )?;
    }
    Mesh::uv_sphere(Vec3::new(-0.6, 1.3, 0.1), 0.25, 64, 32).add_to(
        &mut b,
        "chrome sphere",
        chrome,
    )?;
    Mesh::torus(Vec3::new(0.55, 1.1, 0.25), 0.25, 0.05, 64, 24).add_to(
        &mut b,
        "glossy torus",
        red,
    )?;
    Mesh::cylinder(Vec3::new(0.3, 1.05, -0.45), Vec3::Y, 0.12, 0.45, 48, true)
        .add_to(&mut b, "vase", vase)?;

    // The chandelier: a rod, a hub, three rings on spokes.
    Mesh::cylinder(Vec3::new(0.0, RING_Y, 0.0), Vec3::Y, 0.025, 3.0, 16, false)
        .add_to(&mut b, "rod", brass)?;
    Mesh::uv_sphere(Vec3::new(0.0, RING_Y, 0.0), 0.12, 32, 16).add_to(&mut b, "hub", brass)?;
    for r in RINGS {
        Mesh::torus(Vec3::new(0.0, RING_Y, 0.0), r, 0.018, 128, 12)
            .add_to(&mut b, "ring", brass)?;
    }
    for k in 0..6 {
        let a = k as f32 * TAU / 6.0;
        let spoke = Mesh::cylinder(Vec3::ZERO, Vec3::X, 0.012, RINGS[2], 12, false);
        spoke
            .transformed(
                Mat4::from_translation(Vec3::new(0.0, RING_Y, 0.0)) * Mat4::from_rotation_y(a),
            )
            .add_to(&mut b, "spoke", brass)?;
    }
    // Bulbs hang in strands below the rings, ring shares proportional to circumference.
    let l = sphere_radiance(TOTAL_POWER, n, radius);
    let total: f32 = RINGS.iter().sum();
    for _ in 0..n {
        let mut t = uniform(&mut rng, 0.0, total);
        let mut ring = RINGS[2];
        for r in RINGS {
            if t < r {
                ring = r;
                break;
            }
            t -= r;
        }
        let phi = uniform(&mut rng, 0.0, TAU);
        let drop = uniform(&mut rng, 0.05, 0.6) * ring / RINGS[2];
        let c = Vec3::new(
            ring * phi.cos(),
            RING_Y - 0.018 - radius - drop,
            ring * phi.sin(),
        );
        let warm = Vec3::new(
            1.0,
            uniform(&mut rng, 0.7, 0.85),
            uniform(&mut rng, 0.45, 0.6),
        );
        b.add_sphere_light(
            c,
            radius,
            warm / render_core::colour::luminance(warm) * l,
            None,
        )?;
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        Vec3::new(0.0, 2.1, 5.2),
        Vec3::new(0.0, 1.75, 0.0),
        Vec3::Y,
        50f32.to_radians(),
        320,
        240,
    ))?);
    Ok(b)
}
