//! The compact node codes and the importance kernel that reads them: the leaf module that the
//! compact layout (`compact.rs`), its wide nodes (`quad.rs`, `oct.rs`, `lane_slots.rs`) and the
//! descents import, and which imports none of them.
//!
//! Every quantisation rounds towards more importance, so the compact bounds contain the exact
//! ones and the compact importance is zero only where the exact one is:
//! * boxes: 16 bits per coordinate over the root box, lower corners rounded down and upper
//!   corners up (checked against the decoding arithmetic itself);
//! * the cone axis: 16 bits per component, normalised when decoded; the angle between the
//!   decoded and the exact axis (plus 1e-5 rad of slack) is added to θo;
//! * cos θo and cos θe: 16 bits, rounded down (wider angles); sin θo is √(1 − cos²θo) of the
//!   rounded cosine, so the pair stays one angle;
//! * the half-space flag is set only if the widened θo + θe ≤ π/2 still holds.
//!
//! Power stays f32, as do all products (Φ · cos θ′ · cos θ′ᵢ / d² in f32, as in the exact
//! importance).

use crate::lanes::Lanes;
use crate::{BuildError, FLAG_HALF_SPACE, FLAG_TWO_SIDED, Node, NodeExtra};
use glam::Vec3;

/// Floor of the squared distance in the importance: keeps Φ/d² finite when x sits exactly on
/// a point light (r = 0).
pub const MIN_DIST_SQ: f32 = 1e-12;
/// Emitter cosine used where θ′ < θe but cos θ′ ≤ 0 (possible only for θe > π/2): keeps such
/// emitters sampleable instead of giving them zero importance.
pub const MIN_EMIT_COS: f32 = 1e-3;

/// Set in a slot's child code for a leaf: the low bits are then its light.
pub(crate) const LEAF_BIT: u32 = 1 << 31;
/// Largest box code.
const QMAX: u32 = u16::MAX as u32;
/// Scale of the signed cosine and axis codes.
const QSIGNED: f32 = i16::MAX as f32;

/// Slack added to θo beyond the axis' quantisation angle (f32 rounding of the decoded axis).
const AXIS_SLACK: f64 = 1e-5;

/// The box code ↔ position map of one tree: per axis x = origin + code · step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Quant {
    origin: [f32; 3],
    step: [f32; 3],
}

impl Quant {
    /// The map over the root box `lo..hi`: code 65535 decodes to ≥ hi.
    pub(crate) fn new(lo: Vec3, hi: Vec3) -> Result<Quant, BuildError> {
        let mut q = Quant {
            origin: lo.to_array(),
            step: [0.0; 3],
        };
        for k in 0..3 {
            let extent = hi[k] - lo[k];
            if !extent.is_finite() {
                return Err(BuildError::BoundsTooLarge);
            }
            let mut s = (extent as f64 / QMAX as f64) as f32;
            while q.origin[k] + QMAX as f32 * s < hi[k] {
                s = s.next_up();
            }
            if !(q.origin[k] + QMAX as f32 * s).is_finite() {
                return Err(BuildError::BoundsTooLarge);
            }
            q.step[k] = s;
        }
        Ok(q)
    }

    /// The position of `code` on axis `k`, exactly as the importance decodes it.
    #[inline(always)]
    pub(crate) fn decode(&self, k: usize, code: u16) -> f32 {
        self.origin[k] + code as f32 * self.step[k]
    }

    /// The largest code whose position is ≤ v.
    fn encode_down(&self, k: usize, v: f32) -> u16 {
        let s = self.step[k];
        let mut c = if s > 0.0 {
            ((v as f64 - self.origin[k] as f64) / s as f64)
                .floor()
                .clamp(0.0, QMAX as f64) as u32
        } else {
            0
        };
        while c > 0 && self.decode(k, c as u16) > v {
            c -= 1;
        }
        c as u16
    }

    /// The smallest code whose position is ≥ v.
    fn encode_up(&self, k: usize, v: f32) -> u16 {
        let s = self.step[k];
        let mut c = if s > 0.0 {
            ((v as f64 - self.origin[k] as f64) / s as f64)
                .ceil()
                .clamp(0.0, QMAX as f64) as u32
        } else {
            0
        };
        while c < QMAX && self.decode(k, c as u16) < v {
            c += 1;
        }
        c as u16
    }
}

