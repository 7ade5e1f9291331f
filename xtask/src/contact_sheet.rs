//! `cargo xtask contact-sheet`: one labelled PNG of every scene, rendered with the paper's method
//! (`mis3-adaptive`, unbiased default mode), into results/scenes/.
use crate::experiments::compositing::{Canvas, auto_exposure, tonemap};
use crate::experiments::manylights::{Manylights, repo_root};
use clap::Parser;
use std::path::Path;
use std::process::{Command, ExitCode};

/// No options: the scenes, size and spp are fixed so that the sheet is comparable across runs.
#[derive(Parser)]
#[command(
    name = "cargo xtask contact-sheet",
    about = "One labelled PNG of every scene (mis3-adaptive, 16 spp) into results/scenes/"
)]
struct Args {}

/// Built-ins at their defaults, then the compositions of real assets (skipped when absent).
const SCENES: [&str; 17] = [
    "builtin:car",
    "builtin:lamp",
    "builtin:statue",
    "builtin:cornell",
    "builtin:staircase",
    "builtin:glossy-spheres",
    "builtin:diffuse-quads",
    "builtin:grid",
    "builtin:emissive-mesh",
    "builtin:rooms",
    "../shared/scenes/bisml_cornell/bisml_cornell.glb",
    "experiments/scenes/toycar.toml",
    "experiments/scenes/buddha.toml",
    "experiments/scenes/bunny.toml",
    "experiments/scenes/staircase-wooden.toml",
    "experiments/scenes/staircase-hall.toml",
    "../shared/scenes/lamp_stained_glass/StainedGlassLamp.glb",
];

const TILE_W: u32 = 240;
const TILE_H: u32 = 180;
const LABEL_H: u32 = 18;
const COLUMNS: u32 = 4;
const SPP: &str = "16";

pub fn main(args: &[String]) -> ExitCode {
    crate::run_subcommand(args, |_: &Args| run())
}

fn run() -> Result<(), String> {
    let root = repo_root();
    let ml = Manylights::build()?;
    let out_dir = root.join("results/scenes");
    std::fs::create_dir_all(&out_dir).map_err(|e| e.to_string())?;
    let tmp = std::env::temp_dir().join(format!("manylights-contact-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).map_err(|e| e.to_string())?;
    let mut tiles = Vec::new();
    for spec in SCENES {
        let is_file = !spec.starts_with("builtin:");
        if is_file && !root.join(spec).exists() {
            eprintln!("skipping {spec}: not present on this machine");
            continue;
        }
        let exr = tmp.join(format!("{}.exr", tiles.len()));
        eprintln!("rendering {spec}…");
        let out = Command::new(&ml.exe)
            .current_dir(&root)
            .args([
                "render",
                spec,
                "--strategy",
                "mis3-adaptive",
                "--spp",
                SPP,
                "--seed",
                "1",
                "--aux",
                "--quiet",
            ])
            .args([
                "--width",
                &TILE_W.to_string(),
                "--height",
                &TILE_H.to_string(),
                "--out",
            ])
            .arg(&exr)
            .output()
            .map_err(|e| e.to_string())?;
        if !out.status.success() {
            eprintln!(
                "skipping {spec}: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            );
            continue;
        }
        let (w, h, px) = render_core::output::read_exr(&exr)?;
        let mask = render_core::output::read_mask_png(&exr.with_extension("mask.png"), w, h)?;
        let rgb = tonemap(&px, auto_exposure(&px, &mask));
        let label = spec
            .trim_start_matches("builtin:")
            .trim_start_matches("../shared/scenes/")
            .trim_start_matches("experiments/scenes/");
        tiles.push((label.to_string(), w, h, rgb));
    }
    let rows = (tiles.len() as u32).div_ceil(COLUMNS);
    let mut canvas = Canvas::new(COLUMNS * TILE_W, rows * (TILE_H + LABEL_H), 255);
    let mut texts = Vec::new();
    for (i, (label, w, h, rgb)) in tiles.iter().enumerate() {
        let (cx, cy) = (
            i as u32 % COLUMNS * TILE_W,
            i as u32 / COLUMNS * (TILE_H + LABEL_H),
        );
        canvas.blit(rgb, *w, (0, 0, *w, *h), cx, cy + LABEL_H, TILE_W, TILE_H);
        texts.push((cx as i32 + 4, cy as i32 + 2, 13, label.clone()));
    }
    let path = out_dir.join("contact-sheet.png");
    canvas.save_with_text(Path::new(&path), &texts)?;
    let _ = std::fs::remove_dir_all(&tmp);
    eprintln!(
        "wrote {} ({} scenes, mis3-adaptive at {SPP} spp)",
        path.display(),
        tiles.len()
    );
    Ok(())
}
