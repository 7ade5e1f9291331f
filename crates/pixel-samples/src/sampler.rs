//! Samplers: where the numbers of a pixel sample come from.
//!
//! Every strategy draws its numbers through [`crate::rng::SampleStream`], one dimension at a
//! time; the sampler decides what the value of (seed, pixel, sample index, dimension) is. The
//! dimensions come in pairs (2k, 2k + 1): `next_2d` always takes one whole pair, a 1D draw
//! takes the next dimension. The film position (the pixel filter's sample) is pair 0; what a
//! strategy draws after it is in the order its code draws it (ARCHITECTURE.md lists it).
//!
//! - `independent`: every value an independent hash (the renderer's original numbers, bit for
//!   bit).
//! - `stratified`: jittered strata per pair, pbrt's `stratified` sampler: the pair's square cut
//!   into nx × ny ≥ spp cells (nx = ⌊√spp⌋), sample i of a pixel in cell π(i) of a permutation
//!   hashed from (seed, pixel, pair), jittered inside it. Needs the render's spp.
//! - `sobol`: the first two Sobol dimensions (a (0,2)-sequence) for each pair, the sample index
//!   shuffled and each coordinate Owen-scrambled by hashes of (seed, pixel, pair) (Burley 2020,
//!   "Practical hash-based Owen scrambling"; pbrt-v4's padded Sobol sampler and Cycles'
//!   Sobol–Burley are of this family). The first 2^m samples of a pixel form a (0,m,2)-net in
//!   every pair, whatever m: passes stay progressive. Pixels are scrambled independently (no
//!   blue-noise ordering across pixels, as pbrt-v4's ZSobol has).
//! - `lowdiscrepancy`: pbrt-v3's (0,2)-sequence sampler, the one the authors' scene names: the
//!   same shuffled pairs, randomised by a random-digit (XOR) scramble per pixel and dimension
//!   instead of Owen's. pbrt-v3 draws a fixed power-of-two set per pixel and shuffles it;
//!   ours is the progressive equivalent (every power-of-two prefix is a net).
//! - `zsobol`: one Owen-scrambled Sobol sequence over the whole image, handed out to pixels
//!   along a shuffled Morton curve (pbrt-v4's ZSobol, [`crate::zsobol`]): blue-noise error
//!   across pixels. Needs the render's spp.
//!
//! Every value is uniform on its own under every sampler, so each sample is unbiased. Under the
//! stratified ones the samples of one pixel are correlated with each other, and a strategy that
//! learns from a pixel's earlier samples (heuristic 2's hit tallies, N_max per pass) learns from
//! numbers correlated with the later ones; the convergence tests check that the images agree.
pub use crate::hash::owen_scramble;
use serde::{Deserialize, Serialize};

/// Which sequence a render's numbers come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sampler {
    /// Independent uniform numbers per dimension.
    #[default]
    Independent,
    /// Jittered strata per dimension pair, over the render's spp.
    Stratified,
    /// Shuffled, Owen-scrambled (0,2)-sequences in consecutive dimension pairs.
    Sobol,
    /// Shuffled, XOR-scrambled (0,2)-sequences in consecutive dimension pairs (pbrt-v3).
    #[serde(rename = "lowdiscrepancy")]
    LowDiscrepancy,
    /// One Sobol sequence over the image in shuffled Morton order (pbrt-v4's ZSobol).
    #[serde(rename = "zsobol")]
    ZSobol,
}

impl Sampler {
    pub const ALL: [Sampler; 5] = [
        Sampler::Independent,
        Sampler::Stratified,
        Sampler::Sobol,
        Sampler::LowDiscrepancy,
        Sampler::ZSobol,
    ];

