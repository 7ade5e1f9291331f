//! Compositing of images for the reports: tone mapping, false-colour error maps, a canvas to
//! blit into, inset choice and the comparison strip.
use super::charts::register_font;
use glam::Vec3;
use plotters::prelude::*;
use std::path::Path;

/// Scale that maps the 97th percentile of the luminance of the unlit pixels to 0.9 (1 when no
/// pixel is unlit): [`render_core::colour::auto_exposure_scale`], as the renderer's previews.
pub fn auto_exposure(px: &[Vec3], unlit: &[bool]) -> f32 {
    if !unlit.iter().any(|&u| u) {
        return 1.0;
    }
    render_core::colour::auto_exposure_scale(px, unlit)
}

fn srgb(c: f32) -> u8 {
    let c = if c.is_finite() {
        c.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Linear × scale → sRGB 8-bit RGB.
pub fn tonemap(px: &[Vec3], scale: f32) -> Vec<u8> {
    px.iter()
        .flat_map(|p| (*p * scale).to_array())
        .map(srgb)
        .collect()
}

/// Per-pixel relMSE → colour: log scale from 1e-4 (dark blue) to 10 (yellow); lit pixels grey.
pub fn error_colour(e: f32, unlit: bool) -> [u8; 3] {
    if !unlit {
        return [90, 90, 90];
    }
    const STOPS: [[f32; 3]; 5] = [
        [0.07, 0.02, 0.25],
        [0.25, 0.15, 0.55],
        [0.15, 0.55, 0.55],
        [0.45, 0.80, 0.30],
        [0.99, 0.90, 0.15],
    ];
    let t = ((e.max(1e-12).log10() + 4.0) / 5.0).clamp(0.0, 1.0) * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f32;
    let c: Vec<u8> = (0..3)
        .map(|k| ((STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f) * 255.0) as u8)
        .collect();
    [c[0], c[1], c[2]]
}

/// An RGB8 image to compose strips in.
pub struct Canvas {
    pub w: u32,
    pub h: u32,
    pub buf: Vec<u8>,
}

impl Canvas {
    pub fn new(w: u32, h: u32, grey: u8) -> Self {
        Canvas {
            w,
            h,
            buf: vec![grey; (w * h * 3) as usize],
        }
    }
    fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as u32) < self.w && (y as u32) < self.h {
            let i = ((y as u32 * self.w + x as u32) * 3) as usize;
            self.buf[i..i + 3].copy_from_slice(&c);
        }
    }
    /// Blits the `src` (RGB8, sw × sh) region (rx, ry, rw, rh) at (x, y) scaled to dw × dh (nearest).
    #[allow(clippy::too_many_arguments)]
    pub fn blit(
        &mut self,
        src: &[u8],
        sw: u32,
        region: (u32, u32, u32, u32),
        x: u32,
        y: u32,
        dw: u32,
        dh: u32,
    ) {
        let (rx, ry, rw, rh) = region;
        for j in 0..dh {
            for i in 0..dw {
                let sx = rx + (i as u64 * rw as u64 / dw as u64) as u32;
                let sy = ry + (j as u64 * rh as u64 / dh as u64) as u32;
                let k = ((sy * sw + sx) * 3) as usize;
                self.put(
                    (x + i) as i64,
                    (y + j) as i64,
                    [src[k], src[k + 1], src[k + 2]],
                );
            }
        }
    }
    pub fn rect(&mut self, x: u32, y: u32, w: u32, h: u32, c: [u8; 3], thick: u32) {
        for t in 0..thick {
            let (x0, y0) = (x as i64 + t as i64, y as i64 + t as i64);
            let (x1, y1) = ((x + w) as i64 - 1 - t as i64, (y + h) as i64 - 1 - t as i64);
            for xx in x0..=x1 {
                self.put(xx, y0, c);
                self.put(xx, y1, c);
            }
            for yy in y0..=y1 {
                self.put(x0, yy, c);
                self.put(x1, yy, c);
            }
        }
    }
    /// Draws `texts` (x, y, size, string) with plotters and saves the PNG.
    pub fn save_with_text(
        mut self,
        path: &Path,
        texts: &[(i32, i32, u32, String)],
    ) -> Result<(), String> {
        register_font();
        {
            let root =
                BitMapBackend::with_buffer(&mut self.buf, (self.w, self.h)).into_drawing_area();
            for (x, y, size, s) in texts {
                let style = ("sans-serif", *size as f64).into_font().color(&BLACK);
                root.draw(&Text::new(s.clone(), (*x, *y), style))
                    .map_err(|e| e.to_string())?;
            }
            root.present().map_err(|e| e.to_string())?;
        }
        save_png(path, self.w, self.h, &self.buf)
    }
}

pub fn save_png(path: &Path, w: u32, h: u32, buf: &[u8]) -> Result<(), String> {
    render_core::output::write_png_rgb8(path, w, h, buf)
}

/// Picks `n` non-overlapping squares where `score` (per pixel, row-major) sums highest.
pub fn pick_insets(score: &[f32], w: u32, h: u32, n: usize) -> Vec<[u32; 3]> {
    let size = (w.min(h) / 4).max(4).min(w.min(h));
    let stride = (size / 4).max(1);
    let mut cands = Vec::new();
    let mut y = 0;
    while y + size <= h {
        let mut x = 0;
        while x + size <= w {
            let mut s = 0.0f64;
            for j in y..y + size {
                for i in x..x + size {
                    let v = score[(j * w + i) as usize];
                    if v.is_finite() {
                        s += v as f64;
                    }
                }
            }
            cands.push((s, x, y));
            x += stride;
        }
        y += stride;
    }
    cands.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut out: Vec<[u32; 3]> = Vec::new();
    for (_, x, y) in cands {
        if out.len() == n {
            break;
        }
        let overlaps = out
            .iter()
            .any(|o| x < o[0] + size && o[0] < x + size && y < o[1] + size && o[1] < y + size);
        if !overlaps {
            out.push([x, y, size]);
        }
    }
    out
}

