//! What a render keeps per pixel while it runs, and whether the machine can hold it.
use crate::estimator::{MAX_AUX, PIXEL_MEMORY};
use glam::Vec3;

/// A pixel's running sums over its samples so far.
#[derive(Clone, Copy, Default)]
pub(super) struct PixelAccum {
    pub(super) sum: [f64; 3],
    pub(super) sum_sq: [f64; 3],
    pub(super) light_hits: u32,
    /// Extra emission rays traced (beyond one per sample) and how many of them saw a light.
    pub(super) extra_rays: u32,
    pub(super) extra_lit: u32,
    /// The next sample takes extra emission rays (`emission_rays::plan_splits`).
    pub(super) split: bool,
    pub(super) aux: [f64; MAX_AUX],
    pub(super) memory: [f32; PIXEL_MEMORY],
}

/// Bytes a render of `width` × `height` pixels holds at its peak: the per-pixel accumulators,
/// then the finished image, its variance, light mask and `aux_channels` maps, and an output
/// image being encoded (EXR or PNG).
pub fn memory_estimate(width: u32, height: u32, aux_channels: usize) -> u64 {
    (width as u64 * height as u64).saturating_mul(bytes_per_pixel(aux_channels))
}

/// A pixel's share of [`memory_estimate`].
fn bytes_per_pixel(aux_channels: usize) -> u64 {
    let finished = 3 * size_of::<Vec3>() + size_of::<f32>() * (1 + aux_channels);
    (size_of::<PixelAccum>() + finished) as u64
}

/// Refuses, before anything is allocated, a render that needs more memory than the machine
/// has (where the platform says how much it has).
pub fn check_memory(width: u32, height: u32, aux_channels: usize) -> Result<(), String> {
    check_memory_with(width, height, aux_channels, 0)
}

/// [`check_memory`] for a render that holds `extra_per_pixel` bytes more per pixel.
pub(super) fn check_memory_with(
    width: u32,
    height: u32,
    aux_channels: usize,
    extra_per_pixel: usize,
) -> Result<(), String> {
    let per_pixel = bytes_per_pixel(aux_channels) + extra_per_pixel as u64;
    // Saturating: a 2^32 × 2^32 image's bytes do not fit 64 bits.
    let need = (width as u64 * height as u64).saturating_mul(per_pixel);
    match host::physical_memory_bytes() {
        Some(have) if need > have => Err(format!(
            "a {width}×{height} render needs about {:.1} GiB ({per_pixel} bytes per pixel), more \
             than this machine's {:.1} GiB of memory",
            width as f64 * height as f64 * per_pixel as f64 / GIB,
            have as f64 / GIB
        )),
        _ => Ok(()),
    }
}

const GIB: f64 = (1u64 << 30) as f64;
