//! The `zsobol` sampler (after Ahmed and Wonka 2020, "Screen-space blue-noise diffusion of
//! Monte Carlo sampling error via hierarchical ordering of pixels", as pbrt-v4's ZSobol): one
//! Sobol sequence for the whole image, its points handed out to pixels along a Morton (Z)
//! curve, sample i of pixel p at index (morton(p) << log2 spp) | i. The base-4 digits of that
//! index are shuffled by permutations hashed from the digits above them and the dimension pair,
//! so that neighbouring pixels get disjoint, well-spread parts of the sequence: any aligned
//! 2^k × 2^k block of pixels with all its samples is a (0, m, 2)-net in every pair, and the
//! error spreads over the image as blue noise.
//!
//! The sample count is fixed in advance (rounded up to a power of two for the index layout);
//! each value is a function of (seed, pixel, sample index, dimension) alone, as for every
//! sampler.
use crate::hash::mix64;
use crate::hash::owen_scramble;

/// Where one pixel sample sits in the image's sequence.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ZOrder {
    /// (morton(x, y) << log2 spp) | sample index, before the digit shuffle.
    pub index: u64,
    /// Bits of `index` in use: 2·⌈log2 max(width, height)⌉ + ⌈log2 spp⌉.
    pub bits: u32,
    /// A hash of the seed alone: the scrambles are the image's, not the pixel's.
    pub seed_key: u64,
}

impl ZOrder {
    /// Sample `sample` of pixel (x, y) of a `width` × `height` image taking `spp` samples.
    pub fn new(
        seed_key: u64,
        (x, y): (u32, u32),
        (width, height): (u32, u32),
        spp: u32,
        sample: u32,
    ) -> ZOrder {
        let bits = index_bits((width, height), spp);
        debug_assert!(bits <= 64, "Sampler::check_image refuses this size");
        let log2_spp = ceil_log2(spp.max(1));
        let index = (morton(x, y) << log2_spp) | (sample as u64 & ((1u64 << log2_spp) - 1));
        ZOrder {
            index,
            bits,
            seed_key,
        }
    }
}

/// Bits of the index that numbers every sample of a `width` × `height` image taking `spp`
/// samples: 2·⌈log2 max(width, height)⌉ + ⌈log2 spp⌉. At most 64 fit.
pub(crate) fn index_bits((width, height): (u32, u32), spp: u32) -> u32 {
    2 * ceil_log2(width.max(height)) + ceil_log2(spp.max(1))
}

fn ceil_log2(n: u32) -> u32 {
    32 - (n.max(1) - 1).leading_zeros()
}

/// Interleaves the bits of x (even positions) and y (odd positions).
fn morton(x: u32, y: u32) -> u64 {
    let spread = |v: u32| {
        let mut v = v as u64;
        v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
        v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    };
    spread(x) | (spread(y) << 1)
}

/// The 24 permutations of the four base-4 digits.
const PERMUTATIONS: [[u8; 4]; 24] = {
    let mut out = [[0u8; 4]; 24];
    let mut n = 0;
    let mut a = 0;
    while a < 4 {
        let mut b = 0;
        while b < 4 {
            let mut c = 0;
            while c < 4 {
                let d = 6 - a - b - c;
                if a != b && a != c && b != c && d < 4 && d != a && d != b && d != c {
                    out[n] = [a as u8, b as u8, c as u8, d as u8];
                    n += 1;
                }
                c += 1;
            }
            b += 1;
        }
        a += 1;
    }
    out
};

