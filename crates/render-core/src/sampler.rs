//! Samplers: where the numbers of a pixel sample come from.
//!
//! Every strategy draws its numbers through [`crate::rng::SampleStream`], one dimension at a
//! time; the sampler decides what the value of (seed, pixel, sample index, dimension) is.
//!
//! - `independent`: every value an independent hash (the renderer's original numbers, bit for
//!   bit).
//! - `sobol`: the first two Sobol dimensions (a (0,2)-sequence) for each pair of consecutive
//!   dimensions (2k, 2k+1), the sample index shuffled and each coordinate Owen-scrambled by
//!   hashes of (seed, pixel, k) (Burley 2020, "Practical hash-based Owen scrambling"; pbrt-v4's
//!   padded Sobol sampler and Cycles' Sobol–Burley are of this family). The first 2^m samples
//!   of a pixel form a (0,m,2)-net in every pair, whatever m: passes stay progressive. The
//!   shuffle decorrelates the pairs from each other; pixels are scrambled independently (no
//!   blue-noise ordering across pixels).
//!
//! Every value is uniform on its own under either sampler, so each sample is unbiased. With
//! `sobol` the samples of one pixel are stratified against each other, and a strategy that
//! learns from a pixel's earlier samples (heuristic 2's hit tallies, N_max per pass) learns from
//! numbers correlated with the later ones; the convergence tests check that the images agree.
use serde::{Deserialize, Serialize};

/// Which sequence a render's numbers come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sampler {
    /// Independent uniform numbers per dimension.
    #[default]
    Independent,
    /// Shuffled, Owen-scrambled (0,2)-sequences in consecutive dimension pairs.
    Sobol,
}

impl Sampler {
    pub const ALL: [Sampler; 2] = [Sampler::Independent, Sampler::Sobol];

    /// The name on the command line and in the render's JSON.
    pub fn name(self) -> &'static str {
        match self {
            Sampler::Independent => "independent",
            Sampler::Sobol => "sobol",
        }
    }

    /// The sampler called `name`, if any.
    pub fn from_name(name: &str) -> Option<Sampler> {
        Sampler::ALL.into_iter().find(|s| s.name() == name)
    }
}

impl std::fmt::Display for Sampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Laine and Karras's permutation as Burley gives it: every output bit depends only on the
/// input bits below it (additions carry upwards; products with even constants shift up), and
/// the map is a bijection.
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen scrambling of `x` read as a binary fraction (most significant bit first): each bit is
/// flipped by a hash of the bits above it. The first 2^m integers map onto one aligned block of
/// 2^m integers.
#[inline]
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// The second Sobol dimension (primitive polynomial x + 1, direction numbers all 1), as a
/// 32-bit fraction.
#[inline]
fn sobol_second(mut index: u32) -> u32 {
    let (mut v, mut r) = (1u32 << 31, 0u32);
    while index != 0 {
        if index & 1 != 0 {
            r ^= v;
        }
        index >>= 1;
        v ^= v >> 1;
    }
    r
}

