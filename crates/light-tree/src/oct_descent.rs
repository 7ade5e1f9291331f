//! The E&K descent on the eight-wide octs (`oct.rs`), with its pmf replay: one eight-lane
//! evaluation (AVX where the CPU has it, chosen at run time) and one categorical choice per
//! three levels of the binary tree.
//!
//! **The choice.** The top 63 bits u of one 64-bit uniform number pick among the eight
//! lanes: lane k owns [t(k), t(k+1)) of [0, 2⁶³), with t(k) = ⌊2⁶³ · C(k) / S⌋, C(k) the sum
//! of the sanitised lanes before k (summed in f64 in lane order), S the sum of all eight, and
//! the range of the last lane of non-zero weight ending at 2⁶³. The pmf of the choice is the
//! exact length of the lane's range over 2⁶³, and the replay computes the same bounds from the
//! same lanes, so the pmf at sampling and at replay are the same bits. A rescaling source
//! ([`Rescaled`]) continues with ⌊2⁶⁴ (u − t(k)) / (t(k+1) − t(k))⌋: one 128-bit division per
//! three levels, and one bit of the number dropped per step. A lane of zero weight owns
//! nothing and is never chosen; a step with one lane of non-zero weight draws no number.
//! Unlike a quotient of f32 importances, a lane whose share of the step is below 2⁻⁶³ gets
//! pmf 0 at sampling and at replay alike.
//!
//! A `start` at a depth not divisible by 3 takes one or two binary steps (the node pairs)
//! first. Both lane implementations give the same bits (`lanes.rs`), so a descent is the same
//! with and without AVX.
//!
//! [`Rescaled`]: crate::Rescaled

use crate::codes::{LEAF_BIT, receiver_pair, slots_evaluated_for, slots_importance};
use crate::descent_step::{DescentRandom, choose, chosen, sanitize};
use crate::lanes::{Fast8, Lanes};
use crate::oct::TwoOcts;
use crate::{LightTree, NodeId};
use glam::Vec3;
use std::marker::PhantomData;

/// 2⁶³.
const TWO_63: f64 = 9_223_372_036_854_775_808.0;

/// The lanes the eight-wide descent evaluates on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DescentSimd {
    /// One 256-bit AVX pass (x86-64 CPUs with AVX2).
    Avx2,
    /// Two four-lane passes: SSE2 on x86-64, portable arrays elsewhere.
    Fallback,
}

impl DescentSimd {
    /// The best lanes this CPU has.
    pub fn detect() -> DescentSimd {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return DescentSimd::Avx2;
        }
        DescentSimd::Fallback
    }
}

/// A cache of one receiver's E&K oct lanes for [`LightTree::pmf_from_cached`], keyed by oct
/// index. The lanes are a pure function of (oct, x, n), so a cached value is the recomputed
/// one.
pub trait LaneCache {
    /// The cached lanes of `oct`, if kept.
    fn get(&mut self, oct: u32) -> Option<[f32; 8]>;
    /// Keeps `lanes` as those of `oct` (a cache may drop them).
    fn put(&mut self, oct: u32, lanes: [f32; 8]);
}

/// Where a descent or replay takes an oct's eight sanitised-before-use lanes from.
trait OctLanes {
    fn lanes(&mut self, tree: &LightTree, oct: u32) -> [f32; 8];
}

/// The compact E&K importance at (x, n), on lanes `L`.
struct Ek<L> {
    x: Vec3,
    n: Vec3,
    lanes: PhantomData<L>,
}

impl<L> Ek<L> {
    #[inline(always)]
    fn at((x, n): (Vec3, Vec3)) -> Self {
        Ek {
            x,
            n,
            lanes: PhantomData,
        }
    }
}

impl<L: Lanes<8>> OctLanes for Ek<L> {
    #[inline(always)]
    fn lanes(&mut self, tree: &LightTree, oct: u32) -> [f32; 8] {
        let c = &tree.compact;
        slots_importance::<8, L, _>(&c.octs[oct as usize].0, &c.quant, self.x, self.n)
    }
}