/// The index shuffled digit by digit from the top: each base-4 digit permuted by one of the
/// 24 permutations, chosen by a hash of the original digits above it and of the pair; an odd
/// last bit flipped by a hash bit. A bijection that maps aligned blocks onto aligned blocks.
/// `at_shift[s]` is [`digit_key`]`(pair, s)`.
#[inline]
fn shuffle_digits(z: &ZOrder, at_shift: &[u64; 64]) -> u64 {
    let mut out = 0u64;
    let mut shift = z.bits;
    while shift > 0 {
        let width = if shift == 1 { 1 } else { 2 };
        shift -= width;
        let above = if shift + width >= 64 {
            0
        } else {
            z.index >> (shift + width)
        };
        let h = mix64(above ^ at_shift[shift as usize]);
        let digit = (z.index >> shift) & ((1 << width) - 1);
        let permuted = if width == 2 {
            PERMUTATIONS[(h % 24) as usize][digit as usize] as u64
        } else {
            digit ^ (h & 1)
        };
        out |= permuted << shift;
    }
    out
}

/// The hash the permutation of the digit at bit `shift` starts from, before the digits above
/// it are mixed in: the same for every pixel and sample of the image.
fn digit_key(pair: u64, shift: u32) -> u64 {
    mix64(pair ^ ((shift as u64) << 56))
}

/// What every sample of a render shares for one dimension pair: the pair's hash and its
/// digit keys, for the seed's hash `seed_key` and pair number `number` (dims 2k, 2k + 1 are
/// pair k + 1).
#[derive(Clone, Copy)]
struct PairKeys {
    seed_key: u64,
    number: u64,
    pair: u64,
    at_shift: [u64; 64],
}

impl PairKeys {
    /// Matches no pair (numbers are below 2³²).
    const NONE: PairKeys = PairKeys {
        seed_key: 0,
        number: u64::MAX,
        pair: 0,
        at_shift: [0; 64],
    };

    fn new(seed_key: u64, number: u64) -> PairKeys {
        let pair = mix64(seed_key ^ number.wrapping_mul(0xa076_1d64_78bd_642f));
        PairKeys {
            seed_key,
            number,
            pair,
            at_shift: std::array::from_fn(|s| digit_key(pair, s as u32)),
        }
    }
}

/// Pairs whose keys a thread keeps: a sample's first 32 dimensions never evict each other.
const KEPT_PAIRS: usize = 16;

thread_local! {
    /// Each thread's keys of the pairs it drew last, by pair number modulo [`KEPT_PAIRS`]: a
    /// memo of a pure function, so the values do not depend on which thread draws them.
    static KEPT: std::cell::RefCell<[PairKeys; KEPT_PAIRS]> =
        const { std::cell::RefCell::new([PairKeys::NONE; KEPT_PAIRS]) };
}

/// The second Sobol dimension at a 64-bit index, as a 32-bit fraction.
///
/// Its generator matrix is Pascal's triangle mod 2: index bit k adds C(k, j) mod 2 to bit
/// 63 − j of the result. Read as polynomials over GF(2), that maps f(t) = Σ x_k t^k to
/// f(t + 1), and (t + 1)^k factors over the set bits b of k into (t^(2^b) + 1): one shift,
/// mask and xor per bit of the exponent, six in all, instead of a loop over the index's
/// bits. The same linear map, so the same bits (`pascal_shift_is_the_direction_loop`).
#[inline]
pub(crate) fn sobol_second_64(index: u64) -> u32 {
    const KEEP: [u64; 6] = [
        0x5555_5555_5555_5555,
        0x3333_3333_3333_3333,
        0x0f0f_0f0f_0f0f_0f0f,
        0x00ff_00ff_00ff_00ff,
        0x0000_ffff_0000_ffff,
        0x0000_0000_ffff_ffff,
    ];
    let mut y = index;
    for (b, keep) in KEEP.iter().enumerate() {
        y ^= (y >> (1u32 << b)) & keep;
    }
    (y.reverse_bits() >> 32) as u32
}

