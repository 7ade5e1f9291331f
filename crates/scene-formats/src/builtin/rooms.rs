//! `rooms`: a floor plan where visibility decides (issue 25). Six rooms, three on each side of
//! a corridor along x, each with a door in the wall it shares with the corridor, under one
//! ceiling; a few thousand small lights spread over all seven spaces (sphere lights and small
//! one-sided emissive triangles under the ceiling and on the walls). The camera stands in the
//! middle south room and looks through its door across the corridor into the middle north
//! room, so most lights are hidden from most shading points by walls.
use super::mesh::Mesh;
use super::{Params, area_radiance, emitter, light_color, pick, sphere_radiance, uniform};
use glam::{Vec2, Vec3};
use rand_pcg::Pcg32;
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;

/// Total emitted power, shared evenly by every light whatever its shape.
const TOTAL_POWER: f32 = 1500.0;
/// Room width along x, room depth along z, corridor half-width, storey height.
const ROOM_W: f32 = 6.0;
const ROOM_D: f32 = 5.0;
const HALF_CORRIDOR: f32 = 1.0;
const HEIGHT: f32 = 3.0;
const WALL: f32 = 0.1;
/// Door: half-width and height.
const DOOR_HALF: f32 = 0.75;
const DOOR_H: f32 = 2.2;
/// Sphere light radius and emissive triangle side.
const RADIUS: f32 = 0.02;
const TRI_SIDE: f32 = 0.08;
/// Share of the lights that are emissive triangles.
const TRIANGLE_SHARE: f32 = 0.4;
/// Emitter materials of the triangles (one colour each).
const COLORS: usize = 6;
/// No light within this distance of the camera.
const CAMERA_CLEARANCE: f32 = 0.8;