/// [`Ek`] through a [`LaneCache`].
struct CachedEk<'c, L, C> {
    ek: Ek<L>,
    cache: &'c mut C,
}

impl<L: Lanes<8>, C: LaneCache> OctLanes for CachedEk<'_, L, C> {
    #[inline(always)]
    fn lanes(&mut self, tree: &LightTree, oct: u32) -> [f32; 8] {
        if let Some(v) = self.cache.get(oct) {
            return v;
        }
        let v = self.ek.lanes(tree, oct);
        self.cache.put(oct, v);
        v
    }
}

/// `width` / 2⁶³, the probability of a lane whose range is `width` long.
#[inline(always)]
fn fraction(width: u64) -> f32 {
    (width as f64 / TWO_63) as f32
}

/// The lanes as the descent uses them (`sanitize`); a loop, not an array map, so that it
/// inlines into the AVX descent.
#[inline(always)]
fn sanitized(mut g: [f32; 8]) -> [f32; 8] {
    for v in &mut g {
        *v = sanitize(*v);
    }
    g
}

/// The sum of the lanes in f64, in lane order.
#[inline(always)]
fn sum(g: &[f32; 8]) -> f64 {
    let mut total = 0.0f64;
    for &v in g {
        total += v as f64;
    }
    total
}

/// t(k) below 2⁶³ (see the module doc): truncated and saturating, so monotone in `c`. (A
/// signed conversion is one instruction; an unsigned 64-bit one is a branchy sequence.)
#[inline(always)]
fn bound(c: f64, scale: f64) -> u64 {
    (c * scale) as i64 as u64
}

/// The lanes of non-zero weight as a bit mask.
#[inline(always)]
fn support(g: &[f32; 8]) -> u32 {
    let mut mask = 0;
    for (k, &v) in g.iter().enumerate() {
        mask |= ((v > 0.0) as u32) << k;
    }
    mask
}

/// One choice among the sanitised lanes `g`: `(lane, its probability)`, or `None` when all
/// are 0 (see the module doc).
#[inline(always)]
fn pick<R: DescentRandom>(g: &[f32; 8], rng: &mut R) -> Option<(usize, f32)> {
    let mask = support(g);
    if mask == 0 {
        return None;
    }
    let last = 31 - mask.leading_zeros() as usize;
    if mask.count_ones() == 1 {
        return Some((last, 1.0));
    }
    let scale = TWO_63 / sum(g);
    let u = rng.draw() >> 1;
    // Branch-free: t[k] is lane k's lower bound (2⁶³ past the last lane), and the lane is
    // the number of bounds t[1..] at or below u (a data-dependent exit mispredicts).
    let mut t = [1u64 << 63; 9];
    t[0] = 0;
    let mut c = 0.0f64;
    let mut lane = 0usize;
    for k in 1..8 {
        c += g[k - 1] as f64;
        let b = bound(c, scale);
        t[k] = if k <= last { b } else { 1 << 63 };
        lane += (t[k] <= u) as usize;
    }
    let (lo, hi) = (t[lane], t[lane + 1]);
    let width = hi - lo;
    rng.chose(u - lo, width);
    Some((lane, fraction(width)))
}

/// The probability that [`pick`] takes `lane` from the same sanitised lanes, by the same
/// operations.
#[inline(always)]
fn share(g: &[f32; 8], lane: usize) -> f32 {
    let mask = support(g);
    if mask & (1 << lane) == 0 {
        return 0.0;
    }
    if mask.count_ones() == 1 {
        return 1.0;
    }
    let last = 31 - mask.leading_zeros() as usize;
    let scale = TWO_63 / sum(g);
    let mut c = 0.0f64;
    let mut lo = 0u64;
    for &v in &g[..lane] {
        c += v as f64;
        lo = bound(c, scale);
    }
    let hi = if lane == last {
        1u64 << 63
    } else {
        bound(c + g[lane] as f64, scale)
    };
    fraction(hi - lo)
}