/// The hash of the dimension pair (2k, 2k + 1) that holds `dim`, and the sample's index
/// shuffled by it: what the pair's two dimensions share. The pair's keys come from the
/// thread's memo, computed on a miss.
#[inline]
fn pair_index(z: &ZOrder, dim: u32) -> (u64, u64) {
    let number = dim as u64 / 2 + 1;
    KEPT.with(|kept| {
        let mut kept = kept.borrow_mut();
        let keys = &mut kept[number as usize % KEPT_PAIRS];
        if keys.number != number || keys.seed_key != z.seed_key {
            *keys = PairKeys::new(z.seed_key, number);
        }
        (keys.pair, shuffle_digits(z, &keys.at_shift))
    })
}

/// Dimension 2k's Sobol fraction and scramble seed, from its pair's hash and shuffled index.
#[inline]
fn even_raw(pair: u64, index: u64) -> (u32, u32) {
    ((index.reverse_bits() >> 32) as u32, pair as u32)
}

/// Dimension 2k + 1's.
#[inline]
fn odd_raw(pair: u64, index: u64) -> (u32, u32) {
    (sobol_second_64(index), (pair >> 32) as u32)
}

/// The `zsobol` value (a 32-bit fraction) of dimension `dim` of the sample at `z`.
pub(crate) fn zsobol_value(z: &ZOrder, dim: u32) -> u32 {
    let (pair, index) = pair_index(z, dim);
    let (raw, scramble) = if dim % 2 == 0 {
        even_raw(pair, index)
    } else {
        odd_raw(pair, index)
    };
    owen_scramble(raw, scramble)
}

/// [`zsobol_value`] of dimensions `dim` and `dim + 1` (`dim` even), the pair's digit shuffle
/// done once: the same two values.
pub(crate) fn zsobol_pair(z: &ZOrder, dim: u32) -> [u32; 2] {
    debug_assert!(dim % 2 == 0);
    let (pair, index) = pair_index(z, dim);
    let ((r0, s0), (r1, s1)) = (even_raw(pair, index), odd_raw(pair, index));
    [owen_scramble(r0, s0), owen_scramble(r1, s1)]
}

#[cfg(test)]
mod tests {

    /// The direction numbers v₁ = 2⁶³, v_{k+1} = v_k ⊕ (v_k ≫ 1), xored for the set bits.
    fn direction_loop(mut index: u64) -> u32 {
        let (mut v, mut r) = (1u64 << 63, 0u64);
        while index != 0 {
            if index & 1 != 0 {
                r ^= v;
            }
            index >>= 1;
            v ^= v >> 1;
        }
        (r >> 32) as u32
    }

    /// Both maps are linear over GF(2), so agreeing on every unit index proves them equal;
    /// a few thousand others check the xor of several bits too.
    #[test]
    fn pascal_shift_is_the_direction_loop() {
        for k in 0..64 {
            assert_eq!(sobol_second_64(1 << k), direction_loop(1 << k), "bit {k}");
        }
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for i in 0..5000u64 {
            x = mix64(x ^ i);
            for index in [x, x & 0xffff_ffff, i] {
                assert_eq!(sobol_second_64(index), direction_loop(index));
            }
        }
    }
    use super::*;

    /// A pair drawn at once is its two dimensions drawn one by one.
    #[test]
    fn a_pair_is_its_two_dimensions() {
        for (i, spp) in [(0u32, 1u32), (3, 4), (5, 8), (100, 256)] {
            for (x, y) in [(0, 0), (13, 7), (255, 200)] {
                let z = ZOrder::new(mix64(5), (x, y), (256, 256), spp, i);
                for dim in (0..40).step_by(2) {
                    let want = [zsobol_value(&z, dim), zsobol_value(&z, dim + 1)];
                    assert_eq!(zsobol_pair(&z, dim), want, "dim {dim}");
                }
            }
        }
    }

