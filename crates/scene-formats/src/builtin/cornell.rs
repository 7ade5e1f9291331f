//! `cornell`: the modified Cornell box of Liu, Xu and Yan (2019) in spirit: the box
//! x ∈ [−1, 1], y ∈ [0, 2], z ∈ [−1, 1] open towards the camera (+z), five diffuse walls, two
//! very glossy objects (roughness 0.1 → α = 0.01 by default), and tiny sphere lights
//! (r = 0.001 by default, 0.0005 of the box size) spelling letters on the side walls:
//! "EGSR" over "2019" on the left, "BRDF" over "MIS" on the right, with the authors' three
//! main radiances. The camera is theirs (eye (0, 1, 6.8), 19.5°).
use super::mesh::Mesh;
use super::{Params, uniform};
use glam::{Mat4, Vec3};
use render_core::camera::Camera;
use render_core::colour::luminance;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;

/// The authors' light count and radius: at these the radiances below are theirs.
const REF_LIGHTS: usize = 1494;
const REF_RADIUS: f32 = 0.001;
const WARM: Vec3 = Vec3::new(282.0, 196.5, 105.0);
const BLUE: Vec3 = Vec3::new(67.5, 37.5, 256.5);
const PINK: Vec3 = Vec3::new(300.0, 180.0, 225.0);

/// 5 × 7 glyphs, top row first, `#` = lit.
fn glyph(c: char) -> [&'static str; 7] {
    match c {
        'E' => [
            "#####", "#....", "#....", "####.", "#....", "#....", "#####",
        ],
        'G' => [
            ".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".###.",
        ],
        'S' => [
            ".####", "#....", "#....", ".###.", "....#", "....#", "####.",
        ],
        'R' => [
            "####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#",
        ],
        'B' => [
            "####.", "#...#", "#...#", "####.", "#...#", "#...#", "####.",
        ],
        'D' => [
            "####.", "#...#", "#...#", "#...#", "#...#", "#...#", "####.",
        ],
        'F' => [
            "#####", "#....", "#....", "####.", "#....", "#....", "#....",
        ],
        'M' => [
            "#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#",
        ],
        'I' => [
            "#####", "..#..", "..#..", "..#..", "..#..", "..#..", "#####",
        ],
        '2' => [
            ".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####",
        ],
        '0' => [
            ".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###.",
        ],
        '1' => [
            "..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###.",
        ],
        '9' => [
            ".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##..",
        ],
        _ => ["....."; 7],
    }
}

/// A lit cell of the lettering: its centre on the wall plane, the wall's in-plane axes
/// (reading direction, up) and its radiance at the reference count and radius.
struct Cell {
    center: Vec3,
    along: Vec3,
    radiance: Vec3,
}

/// Cell size: 4 glyphs of 5 columns plus gaps across 1.8 units of wall.
const CELL: f32 = 0.075;

fn letter_cells(text: &str, wall_x: f32, top_y: f32, radiance: Vec3, cells: &mut Vec<Cell>) {
    // Seen from inside the box, reading runs towards −z on the left wall and +z on the right.
    let along = if wall_x < 0.0 { Vec3::NEG_Z } else { Vec3::Z };
    let width = text.chars().count() as f32 * 6.0 - 1.0;
    let start = -along * (0.5 * width * CELL) + Vec3::new(wall_x, top_y, 0.0);
    for (k, ch) in text.chars().enumerate() {
        for (row, line) in glyph(ch).iter().enumerate() {
            for (col, px) in line.chars().enumerate() {
                if px == '#' {
                    let u = (k * 6 + col) as f32 + 0.5;
                    let center = start + along * (u * CELL) - Vec3::Y * ((row as f32 + 0.5) * CELL);
                    cells.push(Cell {
                        center,
                        along,
                        radiance,
                    });
                }
            }
        }
    }
}

pub fn build(p: &Params) -> Result<SceneBuilder, SceneError> {
    let (n, radius, roughness) = (p.lights()?, p.radius()?, p.roughness()?);
    let mut rng = p.rng()?;
    let mut b = p.builder();

    let white = b.add_material(Material::diffuse("walls", Vec3::new(0.725, 0.71, 0.68)))?;
    let pink = b.add_material(Material::simple(
        "glossy pink",
        Vec3::new(0.3, 0.1, 0.2),
        0.0,
        roughness,
    ))?;
    let teal = b.add_material(Material::simple(
        "glossy teal",
        Vec3::new(0.1, 0.3, 0.3),
        0.0,
        roughness,
    ))?;

    // Five walls facing into the box.
    let walls = [
        (
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 0.0),
        ), // floor, +y
        (
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ), // ceiling, −y
        (
            Vec3::new(0.0, 1.0, -1.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ), // back, +z
        (
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ), // left, +x
        (
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 0.0),
        ), // right, −x
    ];
    for (c, u, v) in walls {
        Mesh::quad(c, u, v).add_to(&mut b, "wall", white)?;
    }
    Mesh::uv_sphere(Vec3::new(0.5, 0.32, 0.3), 0.32, 128, 64).add_to(
        &mut b,
        "glossy sphere",
        pink,
    )?;
    let tall = Mesh::rounded_box(Vec3::ZERO, Vec3::new(0.28, 0.6, 0.28), 0.1, 6);
    tall.transformed(
        Mat4::from_translation(Vec3::new(-0.4, 0.6, -0.3)) * Mat4::from_rotation_y(0.4),
    )
    .add_to(&mut b, "glossy block", teal)?;

    let mut cells = Vec::new();
    let x = 1.0 - radius - 1e-4;
    letter_cells("EGSR", -x, 1.85, WARM, &mut cells);
    letter_cells("2019", -x, 1.1, BLUE, &mut cells);
    letter_cells("BRDF", x, 1.85, PINK, &mut cells);
    letter_cells("MIS", x, 1.1, PINK, &mut cells);
    // Lights spread evenly over the lit cells in order; radiances scaled so the total power is
    // that of the reference layout (1494 lights of r = 0.001 with the radiances above).
    let cell_of = |i: usize, count: usize| {
        &cells[((i as f64 + 0.5) * cells.len() as f64 / count as f64) as usize]
    };
    let power = |count: usize, r: f32| -> f32 {
        (0..count)
            .map(|i| luminance(cell_of(i, count).radiance))
            .sum::<f32>()
            * r
            * r
    };
    let scale = power(REF_LIGHTS, REF_RADIUS) / power(n, radius);
    for i in 0..n {
        let cell = cell_of(i, n);
        let jitter = cell.along * uniform(&mut rng, -0.45, 0.45) * CELL
            + Vec3::Y * uniform(&mut rng, -0.45, 0.45) * CELL;
        b.add_sphere_light(cell.center + jitter, radius, cell.radiance * scale, None)?;
    }
    b.add_camera(p.camera(Camera::look_at(
        "main",
        Vec3::new(0.0, 1.0, 6.8),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::Y,
        19.5f32.to_radians(),
        256,
        256,
    ))?);
    Ok(b)
}
