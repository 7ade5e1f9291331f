//! What the learned selection learns (issue 25): the selection probability of every light of
//! `builtin:rooms` at one shading point, unshadowed (the prior alone) on the left and after
//! some passes of `learned+bsdf` on the right, as a top view of the floor plan.
//!
//! Each light is a square coloured by log₁₀ of its probability (one scale for both panels,
//! dark blue → yellow); filled where the light's centre is visible from the point, hollow where
//! a wall hides it. Grey lines are the vertical faces (walls, furniture); the white cross is the
//! shading point. It also prints the probability each side puts on visible lights.
//!
//! `cargo run --release -p samplers --example learned_map -- OUT.png [PASSES] [FILM_X FILM_Y]`
//! (defaults: 32 passes at 128², the point the camera sees at film position (0.5, 0.9), on the
//! floor of its own room).
use image::{Rgb, RgbImage};
use render_core::light::LightShape;
use render_core::render::{RenderSettings, render, shading_point};
use render_core::scene::Scene;
use render_core::{Vec2, Vec3};
use samplers::learned::LearnedConfig;
use samplers::learned::regions::RegionTable;
use samplers::learned::selection::LearnedSelection;
use samplers::learned::strategy::LearnedStrategy;
use samplers::selection::LightSelection;
use samplers::tree_selection::PowerUnits;

const PANEL: u32 = 420;
const MARGIN: u32 = 10;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = args
        .first()
        .ok_or("usage: learned_map OUT.png [PASSES] [FILM_X FILM_Y]")?;
    let passes: u32 = args
        .get(1)
        .map_or(Ok(32), |s| s.parse())
        .map_err(|e| format!("{e}"))?;
    let film = match (args.get(2), args.get(3)) {
        (Some(x), Some(y)) => Vec2::new(
            x.parse().map_err(|e| format!("{e}"))?,
            y.parse().map_err(|e| format!("{e}"))?,
        ),
        _ => Vec2::new(0.5, 0.9),
    };
    let scene = scene_formats::load_scene("builtin:rooms", None).map_err(|e| e.to_string())?;
    let config = LearnedConfig::default();
    let strategy = LearnedStrategy {
        name: "learned+bsdf".into(),
        selection: LearnedSelection::new(&scene, PowerUnits::Watts, config)?,
        with_bsdf: true,
        light_samples: 1,
        pass_weights: samplers::learned::PassWeights::Equal,
    };
    let camera = scene.camera(None).map_err(|e| e.to_string())?;
    let settings = RenderSettings {
        width: 128,
        height: 128,
        spp: Some(passes),
        seed: 1,
        time_budget: None,
        threads: None,
        camera: camera.clone(),
        sampler: Default::default(),
        filter: Default::default(),
        reconstruction: Default::default(),
        emission_rays: Default::default(),
        engine: Default::default(),
    };
    render(&scene, &strategy, &settings, &|_, _| {})?;

    let dir = camera.ray_direction(film, 1.0);
    let hit = scene
        .intersect(camera.position, dir, 0.0, f32::INFINITY)
        .ok_or("the camera ray at that film position hits nothing")?;
    let sp = shading_point(&scene, hit, -dir).ok_or("no shading point there")?;
    let sel = &strategy.selection;
    let learnt_table = sel.table.read().unwrap_or_else(|e| e.into_inner());
    let unlearnt = RegionTable::new(sel.cut.len(), config.max_regions);
    let prior = sel.prepare_with(&scene, &sp, &unlearnt);
    let learnt = sel.prepare_with(&scene, &sp, &learnt_table);

    let x = sp.point();
    let lights: Vec<(Vec3, bool, f32, f32)> = (0..scene.lights.len() as u32)
        .map(|l| {
            let light = &scene.lights[l as usize];
            let (blo, bhi) = light.bounds();
            let c = 0.5 * (blo + bhi);
            // Aim at the near side of a sphere light, which would otherwise hide its own centre.
            let target = match light.shape {
                LightShape::Sphere { center, radius } => {
                    center + radius * (x - center).normalize_or_zero()
                }
                _ => c,
            };
            let (d, dist) = ((target - x).normalize(), (target - x).length());
            let origin = render_core::scene::offset_origin(x, sp.bsdf.ng, d);
            let seen = !scene.occluded(origin, d, dist * 0.999);
            (c, seen, sel.pmf(&prior, &sp, l), sel.pmf(&learnt, &sp, l))
        })
        .collect();
    let on_visible = |k: usize| -> f64 {
        let pick = |t: &(Vec3, bool, f32, f32)| if k == 0 { t.2 } else { t.3 } as f64;
        lights.iter().filter(|t| t.1).map(pick).sum::<f64>() / lights.iter().map(pick).sum::<f64>()
    };
    let visible = lights.iter().filter(|t| t.1).count();
    println!(
        "point {x:?} in region {:#x}; {visible} of {} light centres visible; probability on them: \
         unshadowed {:.3}, learnt after {passes} passes {:.3}",
        learnt.key,
        lights.len(),
        on_visible(0),
        on_visible(1)
    );

    let image = draw(&scene, &lights, x);
    image.save(out).map_err(|e| format!("{out}: {e}"))?;
    println!("wrote {out}");
    Ok(())
}