/// A cosine code rounded down: the largest c with c / 32767 (as decoded) ≤ `cos`.
fn encode_cos_down(cos: f64) -> i16 {
    let mut c = (cos * QSIGNED as f64)
        .floor()
        .clamp(-QSIGNED as f64, QSIGNED as f64) as i32;
    while c > -(i16::MAX as i32) && (decode_cos(c as i16) as f64) > cos {
        c -= 1;
    }
    c as i16
}

#[inline(always)]
pub(crate) fn decode_cos(c: i16) -> f32 {
    // A product rather than a quotient (shorter latency); the encoder checks this very value.
    c as f32 * (1.0 / QSIGNED)
}

/// One child's compact bounds, before it is placed in its pair.
pub(crate) struct Slot {
    pub(crate) qbox: [u16; 6],
    pub(crate) axis: [i16; 3],
    pub(crate) cos_o: i16,
    pub(crate) cos_e: i16,
    pub(crate) power: f32,
    pub(crate) flags: u8,
}

/// The compact bounds of `node`: see the module docs for the rounding.
pub(crate) fn slot(q: &Quant, node: &Node, extra: &NodeExtra) -> Slot {
    let (lo, hi) = node.aabb();
    let mut qbox = [0u16; 6];
    for k in 0..3 {
        qbox[k] = q.encode_down(k, lo[k]);
        qbox[k + 3] = q.encode_up(k, hi[k]);
    }
    let a = node.axis().as_dvec3();
    let mut axis = [0i16; 3];
    for k in 0..3 {
        axis[k] = (a[k] * QSIGNED as f64)
            .round()
            .clamp(-QSIGNED as f64, QSIGNED as f64) as i16;
    }
    if axis == [0; 3] {
        axis = [0, 0, i16::MAX];
    }
    let decoded = glam::DVec3::new(axis[0] as f64, axis[1] as f64, axis[2] as f64).normalize();
    let delta = if a.length_squared() > 0.0 {
        decoded.dot(a.normalize()).clamp(-1.0, 1.0).acos()
    } else {
        std::f64::consts::PI
    };
    let theta_o = (extra.theta_o as f64 + delta + AXIS_SLACK).min(std::f64::consts::PI);
    let theta_e = extra.theta_e as f64;
    let mut flags = 0;
    if node.two_sided() {
        flags |= FLAG_TWO_SIDED;
    } else if node.flags & FLAG_HALF_SPACE != 0 && theta_o + theta_e <= std::f64::consts::FRAC_PI_2
    {
        flags |= FLAG_HALF_SPACE;
    }
    Slot {
        qbox,
        axis,
        cos_o: encode_cos_down(theta_o.cos()),
        cos_e: encode_cos_down(theta_e.cos()),
        power: node.power(),
        flags,
    }
}

/// N compact slots, lane by lane: two node pairs side by side (`compact.rs`), a quad or an
/// oct (`quad.rs`, `oct.rs`).
pub(crate) trait Slots<const N: usize> {
    /// Box codes on row `k` (lower x, y, z, then upper x, y, z).
    fn qbox(&self, k: usize) -> [u16; N];
    /// Axis codes on component `k`.
    fn axis(&self, k: usize) -> [i16; N];
    fn cos_o(&self) -> [i16; N];
    fn cos_e(&self) -> [i16; N];
    fn power(&self) -> [f32; N];
    fn flags(&self) -> [u8; N];
}

/// The compact importances of N slots: the exact importance's formula, term for term, on
/// the decoded bounds, with selects instead of early exits. Each lane only sees its own node,
/// so a node's value is the same bits in any slot of any pair, quad or oct, on any lanes.
#[inline(always)]
pub(crate) fn slots_importance<const N: usize, L: Lanes<N>, S: Slots<N>>(
    s: &S,
    q: &Quant,
    x: Vec3,
    n: Vec3,
) -> [f32; N] {
    slots_evaluated::<N, L, S>(s, q, x, n).importance
}

/// What [`slots_importance`] computes on the way, lane by lane.
pub(crate) struct SlotsEvaluated<const N: usize> {
    /// The compact importance.
    pub(crate) importance: [f32; N],
    /// The decoded box centre − x, per axis.
    pub(crate) to_centre: [[f32; N]; 3],
    /// The decoded box's half-diagonal squared (the bounding sphere's radius²).
    pub(crate) radius_sq: [f32; N],
}

