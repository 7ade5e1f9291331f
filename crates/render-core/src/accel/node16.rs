//! The node test in one 16-lane pass: lanes 0–7 hold the eight children's near slabs, lanes
//! 8–15 their far slabs, so each axis costs one subtraction and one multiplication instead of
//! two. Per lane it does the 8-lane test's operations on the same operands in the same order
//! (near: max(x, max(y, max(z, tmin))); far: min(min(x, min(y, z)) · FAR_SCALE, tmax)), the
//! halves told apart by masks, so it finds the same children at the same distances.
//!
//! The pass is written once over [`Lanes16`]: AVX-512F intrinsics, and plain arrays with SSE's
//! `min`/`max` rule, which lets the tests check the pass on CPUs without AVX-512.
use super::node::{BoxRay, FAR_SCALE, Node8, NodeTest};

/// Sixteen f32 lanes, each operation one IEEE operation per lane.
pub trait Lanes16: Copy {
    /// Lanes 0–7 from `lo`, 8–15 from `hi`.
    fn halves(lo: &[f32; 8], hi: &[f32; 8]) -> Self;
    fn splat(x: f32) -> Self;
    fn sub(self, b: Self) -> Self;
    fn mul(self, b: Self) -> Self;
    /// SSE's rule: `b` when either is NaN or both are equal.
    fn max(self, b: Self) -> Self;
    fn min(self, b: Self) -> Self;
    /// `self` with lanes 8–15 taken from `a`.
    fn upper_from(self, a: Self) -> Self;
    /// `self` with lanes 0–7 taken from `a`.
    fn lower_from(self, a: Self) -> Self;
    /// `self` with lanes 8–15 set to `a.min(b)`.
    fn min_upper(self, a: Self, b: Self) -> Self;
    /// `self` with lanes 0–7 set to `a.max(b)`.
    fn max_lower(self, a: Self, b: Self) -> Self;
    /// Bit i (0–7) set where lane i of `lo` ≤ lane 8 + i of `hi` (false with a NaN), and
    /// lanes 0–7 of `lo`.
    fn le_across(lo: Self, hi: Self) -> (u32, [f32; 8]);
}

/// The 16-lane pass over `L`.
#[inline(always)]
pub fn test16<L: Lanes16>(n: &Node8, r: &BoxRay, tmax: f32) -> (u32, [f32; 8]) {
    let slab = |axis: usize| {
        L::halves(&n.bounds[r.near(axis)], &n.bounds[r.far(axis)])
            .sub(L::splat(r.o[axis]))
            .mul(L::splat(r.inv[axis]))
    };
    let (x, y, z) = (slab(0), slab(1), slab(2));
    // [max(z, tmin) | min(y, z)]
    let a = z.upper_from(y);
    let b = z.lower_from(L::splat(r.tmin));
    let r1 = a.max(b).min_upper(a, b);
    // [max(y, ·) | min(x, ·)]
    let a = y.upper_from(x);
    let r2 = a.max(r1).min_upper(a, r1);
    // [max(x, ·) | · · FAR_SCALE], then the far half's min with tmax.
    let r3 = r2.mul(L::splat(FAR_SCALE)).max_lower(x, r2);
    let r4 = r3.min(L::splat(tmax));
    L::le_across(r3, r4)
}

/// Plain arrays: the pass as AVX-512 runs it, on any CPU (for the tests).
#[cfg(test)]
#[derive(Clone, Copy)]
pub struct Array16([f32; 16]);

#[cfg(test)]
impl Array16 {
    #[inline(always)]
    fn zip(self, b: Array16, f: impl Fn(f32, f32) -> f32) -> Array16 {
        Array16(std::array::from_fn(|i| f(self.0[i], b.0[i])))
    }
    #[inline(always)]
    fn pick(self, a: Array16, upper: bool) -> Array16 {
        Array16(std::array::from_fn(|i| {
            if (i >= 8) == upper { a.0[i] } else { self.0[i] }
        }))
    }
}