/// The two panels side by side, one shared colour scale.
fn draw(scene: &Scene, lights: &[(Vec3, bool, f32, f32)], point: Vec3) -> RgbImage {
    let (lo, hi) = scene.bounds;
    let span = (hi.x - lo.x).max(hi.z - lo.z).max(1e-6);
    let to_px = |p: Vec3, panel: u32| -> (i64, i64) {
        let u = (p.x - lo.x) / span;
        let v = (p.z - lo.z) / span;
        let off = MARGIN + panel * (PANEL + MARGIN);
        (
            (off as f32 + u * PANEL as f32) as i64,
            (MARGIN as f32 + v * PANEL as f32) as i64,
        )
    };
    let height = ((hi.z - lo.z) / span * PANEL as f32).ceil() as u32;
    let mut img = RgbImage::from_pixel(
        2 * PANEL + 3 * MARGIN,
        height + 2 * MARGIN,
        Rgb([12, 12, 16]),
    );
    for t in &scene.triangles {
        let ng = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize_or_zero();
        if ng.y.abs() > 0.1 {
            continue;
        }
        for panel in 0..2 {
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                line(
                    &mut img,
                    to_px(t.p[a], panel),
                    to_px(t.p[b], panel),
                    Rgb([70, 70, 78]),
                );
            }
        }
    }
    let logs: Vec<f32> = lights
        .iter()
        .flat_map(|t| [t.2, t.3])
        .filter(|&p| p > 0.0)
        .map(f32::log10)
        .collect();
    let (min, max) = logs
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    for (c, seen, p_prior, p_learnt) in lights {
        for (panel, p) in [(0u32, *p_prior), (1, *p_learnt)] {
            let t = if p > 0.0 && max > min {
                (p.log10() - min) / (max - min)
            } else {
                0.0
            };
            square(&mut img, to_px(*c, panel), colour(t), *seen);
        }
    }
    for panel in 0..2 {
        let (px, py) = to_px(point, panel);
        line(&mut img, (px - 6, py), (px + 6, py), Rgb([255, 255, 255]));
        line(&mut img, (px, py - 6), (px, py + 6), Rgb([255, 255, 255]));
    }
    img
}

/// Dark blue → magenta → yellow for t in [0, 1].
fn colour(t: f32) -> Rgb<u8> {
    let stops = [
        [30.0, 30.0, 120.0],
        [200.0, 40.0, 140.0],
        [255.0, 230.0, 60.0],
    ];
    let s = t.clamp(0.0, 1.0) * 2.0;
    let (i, f) = ((s.floor() as usize).min(1), s - s.floor().min(1.0));
    let c = |k: usize| (stops[i][k] + (stops[i + 1][k] - stops[i][k]) * f) as u8;
    Rgb([c(0), c(1), c(2)])
}

/// A 5 × 5 square at `(x, y)`: filled, or its outline only.
fn square(img: &mut RgbImage, (x, y): (i64, i64), c: Rgb<u8>, filled: bool) {
    for dy in -2..=2i64 {
        for dx in -2..=2i64 {
            if filled || dx.abs() == 2 || dy.abs() == 2 {
                put(img, x + dx, y + dy, c);
            }
        }
    }
}

fn line(img: &mut RgbImage, (x0, y0): (i64, i64), (x1, y1): (i64, i64), c: Rgb<u8>) {
    let n = (x1 - x0).abs().max((y1 - y0).abs()).max(1);
    for i in 0..=n {
        put(img, x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n, c);
    }
}

fn put(img: &mut RgbImage, x: i64, y: i64, c: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, c);
    }
}