/// Where a descent stands after its binary steps.
#[derive(Clone, Copy)]
enum Entry {
    /// It ended (at a leaf, or at a dead end).
    Done(Option<(usize, f32)>),
    /// It goes on from this oct, with this pmf so far.
    Oct(u32, f32),
}

/// What one oct step leads to.
enum Step {
    Next(u32),
    Done(Option<(usize, f32)>),
}

impl LightTree {
    /// The descent of [`LightTree::sample_from`] on lanes `L8`.
    #[inline(always)]
    fn oct_descend<L8: Lanes<8>, R: DescentRandom>(
        &self,
        start: NodeId,
        xn: (Vec3, Vec3),
        rng: &mut R,
    ) -> Option<(usize, f32)> {
        let entry = self.oct_entry(start, xn, rng);
        self.oct_finish::<L8, R>(entry, xn, rng)
    }

    /// A descent's binary steps from `start` down to a depth divisible by 3 (none from such a
    /// depth): where it enters the octs, or its end.
    #[inline(always)]
    fn oct_entry<R: DescentRandom>(
        &self,
        start: NodeId,
        (x, n): (Vec3, Vec3),
        rng: &mut R,
    ) -> Entry {
        let mut id = start;
        let mut pmf = 1.0f32;
        while !self.nodes[id as usize].depth().is_multiple_of(3) {
            let node = &self.nodes[id as usize];
            let Some(pair) = self.children_pair(id) else {
                return Entry::Done(Some((node.child_or_light as usize, pmf)));
            };
            let [il, ir] = self.pair_importances(pair, x, n);
            let (il, ir) = (sanitize(il), sanitize(ir));
            let Some((left, f)) = choose(il, ir, rng) else {
                return Entry::Done(None);
            };
            pmf *= f;
            id = if left { id + 1 } else { node.child_or_light };
        }
        let node = &self.nodes[id as usize];
        if node.is_leaf() {
            return Entry::Done(Some((node.child_or_light as usize, pmf)));
        }
        Entry::Oct(self.compact.oct_of[id as usize], pmf)
    }

    /// The oct steps of a descent from `oct`, with `pmf` so far.
    #[inline(always)]
    fn oct_steps<W: OctLanes, R: DescentRandom>(
        &self,
        mut oct: u32,
        mut pmf: f32,
        weights: &mut W,
        rng: &mut R,
    ) -> Option<(usize, f32)> {
        loop {
            let g = sanitized(weights.lanes(self, oct));
            match self.oct_step(oct, &g, &mut pmf, rng) {
                Step::Next(next) => oct = next,
                Step::Done(found) => return found,
            }
        }
    }

    /// One step from `oct`, whose sanitised lanes are `g`: the next oct, or the end.
    #[inline(always)]
    fn oct_step<R: DescentRandom>(
        &self,
        oct: u32,
        g: &[f32; 8],
        pmf: &mut f32,
        rng: &mut R,
    ) -> Step {
        let Some((lane, f)) = pick(g, rng) else {
            return Step::Done(None);
        };
        *pmf *= f;
        let code = self.compact.octs[oct as usize].child[lane];
        if code & LEAF_BIT != 0 {
            return Step::Done(Some(((code & !LEAF_BIT) as usize, *pmf)));
        }
        Step::Next(code)
    }

