//! An eight-wide BVH node: its children's float bounds in structure-of-arrays rows, so one
//! ray meets all eight boxes in one pass: one 8-lane pass with AVX2, two 4-lane passes with
//! SSE2. Both passes do the same operations per lane (slab distances as (bound − origin) ×
//! (1/direction), never fused), so they find the same children at the same distances.
use super::lanes::F4;
use glam::Vec3;

/// Bound rows in a node: min and max per axis.
const ROWS: usize = 6;

/// Child code: an inner node's index, or with [`LEAF`] set a leaf's first packet and its
/// triangle and sphere packet counts.
pub const LEAF: u32 = 1 << 31;
const TRI_SHIFT: u32 = 28;
const SPHERE_SHIFT: u32 = 26;
/// Largest packet index a leaf can start at.
pub const MAX_PACKET: u32 = (1 << SPHERE_SHIFT) - 1;
/// Most triangle and sphere packets in one leaf.
pub const MAX_TRI_PACKETS: u32 = 7;
pub const MAX_SPHERE_PACKETS: u32 = 3;

/// A leaf's child code.
pub fn leaf_code(first: u32, tri_packets: u32, sphere_packets: u32) -> u32 {
    assert!(
        first <= MAX_PACKET,
        "more than {MAX_PACKET} primitive packets"
    );
    debug_assert!(tri_packets <= MAX_TRI_PACKETS && sphere_packets <= MAX_SPHERE_PACKETS);
    LEAF | tri_packets << TRI_SHIFT | sphere_packets << SPHERE_SHIFT | first
}

/// (first packet, triangle packets, sphere packets) of a leaf code.
#[inline(always)]
pub fn leaf_parts(code: u32) -> (u32, u32, u32) {
    (
        code & MAX_PACKET,
        (code >> TRI_SHIFT) & 7,
        (code >> SPHERE_SHIFT) & 3,
    )
}

/// Eight children's boxes and codes; unused slots have empty boxes (min +∞, max −∞) and
/// empty leaves.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node8 {
    /// min x, max x, min y, max y, min z, max z.
    pub(super) bounds: [[f32; 8]; ROWS],
    pub child: [u32; 8],
}

impl Node8 {
    pub fn empty() -> Node8 {
        let mut bounds = [[f32::INFINITY; 8]; ROWS];
        for axis in 0..3 {
            bounds[2 * axis + 1] = [f32::NEG_INFINITY; 8];
        }
        Node8 {
            bounds,
            // An empty leaf: a ray whose NaN distances pass every box test finds nothing
            // there (code 0 would be the root, and a loop).
            child: [LEAF; 8],
        }
    }

    pub fn set(&mut self, slot: usize, lo: Vec3, hi: Vec3, code: u32) {
        for axis in 0..3 {
            self.bounds[2 * axis][slot] = lo[axis];
            self.bounds[2 * axis + 1][slot] = hi[axis];
        }
        self.child[slot] = code;
    }
}

/// What the node test needs of a ray: origin, inverse direction, and per axis whether the
/// direction is negative, which makes the max row the near slab.
pub struct BoxRay {
    pub(super) o: [f32; 3],
    pub(super) inv: [f32; 3],
    neg: [bool; 3],
    pub(super) tmin: f32,
}

/// pbrt's widening of the far slab distance, 1 + 2γ₃, so rounding never loses a box the ray
/// grazes.
pub(super) const FAR_SCALE: f32 =
    1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

impl BoxRay {
    /// `d` must not hold −0.0 (the caller adds +0.0), so the sign picks the slab 1/d points to.
    pub fn new(o: Vec3, d: Vec3, tmin: f32) -> BoxRay {
        let mut r = BoxRay {
            o: o.into(),
            inv: [0.0; 3],
            neg: [false; 3],
            tmin,
        };
        for axis in 0..3 {
            r.inv[axis] = 1.0 / d[axis];
            r.neg[axis] = r.inv[axis] < 0.0;
        }
        r
    }

    /// The ray's origin.
    #[inline(always)]
    pub fn origin(&self) -> Vec3 {
        Vec3::from(self.o)
    }

    /// The row of the near slab on `axis` (written so the compiler sees it is below 6).
    #[inline(always)]
    pub fn near(&self, axis: usize) -> usize {
        2 * axis + self.neg[axis] as usize
    }

    /// The row of the far slab on `axis`.
    #[inline(always)]
    pub fn far(&self, axis: usize) -> usize {
        2 * axis + 1 - self.neg[axis] as usize
    }
}

/// Children of `n` the ray enters before `tmax` (bits 0–7) and the entry distances.
pub trait NodeTest {
    fn test(n: &Node8, r: &BoxRay, tmax: f32) -> (u32, [f32; 8]);

    /// [`NodeTest::test`] for one ray of a packet: sets `bit` in `entered` for each child the
    /// ray enters and lowers `near` to the ray's entry distance where that is nearer.
    #[inline(always)]
    fn test_into(
        n: &Node8,
        r: &BoxRay,
        tmax: f32,
        bit: u32,
        (entered, near): (&mut [u32; 8], &mut [f32; 8]),
    ) {
        let (mask, tnear) = Self::test(n, r, tmax);
        for k in 0..8 {
            let hit = (mask >> k) & 1;
            entered[k] |= bit * hit;
            let t = if hit != 0 { tnear[k] } else { f32::INFINITY };
            near[k] = if t < near[k] { t } else { near[k] };
        }
    }
}

/// Two 4-lane passes (SSE2 on x86-64).
pub struct Lanes4;