    #[test]
    fn the_permutation_table_holds_all_24() {
        let mut seen: Vec<[u8; 4]> = PERMUTATIONS.to_vec();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 24);
    }

    /// The kept keys give the values of keys computed afresh for the draw, whatever the seeds
    /// and pairs drawn before (seeds alternate here, pairs past the kept ones evict and refill).
    #[test]
    fn kept_keys_give_the_unkept_values() {
        for k in 0..3000u64 {
            let seed_key = mix64(k % 3);
            let (x, y) = ((k * 7 % 200) as u32, (k * 13 % 150) as u32);
            let z = ZOrder::new(seed_key, (x, y), (200, 150), 64, (k % 64) as u32);
            let dim = (k * 5 % 80) as u32;
            let pair = mix64(seed_key ^ (dim as u64 / 2 + 1).wrapping_mul(0xa076_1d64_78bd_642f));
            let at_shift = std::array::from_fn(|s| digit_key(pair, s as u32));
            let fresh = (pair, shuffle_digits(&z, &at_shift));
            assert_eq!(pair_index(&z, dim), fresh, "case {k}");
        }
    }

    #[test]
    fn the_digit_shuffle_is_a_bijection() {
        for bits in [5u32, 6, 9] {
            let mut out: Vec<u64> = (0..1u64 << bits)
                .map(|i| {
                    let keys = PairKeys::new(3, 77);
                    shuffle_digits(
                        &ZOrder {
                            index: i,
                            bits,
                            seed_key: 3,
                        },
                        &keys.at_shift,
                    )
                })
                .collect();
            out.sort_unstable();
            assert_eq!(out, (0..1u64 << bits).collect::<Vec<_>>(), "{bits} bits");
        }
    }

    fn points(
        block: (u32, u32, u32),
        image: (u32, u32),
        spp: u32,
        dims: (u32, u32),
    ) -> Vec<(f64, f64)> {
        let (x0, y0, side) = block;
        let mut pts = Vec::new();
        for y in y0..y0 + side {
            for x in x0..x0 + side {
                for i in 0..spp {
                    let z = ZOrder::new(mix64(11), (x, y), image, spp, i);
                    let f = |d| zsobol_value(&z, d) as f64 / 4294967296.0;
                    pts.push((f(dims.0), f(dims.1)));
                }
            }
        }
        pts
    }

    fn is_net(pts: &[(f64, f64)]) -> bool {
        let m = pts.len().trailing_zeros();
        (0..=m).all(|a| {
            let (nx, ny) = (1usize << a, 1usize << (m - a));
            let mut cells = vec![0u32; nx * ny];
            for &(x, y) in pts {
                cells[(x * nx as f64) as usize * ny + (y * ny as f64) as usize] += 1;
            }
            cells.iter().all(|&c| c == 1)
        })
    }

    /// A pixel's own samples, and an aligned 2 × 2 or 4 × 4 block of pixels with all theirs,
    /// are (0, m, 2)-nets in every pair (spp 8: odd log2, the single-bit digit included).
    #[test]
    fn aligned_pixel_blocks_are_nets() {
        for spp in [4u32, 8] {
            for dims in [(0, 1), (4, 5), (20, 21)] {
                for block in [(5, 3, 1), (2, 6, 2), (4, 8, 4)] {
                    let pts = points(block, (64, 48), spp, dims);
                    assert!(is_net(&pts), "spp {spp}, dims {dims:?}, block {block:?}");
                }
            }
        }
    }

    /// Different pairs of one pixel block are decorrelated (chi-square over 8 × 8 cells of
    /// dimension 0 against dimension 2; 63 degrees of freedom, p = 1e-4 at 110).
    #[test]
    fn pairs_are_decorrelated() {
        let pts = points((0, 0, 16), (64, 64), 4, (0, 2));
        let mut cells = [0u32; 64];
        for &(x, y) in &pts {
            cells[(x * 8.0) as usize * 8 + (y * 8.0) as usize] += 1;
        }
        let e = pts.len() as f64 / 64.0;
        let chi2: f64 = cells.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 110.0, "chi2 = {chi2}");
    }
}
