//! `cargo xtask glossy-mask SCENE WIDTH HEIGHT OUT.png [--max-alpha A]`: a mask for
//! `manylights compare --mask` that keeps only the pixels whose camera ray through the pixel
//! centre hits a surface with GGX α < A (default 0.05), e.g. the bunny and armadillo of the
//! authors' Cornell box (non-black = left out, as in a render's light mask).
use clap::Parser;
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
    /// Camera name (default: the scene's first).
    #[arg(long)]
    camera: Option<String>,
}

pub fn main(args: &[String]) -> ExitCode {
    let a = match Args::try_parse_from(args) {
        Ok(a) => a,
        Err(e) => e.exit(),
    };
    match run(&a) {
        Ok(n) => {
            eprintln!("glossy pixels: {n}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(a: &Args) -> Result<usize, String> {
    if a.width == 0 || a.height == 0 {
        return Err("width and height must be positive".into());
    }
    let scene =
        scene_formats::load_scene(&a.scene, a.camera.as_deref()).map_err(|e| e.to_string())?;
    let camera = scene.camera(None).map_err(|e| e.to_string())?;
    let (w, h) = (a.width, a.height);
    let aspect = w as f32 / h as f32;
    let mut excluded = vec![1.0f32; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let film =
                render_core::Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let dir = camera.ray_direction(film, aspect);
            if let Some(hit) = scene.intersect(camera.position, dir, 0.0, f32::INFINITY)
                && let Some(m) = hit.material
                && scene.materials[m as usize].params_at(hit.uv).alpha < a.max_alpha
            {
                excluded[(y * w + x) as usize] = 0.0;
            }
        }
    }
    render_core::output::write_mask_png(&a.out, w, h, &excluded)?;
    Ok(excluded.iter().filter(|&&e| e == 0.0).count())
}