/// The seven spaces as (min, max) floor corners in x–z: rooms 0..6, then the corridor.
fn spaces() -> Vec<(Vec2, Vec2)> {
    let mut s = Vec::new();
    for side in [-1.0f32, 1.0] {
        for col in 0..3 {
            let x0 = (col as f32 - 1.5) * ROOM_W;
            let (z0, z1) = if side < 0.0 {
                (-HALF_CORRIDOR - ROOM_D, -HALF_CORRIDOR)
            } else {
                (HALF_CORRIDOR, HALF_CORRIDOR + ROOM_D)
            };
            s.push((Vec2::new(x0, z0), Vec2::new(x0 + ROOM_W, z1)));
        }
    }
    s.push((
        Vec2::new(-1.5 * ROOM_W, -HALF_CORRIDOR),
        Vec2::new(1.5 * ROOM_W, HALF_CORRIDOR),
    ));
    s
}

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let (n, roughness) = (p.lights()?, p.roughness()?);
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let glossy = b.add_material(Material::simple(
        "glossy floor",
        Vec3::new(0.2, 0.16, 0.12),
        0.0,
        roughness,
    ))?;
    let tiles = b.add_material(Material::simple(
        "glossy tiles",
        Vec3::new(0.35, 0.36, 0.38),
        0.0,
        roughness * 0.6,
    ))?;
    let carpet = b.add_material(Material::diffuse("carpet", Vec3::new(0.45, 0.3, 0.25)))?;
    let wall = b.add_material(Material::diffuse("walls", Vec3::new(0.75, 0.73, 0.68)))?;
    let ceiling = b.add_material(Material::diffuse("ceiling", Vec3::splat(0.8)))?;
    let wood = b.add_material(Material::simple(
        "furniture",
        Vec3::new(0.45, 0.28, 0.15),
        0.0,
        0.5,
    ))?;

    let (x_lo, x_hi) = (-1.5 * ROOM_W, 1.5 * ROOM_W);
    let z_hi = HALF_CORRIDOR + ROOM_D;
    // Floors: each room its own (glossy or diffuse), the corridor glossy tiles.
    let floor_mats = [carpet, glossy, carpet, carpet, glossy, carpet];
    for (i, (lo, hi)) in spaces().into_iter().enumerate() {
        let c = 0.5 * (lo + hi);
        let m = floor_mats.get(i).copied().unwrap_or(tiles);
        Mesh::plane(Vec3::new(c.x, 0.0, c.y), hi.x - lo.x, hi.y - lo.y)
            .add_to(&mut b, "floor", m)?;
    }
    // One ceiling over everything, facing down.
    Mesh::quad(
        Vec3::new(0.0, HEIGHT, 0.0),
        Vec3::new(0.5 * (x_hi - x_lo), 0.0, 0.0),
        Vec3::new(0.0, 0.0, z_hi),
    )
    .add_to(&mut b, "ceiling", ceiling)?;

    let mut walls = Mesh::default();
    // Outer walls.
    walls.append(&Mesh::cuboid(
        Vec3::new(x_lo - WALL, 0.0, -z_hi - WALL),
        Vec3::new(x_hi + WALL, HEIGHT, -z_hi),
    ));
    walls.append(&Mesh::cuboid(
        Vec3::new(x_lo - WALL, 0.0, z_hi),
        Vec3::new(x_hi + WALL, HEIGHT, z_hi + WALL),
    ));
    walls.append(&Mesh::cuboid(
        Vec3::new(x_lo - WALL, 0.0, -z_hi),
        Vec3::new(x_lo, HEIGHT, z_hi),
    ));
    walls.append(&Mesh::cuboid(
        Vec3::new(x_hi, 0.0, -z_hi),
        Vec3::new(x_hi + WALL, HEIGHT, z_hi),
    ));
    // Walls between neighbouring rooms (x = ±ROOM_W / 2), on both sides of the corridor.
    for x in [-0.5 * ROOM_W, 0.5 * ROOM_W] {
        for (z0, z1) in [(-z_hi, -HALF_CORRIDOR), (HALF_CORRIDOR, z_hi)] {
            walls.append(&Mesh::cuboid(
                Vec3::new(x - 0.5 * WALL, 0.0, z0),
                Vec3::new(x + 0.5 * WALL, HEIGHT, z1),
            ));
        }
    }
    // Corridor walls with one door per room, at a per-room offset along x (the middle rooms'
    // doors face each other, so the camera sees through both).
    let door_offsets = [1.2f32, 0.0, -1.4, -1.0, 0.0, 1.6];
    for (side, z) in [(0usize, -HALF_CORRIDOR), (1, HALF_CORRIDOR)] {
        let z0 = z - 0.5 * WALL;
        let z1 = z + 0.5 * WALL;
        for col in 0..3 {
            let x0 = (col as f32 - 1.5) * ROOM_W;
            let x1 = x0 + ROOM_W;
            let door = x0 + 0.5 * ROOM_W + door_offsets[side * 3 + col];
            let (d0, d1) = (door - DOOR_HALF, door + DOOR_HALF);
            walls.append(&Mesh::cuboid(
                Vec3::new(x0, 0.0, z0),
                Vec3::new(d0, HEIGHT, z1),
            ));
            walls.append(&Mesh::cuboid(
                Vec3::new(d1, 0.0, z0),
                Vec3::new(x1, HEIGHT, z1),
            ));
            walls.append(&Mesh::cuboid(
                Vec3::new(d0, DOOR_H, z0),
                Vec3::new(d1, HEIGHT, z1),
            ));
        }
    }
    walls.add_to(&mut b, "walls", wall)?;

    // A table and a cabinet in every room, placed at random but clear of its door.
    let mut furniture = Mesh::default();
    for (lo, hi) in spaces().into_iter().take(6) {
        let cx = uniform(&mut rng, lo.x + 1.2, hi.x - 1.2);
        let cz = 0.5 * (lo.y + hi.y) + uniform(&mut rng, -0.6, 0.6);
        furniture.append(&Mesh::cuboid(
            Vec3::new(cx - 0.7, 0.0, cz - 0.45),
            Vec3::new(cx + 0.7, 0.75, cz + 0.45),
        ));
        let far_z = if lo.y < 0.0 { lo.y } else { hi.y - 0.5 };
        let kx = uniform(&mut rng, lo.x + 0.5, hi.x - 1.5);
        furniture.append(&Mesh::cuboid(
            Vec3::new(kx, 0.0, far_z),
            Vec3::new(kx + 1.0, 1.8, far_z + 0.5),
        ));
    }
    furniture.add_to(&mut b, "furniture", wood)?;

    let eye = Vec3::new(1.4, 1.5, -HALF_CORRIDOR - ROOM_D + 1.2);
    let target = Vec3::new(-0.2, 1.1, HALF_CORRIDOR + 3.0);

    // Lights: every space gets its share (the corridor as much as a room), each light a
    // sphere under the ceiling or on a wall, or a small triangle facing down from the ceiling.
    let ls = sphere_radiance(TOTAL_POWER, n, RADIUS);
    let tri_area = 0.25 * 3f32.sqrt() * TRI_SIDE * TRI_SIDE;
    let lt = area_radiance(TOTAL_POWER, n, tri_area);
    let mut mats = Vec::with_capacity(COLORS);
    for i in 0..COLORS {
        mats.push(b.add_material(emitter(
            &format!("lamp {i}"),
            light_color(&mut rng) * lt,
            false,
        ))?);
    }
    let mut tris = vec![Mesh::default(); COLORS];
    let spaces = spaces();
    for _ in 0..n {
        let (lo, hi) = spaces[pick(&mut rng, spaces.len())];
        let triangle = uniform(&mut rng, 0.0, 1.0) < TRIANGLE_SHARE;
        let mut c = light_position(&mut rng, lo, hi, triangle);
        while c.distance(eye) < CAMERA_CLEARANCE {
            c = light_position(&mut rng, lo, hi, triangle);
        }
        if triangle {
            let k = pick(&mut rng, COLORS);
            tris[k].append(&down_triangle(c, uniform(&mut rng, 0.0, 1.0)));
        } else {
            b.add_sphere_light(c, RADIUS, light_color(&mut rng) * ls, None)?;
        }
    }
    for (k, m) in tris.iter().enumerate() {
        if m.triangle_count() > 0 {
            m.add_to(&mut b, &format!("lamps {k}"), mats[k])?;
        }
    }

    b.add_camera(p.camera(Camera::look_at(
        "main",
        eye,
        target,
        Vec3::Y,
        60f32.to_radians(),
        320,
        240,
    ))?);
    Ok(b)
}