#[cfg(test)]
impl Lanes16 for Array16 {
    fn halves(lo: &[f32; 8], hi: &[f32; 8]) -> Self {
        Array16(std::array::from_fn(
            |i| if i < 8 { lo[i] } else { hi[i - 8] },
        ))
    }
    fn splat(x: f32) -> Self {
        Array16([x; 16])
    }
    fn sub(self, b: Self) -> Self {
        self.zip(b, |x, y| x - y)
    }
    fn mul(self, b: Self) -> Self {
        self.zip(b, |x, y| x * y)
    }
    fn max(self, b: Self) -> Self {
        self.zip(b, |x, y| if x > y { x } else { y })
    }
    fn min(self, b: Self) -> Self {
        self.zip(b, |x, y| if x < y { x } else { y })
    }
    fn upper_from(self, a: Self) -> Self {
        self.pick(a, true)
    }
    fn lower_from(self, a: Self) -> Self {
        self.pick(a, false)
    }
    fn min_upper(self, a: Self, b: Self) -> Self {
        self.pick(a.min(b), true)
    }
    fn max_lower(self, a: Self, b: Self) -> Self {
        self.pick(a.max(b), false)
    }
    fn le_across(lo: Self, hi: Self) -> (u32, [f32; 8]) {
        let mask = (0..8).map(|i| ((lo.0[i] <= hi.0[i + 8]) as u32) << i).sum();
        (mask, std::array::from_fn(|i| lo.0[i]))
    }
}

#[cfg(test)]
impl NodeTest for Array16 {
    #[inline(always)]
    fn test(n: &Node8, r: &BoxRay, tmax: f32) -> (u32, [f32; 8]) {
        test16::<Array16>(n, r, tmax)
    }
}

/// AVX-512F lanes; only for callers that checked the CPU has AVX-512F.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub struct Avx512(std::arch::x86_64::__m512);

// Intrinsics in `#[inline(always)]` bodies, as for the AVX2 test: they are only inlined into
// traversals compiled with AVX-512F enabled, which run after `is_x86_feature_detected!`.
// SAFETY (every block below): as just said; loads read eight f32s of a `&[f32; 8]`.
#[cfg(target_arch = "x86_64")]
impl Lanes16 for Avx512 {
    #[inline(always)]
    fn halves(lo: &[f32; 8], hi: &[f32; 8]) -> Self {
        use std::arch::x86_64::*;
        unsafe {
            let lo = _mm512_castps256_ps512(_mm256_loadu_ps(lo.as_ptr()));
            let hi = _mm256_castps_pd(_mm256_loadu_ps(hi.as_ptr()));
            Avx512(_mm512_castpd_ps(_mm512_insertf64x4::<1>(
                _mm512_castps_pd(lo),
                hi,
            )))
        }
    }
    #[inline(always)]
    fn splat(x: f32) -> Self {
        unsafe { Avx512(std::arch::x86_64::_mm512_set1_ps(x)) }
    }
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        unsafe { Avx512(std::arch::x86_64::_mm512_sub_ps(self.0, b.0)) }
    }
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        unsafe { Avx512(std::arch::x86_64::_mm512_mul_ps(self.0, b.0)) }
    }
    #[inline(always)]
    fn max(self, b: Self) -> Self {
        unsafe { Avx512(std::arch::x86_64::_mm512_max_ps(self.0, b.0)) }
    }
    #[inline(always)]
    fn min(self, b: Self) -> Self {
        unsafe { Avx512(std::arch::x86_64::_mm512_min_ps(self.0, b.0)) }
    }
    #[inline(always)]
    fn upper_from(self, a: Self) -> Self {
        unsafe { Avx512(std::arch::x86_64::_mm512_mask_mov_ps(self.0, 0xFF00, a.0)) }
    }
    #[inline(always)]
    fn lower_from(self, a: Self) -> Self {
        unsafe { Avx512(std::arch::x86_64::_mm512_mask_mov_ps(self.0, 0x00FF, a.0)) }
    }
    #[inline(always)]
    fn min_upper(self, a: Self, b: Self) -> Self {
        unsafe {
            Avx512(std::arch::x86_64::_mm512_mask_min_ps(
                self.0, 0xFF00, a.0, b.0,
            ))
        }
    }
    #[inline(always)]
    fn max_lower(self, a: Self, b: Self) -> Self {
        unsafe {
            Avx512(std::arch::x86_64::_mm512_mask_max_ps(
                self.0, 0x00FF, a.0, b.0,
            ))
        }
    }
    #[inline(always)]
    fn le_across(lo: Self, hi: Self) -> (u32, [f32; 8]) {
        use std::arch::x86_64::*;
        unsafe {
            let t0 = _mm512_castps512_ps256(lo.0);
            let t1 = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(hi.0)));
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32;
            let mut tnear = [0.0f32; 8];
            _mm256_storeu_ps(tnear.as_mut_ptr(), t0);
            (mask, tnear)
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl NodeTest for Avx512 {
    #[inline(always)]
    fn test(n: &Node8, r: &BoxRay, tmax: f32) -> (u32, [f32; 8]) {
        test16::<Avx512>(n, r, tmax)
    }
}
