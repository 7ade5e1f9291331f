//! N nodes' arithmetic at once: an N-lane f32 vector whose lanes hold N nodes (a pair's two
//! children beside another pair's, a quad's four grandchildren, an oct's eight great-
//! grandchildren). Lanes never mix, so a node's value does not depend on what shares the
//! vector. Four lanes: SSE2 on x86_64 (always present there); eight: AVX where the CPU has it
//! (chosen at run time, `DescentSimd`), two SSE2 halves otherwise; plain arrays elsewhere.
//! All use only IEEE-exact operations (+ − × ÷ √, min, max, compares, bit selects) in the
//! same order, so all give the same bits. Masks are lanes of all ones or all zeros, in the
//! same type.

// The portable lanes only run elsewhere, and in the tests that compare them with SSE2.
#![cfg_attr(all(target_arch = "x86_64", not(test)), allow(dead_code))]

use std::ops::{Add, Div, Mul, Sub};

/// The operations the compact importance needs, on `N` lanes.
pub(crate) trait Lanes<const N: usize>:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// The lanes `v`.
    fn load(v: [f32; N]) -> Self;
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
    /// The lanes.
    fn out(self) -> [f32; N];
    /// `mask ? a : b` per lane.
    #[inline(always)]
    fn select(mask: Self, a: Self, b: Self) -> Self {
        mask.and(a).or(mask.andnot(b))
    }
}

/// The portable lanes (and the reference that the SIMD lanes are tested against).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable<const N: usize>(pub [f32; N]);

/// Four portable lanes.
pub(crate) type Scalar4 = Portable<4>;

impl<const N: usize> Portable<N> {
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Portable(self.0.map(f))
    }
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        Portable(std::array::from_fn(|k| f(self.0[k], o.0[k])))
    }
    #[inline(always)]
    fn bits(self, o: Self, f: impl Fn(u32, u32) -> u32) -> Self {
        self.zip(o, |a, b| f32::from_bits(f(a.to_bits(), b.to_bits())))
    }
}

macro_rules! portable_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<const N: usize> $tr for Portable<N> {
            type Output = Portable<N>;
            #[inline(always)]
            fn $f(self, o: Portable<N>) -> Portable<N> {
                self.zip(o, |a, b| a $op b)
            }
        }
    };
}
portable_op!(Add, add, +);
portable_op!(Sub, sub, -);
portable_op!(Mul, mul, *);
portable_op!(Div, div, /);

const ONES: u32 = u32::MAX;

