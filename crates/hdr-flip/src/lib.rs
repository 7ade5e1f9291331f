//! HDR-ꟻLIP of a render against its reference (Andersson et al., "ꟻLIP: A Difference
//! Evaluator for Alternating Images", HPG 2020, and "Visualizing Errors in Rendered High
//! Dynamic Range Images", Eurographics 2021 short papers): the per-pixel error map in [0, 1],
//! its means over all pixels and over the unlit ones, and the map in magma colours.
//!
//! LDR-ꟻLIP itself is the `nv-flip` crate (NVIDIA's C++ code, built with `cc`). The HDR part
//! around it is here, as the HDR paper describes it: an exposure range from the reference
//! (from the exposure that brings its brightest pixel to 0.85 after tone mapping to the one
//! that brings its median there), N = max(2, ⌈range⌉) exposures over it, each image exposed,
//! tone mapped (ACES, with ꟻLIP's 0.6 pre-exposure) and clamped, LDR-ꟻLIP per exposure, and per
//! pixel the maximum over the exposures. One difference from NVIDIA's tool: the crate takes
//! 8-bit sRGB, so the tone-mapped images are quantised to 8 bits before LDR-ꟻLIP (an image
//! against itself still scores exactly 0).
use glam::Vec3;

/// ꟻLIP's default observer: a 0.7 m wide 4K monitor seen from 0.7 m (67 pixels per degree).
pub const PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// The target of the exposure range: the tone-mapped value its ends bring a pixel to.
const RANGE_TARGET: f32 = 0.85;

/// At most this many exposures (the paper's count is the range in stops; a reference with 64
/// stops between its median and its maximum is not one to score anyway).
const MAX_EXPOSURES: usize = 64;

/// ꟻLIP's ACES tone mapping (Narkowicz's fit) of a linear value exposed by ꟻLIP's 0.6.
fn tone_map(x: f32) -> f32 {
    let x = 0.6 * x;
    let y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
    y.clamp(0.0, 1.0)
}

