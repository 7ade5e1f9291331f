//! Four nodes' arithmetic at once: a four-lane f32 vector whose lanes hold the two children of
//! one node pair (lanes 0, 1) and of another (lanes 2, 3). Lanes never mix, so a node's value
//! does not depend on what shares the vector. SSE2 on x86_64 (always present
//! there), plain arrays elsewhere; both use only IEEE-exact operations (+ − × ÷ √, min, max,
//! compares, bit selects) in the same order, so both give the same bits. Masks are lanes of
//! all ones or all zeros, in the same type.

// The portable lanes only run elsewhere, and in the tests that compare them with SSE2.
#![cfg_attr(all(target_arch = "x86_64", not(test)), allow(dead_code))]

use std::ops::{Add, Div, Mul, Sub};

/// The operations the pair importance needs.
pub(crate) trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// `[a, b, c, d]`.
    fn quad(a: f32, b: f32, c: f32, d: f32) -> Self;
    fn splat(v: f32) -> Self;
    fn sqrt(self) -> Self;
    /// `self < o ? self : o` per lane (SSE `minps`).
    fn min(self, o: Self) -> Self;
    /// `self > o ? self : o` per lane (SSE `maxps`).
    fn max(self, o: Self) -> Self;
    fn abs(self) -> Self;
    fn le(self, o: Self) -> Self;
    fn ge(self, o: Self) -> Self;
    fn and(self, o: Self) -> Self;
    fn or(self, o: Self) -> Self;
    /// `!self & o`.
    fn andnot(self, o: Self) -> Self;
    /// The four lanes.
    fn out(self) -> [f32; 4];
    /// `mask ? a : b` per lane.
    #[inline(always)]
    fn select(mask: Self, a: Self, b: Self) -> Self {
        mask.and(a).or(mask.andnot(b))
    }
    /// A mask from four flags.
    #[inline(always)]
    fn mask(f: [bool; 4]) -> Self {
        let m = |b: bool| f32::from_bits(if b { u32::MAX } else { 0 });
        Self::quad(m(f[0]), m(f[1]), m(f[2]), m(f[3]))
    }
}

/// The portable lanes (and the reference that the SSE2 lanes are tested against).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scalar4(pub [f32; 4]);

impl Scalar4 {
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Scalar4(self.0.map(f))
    }
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        let (a, b) = (self.0, o.0);
        Scalar4([f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2]), f(a[3], b[3])])
    }
    #[inline(always)]
    fn bits(self, o: Self, f: impl Fn(u32, u32) -> u32) -> Self {
        self.zip(o, |a, b| f32::from_bits(f(a.to_bits(), b.to_bits())))
    }
}

macro_rules! scalar_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl $tr for Scalar4 {
            type Output = Scalar4;
            #[inline(always)]
            fn $f(self, o: Scalar4) -> Scalar4 {
                self.zip(o, |a, b| a $op b)
            }
        }
    };
}
scalar_op!(Add, add, +);
scalar_op!(Sub, sub, -);
scalar_op!(Mul, mul, *);
scalar_op!(Div, div, /);

const ONES: u32 = u32::MAX;

impl Lanes for Scalar4 {
    #[inline(always)]
    fn quad(a: f32, b: f32, c: f32, d: f32) -> Self {
        Scalar4([a, b, c, d])
    }
    #[inline(always)]
    fn splat(v: f32) -> Self {
        Scalar4([v; 4])
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(f32::sqrt)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        self.zip(o, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        self.zip(o, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        self.map(f32::abs)
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self {
        self.zip(o, |a, b| f32::from_bits(if a <= b { ONES } else { 0 }))
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self {
        self.zip(o, |a, b| f32::from_bits(if a >= b { ONES } else { 0 }))
    }
    #[inline(always)]
    fn and(self, o: Self) -> Self {
        self.bits(o, |a, b| a & b)
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        self.bits(o, |a, b| a | b)
    }
    #[inline(always)]
    fn andnot(self, o: Self) -> Self {
        self.bits(o, |a, b| !a & b)
    }
    #[inline(always)]
    fn out(self) -> [f32; 4] {
        self.0
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use sse::Sse4;

#[cfg(target_arch = "x86_64")]
mod sse {
    use super::Lanes;
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Sub};

    /// SSE2 lanes (SSE2 is part of x86_64, so no run-time check is needed).
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Sse4(__m128);

    macro_rules! sse_op {
        ($tr:ident, $f:ident, $intr:ident) => {
            impl $tr for Sse4 {
                type Output = Sse4;
                #[inline(always)]
                fn $f(self, o: Sse4) -> Sse4 {
                    // SAFETY: SSE2 is always available on x86_64.
                    Sse4(unsafe { $intr(self.0, o.0) })
                }
            }
        };
    }
    sse_op!(Add, add, _mm_add_ps);
    sse_op!(Sub, sub, _mm_sub_ps);
    sse_op!(Mul, mul, _mm_mul_ps);
    sse_op!(Div, div, _mm_div_ps);

    // SAFETY (every block below): SSE2 is always available on x86_64; no memory is touched.
    impl Lanes for Sse4 {
        #[inline(always)]
        fn quad(a: f32, b: f32, c: f32, d: f32) -> Self {
            Sse4(unsafe { _mm_set_ps(d, c, b, a) })
        }
        #[inline(always)]
        fn splat(v: f32) -> Self {
            Sse4(unsafe { _mm_set1_ps(v) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            Sse4(unsafe { _mm_sqrt_ps(self.0) })
        }
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            Sse4(unsafe { _mm_min_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            Sse4(unsafe { _mm_max_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            Sse4(unsafe { _mm_andnot_ps(_mm_set1_ps(-0.0), self.0) })
        }
        #[inline(always)]
        fn le(self, o: Self) -> Self {
            Sse4(unsafe { _mm_cmple_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn ge(self, o: Self) -> Self {
            Sse4(unsafe { _mm_cmpge_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn and(self, o: Self) -> Self {
            Sse4(unsafe { _mm_and_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn or(self, o: Self) -> Self {
            Sse4(unsafe { _mm_or_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn andnot(self, o: Self) -> Self {
            Sse4(unsafe { _mm_andnot_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn out(self) -> [f32; 4] {
            let mut out = [0.0f32; 4];
            unsafe { _mm_storeu_ps(out.as_mut_ptr(), self.0) };
            out
        }
    }
}

/// The lanes the queries run on.
#[cfg(target_arch = "x86_64")]
pub(crate) type Fast = Sse4;
/// The lanes the queries run on.
#[cfg(not(target_arch = "x86_64"))]
pub(crate) type Fast = Scalar4;