    /// Two descents side by side ([`LightTree::sample_pair_from`]): while both are in the
    /// octs, one sixteen-lane pass on `L16` evaluates both steps, so their dependency chains
    /// overlap; a descent left alone finishes on `L8`. Each descent draws from its own source
    /// in its own order, so each is [`LightTree::oct_descend`]'s, bit for bit.
    #[inline(always)]
    fn oct_descend_pair<L16: Lanes<16>, L8: Lanes<8>, R: DescentRandom>(
        &self,
        start: [NodeId; 2],
        xn: [(Vec3, Vec3); 2],
        [ra, rb]: [&mut R; 2],
    ) -> [Option<(usize, f32)>; 2] {
        let ea = self.oct_entry(start[0], xn[0], ra);
        let eb = self.oct_entry(start[1], xn[1], rb);
        let same_kind = (xn[0].1 == Vec3::ZERO) == (xn[1].1 == Vec3::ZERO);
        let (Entry::Oct(mut a, mut pa), Entry::Oct(mut b, mut pb), true) = (ea, eb, same_kind)
        else {
            return [
                self.oct_finish::<L8, R>(ea, xn[0], ra),
                self.oct_finish::<L8, R>(eb, xn[1], rb),
            ];
        };
        let receivers = receiver_pair::<L16>(xn[0], xn[1]);
        let c = &self.compact;
        loop {
            let both = TwoOcts(&c.octs[a as usize], &c.octs[b as usize]);
            let g = slots_evaluated_for::<16, L16, _>(&both, &c.quant, &receivers).importance;
            let (mut ga, mut gb) = ([0.0f32; 8], [0.0f32; 8]);
            ga.copy_from_slice(&g[..8]);
            gb.copy_from_slice(&g[8..]);
            let sa = self.oct_step(a, &sanitized(ga), &mut pa, ra);
            let sb = self.oct_step(b, &sanitized(gb), &mut pb, rb);
            match (sa, sb) {
                (Step::Next(na), Step::Next(nb)) => (a, b) = (na, nb),
                (Step::Next(na), Step::Done(fb)) => {
                    return [self.oct_finish::<L8, R>(Entry::Oct(na, pa), xn[0], ra), fb];
                }
                (Step::Done(fa), Step::Next(nb)) => {
                    return [fa, self.oct_finish::<L8, R>(Entry::Oct(nb, pb), xn[1], rb)];
                }
                (Step::Done(fa), Step::Done(fb)) => return [fa, fb],
            }
        }
    }

    /// The rest of one descent from `entry`, on lanes `L8`.
    #[inline(always)]
    fn oct_finish<L8: Lanes<8>, R: DescentRandom>(
        &self,
        entry: Entry,
        xn: (Vec3, Vec3),
        rng: &mut R,
    ) -> Option<(usize, f32)> {
        match entry {
            Entry::Done(found) => found,
            Entry::Oct(oct, pmf) => self.oct_steps(oct, pmf, &mut Ek::<L8>::at(xn), rng),
        }
    }

    /// The replay of [`LightTree::oct_descend`] along `light`'s bit trail.
    #[inline(always)]
    fn oct_replay<W: OctLanes>(
        &self,
        start: NodeId,
        (x, n): (Vec3, Vec3),
        weights: &mut W,
        light: usize,
    ) -> f32 {
        let leaf = self.leaf_of[light];
        let (first, last) = self.subtree_range(start);
        if leaf < first || leaf > last {
            return 0.0;
        }
        let leaf_depth = self.nodes[leaf as usize].depth();
        let mut id = start;
        let mut depth = self.nodes[start as usize].depth();
        if depth == leaf_depth {
            return 1.0;
        }
        // `start` is interior here, so its depth is below 64.
        let mut bits = self.trails[light] >> depth;
        let mut pmf = 1.0f32;
        while !depth.is_multiple_of(3) {
            let Some(pair) = self.children_pair(id) else {
                return 0.0;
            };
            let [il, ir] = self.pair_importances(pair, x, n);
            let right = bits & 1 == 1;
            let Some(f) = chosen(sanitize(il), sanitize(ir), right) else {
                return 0.0;
            };
            pmf *= f;
            id = if right {
                self.nodes[id as usize].child_or_light
            } else {
                id + 1
            };
            bits >>= 1;
            depth += 1;
            if depth == leaf_depth {
                return pmf;
            }
        }
        let mut oct = self.compact.oct_of[id as usize];
        loop {
            let g = sanitized(weights.lanes(self, oct));
            let below = leaf_depth - depth;
            let mut lane = 4 * (bits & 1) as usize;
            if below >= 2 {
                lane += 2 * ((bits >> 1) & 1) as usize;
            }
            if below >= 3 {
                lane += ((bits >> 2) & 1) as usize;
            }
            let f = share(&g, lane);
            if f == 0.0 {
                return 0.0;
            }
            pmf *= f;
            if below <= 3 {
                return pmf;
            }
            oct = self.compact.octs[oct as usize].child[lane];
            bits >>= 3;
            depth += 3;
        }
    }