    /// The name on the command line and in the render's JSON.
    pub fn name(self) -> &'static str {
        match self {
            Sampler::Independent => "independent",
            Sampler::Stratified => "stratified",
            Sampler::Sobol => "sobol",
            Sampler::LowDiscrepancy => "lowdiscrepancy",
            Sampler::ZSobol => "zsobol",
        }
    }

    /// The sampler called `name`, if any.
    pub fn from_name(name: &str) -> Option<Sampler> {
        Sampler::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Whether the sampler needs to know a pixel's sample count in advance.
    pub fn needs_spp(self) -> bool {
        matches!(self, Sampler::Stratified | Sampler::ZSobol)
    }

    /// Refuses an image (its sample grid, splat border included) and a sample count the
    /// sampler cannot number: `zsobol` numbers all of a render's samples with one 64-bit index.
    pub fn check_image(self, (width, height): (u32, u32), spp: u32) -> Result<(), String> {
        let bits = crate::zsobol::index_bits((width, height), spp);
        if self == Sampler::ZSobol && bits > 64 {
            return Err(format!(
                "the zsobol sampler numbers a render's samples with one 64-bit index; a \
                 {width}×{height} sample grid at {spp} spp needs {bits} bits: lower the spp or \
                 the resolution, or choose another sampler"
            ));
        }
        Ok(())
    }

    /// Whether a 2D draw must start on an even dimension (a pair of the sequence).
    #[inline]
    pub(crate) fn pairs_dimensions(self) -> bool {
        self != Sampler::Independent
    }

    /// The 64 bits of dimension `dim` of the sample at `at`, from the independent hash
    /// `independent` of the same dimension.
    #[inline]
    pub(crate) fn bits(self, at: &SamplePosition, dim: u32, independent: u64) -> u64 {
        let sequence = match self {
            Sampler::Independent => return independent,
            Sampler::Stratified => stratified_value(at, dim, independent),
            Sampler::Sobol => sobol_value(at.pixel_key, at.index, dim),
            Sampler::LowDiscrepancy => xor_scrambled_sobol_value(at.pixel_key, at.index, dim),
            Sampler::ZSobol => crate::zsobol::zsobol_value(&at.z, dim),
        };
        with_independent(sequence, independent)
    }

    /// The bits of dimensions `dim` and `dim + 1` ([`Sampler::bits`] of each), where a
    /// sequence sampler computes what the pair shares (its hash and shuffled index) once.
    /// `dim` must be even for the samplers that pair dimensions.
    #[inline]
    pub(crate) fn bits_2d(self, at: &SamplePosition, dim: u32, independent: [u64; 2]) -> [u64; 2] {
        let [(raw0, s0), (raw1, s1)] = match self {
            Sampler::Sobol | Sampler::LowDiscrepancy => {
                shuffled_sobol_pair(at.pixel_key, at.index, dim)
            }
            Sampler::ZSobol => {
                let [a, b] = crate::zsobol::zsobol_pair(&at.z, dim);
                return [
                    with_independent(a, independent[0]),
                    with_independent(b, independent[1]),
                ];
            }
            _ => {
                return [
                    self.bits(at, dim, independent[0]),
                    self.bits(at, dim + 1, independent[1]),
                ];
            }
        };
        let (a, b) = if self == Sampler::Sobol {
            (owen_scramble(raw0, s0), owen_scramble(raw1, s1))
        } else {
            (raw0 ^ s0, raw1 ^ s1)
        };
        [
            with_independent(a, independent[0]),
            with_independent(b, independent[1]),
        ]
    }
}

/// A sequence's 32 bits on top, independent ones below them.
#[inline]
fn with_independent(sequence: u32, independent: u64) -> u64 {
    ((sequence as u64) << 32) | (independent & 0xffff_ffff)
}

impl std::fmt::Display for Sampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which sample of which pixel a stream draws for.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SamplePosition {
    /// A hash of (seed, pixel).
    pub pixel_key: u64,
    /// The sample's index within its pixel.
    pub index: u32,
    /// The pixel's planned sample count (`stratified` only; 0 if unknown).
    pub pixel_samples: u32,
    /// The sample's place in the image's sequence (`zsobol` only).
    pub z: crate::zsobol::ZOrder,
}

/// The second Sobol dimension at a 32-bit index, as a 32-bit fraction: the 64-bit
/// generator (`zsobol::sobol_second_64`) on 32 bits, whose upper half it leaves zero (the
/// direction numbers only shift right), so its last step and half its bit reversal drop out.
#[inline]
fn sobol_second(index: u32) -> u32 {
    const KEEP: [u32; 5] = [
        0x5555_5555,
        0x3333_3333,
        0x0f0f_0f0f,
        0x00ff_00ff,
        0x0000_ffff,
    ];
    let mut y = index;
    for (b, keep) in KEEP.iter().enumerate() {
        y ^= (y >> (1u32 << b)) & keep;
    }
    y.reverse_bits()
}

/// The hash of one dimension pair of one pixel, from which its shuffle and scrambles come.
#[inline]
fn pair_hash(pixel_key: u64, dim: u32) -> u64 {
    crate::hash::mix64(pixel_key ^ (dim as u64 / 2 + 1).wrapping_mul(0xd6e8_feb8_6659_fd93))
}