impl NodeTest for Lanes4 {
    #[inline(always)]
    fn test(n: &Node8, r: &BoxRay, tmax: f32) -> (u32, [f32; 8]) {
        let mut tnear = [0.0; 8];
        let mut mask = 0;
        for half in 0..2 {
            let row = |i: usize| -> F4 {
                let a: &[f32; 4] = n.bounds[i][4 * half..4 * half + 4].try_into().unwrap();
                F4::load(a)
            };
            let slab = |i: usize, axis: usize| {
                row(i).sub(F4::splat(r.o[axis])).mul(F4::splat(r.inv[axis]))
            };
            let t0 = slab(r.near(0), 0)
                .max(slab(r.near(1), 1).max(slab(r.near(2), 2).max(F4::splat(r.tmin))));
            let t1 = slab(r.far(0), 0)
                .min(slab(r.far(1), 1).min(slab(r.far(2), 2)))
                .mul(F4::splat(FAR_SCALE))
                .min(F4::splat(tmax));
            mask |= t0.le(t1) << (4 * half);
            tnear[4 * half..4 * half + 4].copy_from_slice(&t0.to_array());
        }
        (mask, tnear)
    }
}

/// One 8-lane pass; only for callers that checked AVX2 is present. It picks each axis's
/// near and far rows by the sign of 1/d, which `BoxRay::new` leaves never −0 nor NaN (the
/// direction is finite and has no −0.0), so it picks the rows `BoxRay::near` names.
#[cfg(target_arch = "x86_64")]
pub struct Avx2;

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// The eight children's entry and exit distances (t0, t1); a child is entered where
    /// t0 ≤ t1.
    // Intrinsics written here, not in a `#[target_feature]` function (which LLVM would not
    // inline): this body is only inlined into the AVX2 traversals, which enable AVX2.
    #[inline(always)]
    fn slabs(
        n: &Node8,
        r: &BoxRay,
        tmax: f32,
    ) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
        use std::arch::x86_64::*;
        // SAFETY: only instantiated inside functions compiled with AVX2 enabled, which run
        // after `is_x86_feature_detected!("avx2")`; each row is eight readable f32s.
        unsafe {
            // (near, far) slabs of `axis`: both rows' distances, then the sign of 1/d picks
            // (the max row is near where it is negative), so no row index is computed. A
            // macro, not a closure: a closure may be left out of line, without AVX2.
            macro_rules! slabs {
                ($axis:literal) => {{
                    let o = _mm256_set1_ps(r.o[$axis]);
                    let inv = _mm256_set1_ps(r.inv[$axis]);
                    let lo = _mm256_loadu_ps(n.bounds[2 * $axis].as_ptr());
                    let hi = _mm256_loadu_ps(n.bounds[2 * $axis + 1].as_ptr());
                    let lo = _mm256_mul_ps(_mm256_sub_ps(lo, o), inv);
                    let hi = _mm256_mul_ps(_mm256_sub_ps(hi, o), inv);
                    (_mm256_blendv_ps(lo, hi, inv), _mm256_blendv_ps(hi, lo, inv))
                }};
            }
            let ((nx, fx), (ny, fy), (nz, fz)) = (slabs!(0), slabs!(1), slabs!(2));
            let t0 = _mm256_max_ps(
                nx,
                _mm256_max_ps(ny, _mm256_max_ps(nz, _mm256_set1_ps(r.tmin))),
            );
            let t1 = _mm256_min_ps(
                _mm256_mul_ps(
                    _mm256_min_ps(fx, _mm256_min_ps(fy, fz)),
                    _mm256_set1_ps(FAR_SCALE),
                ),
                _mm256_set1_ps(tmax),
            );
            (t0, t1)
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl NodeTest for Avx2 {
    #[inline(always)]
    fn test(n: &Node8, r: &BoxRay, tmax: f32) -> (u32, [f32; 8]) {
        use std::arch::x86_64::*;
        let (t0, t1) = Avx2::slabs(n, r, tmax);
        // SAFETY: as in `Avx2::slabs`.
        unsafe {
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32;
            let mut tnear = [0.0f32; 8];
            _mm256_storeu_ps(tnear.as_mut_ptr(), t0);
            (mask, tnear)
        }
    }

    /// The default's operations in lanes: the hit mask as lanes ands in `bit` and picks t0
    /// or +∞, and `min_ps(t, near)` is `t < near ? t : near`.
    #[inline(always)]
    fn test_into(
        n: &Node8,
        r: &BoxRay,
        tmax: f32,
        bit: u32,
        (entered, near): (&mut [u32; 8], &mut [f32; 8]),
    ) {
        use std::arch::x86_64::*;
        let (t0, t1) = Avx2::slabs(n, r, tmax);
        // SAFETY: as in `Avx2::slabs`; `entered` and `near` are eight lanes each.
        unsafe {
            let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1);
            let e = _mm256_loadu_si256(entered.as_ptr() as *const __m256i);
            let add = _mm256_and_si256(_mm256_castps_si256(hit), _mm256_set1_epi32(bit as i32));
            _mm256_storeu_si256(
                entered.as_mut_ptr() as *mut __m256i,
                _mm256_or_si256(e, add),
            );
            let t = _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), t0, hit);
            let m = _mm256_min_ps(t, _mm256_loadu_ps(near.as_ptr()));
            _mm256_storeu_ps(near.as_mut_ptr(), m);
        }
    }
}

/// Asks for every cache line of `*p` ahead of its use (nothing where there is no such hint).
#[inline(always)]
pub fn prefetch<T>(p: &T) {
    #[cfg(target_arch = "x86_64")]
    for line in (0..size_of::<T>()).step_by(64) {
        // SAFETY: a prefetch never faults, and the address lies inside `*p`; SSE is part of x86-64.
        unsafe {
            use std::arch::x86_64::*;
            _mm_prefetch::<_MM_HINT_T0>((p as *const T as *const i8).add(line));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
