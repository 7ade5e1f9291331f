//! Image and metadata files, each written to a temporary name and renamed into place, so
//! an interrupted or failed write never leaves a partial file under the final name; a
//! [`FileSet`] puts several in place together (a render's image, previews and record).
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

/// Runs `write` on a temporary path beside `path`, then renames it to `path` (a
/// [`FileSet`] of one file).
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), String> {
    let mut set = FileSet::default();
    set.stage(path, write)?;
    set.commit()
}

/// Files written together: each to a temporary name beside its own, then [`FileSet::commit`]
/// renames them all into place, in the order written (a record written last names files
/// already in place). A write that fails, or a set dropped before its commit, removes the
/// temporary files and leaves every final name as it was; a rename that fails (a directory
/// put in a file's place meanwhile) leaves those renamed before it.
#[derive(Default)]
pub struct FileSet {
    /// (temporary, final) paths, in the order written.
    staged: Vec<(PathBuf, PathBuf)>,
}

impl FileSet {
    /// Writes one file of the set to its temporary name (`write` gets that path).
    pub fn stage(
        &mut self,
        path: &Path,
        write: impl FnOnce(&Path) -> Result<(), String>,
    ) -> Result<(), String> {
        let tmp = temp_path(path);
        self.staged.push((tmp.clone(), path.to_path_buf()));
        write(&tmp).map_err(|e| format!("cannot write {}: {e}", path.display()))
    }

    /// Renames every staged file into place, in the order written.
    pub fn commit(mut self) -> Result<(), String> {
        let staged = std::mem::take(&mut self.staged);
        let mut left = staged.iter();
        for (tmp, path) in left.by_ref() {
            if let Err(e) = std::fs::rename(tmp, path) {
                let _ = std::fs::remove_file(tmp);
                for (tmp, _) in left {
                    let _ = std::fs::remove_file(tmp);
                }
                return Err(format!("cannot write {}: {e}", path.display()));
            }
        }
        Ok(())
    }
}