// Helpers of `slots_evaluated` as functions, not closures or array maps: inside the AVX
// descent (a `#[target_feature]` function) LLVM inlines these, and with them the intrinsics;
// closures were left as calls there, each intrinsic a call too.

#[inline(always)]
fn dot3<L: Copy + std::ops::Add<Output = L> + std::ops::Mul<Output = L>>(
    a: &[L; 3],
    b: &[L; 3],
) -> L {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Integer codes as lanes of f32.
#[inline(always)]
fn from_codes<const N: usize, L: Lanes<N>, T: Copy + Into<f32>>(c: [T; N]) -> L {
    let mut f = [0.0f32; N];
    for k in 0..N {
        f[k] = c[k].into();
    }
    L::load(f)
}

#[inline(always)]
fn cosines<const N: usize, L: Lanes<N>>(c: [i16; N]) -> L {
    let mut f = [0.0f32; N];
    for k in 0..N {
        f[k] = decode_cos(c[k]);
    }
    L::load(f)
}

/// The lanes whose `flags` have `flag`, as a mask.
#[inline(always)]
fn flag_mask<const N: usize, L: Lanes<N>>(flags: &[u8; N], flag: u8) -> L {
    let mut f = [0.0f32; N];
    for k in 0..N {
        f[k] = f32::from_bits(if flags[k] & flag != 0 { u32::MAX } else { 0 });
    }
    L::load(f)
}

/// [`slots_importance`] with its decoded centres and radii (unused outputs cost nothing once
/// inlined).
#[inline(always)]
pub(crate) fn slots_evaluated<const N: usize, L: Lanes<N>, S: Slots<N>>(
    s: &S,
    q: &Quant,
    x: Vec3,
    n: Vec3,
) -> SlotsEvaluated<N> {
    slots_evaluated_for::<N, L, S>(s, q, &receiver::<N, L>(x, n))
}

/// A receiver per lane: its position, its normal (zero: none, then for every lane) and the
/// normal's absolute components.
pub(crate) struct LaneReceiver<L> {
    pub(crate) x: [L; 3],
    pub(crate) n: [L; 3],
    pub(crate) n_abs: [L; 3],
    pub(crate) has_n: bool,
}

/// One receiver (x, n) in every lane.
#[inline(always)]
pub(crate) fn receiver<const N: usize, L: Lanes<N>>(x: Vec3, n: Vec3) -> LaneReceiver<L> {
    LaneReceiver {
        x: [L::splat(x.x), L::splat(x.y), L::splat(x.z)],
        n: [L::splat(n.x), L::splat(n.y), L::splat(n.z)],
        n_abs: [
            L::splat(n.x.abs()),
            L::splat(n.y.abs()),
            L::splat(n.z.abs()),
        ],
        has_n: n != Vec3::ZERO,
    }
}

/// Receiver `a` in lanes 0–7 and `b` in lanes 8–15 (two descents side by side); both must
/// have a normal or both none.
#[inline(always)]
pub(crate) fn receiver_pair<L: Lanes<16>>(a: (Vec3, Vec3), b: (Vec3, Vec3)) -> LaneReceiver<L> {
    debug_assert_eq!(a.1 == Vec3::ZERO, b.1 == Vec3::ZERO);
    let (xa, na, xb, nb) = (a.0, a.1, b.0, b.1);
    LaneReceiver {
        x: [halves(xa.x, xb.x), halves(xa.y, xb.y), halves(xa.z, xb.z)],
        n: [halves(na.x, nb.x), halves(na.y, nb.y), halves(na.z, nb.z)],
        n_abs: [
            halves(na.x.abs(), nb.x.abs()),
            halves(na.y.abs(), nb.y.abs()),
            halves(na.z.abs(), nb.z.abs()),
        ],
        has_n: a.1 != Vec3::ZERO,
    }
}

/// `a` in lanes 0–7, `b` in lanes 8–15.
#[inline(always)]
fn halves<L: Lanes<16>>(a: f32, b: f32) -> L {
    let mut v = [a; 16];
    v[8..].fill(b);
    L::load(v)
}

/// [`slots_evaluated`] for a receiver per lane.
#[inline(always)]
pub(crate) fn slots_evaluated_for<const N: usize, L: Lanes<N>, S: Slots<N>>(
    s: &S,
    q: &Quant,
    r: &LaneReceiver<L>,
) -> SlotsEvaluated<N> {
    let half_l = L::splat(0.5);
    let mut c = [L::splat(0.0); 3];
    let mut h = [L::splat(0.0); 3];
    for k in 0..3 {
        let (o, st) = (L::splat(q.origin[k]), L::splat(q.step[k]));
        let lo = o + from_codes::<N, L, _>(s.qbox(k)) * st;
        let hi = o + from_codes::<N, L, _>(s.qbox(k + 3)) * st;
        c[k] = (lo + hi) * half_l - r.x[k];
        h[k] = (hi - lo) * half_l;
    }
    let zero = L::splat(0.0);
    let one = L::splat(1.0);

    let ax = [
        from_codes::<N, L, _>(s.axis(0)),
        from_codes::<N, L, _>(s.axis(1)),
        from_codes::<N, L, _>(s.axis(2)),
    ];
    let flags = s.flags();
    let inv_len = one / dot3(&ax, &ax).sqrt();
    let ax = [ax[0] * inv_len, ax[1] * inv_len, ax[2] * inv_len];

    let has_n = r.has_n;
    let nv = r.n;
    // Box tests: wholly behind the tangent plane; behind the box of a half-space emitter.
    let mut dark = zero;
    if has_n {
        dark = (dot3(&nv, &c) + dot3(&r.n_abs, &h)).le(zero);
    }
    let half_space = flag_mask::<N, L>(&flags, FLAG_HALF_SPACE);
    let to_x = [zero - c[0], zero - c[1], zero - c[2]];
    let ax_abs = [ax[0].abs(), ax[1].abs(), ax[2].abs()];
    let behind = (dot3(&ax, &to_x) + dot3(&ax_abs, &h)).le(zero);
    dark = dark.or(half_space.and(behind));

    let d2 = dot3(&c, &c);
    let r2 = dot3(&h, &h);
    let d2c = d2.max(L::splat(0.25) * r2).max(L::splat(MIN_DIST_SQ));
    let inside = d2.le(r2);
    let inv_d = one / d2.sqrt();
    let sin_u = (r2.sqrt() * inv_d).min(one);
    let cos_u = (one - sin_u * sin_u).max(zero).sqrt();

    // Emitter: θ between the axis and x − c.
    // The dot products with c run beside the square root and the division (a shorter chain
    // than normalising c first).
    let mut cos_t = zero - dot3(&ax, &c) * inv_d;
    let two_sided = flag_mask::<N, L>(&flags, FLAG_TWO_SIDED);
    cos_t = L::select(two_sided, cos_t.abs(), cos_t);
    let sin_t = (one - cos_t * cos_t).max(zero).sqrt();
    let cos_o = cosines::<N, L>(s.cos_o());
    let cos_e = cosines::<N, L>(s.cos_e());
    let sin_o = (one - cos_o * cos_o).max(zero).sqrt();
    let within = cos_t.ge(cos_o);
    let cos_x = L::select(within, one, cos_t * cos_o + sin_t * sin_o);
    let sin_x = L::select(within, zero, sin_t * cos_o - cos_t * sin_o);
    let cos_p = L::select(cos_x.ge(cos_u), one, cos_x * cos_u + sin_x * sin_u);
    let mut cone_dark = cos_p.le(cos_e);
    let emit = cos_p.max(L::splat(MIN_EMIT_COS));

    // Receiver: θi between n and c − x.
    let recv = if has_n {
        let cos_i = dot3(&nv, &c) * inv_d;
        let sin_i = (one - cos_i * cos_i).max(zero).sqrt();
        let recv = L::select(cos_i.ge(cos_u), one, cos_i * cos_u + sin_i * sin_u);
        cone_dark = cone_dark.or(recv.le(zero));
        recv
    } else {
        one
    };

    let near = L::load(s.power()) / d2c;
    let outside = near * emit * recv;
    let value = L::select(inside, near, cone_dark.andnot(outside));
    SlotsEvaluated {
        importance: dark.andnot(value).out(),
        to_centre: [c[0].out(), c[1].out(), c[2].out()],
        radius_sq: r2.out(),
    }
}
