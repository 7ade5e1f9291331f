//! Image and metadata files, each written to a temporary name and renamed into place, so
//! an interrupted or failed write never leaves a partial file under the final name.
use crate::texture::linear_to_srgb;
use glam::Vec3;
use std::path::{Path, PathBuf};

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp.{ext}", std::process::id()))
}

/// Runs `write` on a temporary path beside `path`, then renames it to `path`.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), String> {
    let tmp = temp_path(path);
    match write(&tmp) {
        Ok(()) => std::fs::rename(&tmp, path).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            format!("cannot write {}: {e}", path.display())
        }),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(format!("cannot write {}: {e}", path.display()))
        }
    }
}

/// Linear RGB float32 EXR.
pub fn write_exr(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<(), String> {
    write_atomically(path, |tmp| {
        exr::prelude::write_rgb_file(tmp, width as usize, height as usize, |x, y| {
            let p = pixels[y * width as usize + x];
            (p.x, p.y, p.z)
        })
        .map_err(|e| e.to_string())
    })
}

/// Reads an RGB(A) EXR back into linear pixels.
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<Vec3>), String> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![Vec3::ZERO; res.width() * res.height()]),
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = Vec3::new(r, g, b)
        },
    )
    .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let size = image.layer_data.size;
    Ok((
        size.width() as u32,
        size.height() as u32,
        image.layer_data.channel_data.pixels.1,
    ))
}

pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), String> {
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            rgb,
            width,
            height,
            image::ColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())
    })
}

/// sRGB preview: linear × 2^exposure, clamped.
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Vec3],
    exposure: f32,
) -> Result<(), String> {
    let scale = 2f32.powf(exposure);
    let rgb: Vec<u8> = pixels
        .iter()
        .flat_map(|p| (*p * scale).to_array())
        .map(|c| (linear_to_srgb(if c.is_finite() { c } else { 0.0 }) * 255.0 + 0.5) as u8)
        .collect();
    write_png_rgb8(path, width, height, &rgb)
}

/// Greyscale-as-RGB PNG of values in [0, 1].
pub fn write_mask_png(path: &Path, width: u32, height: u32, values: &[f32]) -> Result<(), String> {
    let rgb: Vec<u8> = values
        .iter()
        .flat_map(|v| [(v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8; 3])
        .collect();
    write_png_rgb8(path, width, height, &rgb)
}

pub fn write_json(path: &Path, value: &serde_json::Value) -> Result<(), String> {
    write_atomically(path, |tmp| {
        let text = serde_json::to_string_pretty(value).map_err(|e| e.to_string())?;
        std::fs::write(tmp, text + "\n").map_err(|e| e.to_string())
    })
}

/// Reads a light mask PNG written by [`write_mask_png`]: true where the camera sees *no* light.
pub fn read_mask_png(path: &Path, width: u32, height: u32) -> Result<Vec<bool>, String> {
    let img = image::open(path)
        .map_err(|e| format!("cannot read mask {}: {e}", path.display()))?
        .to_luma8();
    if img.dimensions() != (width, height) {
        return Err(format!(
            "mask {} is {:?}, expected {width}x{height}",
            path.display(),
            img.dimensions()
        ));
    }
    Ok(img.pixels().map(|p| p.0[0] == 0).collect())
}
