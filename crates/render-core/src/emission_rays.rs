//! Extra camera rays that gather only the emission seen directly (splitting of the camera
//! sample's emission term).
//!
//! A pixel that straddles a light's silhouette is noisy through its own coverage: whether a
//! camera ray lands on the emitter or beside it. No light-sampling strategy touches that noise,
//! and a costly one that reaches few samples per pixel keeps it all (issue 22: on the emissive
//! mesh `mis3-adaptive` at 5 spp lost over all pixels to `power+bsdf` at 250 spp while winning
//! over the unlit ones). A sample may therefore trace `k − 1` more camera rays through its pixel
//! and average their emission with its own: the pixel's value is
//! w₀ (direct₀) + (1/k) Σⱼ wⱼ Le(xⱼ), the same expectation as one ray's w₀ (Le₀ + direct₀).
//!
//! Which samples split is fixed before they are drawn, from the pixel's earlier passes only, so
//! the estimate stays unbiased and the image the same for any thread count: every pixel in the
//! first pass, then the pixels whose earlier rays saw a light on some rays but not on all.
use crate::rng::SampleStream;
use crate::sampler::Sampler;

/// Camera rays per camera sample that gather emission (`1`: only the sample's own ray).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmissionRays(u32);

impl Default for EmissionRays {
    fn default() -> Self {
        Self::OFF
    }
}

/// Most rays a sample may take (a typo should not turn a render into an hour of camera rays).
pub const MAX_EMISSION_RAYS: u32 = 1024;

impl EmissionRays {
    /// One ray per sample: today's estimator, bit for bit.
    pub const OFF: Self = Self(1);

    /// `k` rays per splitting sample, 1 ≤ k ≤ [`MAX_EMISSION_RAYS`].
    pub fn new(k: u32) -> Result<Self, String> {
        if (1..=MAX_EMISSION_RAYS).contains(&k) {
            Ok(Self(k))
        } else {
            Err(format!(
                "emission rays must be between 1 and {MAX_EMISSION_RAYS}, not {k}"
            ))
        }
    }

    /// Rays per splitting sample.
    pub fn get(self) -> u32 {
        self.0
    }

    /// Rays the next sample of a pixel takes: all `k` where [`plan_splits`] marked it, else one.
    pub fn rays_for(self, split: bool) -> u32 {
        if split { self.0 } else { 1 }
    }

    /// The random numbers of a pixel's extra rays: a stream of its own (another seed), whose
    /// sample index runs over every extra ray of the pixel, `(k − 1)` per sample, so that a
    /// sequence sampler stratifies them all together.
    pub fn stream(
        self,
        sampler: Sampler,
        seed: u64,
        pixel: u64,
        spp: Option<u32>,
        sample: u64,
        ray: u32,
    ) -> SampleStream {
        let extra = u64::from(self.0 - 1);
        let pixel_samples = spp.map_or(0, |n| (u64::from(n) * extra).min(u64::from(u32::MAX)));
        SampleStream::with_sampler(
            sampler,
            seed ^ EMISSION_SEED,
            pixel,
            sample * extra + ray as u64,
        )
        .with_pixel_samples(pixel_samples as u32)
    }
}

/// Which pixels of a `width`-wide grid split their next sample, from what their rays saw so
/// far (`seen(i)` = (rays traced, rays that saw a light)): every pixel before any ray, then the
/// pixels not yet seen to be fully inside a light whose 3 × 3 neighbourhood has seen one. The
/// neighbourhood matters for lights smaller than a pixel, which a pixel's own first rays may all
/// miss.
pub fn plan_splits(width: usize, seen: impl Fn(usize) -> (u32, u32), split: &mut [bool]) {
    let height = split.len() / width.max(1);
    for (i, s) in split.iter_mut().enumerate() {
        let (rays, lit) = seen(i);
        if rays == 0 {
            *s = true;
            continue;
        }
        let (x, y) = (i % width, i / width);
        let near_light = (y.saturating_sub(1)..(y + 2).min(height)).any(|ny| {
            (x.saturating_sub(1)..(x + 2).min(width)).any(|nx| seen(ny * width + nx).1 > 0)
        });
        *s = near_light && lit < rays;
    }
}

/// Mixed into the seed of the extra rays' streams, so they do not repeat the camera sample's.
const EMISSION_SEED: u64 = 0x9e6c_63d0_676a_9a99;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_the_first_pass_and_the_pixels_near_a_light() {
        let k = EmissionRays::new(8).unwrap();
        assert_eq!((k.rays_for(true), k.rays_for(false)), (8, 1));
        assert_eq!(EmissionRays::OFF.rays_for(true), 1);
        // A 4 × 3 grid: nothing traced yet, then one lit ray at (1, 1) and a fully lit (3, 2).
        let mut split = vec![false; 12];
        plan_splits(4, |_| (0, 0), &mut split);
        assert!(split.iter().all(|&s| s));
        let seen = |i: usize| match i {
            5 => (8, 1),
            11 => (8, 8),
            _ => (8, 0),
        };
        plan_splits(4, seen, &mut split);
        let expected = [
            true, true, true, false, // row 0: neighbours of (1, 1)
            true, true, true, true, // row 1: (3, 1) is next to the lit (3, 2)
            true, true, true, false, // row 2: (3, 2) is fully lit
        ];
        assert_eq!(split, expected);
    }

    #[test]
    fn out_of_range_counts_are_refused() {
        assert!(EmissionRays::new(0).is_err());
        assert!(EmissionRays::new(MAX_EMISSION_RAYS + 1).is_err());
        assert_eq!(EmissionRays::new(1).unwrap(), EmissionRays::OFF);
    }
}