/// One column of a strip: a label, the image, and its error map (None for the reference).
pub struct StripColumn {
    pub label: String,
    pub caption: String,
    pub image: Vec<Vec3>,
    pub error: Option<Vec<f32>>,
}

const INSET_COLOURS: [[u8; 3]; 3] = [[255, 60, 40], [40, 200, 255], [255, 220, 0]];

/// Full reference image with the insets marked, then per column: each inset zoomed, and the
/// per-pixel relMSE map; the label above and the caption (relMSE) below.
#[allow(clippy::too_many_arguments)]
pub fn comparison_strip(
    path: &Path,
    title: &str,
    w: u32,
    h: u32,
    reference: &[Vec3],
    unlit: &[bool],
    insets: &[[u32; 3]],
    columns: &[StripColumn],
) -> Result<(), String> {
    let scale = auto_exposure(reference, unlit);
    let tile = 128u32;
    let map_h = (tile as u64 * h as u64 / w as u64).max(1) as u32;
    let pad = 8u32;
    let header = 28u32;
    let label_h = 20u32;
    let caption_h = 36u32;
    let col_h = label_h + insets.len() as u32 * (tile + pad) + map_h + caption_h;
    let full_h = (col_h - label_h - caption_h).max(tile);
    let full_w = (full_h as u64 * w as u64 / h as u64) as u32;
    let width = pad + full_w + pad + columns.len() as u32 * (tile + pad);
    let height = header + col_h.max(full_h + label_h) + pad;
    let mut c = Canvas::new(width, height, 255);
    let mut texts = vec![(pad as i32, 6, 16, title.to_string())];

    let ref_rgb = tonemap(reference, scale);
    let (fx, fy) = (pad, header + label_h);
    c.blit(&ref_rgb, w, (0, 0, w, h), fx, fy, full_w, full_h);
    for (k, r) in insets.iter().enumerate() {
        let sx = full_w as f64 / w as f64;
        let sy = full_h as f64 / h as f64;
        c.rect(
            fx + (r[0] as f64 * sx) as u32,
            fy + (r[1] as f64 * sy) as u32,
            ((r[2] as f64 * sx) as u32).max(3),
            ((r[2] as f64 * sy) as u32).max(3),
            INSET_COLOURS[k % 3],
            2,
        );
    }
    texts.push((fx as i32, (header + 2) as i32, 13, "reference".into()));

    for (ci, col) in columns.iter().enumerate() {
        let x = pad + full_w + pad + ci as u32 * (tile + pad);
        let mut y = header;
        texts.push((x as i32, (y + 2) as i32, 13, col.label.clone()));
        y += label_h;
        let rgb = tonemap(&col.image, scale);
        for (k, r) in insets.iter().enumerate() {
            c.blit(&rgb, w, (r[0], r[1], r[2], r[2]), x, y, tile, tile);
            c.rect(x, y, tile, tile, INSET_COLOURS[k % 3], 2);
            y += tile + pad;
        }
        match &col.error {
            Some(e) => {
                let err_rgb: Vec<u8> = e
                    .iter()
                    .zip(unlit)
                    .flat_map(|(v, u)| error_colour(*v, *u))
                    .collect();
                c.blit(&err_rgb, w, (0, 0, w, h), x, y, tile, map_h);
            }
            None => texts.push((x as i32, (y + 4) as i32, 11, "error map: log relMSE".into())),
        }
        y += map_h + 4;
        for (li, line) in col.caption.lines().enumerate() {
            texts.push((x as i32, (y + li as u32 * 15) as i32, 12, line.to_string()));
        }
    }
    c.save_with_text(path, &texts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn insets_do_not_overlap_and_find_the_hot_spot() {
        let (w, h) = (32u32, 16u32);
        let mut s = vec![0.0f32; (w * h) as usize];
        s[(10 * w + 25) as usize] = 100.0;
        let r = pick_insets(&s, w, h, 2);
        assert_eq!(r.len(), 2);
        let a = r[0];
        assert!(a[0] <= 25 && 25 < a[0] + a[2] && a[1] <= 10 && 10 < a[1] + a[2]);
        let b = r[1];
        assert!(
            !(b[0] < a[0] + a[2] && a[0] < b[0] + b[2] && b[1] < a[1] + a[2] && a[1] < b[1] + b[2])
        );
    }

    #[test]
    fn strips_draw() {
        let dir = std::env::temp_dir().join(format!("xtask-strip-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (w, h) = (16u32, 8u32);
        let img = vec![Vec3::splat(0.3); (w * h) as usize];
        let unlit = vec![true; (w * h) as usize];
        let cols = vec![StripColumn {
            label: "A".into(),
            caption: "relMSE 1e-2".into(),
            image: img.clone(),
            error: Some(vec![0.01; (w * h) as usize]),
        }];
        comparison_strip(
            &dir.join("s.png"),
            "t",
            w,
            h,
            &img,
            &unlit,
            &[[0, 0, 4]],
            &cols,
        )
        .unwrap();
        assert!(image::open(dir.join("s.png")).is_ok());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