/// The unscrambled Sobol coordinate of dimension `dim`'s pair at the shuffled index, and the
/// pair's hash.
#[inline]
fn shuffled_sobol(pixel_key: u64, index: u32, dim: u32) -> (u32, u32) {
    let pair = pair_hash(pixel_key, dim);
    coordinate(pair, first_dimension(index, pair), dim % 2 == 1)
}

/// [`shuffled_sobol`] of both dimensions of the pair that starts at the even `dim`, the
/// pair's hash and shuffled index computed once.
#[inline]
fn shuffled_sobol_pair(pixel_key: u64, index: u32, dim: u32) -> [(u32, u32); 2] {
    debug_assert!(dim % 2 == 0);
    let pair = pair_hash(pixel_key, dim);
    let first = first_dimension(index, pair);
    [
        coordinate(pair, first, false),
        coordinate(pair, first, true),
    ]
}

/// The first Sobol dimension at the index shuffled by `pair` (an Owen scrambling of the
/// index, whose closing bit reversal the first dimension's own reversal undoes).
#[inline]
fn first_dimension(index: u32, pair: u64) -> u32 {
    crate::hash::laine_karras(index.reverse_bits(), pair as u32)
}

/// The pair's first or second (`odd`) coordinate and its scramble, from the first
/// coordinate (the shuffled index reversed).
#[inline]
fn coordinate(pair: u64, first: u32, odd: bool) -> (u32, u32) {
    if odd {
        (
            sobol_second(first.reverse_bits()),
            crate::hash::mix64(pair) as u32,
        )
    } else {
        (first, (pair >> 32) as u32)
    }
}

/// The `sobol` sampler's value (a 32-bit fraction) of sample `index` in dimension `dim`, for
/// the pixel whose hash is `pixel_key`.
#[inline]
pub fn sobol_value(pixel_key: u64, index: u32, dim: u32) -> u32 {
    let (raw, scramble) = shuffled_sobol(pixel_key, index, dim);
    owen_scramble(raw, scramble)
}

/// The `lowdiscrepancy` sampler's value: [`sobol_value`]'s point with a random-digit scramble.
#[inline]
pub fn xor_scrambled_sobol_value(pixel_key: u64, index: u32, dim: u32) -> u32 {
    let (raw, scramble) = shuffled_sobol(pixel_key, index, dim);
    raw ^ scramble
}

/// A permutation of 0..n (n ≥ 1) keyed by `seed`, in the manner of Kensler 2013: rounds of
/// bijections of [0, 2^b) (xor with a key, multiplication by an odd number, a right
/// xor-shift), walked along the cycle until the value lands below n.
#[inline]
fn permute_below(i: u32, n: u32, seed: u64) -> u32 {
    let bits = 32 - (n - 1).leading_zeros();
    if bits == 0 {
        return 0;
    }
    let mask = u32::MAX >> (32 - bits);
    let shift = bits.div_ceil(2);
    let mut x = i;
    loop {
        let mut key = seed;
        for _ in 0..4 {
            key = crate::hash::mix64(key);
            x = ((x ^ key as u32) & mask).wrapping_mul((key >> 32) as u32 | 1) & mask;
            x ^= x >> shift;
        }
        if x < n {
            return x;
        }
    }
}

