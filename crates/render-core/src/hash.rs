//! The bit mixer behind the counter-based random numbers, shared by the independent stream
//! ([`crate::rng`]) and the sequence scrambling ([`crate::sampler`]) so that neither imports
//! the other.

/// splitmix64's finaliser: a bijective avalanche mix of 64 bits.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}