/// The linear value that [`tone_map`] takes to `t` (the positive root of a quadratic).
fn inverse_tone_map(t: f32) -> f32 {
    // 0.6x(2.51·0.6x + 0.03) = t(0.6x(2.43·0.6x + 0.59) + 0.14), a quadratic in u = 0.6x
    let (a, b, c) = (2.51 - t * 2.43, 0.03 - t * 0.59, -t * 0.14);
    let u = (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    u / 0.6
}

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Negative and non-finite values count as black (as in the report's previews).
fn clean(c: Vec3) -> Vec3 {
    let f = |v: f32| if v.is_finite() && v > 0.0 { v } else { 0.0 };
    Vec3::new(f(c.x), f(c.y), f(c.z))
}

/// The exposures (in stops) at which the images are compared, from the reference alone.
pub fn exposures(reference: &[Vec3]) -> Vec<f32> {
    let mut lum: Vec<f32> = reference.iter().map(|&c| luminance(clean(c))).collect();
    lum.sort_by(f32::total_cmp);
    let max = lum.last().copied().unwrap_or(0.0);
    if max <= 0.0 {
        return vec![0.0];
    }
    // The median, or where more than half the image is black the median of the rest (the
    // range would otherwise be infinite).
    let median_of = |v: &[f32]| {
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    };
    let mut median = median_of(&lum);
    if median <= 0.0 {
        let first = lum.partition_point(|&l| l <= 0.0);
        median = median_of(&lum[first..]);
    }
    let x = inverse_tone_map(RANGE_TARGET);
    let (start, stop) = ((x / max).log2(), (x / median).log2());
    let n = ((stop - start).ceil() as usize).clamp(2, MAX_EXPOSURES);
    (0..n)
        .map(|k| start + (stop - start) * k as f32 / (n - 1) as f32)
        .collect()
}

/// 8-bit sRGB of `px` exposed by 2^`stops` and tone mapped: LDR-ꟻLIP's input.
fn ldr(px: &[Vec3], stops: f32, w: u32, h: u32) -> nv_flip::FlipImageRgb8 {
    let m = 2f32.powf(stops);
    let srgb = |v: f32| {
        let v = tone_map(v * m);
        let e = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (255.0 * e + 0.5).clamp(0.0, 255.0) as u8
    };
    let bytes: Vec<u8> = px
        .iter()
        .flat_map(|&c| {
            let c = clean(c);
            [srgb(c.x), srgb(c.y), srgb(c.z)]
        })
        .collect();
    nv_flip::FlipImageRgb8::with_data(w, h, &bytes)
}

/// The per-pixel HDR-ꟻLIP error (row-major, in [0, 1]) of `test` against `reference`, both
/// `w` × `h` linear RGB.
pub fn hdr_flip_map(test: &[Vec3], reference: &[Vec3], w: u32, h: u32) -> Result<Vec<f32>, String> {
    let n = w as usize * h as usize;
    if n == 0 {
        return Err("ꟻLIP of an empty image".into());
    }
    if test.len() != n || reference.len() != n {
        return Err(format!(
            "ꟻLIP needs two {w}x{h} images, got {} and {} pixels",
            test.len(),
            reference.len()
        ));
    }
    let mut map = vec![0.0f32; n];
    for stops in exposures(reference) {
        let err = nv_flip::flip(
            ldr(reference, stops, w, h),
            ldr(test, stops, w, h),
            PIXELS_PER_DEGREE,
        )
        .to_vec();
        for (m, e) in map.iter_mut().zip(err) {
            *m = m.max(e);
        }
    }
    Ok(map)
}

/// The mean of `map` over the pixels `mask` keeps (all pixels without one); 0 over none.
pub fn mean(map: &[f32], mask: Option<&[bool]>) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (i, &v) in map.iter().enumerate() {
        if mask.is_none_or(|m| m[i]) {
            sum += v as f64;
            n += 1;
        }
    }
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// A cell's HDR-ꟻLIP: the map and its means.
pub struct Flip {
    pub map: Vec<f32>,
    pub all: f64,
    pub unlit: f64,
}

/// HDR-ꟻLIP of `test` against `reference`; `unlit` marks the pixels of the unlit mean.
pub fn score(
    test: &[Vec3],
    reference: &[Vec3],
    unlit: &[bool],
    w: u32,
    h: u32,
) -> Result<Flip, String> {
    let map = hdr_flip_map(test, reference, w, h)?;
    if unlit.len() != map.len() {
        return Err(format!("the light mask is not {w}x{h}"));
    }
    Ok(Flip {
        all: mean(&map, None),
        unlit: mean(&map, Some(unlit)),
        map,
    })
}

/// RGB8 of `map` in the crate's magma colours (black = no difference, yellow-white = 1).
pub fn magma_rgb(map: &[f32], w: u32, h: u32) -> Vec<u8> {
    nv_flip::FlipImageFloat::with_data(w, h, map)
        .apply_color_lut(&nv_flip::magma_lut())
        .to_vec()
}

/// The crate's magma colours: 256 RGB8 triples; a map value v has colour ⌊255 v + ½⌋.
pub fn magma_palette() -> Vec<u8> {
    nv_flip::magma_lut().to_vec()
}

/// The palette indices of a magma RGB8 image (each pixel's entry of [`magma_palette`]), so that
/// the report can embed it as a one-channel PNG a third the size; `None` if a colour is not in
/// the palette.
pub fn magma_indices(rgb: &[u8]) -> Option<Vec<u8>> {
    let palette = magma_palette();
    let index: std::collections::HashMap<&[u8], u8> = palette
        .chunks(3)
        .enumerate()
        .rev() // a colour listed twice maps to its first index
        .map(|(i, c)| (c, i as u8))
        .collect();
    rgb.chunks(3).map(|c| index.get(c).copied()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth test scene: a gradient with a bright spot, 32 × 24.
    fn image(w: u32, h: u32) -> Vec<Vec3> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
                let spot = if (x - 0.5).hypot(y - 0.5) < 0.1 {
                    20.0
                } else {
                    0.0
                };
                Vec3::new(0.2 + x, 0.1 + 0.5 * y, 0.3) + Vec3::splat(spot)
            })
            .collect()
    }

    #[test]
    fn an_image_against_itself_is_zero() {
        let (w, h) = (32, 24);
        let r = image(w, h);
        let map = hdr_flip_map(&r, &r, w, h).unwrap();
        assert!(map.iter().all(|&e| e == 0.0));
    }

    #[test]
    fn a_larger_difference_scores_higher() {
        let (w, h) = (32, 24);
        let r = image(w, h);
        // deterministic "noise" of two amplitudes on the same pixels
        let noisy = |amp: f32| -> Vec<Vec3> {
            r.iter()
                .enumerate()
                .map(|(i, &c)| {
                    let s = if (i * 7919) % 5 < 2 {
                        1.0 + amp
                    } else {
                        1.0 - amp
                    };
                    c * s
                })
                .collect()
        };
        let mask = vec![true; r.len()];
        let small = score(&noisy(0.1), &r, &mask, w, h).unwrap();
        let large = score(&noisy(0.5), &r, &mask, w, h).unwrap();
        assert!(small.all > 0.01, "{}", small.all);
        assert!(
            large.all > 1.5 * small.all,
            "{} vs {}",
            large.all,
            small.all
        );
        assert!(large.map.iter().all(|e| (0.0..=1.0).contains(e)));
        // a black image against the reference: larger still
        let black = score(&vec![Vec3::ZERO; r.len()], &r, &mask, w, h).unwrap();
        assert!(black.all > large.all, "{} vs {}", black.all, large.all);
    }

    #[test]
    fn unlit_mean_is_over_the_mask() {
        let map = [0.0, 1.0, 0.5, 0.5];
        assert_eq!(mean(&map, None), 0.5);
        assert_eq!(mean(&map, Some(&[true, false, true, false])), 0.25);
        assert_eq!(mean(&map, Some(&[false; 4])), 0.0);
    }

    #[test]
    fn exposure_range_spans_median_to_maximum() {
        // the tone mapper's inverse
        for t in [0.1, 0.5, 0.85] {
            assert!((tone_map(inverse_tone_map(t)) - t).abs() < 1e-5);
        }
        // luminances 1 (median) and 64 (maximum): six stops, so six exposures
        let mut px = vec![Vec3::ONE; 9];
        px[4] = Vec3::splat(64.0);
        let e = exposures(&px);
        assert_eq!(e.len(), 6);
        let x = inverse_tone_map(RANGE_TARGET);
        assert!((e[0] - (x / 64.0).log2()).abs() < 1e-4 && (e[5] - x.log2()).abs() < 1e-4);
        // a flat image: two exposures at one level; a black one: one
        assert_eq!(exposures(&[Vec3::ONE; 4]).len(), 2);
        assert_eq!(exposures(&[Vec3::ZERO; 4]), vec![0.0]);
        // mostly black: the median of the rest, not an infinite range
        let mut mostly_black = vec![Vec3::ZERO; 9];
        mostly_black[0] = Vec3::ONE;
        mostly_black[1] = Vec3::splat(4.0);
        assert!(exposures(&mostly_black).iter().all(|s| s.is_finite()));
    }

    #[test]
    fn bad_sizes_are_errors_not_panics() {
        let r = image(4, 4);
        assert!(hdr_flip_map(&r, &r[..8], 4, 4).is_err());
        assert!(hdr_flip_map(&[], &[], 0, 0).is_err());
        assert!(score(&r, &r, &[true; 3], 4, 4).is_err());
    }

    #[test]
    fn magma_maps_back_to_its_indices() {
        let map: Vec<f32> = (0..256).map(|i| i as f32 / 255.0).collect();
        let rgb = magma_rgb(&map, 16, 16);
        let idx = magma_indices(&rgb).unwrap();
        let palette = magma_palette();
        assert_eq!(palette.len(), 768);
        // the palette applied to the indices gives the magma image back
        let back: Vec<u8> = idx
            .iter()
            .flat_map(|&i| palette[3 * i as usize..3 * i as usize + 3].to_vec())
            .collect();
        assert_eq!(back, rgb);
        assert_eq!((idx[0], idx[255]), (0, 255));
        assert!(magma_indices(&[1, 2, 3]).is_none() || palette.chunks(3).any(|c| c == [1, 2, 3]));
    }

    #[test]
    fn magma_map_has_three_bytes_a_pixel() {
        let rgb = magma_rgb(&[0.0, 1.0], 2, 1);
        assert_eq!(rgb.len(), 6);
        assert!(
            rgb[3..].iter().map(|&b| b as u32).sum::<u32>()
                > rgb[..3].iter().map(|&b| b as u32).sum()
        );
    }
}
