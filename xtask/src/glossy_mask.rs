//! `cargo xtask glossy-mask SCENE WIDTH HEIGHT OUT.png [--max-alpha A] [--subpixels N]
//! [--no-emitter-px]`: a mask for `manylights compare --mask` that keeps only the pixels whose
//! camera rays hit a surface with GGX α < A (default 0.05), e.g. the bunny and armadillo of the
//! authors' Cornell box (non-black = left out, as in a render's light mask).
//!
//! By default one ray through the pixel centre decides. The authors' "objects" set
//! (`../shared/scenes/bisml_cornell/README.md`) is stricter, and `--subpixels 16
//! --no-emitter-px` builds it: a pixel is kept only if every ray of an N×N grid over its area
//! hits a glossy surface (fully covered: no silhouette pixels, whose error is the
//! anti-aliasing of object against wall), and if no ray of that grid in its 3×3 neighbourhood
//! sees a light (no pixel next to a directly visible emitter).
use clap::Parser;
use render_core::Vec2;
use render_core::scene::{NO_LIGHT, Scene};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "cargo xtask glossy-mask",
    about = "Mask of the pixels that see a glossy surface"
)]
struct Args {
    scene: String,
    width: u32,
    height: u32,
    out: PathBuf,
    #[arg(long, default_value_t = 0.05)]
    max_alpha: f32,
    /// Rays per pixel side: a pixel is kept only if all N×N rays of a grid over its area see a
    /// glossy surface (1: the pixel centre alone).
    #[arg(long, default_value_t = 1)]
    subpixels: u32,
    /// Also leave out every pixel whose 3×3 neighbourhood has a ray (of the same grid) that
    /// sees a light.
    #[arg(long)]
    no_emitter_px: bool,
    /// Half-width in pixels of the square the grid covers around the pixel centre: 0.5 is the
    /// pixel; 1 is the support of a splatted triangle filter of radius 1 (every sample that
    /// reaches the pixel).
    #[arg(long, default_value_t = 0.5)]
    footprint: f32,
    /// Camera name (default: the scene's first).
    #[arg(long)]
    camera: Option<String>,
}

pub fn main(args: &[String]) -> ExitCode {
    crate::run_subcommand(args, |a| run(a).map(|n| eprintln!("glossy pixels: {n}")))
}

fn run(a: &Args) -> Result<usize, String> {
    if a.width == 0 || a.height == 0 {
        return Err("width and height must be positive".into());
    }
    if !(a.footprint > 0.0 && a.footprint <= 4.0) {
        return Err(format!("--footprint {} is not in (0, 4]", a.footprint));
    }
    if !(1..=64).contains(&a.subpixels) {
        return Err(format!("--subpixels {} is not in 1..=64", a.subpixels));
    }
    let scene =
        scene_formats::load_scene(&a.scene, a.camera.as_deref()).map_err(|e| e.to_string())?;
    let kept = kept_pixels(&scene, a.width, a.height, &a.grid())?;
    let excluded: Vec<f32> = kept.iter().map(|&k| if k { 0.0 } else { 1.0 }).collect();
    render_core::output::write_mask_png(&a.out, a.width, a.height, &excluded)?;
    Ok(kept.iter().filter(|&&k| k).count())
}

/// Which rays decide a pixel (see the module's doc).
struct Grid {
    max_alpha: f32,
    subpixels: u32,
    footprint: f32,
    no_emitter_px: bool,
}

impl Args {
    fn grid(&self) -> Grid {
        Grid {
            max_alpha: self.max_alpha,
            subpixels: self.subpixels,
            footprint: self.footprint,
            no_emitter_px: self.no_emitter_px,
        }
    }
}

/// Per pixel in row order: whether the mask keeps it.
fn kept_pixels(scene: &Scene, w: u32, h: u32, g: &Grid) -> Result<Vec<bool>, String> {
    let camera = scene.camera(None).map_err(|e| e.to_string())?;
    let aspect = w as f32 / h as f32;
    let n = g.subpixels;
    let mut glossy = vec![true; (w * h) as usize];
    let mut sees_light = vec![false; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            for (dx, dy) in (0..n * n).map(|k| (k % n, k / n)) {
                // Cell centres of an n×n grid over [centre − r, centre + r]².
                let offset = |d: u32| g.footprint * (2.0 * (d as f32 + 0.5) / n as f32 - 1.0);
                let film = Vec2::new(
                    (x as f32 + 0.5 + offset(dx)) / w as f32,
                    (y as f32 + 0.5 + offset(dy)) / h as f32,
                );
                let dir = camera.ray_direction(film, aspect);
                let hit = scene.intersect(camera.position, dir, 0.0, f32::INFINITY);
                glossy[i] &= hit.as_ref().is_some_and(|hit| {
                    hit.material.is_some_and(|m| {
                        scene.materials[m as usize].params_at(hit.uv).alpha < g.max_alpha
                    })
                });
                // Seeing a light as the render's light mask does: an emitter hit from its
                // emitting side (a one-sided emitter seen from behind is dark).
                sees_light[i] |= hit.is_some_and(|hit| {
                    hit.light != NO_LIGHT
                        && scene.lights[hit.light as usize].emitted(hit.ng, hit.uv, -dir)
                            != render_core::Vec3::ZERO
                });
            }
        }
    }
    let near_light = |x: u32, y: u32| {
        let (x0, x1) = (x.saturating_sub(1), (x + 1).min(w - 1));
        let (y0, y1) = (y.saturating_sub(1), (y + 1).min(h - 1));
        (y0..=y1).any(|yy| (x0..=x1).any(|xx| sees_light[(yy * w + xx) as usize]))
    };
    Ok((0..w * h)
        .map(|i| glossy[i as usize] && !(g.no_emitter_px && near_light(i % w, i / w)))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kept(scene: &Scene, subpixels: u32, footprint: f32, no_emitter_px: bool) -> Vec<bool> {
        let g = Grid {
            max_alpha: 0.5,
            subpixels,
            footprint,
            no_emitter_px,
        };
        kept_pixels(scene, 64, 48, &g).unwrap()
    }

    /// Each stricter option drops pixels: the glossy surfaces' silhouettes (all rays of a grid,
    /// then of the filter's support) and the pixels around the emitters the camera sees. Odd
    /// grids hold the centre ray, so they keep a subset of the centre-only mask's pixels.
    #[test]
    fn stricter_options_drop_silhouettes_and_emitter_neighbours() {
        let scene = scene_formats::load_scene("builtin:emissive-mesh?lights=100", None).unwrap();
        let centre = kept(&scene, 1, 0.5, false);
        let pixel = kept(&scene, 9, 0.5, false);
        let support = kept(&scene, 9, 1.0, false);
        let clear = kept(&scene, 9, 1.0, true);
        let subset = |a: &[bool], b: &[bool]| a.iter().zip(b).all(|(&x, &y)| !x || y);
        assert!(subset(&pixel, &centre) && subset(&support, &centre) && subset(&clear, &support));
        let count = |m: &[bool]| m.iter().filter(|&&k| k).count();
        let counts = [
            count(&centre),
            count(&pixel),
            count(&support),
            count(&clear),
        ];
        assert!(
            counts.windows(2).all(|c| c[1] < c[0]) && counts[3] > 0,
            "{counts:?}"
        );
    }
}
