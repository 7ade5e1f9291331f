//! A strategy's pilot: a few camera samples on a sparse grid of pixels, taken before the first
//! pass with random numbers of their own and kept out of the image. Their pixel memory lets a
//! strategy fix what it otherwise learns between passes (mis3-adaptive's N_max) before the
//! first pass, instead of after the second, which matters when a time budget allows only a
//! handful of passes. The image stays unbiased: the pilot's samples are independent of the
//! image's, and what is learnt from them is fixed before the first image sample is drawn.
use crate::rng::SampleStream;
use crate::sampler::Sampler;

/// Salt of the pilot's seed: its samples use numbers of their own, unrelated to the image's.
const PILOT_SEED: u64 = 0x5a4d_17e3_0c2b_9f61;

/// What a strategy asks of the pilot ([`crate::estimator::DirectLighting::pilot`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pilot {
    /// One pixel in `stride` × `stride` (every `stride`-th pixel of every `stride`-th row).
    pub stride: u32,
    /// Camera samples per pilot pixel, taken in order with the pixel's memory carried along.
    pub samples: u32,
}

impl Pilot {
    /// Indices (row-major in a `width` × `height` grid) of the pixels the pilot shades: the
    /// centre pixel of every `stride` × `stride` block, so that the grid's border stays clear.
    pub fn pixels(&self, width: usize, height: usize) -> Vec<usize> {
        let s = self.stride.max(1) as usize;
        let (x0, y0) = (
            (s / 2).min(width.saturating_sub(1)),
            (s / 2).min(height.saturating_sub(1)),
        );
        (y0..height)
            .step_by(s)
            .flat_map(|y| (x0..width).step_by(s).map(move |x| y * width + x))
            .collect()
    }

    /// The random numbers of the pilot's sample `sample` of pixel `pixel`: the render's sampler
    /// under a salted seed, as if the pilot were a render of `self.samples` spp of its own.
    pub fn stream(&self, sampler: Sampler, seed: u64, pixel: u64, sample: u64) -> SampleStream {
        SampleStream::with_sampler(sampler, seed ^ PILOT_SEED, pixel, sample)
            .with_pixel_samples(self.samples)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixels_are_block_centres_inside_the_grid() {
        let p = Pilot {
            stride: 4,
            samples: 2,
        };
        let px = p.pixels(10, 6);
        // x ∈ {2, 6}, y ∈ {2}: rows 2 only (6 is outside).
        assert_eq!(px, vec![2 * 10 + 2, 2 * 10 + 6]);
        // A grid smaller than a block still gets one pixel.
        assert_eq!(p.pixels(1, 1), vec![0]);
        assert_eq!(p.pixels(0, 0), Vec::<usize>::new());
        // Stride 1: every pixel.
        let all = Pilot {
            stride: 1,
            samples: 1,
        };
        assert_eq!(all.pixels(3, 2), (0..6).collect::<Vec<_>>());
    }
}