    /// The lanes the E&K descent evaluates on (detected when the tree is built).
    pub fn descent_simd(&self) -> DescentSimd {
        self.compact.simd
    }

    /// Descend on `simd`'s lanes from now on (the same lights and pmfs, bit for bit: for
    /// tests and timings). Asking for [`DescentSimd::Avx2`] on a CPU without it is an error.
    pub fn set_descent_simd(&mut self, simd: DescentSimd) -> Result<(), String> {
        if simd == DescentSimd::Avx2 && DescentSimd::detect() != DescentSimd::Avx2 {
            return Err("this CPU has no AVX2".into());
        }
        self.compact.simd = simd;
        Ok(())
    }

    /// A descent from `start` under [`LightTree::importance`], three levels per step on the
    /// eight-wide octs (`oct.rs`, `oct_descent.rs`): one dependent load, one eight-lane
    /// evaluation and one choice per three levels. It samples the binary descent in which
    /// interior nodes at depths not divisible by 3 weigh as the sum of their lanes (below a
    /// `start` at such a depth, which takes binary steps first). Returns `(light, pmf within
    /// the subtree)`, or `None` at a dead end; the pmf is [`LightTree::pmf_from`]'s, bit for
    /// bit, whatever the lanes.
    pub fn sample_from<R: DescentRandom>(
        &self,
        start: NodeId,
        x: Vec3,
        n: Vec3,
        rng: &mut R,
    ) -> Option<(usize, f32)> {
        #[cfg(target_arch = "x86_64")]
        if self.compact.simd == DescentSimd::Avx2 {
            // SAFETY: `simd` is Avx2 only where the CPU has AVX2 (`Compact::build`,
            // `set_descent_simd`).
            return unsafe { self.sample_from_avx2(start, x, n, rng) };
        }
        self.oct_descend::<Fast8, R>(start, (x, n), rng)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn sample_from_avx2<R: DescentRandom>(
        &self,
        start: NodeId,
        x: Vec3,
        n: Vec3,
        rng: &mut R,
    ) -> Option<(usize, f32)> {
        self.oct_descend::<crate::lanes::Avx8, R>(start, (x, n), rng)
    }

    /// Two independent descents at once, `[sample_from(start[0], x[0], n[0], rng[0]),
    /// sample_from(start[1], …)]` bit for bit: while both are in the octs their steps are
    /// evaluated in one sixteen-lane pass, so that their dependency chains overlap (a caller
    /// with two shading points' picks at hand, or two clusters of a cut).
    pub fn sample_pair_from<R: DescentRandom>(
        &self,
        start: [NodeId; 2],
        x: [Vec3; 2],
        n: [Vec3; 2],
        rng: [&mut R; 2],
    ) -> [Option<(usize, f32)>; 2] {
        let xn = [(x[0], n[0]), (x[1], n[1])];
        #[cfg(target_arch = "x86_64")]
        if self.compact.simd == DescentSimd::Avx2 {
            // SAFETY: as in `sample_from`.
            return unsafe { self.sample_pair_from_avx2(start, xn, rng) };
        }
        self.oct_descend_pair::<crate::lanes::Pair<Fast8>, Fast8, R>(start, xn, rng)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn sample_pair_from_avx2<R: DescentRandom>(
        &self,
        start: [NodeId; 2],
        xn: [(Vec3, Vec3); 2],
        rng: [&mut R; 2],
    ) -> [Option<(usize, f32)>; 2] {
        use crate::lanes::{Avx8, Pair};
        self.oct_descend_pair::<Pair<Avx8>, Avx8, R>(start, xn, rng)
    }

    /// Probability that [`LightTree::sample_from`] from `start` returns `light` (0 if `light`
    /// is not under `start`), replayed along its bit trail with the same operations.
    pub fn pmf_from(&self, start: NodeId, x: Vec3, n: Vec3, light: usize) -> f32 {
        self.pmf_from_cached(start, x, n, light, &mut NoCache)
    }

    /// [`LightTree::pmf_from`] with each oct's lanes taken from `cache` when it has them and
    /// put there when not: bit for bit the same value. For a caller that replays many pmfs at
    /// one (x, n) (the method's MIS weights at a glossy point), whose replays share the top of
    /// the tree; `cache` must hold lanes of this (x, n) only.
    pub fn pmf_from_cached<C: LaneCache>(
        &self,
        start: NodeId,
        x: Vec3,
        n: Vec3,
        light: usize,
        cache: &mut C,
    ) -> f32 {
        #[cfg(target_arch = "x86_64")]
        if self.compact.simd == DescentSimd::Avx2 {
            // SAFETY: as in `sample_from`.
            return unsafe { self.pmf_from_avx2(start, x, n, light, cache) };
        }
        let ek = Ek::<Fast8>::at((x, n));
        self.oct_replay(start, (x, n), &mut CachedEk { ek, cache }, light)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn pmf_from_avx2<C: LaneCache>(
        &self,
        start: NodeId,
        x: Vec3,
        n: Vec3,
        light: usize,
        cache: &mut C,
    ) -> f32 {
        let ek = Ek::<crate::lanes::Avx8>::at((x, n));
        self.oct_replay(start, (x, n), &mut CachedEk { ek, cache }, light)
    }

    /// The eight-wide node (oct) of `node`, for a caller's own descent over the octs: every
    /// interior node at a depth divisible by 3 has one (`None` for the others). Its lane
    /// `4·b₀ + 2·b₁ + b₂` holds the node reached by the branch bits b₀, b₁, b₂ below `node`
    /// (0 = left); a leaf above that depth takes the first lane of its range, beside empty
    /// lanes of importance 0.
    #[inline]
    pub fn oct_of(&self, node: NodeId) -> Option<u32> {
        let o = *self.compact.oct_of.get(node as usize)?;
        (o != u32::MAX).then_some(o)
    }

    /// The E&K importances of oct `oct`'s eight lanes at (x, n), unsanitised, as the tree's
    /// own descent evaluates them (one eight-lane pass, AVX2 where the CPU has it): the same
    /// bits on either path.
    pub fn oct_importances(&self, oct: u32, x: Vec3, n: Vec3) -> [f32; 8] {
        #[cfg(target_arch = "x86_64")]
        if self.compact.simd == DescentSimd::Avx2 {
            // SAFETY: as in `sample_from`.
            return unsafe { self.oct_importances_avx2(oct, x, n) };
        }
        Ek::<Fast8>::at((x, n)).lanes(self, oct)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn oct_importances_avx2(&self, oct: u32, x: Vec3, n: Vec3) -> [f32; 8] {
        Ek::<crate::lanes::Avx8>::at((x, n)).lanes(self, oct)
    }

    /// The eight lanes of oct `oct` at (x, n) on lanes `L` (tests).
    #[cfg(test)]
    pub(crate) fn oct_lanes<L: Lanes<8>>(&self, oct: u32, x: Vec3, n: Vec3) -> [f32; 8] {
        Ek::<L>::at((x, n)).lanes(self, oct)
    }
}

/// A cache that keeps nothing: the plain replay.
struct NoCache;

impl LaneCache for NoCache {
    #[inline(always)]
    fn get(&mut self, _: u32) -> Option<[f32; 8]> {
        None
    }
    #[inline(always)]
    fn put(&mut self, _: u32, _: [f32; 8]) {}
}