/// Where a light of one space goes: triangles just under the ceiling; spheres under the
/// ceiling (60 %) or on a wall at lamp height (40 %), clear of the walls.
fn light_position(rng: &mut Pcg32, lo: Vec2, hi: Vec2, triangle: bool) -> Vec3 {
    let m = 0.25;
    let x = uniform(rng, lo.x + m, hi.x - m);
    let z = uniform(rng, lo.y + m, hi.y - m);
    if triangle {
        return Vec3::new(x, HEIGHT - 0.01, z);
    }
    if uniform(rng, 0.0, 1.0) < 0.6 {
        return Vec3::new(x, uniform(rng, HEIGHT - 0.4, HEIGHT - 0.1), z);
    }
    // On one of the four walls of the space, 0.1 in front of it.
    let y = uniform(rng, 1.4, 2.2);
    let inset = 0.5 * WALL + RADIUS + 0.08;
    match pick(rng, 4) {
        0 => Vec3::new(lo.x + inset, y, z),
        1 => Vec3::new(hi.x - inset, y, z),
        2 => Vec3::new(x, y, lo.y + inset),
        _ => Vec3::new(x, y, hi.y - inset),
    }
}

/// An equilateral triangle of side `TRI_SIDE` centred at `c`, horizontal, its front face
/// looking down, turned by `turn` of a full circle.
fn down_triangle(c: Vec3, turn: f32) -> Mesh {
    let r = TRI_SIDE / 3f32.sqrt();
    let corner = |k: usize| {
        let a = std::f32::consts::TAU * (turn + k as f32 / 3.0);
        c + Vec3::new(r * a.cos(), 0.0, r * a.sin())
    };
    // Increasing angle from +x towards +z winds counter-clockwise around −y.
    let positions = vec![corner(0), corner(1), corner(2)];
    let n = (positions[1] - positions[0])
        .cross(positions[2] - positions[0])
        .normalize();
    debug_assert!(n.y < 0.0);
    Mesh {
        positions,
        normals: vec![n; 3],
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::Y],
        indices: vec![0, 1, 2],
    }
}