/// The `stratified` sampler's value: the pair's square cut into nx × ny cells (nx = ⌊√spp⌋,
/// ny = ⌈spp/nx⌉), sample `index` in a permuted cell, jittered by the independent bits.
#[inline]
fn stratified_value(at: &SamplePosition, dim: u32, independent: u64) -> u32 {
    let spp = at.pixel_samples.max(1);
    let nx = (spp as f64).sqrt() as u32;
    let ny = spp.div_ceil(nx);
    let pair = pair_hash(at.pixel_key, dim);
    // Samples past the planned count (none, when spp is the limit) reuse the permutation.
    let cell = permute_below(at.index % (nx * ny), nx * ny, pair);
    let (strata, stratum) = if dim % 2 == 0 {
        (nx, cell % nx)
    } else {
        (ny, cell / nx)
    };
    // The cell's share of 2^32, with the jitter's 32 bits spread over it.
    let jitter = ((independent >> 32) * (((1u64 << 32) / strata as u64) as u64)) >> 32;
    let base = (stratum as u64 * (1u64 << 32)) / strata as u64;
    (base + jitter).min(u32::MAX as u64) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SampleStream;

    /// The sequence samplers' values as first written (the shuffled index Owen-scrambled,
    /// reversed for the first dimension, the 64-bit generator for the second): the faster
    /// forms above must give the same bits.
    #[test]
    fn sequence_values_are_those_of_the_plain_formulas() {
        let plain = |pixel_key: u64, index: u32, dim: u32| {
            let pair = pair_hash(pixel_key, dim);
            let shuffled = owen_scramble(index, pair as u32);
            if dim % 2 == 0 {
                (shuffled.reverse_bits(), (pair >> 32) as u32)
            } else {
                let second = crate::zsobol::sobol_second_64(shuffled as u64);
                (second, crate::hash::mix64(pair) as u32)
            }
        };
        for k in 0..50_000u64 {
            let key = crate::hash::mix64(k);
            let (index, dim) = ((key >> 7) as u32 >> (k % 29), (k % 23) as u32);
            let (raw, scramble) = plain(key, index, dim);
            assert_eq!(
                sobol_value(key, index, dim),
                owen_scramble(raw, scramble),
                "{k}"
            );
            assert_eq!(
                xor_scrambled_sobol_value(key, index, dim),
                raw ^ scramble,
                "{k}"
            );
        }
    }

    #[test]
    fn second_dimension_on_32_bits_is_the_64_bit_generator() {
        let mut x = 0x1234_5678u32;
        for k in 0..32 {
            assert_eq!(sobol_second(1 << k), crate::zsobol::sobol_second_64(1 << k));
        }
        for _ in 0..100_000 {
            x = crate::hash::mix64(x as u64) as u32;
            assert_eq!(sobol_second(x), crate::zsobol::sobol_second_64(x as u64));
        }
        assert_eq!(
            sobol_second(u32::MAX),
            crate::zsobol::sobol_second_64(u32::MAX as u64)
        );
    }

    /// A 2D draw's shared work changes nothing: `bits_2d` is `bits` of each dimension.
    #[test]
    fn a_pair_at_once_is_each_dimension_alone() {
        for sampler in Sampler::ALL {
            for k in 0..200u64 {
                let mut at = SampleStream::with_sampler(sampler, 3, k * 7919, k % 37)
                    .with_pixel_samples(64)
                    .in_image(((k % 16) as u32, (k / 16) as u32), (16, 16))
                    .at;
                at.index = (k as u32).wrapping_mul(0x9e37_79b9) >> (k % 32);
                let dim = 2 * (k as u32 % 9);
                let ind = [crate::hash::mix64(k), crate::hash::mix64(!k)];
                let alone = [
                    sampler.bits(&at, dim, ind[0]),
                    sampler.bits(&at, dim + 1, ind[1]),
                ];
                assert_eq!(sampler.bits_2d(&at, dim, ind), alone, "{sampler}, case {k}");
            }
        }
    }

    /// `zsobol` refuses a grid and spp whose sample index would pass 64 bits (2·11 + 32 = 54
    /// fits, 2·20 + 32 = 72 does not); the other samplers take any.
    #[test]
    fn zsobol_refuses_an_index_past_64_bits() {
        let huge = ((1u32 << 20, 1), u32::MAX);
        for s in Sampler::ALL {
            assert!(s.check_image((2048, 2048), u32::MAX).is_ok(), "{s}");
            assert_eq!(
                s.check_image(huge.0, huge.1).is_err(),
                s == Sampler::ZSobol,
                "{s}"
            );
        }
        let e = Sampler::ZSobol.check_image(huge.0, huge.1).unwrap_err();
        assert!(e.contains("72 bits"), "{e}");
    }

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

    /// Sample `i` of `pixel`, read as a pixel of a 256 × 65536 image.
    fn stream(sampler: Sampler, seed: u64, pixel: u64, i: u64, spp: u32) -> SampleStream {
        let xy = ((pixel % 256) as u32, (pixel / 256 % 65536) as u32);
        SampleStream::with_sampler(sampler, seed, pixel, i)
            .with_pixel_samples(spp)
            .in_image(xy, (256, 65536))
    }

    fn pair_points(sampler: Sampler, pixel: u64, n: u32, dims: (u32, u32)) -> Vec<(f64, f64)> {
        pair_points_of(sampler, pixel, n, n, dims)
    }

    fn pair_points_of(
        sampler: Sampler,
        pixel: u64,
        n: u32,
        spp: u32,
        dims: (u32, u32),
    ) -> Vec<(f64, f64)> {
        (0..n)
            .map(|i| {
                let mut s = stream(sampler, 5, pixel, i as u64, spp);
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
        for (sampler, pixel) in [Sampler::Sobol, Sampler::LowDiscrepancy]
            .into_iter()
            .flat_map(|s| [0u64, 17, 1 << 40].map(|p| (s, p)))
        {
            for dims in [(0, 1), (6, 7), (30, 31)] {
                let pts = pair_points(sampler, pixel, 1 << m, dims);
                for a in 0..=m {
                    let (nx, ny) = (1usize << a, 1usize << (m - a));
                    let mut cells = vec![0u32; nx * ny];
                    for &(x, y) in &pts {
                        cells[(x * nx as f64) as usize * ny + (y * ny as f64) as usize] += 1;
                    }
                    assert!(
                        cells.iter().all(|&c| c == 1),
                        "{sampler}: pixel {pixel}, dims {dims:?}, intervals {nx}x{ny}"
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
        for sampler in Sampler::ALL {
            let pts = pair_points(sampler, 3, 1024, (0, 2));
            let mut cells = [0u32; 64];
            for &(x, y) in &pts {
                cells[(x * 8.0) as usize * 8 + (y * 8.0) as usize] += 1;
            }
            let e = 1024.0 / 64.0;
            let chi2: f64 = cells.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
            // 63 degrees of freedom: p = 1e-4 at 110.
            assert!(chi2 < 110.0, "{sampler}: chi2 = {chi2}");
        }
    }

    /// `stratified` puts one sample in each of its nx × ny cells when spp fills them, and
    /// never two in one cell when it does not (spp 50: 7 × 8 cells).
    #[test]
    fn stratified_samples_fill_distinct_cells() {
        for (spp, nx, ny) in [(64u32, 8usize, 8usize), (50, 7, 8), (2, 1, 2)] {
            for dims in [(0, 1), (8, 9)] {
                let pts = pair_points_of(Sampler::Stratified, 11, spp, spp, dims);
                let mut cells = vec![0u32; nx * ny];
                for &(x, y) in &pts {
                    cells[(x * nx as f64) as usize * ny + (y * ny as f64) as usize] += 1;
                }
                assert!(
                    cells.iter().all(|&c| c <= 1),
                    "spp {spp}, dims {dims:?}: {cells:?}"
                );
                assert_eq!(cells.iter().sum::<u32>(), spp);
            }
        }
    }

    #[test]
    fn permutations_below_n_are_bijections() {
        for n in [1u32, 2, 3, 7, 56, 100, 1000] {
            let mut seen: Vec<u32> = (0..n).map(|i| permute_below(i, n, 0x5eed)).collect();
            seen.sort_unstable();
            assert_eq!(seen, (0..n).collect::<Vec<_>>());
        }
    }

    /// Across pixels every dimension is uniform, odd ones drawn alone included (one sample per
    /// pixel, 16 bins, p = 1e-4 bound 44.3 for 15 degrees of freedom).
    #[test]
    fn each_dimension_is_uniform_across_pixels() {
        for (sampler, dim) in Sampler::ALL
            .into_iter()
            .flat_map(|s| [0u32, 1, 5, 12].map(|d| (s, d)))
        {
            let mut bins = [0u32; 16];
            let n = 64_000;
            for pixel in 0..n {
                let mut s = stream(sampler, 9, pixel, 3, 16);
                for _ in 0..dim {
                    s.next_u64();
                }
                bins[(s.next_f32() * 16.0) as usize] += 1;
            }
            let e = n as f64 / 16.0;
            let chi2: f64 = bins.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
            assert!(chi2 < 44.3, "{sampler} dim {dim}: chi2 = {chi2}");
        }
    }

    /// `next_2d` starts a pair on an even dimension, so its two numbers are one net point.
    #[test]
    fn next_2d_takes_a_whole_pair() {
        for sampler in [Sampler::Stratified, Sampler::Sobol, Sampler::LowDiscrepancy] {
            let mut pts = Vec::new();
            for i in 0..64u64 {
                let mut s = SampleStream::with_sampler(sampler, 1, 2, i).with_pixel_samples(64);
                s.next_f32();
                pts.push(s.next_2d());
                assert_eq!(s.dimension(), 4);
            }
            let mut cells = [0u32; 64];
            for p in &pts {
                cells[(p.x * 8.0) as usize * 8 + (p.y * 8.0) as usize] += 1;
            }
            assert!(cells.iter().all(|&c| c == 1), "{sampler}");
        }
    }
}