impl<const N: usize> Lanes<N> for Portable<N> {
    #[inline(always)]
    fn load(v: [f32; N]) -> Self {
        Portable(v)
    }
    #[inline(always)]
    fn splat(v: f32) -> Self {
        Portable([v; N])
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
    fn out(self) -> [f32; N] {
        self.0
    }
}

/// Lanes as two halves: eight as two fours (the fallback where AVX is missing), or sixteen as
/// two eights (two descents side by side, `oct_descent.rs`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pair<L>(L, L);

macro_rules! pair_op {
    ($tr:ident, $f:ident) => {
        impl<L: $tr<Output = L>> $tr for Pair<L> {
            type Output = Pair<L>;
            #[inline(always)]
            fn $f(self, o: Pair<L>) -> Pair<L> {
                Pair(self.0.$f(o.0), self.1.$f(o.1))
            }
        }
    };
}
pair_op!(Add, add);
pair_op!(Sub, sub);
pair_op!(Mul, mul);
pair_op!(Div, div);

/// `Lanes<$full>` as two `Lanes<$half>`, each operation on both halves.
macro_rules! pair_lanes {
    ($half:literal, $full:literal) => {
        impl<L: Lanes<$half>> Lanes<$full> for Pair<L> {
            #[inline(always)]
            fn load(v: [f32; $full]) -> Self {
                let (mut a, mut b) = ([0.0f32; $half], [0.0f32; $half]);
                a.copy_from_slice(&v[..$half]);
                b.copy_from_slice(&v[$half..]);
                Pair(L::load(a), L::load(b))
            }
            #[inline(always)]
            fn splat(v: f32) -> Self {
                Pair(L::splat(v), L::splat(v))
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                Pair(self.0.sqrt(), self.1.sqrt())
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                Pair(self.0.min(o.0), self.1.min(o.1))
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                Pair(self.0.max(o.0), self.1.max(o.1))
            }
            #[inline(always)]
            fn abs(self) -> Self {
                Pair(self.0.abs(), self.1.abs())
            }
            #[inline(always)]
            fn le(self, o: Self) -> Self {
                Pair(self.0.le(o.0), self.1.le(o.1))
            }
            #[inline(always)]
            fn ge(self, o: Self) -> Self {
                Pair(self.0.ge(o.0), self.1.ge(o.1))
            }
            #[inline(always)]
            fn and(self, o: Self) -> Self {
                Pair(self.0.and(o.0), self.1.and(o.1))
            }
            #[inline(always)]
            fn or(self, o: Self) -> Self {
                Pair(self.0.or(o.0), self.1.or(o.1))
            }
            #[inline(always)]
            fn andnot(self, o: Self) -> Self {
                Pair(self.0.andnot(o.0), self.1.andnot(o.1))
            }
            #[inline(always)]
            fn out(self) -> [f32; $full] {
                let mut v = [0.0f32; $full];
                v[..$half].copy_from_slice(&self.0.out());
                v[$half..].copy_from_slice(&self.1.out());
                v
            }
        }
    };
}
pair_lanes!(4, 8);
pair_lanes!(8, 16);

#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{Avx8, Sse4};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::Lanes;
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Sub};

    /// SSE2 lanes (SSE2 is part of x86_64, so no run-time check is needed).
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Sse4(__m128);

    /// AVX lanes. Only constructed inside a `#[target_feature(enable = "avx2")]` function
    /// that runs after the CPU was found to have AVX2 (`DescentSimd::detect`), where these
    /// `#[inline(always)]` methods inline and their intrinsics become single instructions.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Avx8(__m256);

    macro_rules! simd_op {
        ($ty:ident, $tr:ident, $f:ident, $intr:ident) => {
            impl $tr for $ty {
                type Output = $ty;
                #[inline(always)]
                fn $f(self, o: $ty) -> $ty {
                    // SAFETY: SSE2 is always available on x86_64; `Avx8` exists only where
                    // AVX2 was detected (see its doc).
                    $ty(unsafe { $intr(self.0, o.0) })
                }
            }
        };
    }
    simd_op!(Sse4, Add, add, _mm_add_ps);
    simd_op!(Sse4, Sub, sub, _mm_sub_ps);
    simd_op!(Sse4, Mul, mul, _mm_mul_ps);
    simd_op!(Sse4, Div, div, _mm_div_ps);
    simd_op!(Avx8, Add, add, _mm256_add_ps);
    simd_op!(Avx8, Sub, sub, _mm256_sub_ps);
    simd_op!(Avx8, Mul, mul, _mm256_mul_ps);
    simd_op!(Avx8, Div, div, _mm256_div_ps);

    // SAFETY (every block below): SSE2 is always available on x86_64; no memory is touched
    // but the arrays passed in and out.
    impl Lanes<4> for Sse4 {
        #[inline(always)]
        fn load(v: [f32; 4]) -> Self {
            Sse4(unsafe { _mm_loadu_ps(v.as_ptr()) })
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

    // SAFETY (every block below): `Avx8` exists only where AVX2 was detected (its doc); no
    // memory is touched but the arrays passed in and out. The comparisons use the ordered,
    // non-signalling predicates of SSE's `cmpleps` / `cmpgeps` (false on NaN), and min / max
    // return the second operand on NaN as SSE's do.
    impl Lanes<8> for Avx8 {
        #[inline(always)]
        fn load(v: [f32; 8]) -> Self {
            Avx8(unsafe { _mm256_loadu_ps(v.as_ptr()) })
        }
        #[inline(always)]
        fn splat(v: f32) -> Self {
            Avx8(unsafe { _mm256_set1_ps(v) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            Avx8(unsafe { _mm256_sqrt_ps(self.0) })
        }
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            Avx8(unsafe { _mm256_min_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            Avx8(unsafe { _mm256_max_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            Avx8(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0) })
        }
        #[inline(always)]
        fn le(self, o: Self) -> Self {
            Avx8(unsafe { _mm256_cmp_ps::<_CMP_LE_OS>(self.0, o.0) })
        }
        #[inline(always)]
        fn ge(self, o: Self) -> Self {
            Avx8(unsafe { _mm256_cmp_ps::<_CMP_GE_OS>(self.0, o.0) })
        }
        #[inline(always)]
        fn and(self, o: Self) -> Self {
            Avx8(unsafe { _mm256_and_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn or(self, o: Self) -> Self {
            Avx8(unsafe { _mm256_or_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn andnot(self, o: Self) -> Self {
            Avx8(unsafe { _mm256_andnot_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn out(self) -> [f32; 8] {
            let mut out = [0.0f32; 8];
            unsafe { _mm256_storeu_ps(out.as_mut_ptr(), self.0) };
            out
        }
    }
}

/// The four lanes the queries run on.
#[cfg(target_arch = "x86_64")]
pub(crate) type Fast = Sse4;
/// The four lanes the queries run on.
#[cfg(not(target_arch = "x86_64"))]
pub(crate) type Fast = Scalar4;
/// Eight lanes without AVX: two halves of [`Fast`].
pub(crate) type Fast8 = Pair<Fast>;
