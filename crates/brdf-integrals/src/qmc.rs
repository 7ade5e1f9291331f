//! Small deterministic random/quasi-random generators used by the reference integrator and the fits
//! (the library itself depends on no RNG crate).

/// SplitMix64: tiny, fast, good enough to seed and to draw random shifts.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// A generator started from `seed` (any value; equal seeds give equal streams).
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    /// Next 64 uniformly distributed bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Roberts' R2 sequence (a 2-D Kronecker lattice) with a Cranley–Patterson shift: point `i` of a
/// randomly shifted low-discrepancy set. Independent shifts give independent replicates, so the
/// spread of replicate means is an honest error estimate.
#[derive(Clone, Copy, Debug)]
pub struct R2 {
    shift: [f64; 2],
}

const R2_A1: f64 = 0.754_877_666_246_692_8; // 1/g, g = plastic number
const R2_A2: f64 = 0.569_840_290_998_053_3; // 1/g^2

impl R2 {
    /// A sequence with a random shift drawn from `rng`.
    pub fn new(rng: &mut SplitMix64) -> Self {
        Self {
            shift: [rng.next_f64(), rng.next_f64()],
        }
    }
    /// Point `i` of the shifted sequence, in [0, 1)².
    #[inline]
    pub fn get(&self, i: usize) -> [f64; 2] {
        let i = i as f64;
        [
            (self.shift[0] + R2_A1 * i).fract(),
            (self.shift[1] + R2_A2 * i).fract(),
        ]
    }
}
