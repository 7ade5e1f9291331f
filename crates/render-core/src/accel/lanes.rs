//! Four f32 lanes: SSE2 on x86-64 (always present there), plain arrays elsewhere, with the
//! same result bit for bit (`min`/`max` keep SSE's rule: the second operand when either is
//! NaN or both are equal). Every operation is one IEEE operation per lane, never fused, so
//! the AVX2 and SSE2 traversals, which both use these lanes for primitives, agree exactly.

#[cfg(target_arch = "x86_64")]
mod imp {
    use std::arch::x86_64::*;

    /// Four f32 lanes.
    #[derive(Clone, Copy)]
    pub struct F4(pub(crate) __m128);

    impl F4 {
        #[inline(always)]
        pub fn splat(x: f32) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { F4(_mm_set1_ps(x)) }
        }
        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> F4 {
            // SAFETY: `a` is four readable f32s.
            F4(unsafe { _mm_loadu_ps(a.as_ptr()) })
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 4] {
            let mut a = [0.0; 4];
            // SAFETY: `a` is four writable f32s.
            unsafe { _mm_storeu_ps(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        pub fn add(self, b: F4) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { F4(_mm_add_ps(self.0, b.0)) }
        }
        #[inline(always)]
        pub fn sub(self, b: F4) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { F4(_mm_sub_ps(self.0, b.0)) }
        }
        #[inline(always)]
        pub fn mul(self, b: F4) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { F4(_mm_mul_ps(self.0, b.0)) }
        }
        #[inline(always)]
        pub fn div(self, b: F4) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { F4(_mm_div_ps(self.0, b.0)) }
        }
        #[inline(always)]
        pub fn sqrt(self) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { F4(_mm_sqrt_ps(self.0)) }
        }
        /// The sign flipped (−0 from +0, as scalar negation).
        #[inline(always)]
        pub fn neg(self) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { F4(_mm_xor_ps(self.0, _mm_set1_ps(-0.0))) }
        }
        #[inline(always)]
        pub fn min(self, b: F4) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { F4(_mm_min_ps(self.0, b.0)) }
        }
        #[inline(always)]
        pub fn max(self, b: F4) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { F4(_mm_max_ps(self.0, b.0)) }
        }
        /// Lanes where `self <= b` (false when either is NaN), as bits 0–3.
        #[inline(always)]
        pub fn le(self, b: F4) -> u32 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { _mm_movemask_ps(_mm_cmple_ps(self.0, b.0)) as u32 }
        }
        /// Lanes where `self < b` (false when either is NaN), as bits 0–3.
        #[inline(always)]
        pub fn lt(self, b: F4) -> u32 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { _mm_movemask_ps(_mm_cmplt_ps(self.0, b.0)) as u32 }
        }
        /// Lanes where `self != b` or either is NaN, as bits 0–3.
        #[inline(always)]
        pub fn ne(self, b: F4) -> u32 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe { _mm_movemask_ps(_mm_cmpneq_ps(self.0, b.0)) as u32 }
        }
        /// `a` where bit i of `mask` is set, `self` elsewhere.
        #[inline(always)]
        pub fn select(self, mask: u32, a: F4) -> F4 {
            // SAFETY: SSE2 is part of x86-64.
            unsafe {
                let m = _mm_castsi128_ps(_mm_set_epi32(
                    -(((mask >> 3) & 1) as i32),
                    -(((mask >> 2) & 1) as i32),
                    -(((mask >> 1) & 1) as i32),
                    -((mask & 1) as i32),
                ));
                F4(_mm_or_ps(_mm_and_ps(m, a.0), _mm_andnot_ps(m, self.0)))
            }
        }
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod imp {
    /// Four f32 lanes.
    #[derive(Clone, Copy)]
    pub struct F4(pub(crate) [f32; 4]);

    #[inline(always)]
    fn map(a: F4, b: F4, f: impl Fn(f32, f32) -> f32) -> F4 {
        F4([
            f(a.0[0], b.0[0]),
            f(a.0[1], b.0[1]),
            f(a.0[2], b.0[2]),
            f(a.0[3], b.0[3]),
        ])
    }
    #[inline(always)]
    fn bits(a: F4, b: F4, f: impl Fn(f32, f32) -> bool) -> u32 {
        (0..4).map(|i| (f(a.0[i], b.0[i]) as u32) << i).sum()
    }

    impl F4 {
        #[inline(always)]
        pub fn splat(x: f32) -> F4 {
            F4([x; 4])
        }
        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> F4 {
            F4(*a)
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 4] {
            self.0
        }
        #[inline(always)]
        pub fn add(self, b: F4) -> F4 {
            map(self, b, |x, y| x + y)
        }
        #[inline(always)]
        pub fn sub(self, b: F4) -> F4 {
            map(self, b, |x, y| x - y)
        }
        #[inline(always)]
        pub fn mul(self, b: F4) -> F4 {
            map(self, b, |x, y| x * y)
        }
        #[inline(always)]
        pub fn div(self, b: F4) -> F4 {
            map(self, b, |x, y| x / y)
        }
        #[inline(always)]
        pub fn sqrt(self) -> F4 {
            F4(self.0.map(f32::sqrt))
        }
        #[inline(always)]
        pub fn neg(self) -> F4 {
            F4(self.0.map(|x| -x))
        }
        #[inline(always)]
        pub fn min(self, b: F4) -> F4 {
            map(self, b, |x, y| if x < y { x } else { y })
        }
        #[inline(always)]
        pub fn max(self, b: F4) -> F4 {
            map(self, b, |x, y| if x > y { x } else { y })
        }
        #[inline(always)]
        pub fn le(self, b: F4) -> u32 {
            bits(self, b, |x, y| x <= y)
        }
        #[inline(always)]
        pub fn lt(self, b: F4) -> u32 {
            bits(self, b, |x, y| x < y)
        }
        #[inline(always)]
        pub fn ne(self, b: F4) -> u32 {
            bits(self, b, |x, y| x != y)
        }
        #[inline(always)]
        pub fn select(self, mask: u32, a: F4) -> F4 {
            let mut r = self.0;
            for (i, v) in r.iter_mut().enumerate() {
                if mask >> i & 1 == 1 {
                    *v = a.0[i];
                }
            }
            F4(r)
        }
    }
}

pub use imp::F4;

/// Three coordinates, each four lanes wide.
#[derive(Clone, Copy)]
pub struct V4 {
    pub x: F4,
    pub y: F4,
    pub z: F4,
}

impl V4 {
    #[inline(always)]
    pub fn splat(v: glam::Vec3) -> V4 {
        V4 {
            x: F4::splat(v.x),
            y: F4::splat(v.y),
            z: F4::splat(v.z),
        }
    }
    #[inline(always)]
    pub fn sub(self, b: V4) -> V4 {
        V4 {
            x: self.x.sub(b.x),
            y: self.y.sub(b.y),
            z: self.z.sub(b.z),
        }
    }
    /// (x·x' + y·y') + z·z', glam's order, so a lane equals the scalar `Vec3A::dot`.
    #[inline(always)]
    pub fn dot(self, b: V4) -> F4 {
        self.x.mul(b.x).add(self.y.mul(b.y)).add(self.z.mul(b.z))
    }
    /// The cross product, each component as glam computes it.
    #[inline(always)]
    pub fn cross(self, b: V4) -> V4 {
        V4 {
            x: self.y.mul(b.z).sub(b.y.mul(self.z)),
            y: self.z.mul(b.x).sub(b.z.mul(self.x)),
            z: self.x.mul(b.y).sub(b.x.mul(self.y)),
        }
    }
}