/// The `sobol` sampler's value (a 32-bit fraction) of sample `index` in dimension `dim`, for
/// the pixel whose hash is `pixel_key`.
#[inline]
pub fn sobol_value(pixel_key: u64, index: u32, dim: u32) -> u32 {
    let pair =
        crate::hash::mix64(pixel_key ^ (dim as u64 / 2 + 1).wrapping_mul(0xd6e8_feb8_6659_fd93));
    let shuffled = owen_scramble(index, pair as u32);
    let (raw, scramble) = if dim % 2 == 0 {
        (shuffled.reverse_bits(), (pair >> 32) as u32)
    } else {
        (sobol_second(shuffled), crate::hash::mix64(pair) as u32)
    };
    owen_scramble(raw, scramble)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SampleStream;

    #[test]
    fn names_round_trip() {
        for s in Sampler::ALL {
            assert_eq!(Sampler::from_name(s.name()), Some(s));
        }
        assert_eq!(Sampler::from_name("halton"), None);
    }

    #[test]
    fn owen_scrambling_maps_a_prefix_onto_an_aligned_block() {
        for seed in [0u32, 1, 0x1234_5678, 0xdead_beef] {
            for m in [1u32, 4, 8] {
                let mut out: Vec<u32> = (0..1u32 << m).map(|i| owen_scramble(i, seed)).collect();
                let high = out[0] >> m;
                assert!(out.iter().all(|x| x >> m == high), "seed {seed:#x}, m {m}");
                out.sort_unstable();
                out.dedup();
                assert_eq!(out.len(), 1 << m, "not a bijection on the block");
            }
        }
    }

    /// Sobol's second dimension in index order (not Gray-code order) starts 0, 1/2, 3/4, 1/4,
    /// 5/8, 1/8, 3/8, 7/8: beside van der Corput's 0, 1/2, 1/4, 3/4, 1/8, 5/8, 3/8, 7/8 the
    /// points (0, 0), (1/2, 1/2), (1/4, 3/4), (3/4, 1/4), (1/8, 5/8), ... of the 2D sequence.
    #[test]
    fn second_dimension_is_sobol() {
        let want = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        for (i, w) in want.iter().enumerate() {
            assert_eq!(sobol_second(i as u32) as f64 / 4294967296.0, *w);
        }
    }

    fn pair_points(sampler: Sampler, pixel: u64, n: u32, dims: (u32, u32)) -> Vec<(f64, f64)> {
        (0..n)
            .map(|i| {
                let mut s = SampleStream::with_sampler(sampler, 5, pixel, i as u64);
                let mut v = [0.0f64; 64];
                for x in v.iter_mut().take(dims.1.max(dims.0) as usize + 1) {
                    *x = (s.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
                }
                (v[dims.0 as usize], v[dims.1 as usize])
            })
            .collect()
    }

    /// The first 2^m samples of a pixel put exactly one point in every elementary interval of
    /// area 2^-m, in the first pair and in a later one: a (0,m,2)-net.
    #[test]
    fn every_pair_of_a_pixel_is_a_net() {
        let m = 6u32;
        for pixel in [0u64, 17, 1 << 40] {
            for dims in [(0, 1), (6, 7), (30, 31)] {
                let pts = pair_points(Sampler::Sobol, pixel, 1 << m, dims);
                for a in 0..=m {
                    let (nx, ny) = (1usize << a, 1usize << (m - a));
                    let mut cells = vec![0u32; nx * ny];
                    for &(x, y) in &pts {
                        cells[(x * nx as f64) as usize * ny + (y * ny as f64) as usize] += 1;
                    }
                    assert!(
                        cells.iter().all(|&c| c == 1),
                        "pixel {pixel}, dims {dims:?}, intervals {nx}x{ny}"
                    );
                }
            }
        }
    }

    /// Different pairs of one pixel are decorrelated: the 2D projection onto dimension 0 of one
    /// pair and dimension 0 of the next looks random (without the index shuffle their leading
    /// bits would agree for every sample, and this chi-square would be about 256).
    #[test]
    fn pairs_are_decorrelated_from_each_other() {
        let pts = pair_points(Sampler::Sobol, 3, 1024, (0, 2));
        let mut cells = [0u32; 64];
        for &(x, y) in &pts {
            cells[(x * 8.0) as usize * 8 + (y * 8.0) as usize] += 1;
        }
        let e = 1024.0 / 64.0;
        let chi2: f64 = cells.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
        // 63 degrees of freedom: p = 1e-4 at 110.
        assert!(chi2 < 110.0, "chi2 = {chi2}");
    }

    /// Across pixels every dimension is uniform, odd ones drawn alone included (one sample per
    /// pixel, 16 bins, p = 1e-4 bound 44.3 for 15 degrees of freedom).
    #[test]
    fn each_dimension_is_uniform_across_pixels() {
        for dim in [0u32, 1, 5, 12] {
            let mut bins = [0u32; 16];
            let n = 64_000;
            for pixel in 0..n {
                let mut s = SampleStream::with_sampler(Sampler::Sobol, 9, pixel, 3);
                for _ in 0..dim {
                    s.next_u64();
                }
                bins[(s.next_f32() * 16.0) as usize] += 1;
            }
            let e = n as f64 / 16.0;
            let chi2: f64 = bins.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
            assert!(chi2 < 44.3, "dim {dim}: chi2 = {chi2}");
        }
    }

    /// `next_2d` starts a pair on an even dimension, so its two numbers are one net point.
    #[test]
    fn next_2d_takes_a_whole_pair() {
        let mut pts = Vec::new();
        for i in 0..64u64 {
            let mut s = SampleStream::with_sampler(Sampler::Sobol, 1, 2, i);
            s.next_f32();
            pts.push(s.next_2d());
            assert_eq!(s.dimension(), 4);
        }
        let mut cells = [0u32; 64];
        for p in &pts {
            cells[(p.x * 8.0) as usize * 8 + (p.y * 8.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1));
    }
}