impl Drop for FileSet {
    fn drop(&mut self) {
        for (tmp, _) in &self.staged {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Linear RGB float32 EXR, the same bytes for the same pixels: the exr crate's default
/// encoding (RLE, 64×64 tiles) with its tiles in increasing order, which it then keeps
/// although it compresses them in parallel (in its default "unspecified" order a tile went
/// into the file when its compression finished, so the bytes changed from run to run).
pub fn write_exr(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<(), String> {
    write_atomically(path, exr_encoder(width, height, pixels))
}

/// [`write_exr`]'s bytes, written to the path it is given.
pub fn exr_encoder(
    width: u32,
    height: u32,
    pixels: &[Vec3],
) -> impl FnOnce(&Path) -> Result<(), String> + '_ {
    use exr::prelude::*;
    let encoding = Encoding {
        line_order: LineOrder::Increasing,
        ..Encoding::FAST_LOSSLESS
    };
    let channels = SpecificChannels::rgb(move |Vec2(x, y): Vec2<usize>| {
        let p = pixels[y * width as usize + x];
        (p.x, p.y, p.z)
    });
    let image = Image::from_encoded_channels((width as usize, height as usize), encoding, channels);
    move |path: &Path| image.write().to_file(path).map_err(|e| e.to_string())
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
    write_atomically(path, png_rgb8_encoder(width, height, rgb.to_vec()))
}

/// [`write_png_rgb8`]'s bytes, written to the path it is given.
fn png_rgb8_encoder(
    width: u32,
    height: u32,
    rgb: Vec<u8>,
) -> impl FnOnce(&Path) -> Result<(), String> {
    move |path: &Path| {
        image::save_buffer_with_format(
            path,
            &rgb,
            width,
            height,
            image::ColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())
    }
}

/// sRGB preview: linear × 2^exposure, clamped.
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Vec3],
    exposure: f32,
) -> Result<(), String> {
    write_atomically(path, png_encoder(width, height, pixels, exposure))
}

/// [`write_png`]'s bytes, written to the path it is given.
pub fn png_encoder(
    width: u32,
    height: u32,
    pixels: &[Vec3],
    exposure: f32,
) -> impl FnOnce(&Path) -> Result<(), String> {
    let scale = 2f32.powf(exposure);
    let rgb: Vec<u8> = pixels
        .iter()
        .flat_map(|p| (*p * scale).to_array())
        .map(|c| (linear_to_srgb(if c.is_finite() { c } else { 0.0 }) * 255.0 + 0.5) as u8)
        .collect();
    png_rgb8_encoder(width, height, rgb)
}

/// Greyscale-as-RGB PNG of values in [0, 1].
pub fn write_mask_png(path: &Path, width: u32, height: u32, values: &[f32]) -> Result<(), String> {
    write_atomically(path, mask_png_encoder(width, height, values))
}

/// [`write_mask_png`]'s bytes, written to the path it is given.
pub fn mask_png_encoder(
    width: u32,
    height: u32,
    values: &[f32],
) -> impl FnOnce(&Path) -> Result<(), String> {
    let rgb: Vec<u8> = values
        .iter()
        .flat_map(|v| [(v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8; 3])
        .collect();
    png_rgb8_encoder(width, height, rgb)
}

pub fn write_json(path: &Path, value: &serde_json::Value) -> Result<(), String> {
    write_atomically(path, json_encoder(value))
}

/// [`write_json`]'s bytes (pretty-printed, a final newline), written to the path it is given.
pub fn json_encoder(value: &serde_json::Value) -> impl FnOnce(&Path) -> Result<(), String> + '_ {
    move |path: &Path| {
        let text = serde_json::to_string_pretty(value).map_err(|e| e.to_string())?;
        std::fs::write(path, text + "\n").map_err(|e| e.to_string())
    }
}

/// Reads a light mask PNG written by [`write_mask_png`]: true where the camera sees *no* light.
pub fn read_mask_png(path: &Path, width: u32, height: u32) -> Result<Vec<bool>, String> {
    let img = image::open(path)
        .map_err(|e| format!("cannot read mask {}: {e}", path.display()))?
        .to_luma8();
    let (w, h) = img.dimensions();
    if (w, h) != (width, height) {
        return Err(format!(
            "mask {} is {w} wide and {h} high, expected {width} wide and {height} high",
            path.display(),
        ));
    }
    Ok(img.pixels().map(|p| p.0[0] == 0).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A set's files appear only at its commit; a failed write or a dropped set leaves the
    /// final names as they were and no temporary file behind.
    #[test]
    fn a_file_set_is_put_in_place_whole_or_not_at_all() {
        let dir = std::env::temp_dir().join(format!("manylights-fileset-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.txt"), dir.join("b.txt"));
        std::fs::write(&a, "old a").unwrap();
        let text =
            |t: &'static str| move |p: &Path| std::fs::write(p, t).map_err(|e| e.to_string());
        let files_in = || std::fs::read_dir(&dir).unwrap().count();
        // A write that fails: the error names the final file, nothing changes.
        let mut set = FileSet::default();
        set.stage(&a, text("new a")).unwrap();
        let e = set.stage(&b, |_| Err("disk full".into())).unwrap_err();
        assert_eq!(e, format!("cannot write {}: disk full", b.display()));
        drop(set);
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        assert_eq!(files_in(), 1, "no temporary file left");
        // Staged but not committed: the same.
        let mut set = FileSet::default();
        set.stage(&a, text("new a")).unwrap();
        set.stage(&b, text("new b")).unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        drop(set);
        assert_eq!(files_in(), 1);
        // Committed: both in place.
        let mut set = FileSet::default();
        set.stage(&a, text("new a")).unwrap();
        set.stage(&b, text("new b")).unwrap();
        set.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "new b");
        assert_eq!(files_in(), 2);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// An image of many tiles written several times: the same bytes each time, tiles in
    /// increasing order, and the pixels read back.
    #[test]
    fn an_exr_is_the_same_bytes_for_the_same_pixels() {
        let (w, h) = (520u32, 300u32);
        let pixels: Vec<Vec3> = (0..w * h)
            .map(|i| {
                Vec3::new(
                    (i % 97) as f32 * 0.37,
                    (i % 13) as f32,
                    (i / w) as f32 * 1e-3,
                )
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("manylights-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bytes: Vec<Vec<u8>> = (0..6)
            .map(|k| {
                let path = dir.join(format!("{k}.exr"));
                write_exr(&path, w, h, &pixels).unwrap();
                std::fs::read(&path).unwrap()
            })
            .collect();
        let meta = exr::meta::MetaData::read_from_file(dir.join("0.exr"), false).unwrap();
        assert_eq!(
            meta.headers[0].line_order,
            exr::meta::attribute::LineOrder::Increasing
        );
        let back = read_exr(&dir.join("0.exr")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(
            bytes.iter().all(|b| *b == bytes[0]),
            "the bytes differ between writes"
        );
        assert_eq!((back.0, back.1), (w, h));
        assert!(
            back.2
                .iter()
                .zip(&pixels)
                .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits))
        );
    }
}
