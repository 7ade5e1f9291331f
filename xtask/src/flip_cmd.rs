//! `cargo xtask flip IMAGE.exr REFERENCE.exr [--mask M.png]… [--map OUT.png] [--json]`: HDR-ꟻLIP
//! of an EXR against a reference EXR, as the experiment harness scores its cells
//! (`experiments/flip.rs`): the mean over all pixels and, with masks, over the unlit ones, and
//! the error map in magma colours. The companion of `manylights compare` (relMSE), kept here
//! so that the renderer's CLI builds without ꟻLIP's C++.
use crate::experiments::flip;
use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "cargo xtask flip",
    about = "HDR-ꟻLIP of an EXR against a reference EXR (mean over all and over unlit pixels, magma map)"
)]
struct Args {
    image: PathBuf,
    reference: PathBuf,
    /// Light mask written by `render --aux` (non-black = the camera sees a light there); given
    /// more than once, a pixel is unlit only if it is in every mask (as `manylights compare`).
    #[arg(long)]
    mask: Vec<PathBuf>,
    /// Write the per-pixel HDR-ꟻLIP map here (PNG, magma: black 0 → yellow-white 1).
    #[arg(long)]
    map: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

pub fn main(args: &[String]) -> ExitCode {
    crate::run_subcommand(args, run)
}

fn run(a: &Args) -> Result<(), String> {
    let (w, h, x) = render_core::output::read_exr(&a.image)?;
    let (rw, rh, r) = render_core::output::read_exr(&a.reference)?;
    if (w, h) != (rw, rh) {
        return Err(format!(
            "{} is {w}x{h} but the reference {} is {rw}x{rh}",
            a.image.display(),
            a.reference.display()
        ));
    }
    let mut unlit: Option<Vec<bool>> = None;
    for m in &a.mask {
        let u = render_core::output::read_mask_png(m, w, h)?;
        unlit = Some(match unlit {
            Some(acc) => acc.iter().zip(&u).map(|(a, b)| *a && *b).collect(),
            None => u,
        });
    }
    let map = flip::hdr_flip_map(&x, &r, w, h)?;
    let all = flip::mean(&map, None);
    let masked = unlit
        .as_deref()
        .map(|m| (flip::mean(&map, Some(m)), m.iter().filter(|&&u| u).count()));
    if let Some(p) = &a.map {
        flip::save_map(p, &map, w, h)?;
    }
    let exposures = flip::exposures(&r);
    if a.json {
        println!(
            "{}",
            serde_json::json!({
                "flip_all": all,
                "flip_unlit": masked.map(|m| m.0),
                "unlit_pixels": masked.map(|m| m.1),
                "pixels": map.len(),
                "exposures": exposures,
                "pixels_per_degree": flip::PIXELS_PER_DEGREE,
            })
        );
    } else {
        println!("all pixels    HDR-ꟻLIP {all:.6}  ({} px)", map.len());
        if let Some((u, n)) = masked {
            println!("unlit pixels  HDR-ꟻLIP {u:.6}  ({n} px)");
        }
        println!(
            "{} exposures from {:.2} to {:.2} stops, {} pixels per degree",
            exposures.len(),
            exposures.first().unwrap_or(&0.0),
            exposures.last().unwrap_or(&0.0),
            flip::PIXELS_PER_DEGREE
        );
    }
    Ok(())
}
