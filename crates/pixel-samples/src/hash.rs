//! The bit mixers behind the random numbers, shared by the independent stream
//! ([`crate::rng`]) and the sequence samplers ([`crate::sampler`], [`crate::zsobol`]) so that
//! none of them imports another that imports it back: splitmix64's finaliser and Owen
//! scrambling.

/// splitmix64's finaliser: a bijective avalanche mix of 64 bits.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Laine and Karras's permutation as Burley gives it: every output bit depends only on the
/// input bits below it (additions carry upwards; products with even constants shift up), and
/// the map is a bijection.
#[inline]
pub(crate) fn laine_karras(mut x: u32, seed: u32) -> u32 {
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
