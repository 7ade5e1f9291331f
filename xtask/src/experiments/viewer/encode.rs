//! The compact float encoding of the report's previews: shared-exponent RGBE (Ward's Radiance
//! format: 8-bit mantissas and one exponent per pixel, about 1 % relative precision) stored in
//! an ordinary RGB PNG twice the image's height (mantissas above, the exponent below in all
//! three channels), embedded as a base64 data URI. A browser decodes it through a canvas (a
//! data URI does not taint the canvas under file://, a file next to the page would), so the
//! page can re-expose the linear values and compute error maps itself.
use glam::Vec3;

/// The RGBE bytes of one linear value: (r, g, b) mantissas and the exponent e, so that
/// value ≈ (m + 0.5) · 2^(e − 136); (0, 0, 0, 0) for black, negative or non-finite values.
pub fn rgbe(c: Vec3) -> [u8; 4] {
    let c = Vec3::new(finite(c.x), finite(c.y), finite(c.z));
    let max = c.max_element();
    if max < 1e-32 {
        return [0; 4];
    }
    // max = f · 2^e with f in [0.5, 1)
    let e = max.log2().floor() as i32 + 1;
    let e = e.clamp(-128, 127);
    let scale = 256.0 / 2f32.powi(e);
    let m = |v: f32| (v * scale).floor().clamp(0.0, 255.0) as u8;
    [m(c.x), m(c.y), m(c.z), (e + 128) as u8]
}

fn finite(v: f32) -> f32 {
    if v.is_finite() && v > 0.0 { v } else { 0.0 }
}

/// The linear value of RGBE bytes (what the page's decoder computes).
#[cfg(test)]
pub fn from_rgbe(b: [u8; 4]) -> Vec3 {
    if b[3] == 0 {
        return Vec3::ZERO;
    }
    let f = 2f32.powi(b[3] as i32 - 136);
    Vec3::new(b[0] as f32 + 0.5, b[1] as f32 + 0.5, b[2] as f32 + 0.5) * f
}

/// The split RGB8 image (w × 2h) of `px` (w × h, row-major).
pub fn split_rgbe(px: &[Vec3], w: u32, h: u32) -> Vec<u8> {
    let n = (w * h) as usize;
    let mut buf = vec![0u8; n * 6];
    for (i, p) in px.iter().take(n).enumerate() {
        let b = rgbe(*p);
        buf[i * 3..i * 3 + 3].copy_from_slice(&b[..3]);
        buf[(n + i) * 3..(n + i) * 3 + 3].copy_from_slice(&[b[3]; 3]);
    }
    buf
}

/// PNG bytes of an RGB8 (`channels` = 3) or grey (1) image.
pub fn png_bytes(buf: &[u8], w: u32, h: u32, channels: u8) -> Result<Vec<u8>, String> {
    use image::ImageEncoder;
    let colour = match channels {
        1 => image::ExtendedColorType::L8,
        _ => image::ExtendedColorType::Rgb8,
    };
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new_with_quality(
        &mut out,
        image::codecs::png::CompressionType::Best,
        image::codecs::png::FilterType::Adaptive,
    )
    .write_image(buf, w, h, colour)
    .map_err(|e| e.to_string())?;
    Ok(out)
}

/// A `data:image/png;base64,…` URI of PNG bytes.
pub fn data_uri(png: &[u8]) -> String {
    format!("data:image/png;base64,{}", base64(png))
}

/// Standard base64 with padding (RFC 4648).
pub fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let v = (chunk[0] as u32) << 16
            | (*chunk.get(1).unwrap_or(&0) as u32) << 8
            | *chunk.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                s.push(ABC[(v >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// The linear pixels of `split_rgbe` bytes (a test's stand-in for the page's decoder).
#[cfg(test)]
pub fn decode_split(buf: &[u8], w: u32, h: u32) -> Vec<Vec3> {
    let n = (w * h) as usize;
    (0..n)
        .map(|i| {
            let m = &buf[i * 3..i * 3 + 3];
            from_rgbe([m[0], m[1], m[2], buf[(n + i) * 3]])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgbe_round_trip_within_its_precision() {
        let mut worst = 0.0f32;
        for k in 0..2000 {
            // values over 12 decades, channels of different sizes
            let t = k as f32 / 2000.0;
            let c = Vec3::new(
                10f32.powf(-6.0 + 12.0 * t),
                10f32.powf(-6.0 + 12.0 * t) * 0.37,
                10f32.powf(-6.0 + 12.0 * (1.0 - t)) * 1e-3,
            );
            let d = from_rgbe(rgbe(c));
            let max = c.max_element();
            // each channel is exact to half a mantissa step of the largest: 2^-8 of it at most
            let err = (d - c).abs().max_element() / max;
            worst = worst.max(err);
        }
        assert!(worst <= 1.0 / 128.0, "worst relative error {worst}");
        assert!(worst > 0.0, "a real quantisation");
        assert_eq!(rgbe(Vec3::ZERO), [0; 4]);
        assert_eq!(rgbe(Vec3::new(f32::NAN, -1.0, f32::INFINITY)), [0; 4]);
        assert_eq!(from_rgbe([0; 4]), Vec3::ZERO);
    }

    #[test]
    fn split_image_decodes_and_png_is_lossless() {
        let (w, h) = (5u32, 3u32);
        let px: Vec<Vec3> = (0..15).map(|i| Vec3::new(i as f32, 0.5, 1e-3)).collect();
        let buf = split_rgbe(&px, w, h);
        assert_eq!(buf.len(), (w * h * 2 * 3) as usize);
        let png = png_bytes(&buf, w, 2 * h, 3).unwrap();
        let back = image::load_from_memory(&png).unwrap().to_rgb8().into_raw();
        assert_eq!(back, buf);
        for (a, b) in decode_split(&back, w, h).iter().zip(&px) {
            assert!((*a - *b).abs().max_element() <= b.max_element() / 128.0);
        }
    }

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }
}
