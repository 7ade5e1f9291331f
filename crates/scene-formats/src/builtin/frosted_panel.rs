//! `frosted-panel`: a frosted-glass pane (a rough dielectric, one interface) facing the
//! camera, lit from behind by a cloud of small two-sided emissive triangles, with a diffuse
//! floor, a diffuse sphere and a glossy box in front of it and a few lights above the camera
//! so that they are seen. Most of what the pane shows arrives from below its horizon: light
//! selection that culls by the receiver's hemisphere finds none of it.
use super::mesh::Mesh;
use super::{Params, area_radiance, emitter, light_color, pick, uniform};
use glam::Vec3;
use render_core::bsdf::dielectric;
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;

/// Total emitted power of the lights behind the pane, and of those in front.
const BEHIND_POWER: f32 = 60.0;
const FRONT_POWER: f32 = 12.0;
/// Share of the lights that hang in front of the pane, above the camera.
const FRONT_SHARE: f32 = 0.1;
/// Side of each emissive triangle.
const SIDE: f32 = 0.05;
/// Colours of the lights: one emitter material each.
const COLORS: usize = 6;
/// The pane: centre and half extents in x and y, in the plane z = `PANE.0.z`, facing +z.
const PANE: (Vec3, f32, f32) = (Vec3::new(0.0, 1.1, 0.0), 1.3, 1.0);

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let n = p.lights()?;
    let roughness = p.roughness()?;
    let frost = p.number("frost", 1e-3, 1.0)?;
    let ior = p.number("ior", 1.01, 3.0)?;
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let glass = b.add_material(dielectric::material(
        "frosted glass",
        Vec3::new(0.95, 0.97, 1.0),
        ior,
        frost,
    ))?;
    let floor = b.add_material(Material::diffuse("floor", Vec3::splat(0.6)))?;
    let white = b.add_material(Material::diffuse("diffuse sphere", Vec3::splat(0.75)))?;
    let glossy = b.add_material(Material::simple(
        "glossy box",
        Vec3::new(0.6, 0.2, 0.1),
        0.0,
        roughness,
    ))?;
    let (c, hx, hy) = PANE;
    Mesh::quad(c, Vec3::new(hx, 0.0, 0.0), Vec3::new(0.0, hy, 0.0)).add_to(
        &mut b,
        "frosted pane",
        glass,
    )?;
    Mesh::plane(Vec3::ZERO, 12.0, 12.0).add_to(&mut b, "floor", floor)?;
    Mesh::uv_sphere(Vec3::new(-0.55, 0.3, 1.3), 0.3, 48, 24).add_to(
        &mut b,
        "diffuse sphere",
        white,
    )?;
    Mesh::rounded_box(Vec3::new(0.6, 0.25, 1.0), Vec3::splat(0.25), 0.04, 3).add_to(
        &mut b,
        "glossy box",
        glossy,
    )?;

    let n_front = ((n as f32 * FRONT_SHARE) as usize).min(n - 1);
    let n_behind = n - n_front;
    let area = 3f32.sqrt() / 4.0 * SIDE * SIDE;
    // two-sided emitters: each side emits π·L·A
    let l_behind = area_radiance(BEHIND_POWER, n_behind, 2.0 * area);
    let l_front = area_radiance(FRONT_POWER, n_front.max(1), 2.0 * area);
    let colours: Vec<Vec3> = (0..COLORS).map(|_| light_color(&mut rng)).collect();
    let mut mats = Vec::with_capacity(2 * COLORS);
    for (i, c) in colours.iter().enumerate() {
        mats.push(b.add_material(emitter(&format!("behind {i}"), *c * l_behind, true))?);
    }
    for (i, c) in colours.iter().enumerate() {
        mats.push(b.add_material(emitter(&format!("front {i}"), *c * l_front, true))?);
    }
    let mut groups = vec![Mesh::default(); 2 * COLORS];
    for k in 0..n {
        let (centre, group) = if k < n_behind {
            let c = Vec3::new(
                uniform(&mut rng, -2.2, 2.2),
                uniform(&mut rng, 0.1, 2.6),
                uniform(&mut rng, -2.5, -0.3),
            );
            (c, pick(&mut rng, COLORS))
        } else {
            let c = Vec3::new(
                uniform(&mut rng, -2.0, 2.0),
                uniform(&mut rng, 2.4, 2.9),
                uniform(&mut rng, 0.8, 4.0),
            );
            (c, COLORS + pick(&mut rng, COLORS))
        };
        groups[group].append(&small_triangle(&mut rng, centre));
    }
    for (k, m) in groups.iter().enumerate() {
        if m.triangle_count() > 0 {
            m.add_to(&mut b, &format!("emissive triangles {k}"), mats[k])?;
        }
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        Vec3::new(0.0, 1.2, 5.0),
        Vec3::new(0.0, 0.9, 0.0),
        Vec3::Y,
        45f32.to_radians(),
        256,
        256,
    ))?);
    Ok(b)
}

/// An equilateral triangle of side [`SIDE`] around `centre`, turned at random.
fn small_triangle(rng: &mut rand_pcg::Pcg32, centre: Vec3) -> Mesh {
    let z = uniform(rng, -1.0, 1.0);
    let phi = uniform(rng, 0.0, std::f32::consts::TAU);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let normal = Vec3::new(r * phi.cos(), r * phi.sin(), z);
    let frame = render_core::frame::Frame::from_normal(normal);
    let radius = SIDE / 3f32.sqrt();
    let turn = uniform(rng, 0.0, std::f32::consts::TAU);
    let corner = |k: f32| {
        let a = turn + k * std::f32::consts::TAU / 3.0;
        centre + radius * (frame.x * a.cos() + frame.y * a.sin())
    };
    Mesh {
        positions: vec![corner(0.0), corner(1.0), corner(2.0)],
        normals: vec![normal; 3],
        uvs: vec![glam::Vec2::ZERO; 3],
        indices: vec![0, 1, 2],
    }
}
