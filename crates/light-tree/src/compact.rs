//! Compact nodes for the descent (issue 22): the two children of a node side by side in one
//! 64-byte cache line, with quantised bounds (`codes.rs`), and their two importances evaluated
//! together in SIMD lanes with no transcendental function (pbrt-v4's `CompactLightBounds`
//! idea, laid out as a pair).

#[cfg(test)]
use crate::codes::decode_cos;
use crate::codes::{LEAF_BIT, Quant, Slot, Slots, slot, slots_evaluated, slots_importance};
use crate::lanes::{Fast, Lanes};
use crate::oct::OctNode;
use crate::oct_descent::DescentSimd;
use crate::quad::QuadNode;
use crate::{BuildError, LightTree, Node, NodeExtra};
use glam::Vec3;
use rayon::prelude::*;

/// The two children of one node, structure-of-arrays, `[left, right]` in each field; 64 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct NodePair {
    /// Box codes: lower x, y, z, then upper x, y, z.
    qbox: [[u16; 2]; 6],
    /// Axis codes (x, y, z), normalised when decoded.
    axis: [[i16; 2]; 3],
    /// cos θo · 32767, rounded down.
    cos_o: [i16; 2],
    /// cos θe · 32767, rounded down.
    cos_e: [i16; 2],
    power: [f32; 2],
    /// Interior child: index of its own pair. Leaf: `LEAF_BIT | light`.
    pub(crate) child: [u32; 2],
    /// `FLAG_TWO_SIDED`, `FLAG_HALF_SPACE` of each child.
    flags: [u8; 2],
}

impl NodePair {
    fn set(&mut self, side: usize, s: &Slot, child: u32) {
        for k in 0..6 {
            self.qbox[k][side] = s.qbox[k];
        }
        for k in 0..3 {
            self.axis[k][side] = s.axis[k];
        }
        self.cos_o[side] = s.cos_o;
        self.cos_e[side] = s.cos_e;
        self.power[side] = s.power;
        self.flags[side] = s.flags;
        self.child[side] = child;
    }
}

#[derive(Clone, Debug)]
/// The compact layout of a tree: pair 0 holds the root (left) beside an empty slot; every
/// interior node's children form one pair.
pub(crate) struct Compact {
    pub(crate) quant: Quant,
    pub(crate) pairs: Vec<NodePair>,
    /// Per node: `2 · pair + side` of the slot that holds it.
    pub(crate) slot_of: Vec<u32>,
    /// Per pair: the node whose children it holds (`NodeId::MAX` for pair 0, the root's).
    pub(crate) parent: Vec<u32>,
    /// The four-wide nodes a caller-weighted descent reads (`quad.rs`).
    pub(crate) quads: Vec<QuadNode>,
    /// Per node: its quad, `u32::MAX` for leaves and odd-depth nodes.
    pub(crate) quad_of: Vec<u32>,
    /// Per quad: the nodes in its lanes (`NO_NODE` for an empty one), for caller weights.
    pub(crate) quad_nodes: Vec<[crate::NodeId; 4]>,
    /// The eight-wide nodes the E&K descent reads (`oct.rs`).
    pub(crate) octs: Vec<OctNode>,
    /// Per node: its oct, `u32::MAX` for leaves and depths not divisible by 3.
    pub(crate) oct_of: Vec<u32>,
    /// Per oct: the nodes in its lanes (`NO_NODE` for an empty one); kept for the tests only.
    #[cfg(test)]
    pub(crate) oct_nodes: Vec<[crate::NodeId; 8]>,
    /// The lanes the E&K descent evaluates on.
    pub(crate) simd: DescentSimd,
}

impl Compact {
    pub(crate) fn build(nodes: &[Node], extra: &[NodeExtra]) -> Result<Compact, BuildError> {
        let (lo, hi) = nodes[0].aabb();
        let quant = Quant::new(lo, hi)?;
        // Pair indices in DFS order of the interior nodes, from 1 (0 is the root's pair).
        let mut pair_of = vec![u32::MAX; nodes.len()];
        let mut count = 1u32;
        for (id, node) in nodes.iter().enumerate() {
            if !node.is_leaf() {
                pair_of[id] = count;
                count += 1;
            }
        }
        let child_code = |id: usize| match nodes[id].light() {
            Some(light) => LEAF_BIT | light as u32,
            None => pair_of[id],
        };
        let slots: Vec<Slot> = (0..nodes.len())
            .into_par_iter()
            .map(|i| slot(&quant, &nodes[i], &extra[i]))
            .collect();
        let mut pairs = vec![NodePair::default(); count as usize];
        let mut parent = vec![u32::MAX; count as usize];
        let mut slot_of = vec![0u32; nodes.len()];
        pairs[0].set(0, &slots[0], child_code(0));
        // The empty right slot: zero power, so its importance is 0 (a valid axis keeps NaN
        // out of its lane).
        pairs[0].child[1] = LEAF_BIT;
        pairs[0].axis[2][1] = i16::MAX;
        for (id, node) in nodes.iter().enumerate() {
            if let Some((l, r)) = node.children(id as u32) {
                let p = pair_of[id];
                parent[p as usize] = id as u32;
                for (side, c) in [(0, l as usize), (1, r as usize)] {
                    pairs[p as usize].set(side, &slots[c], child_code(c));
                    slot_of[c] = 2 * p + side as u32;
                }
            }
        }
        let (quads, quad_of, quad_nodes) = crate::quad::build(nodes, &slots);
        #[cfg_attr(not(test), allow(unused_variables))]
        let (octs, oct_of, oct_nodes) = crate::oct::build(nodes, &slots);
        Ok(Compact {
            quant,
            pairs,
            slot_of,
            parent,
            quads,
            quad_of,
            quad_nodes,
            octs,
            oct_of,
            #[cfg(test)]
            oct_nodes,
            simd: DescentSimd::detect(),
        })
    }
}

/// The compact E&K importances `[left, right]` of pair `p` for a receiver at `x` with normal
/// `n` (`Vec3::ZERO`: no receiver term).
#[inline(always)]
pub(crate) fn pair_importance<L: Lanes<4>>(p: &NodePair, q: &Quant, x: Vec3, n: Vec3) -> [f32; 2] {
    let v = quad_importance::<L>(p, p, q, x, n);
    [v[0], v[1]]
}

/// Two pairs as four slots: `[a.left, a.right, b.left, b.right]`.
pub(crate) struct TwoPairs<'a>(pub(crate) &'a NodePair, pub(crate) &'a NodePair);

impl TwoPairs<'_> {
    #[inline(always)]
    fn join<T: Copy>(a: [T; 2], b: [T; 2]) -> [T; 4] {
        [a[0], a[1], b[0], b[1]]
    }
}

impl Slots<4> for TwoPairs<'_> {
    #[inline(always)]
    fn qbox(&self, k: usize) -> [u16; 4] {
        Self::join(self.0.qbox[k], self.1.qbox[k])
    }
    #[inline(always)]
    fn axis(&self, k: usize) -> [i16; 4] {
        Self::join(self.0.axis[k], self.1.axis[k])
    }
    #[inline(always)]
    fn cos_o(&self) -> [i16; 4] {
        Self::join(self.0.cos_o, self.1.cos_o)
    }
    #[inline(always)]
    fn cos_e(&self) -> [i16; 4] {
        Self::join(self.0.cos_e, self.1.cos_e)
    }
    #[inline(always)]
    fn power(&self) -> [f32; 4] {
        Self::join(self.0.power, self.1.power)
    }
    #[inline(always)]
    fn flags(&self) -> [u8; 4] {
        Self::join(self.0.flags, self.1.flags)
    }
}

/// Four pairs as eight slots, pair k in lanes 2k and 2k + 1.
pub(crate) struct FourPairs<'a>(pub(crate) [&'a NodePair; 4]);

impl FourPairs<'_> {
    #[inline(always)]
    fn join<T: Copy>(&self, f: impl Fn(&NodePair) -> [T; 2]) -> [T; 8] {
        let [a, b, c, d] = self.0.map(f);
        [a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]]
    }
}

impl Slots<8> for FourPairs<'_> {
    #[inline(always)]
    fn qbox(&self, k: usize) -> [u16; 8] {
        self.join(|p| p.qbox[k])
    }
    #[inline(always)]
    fn axis(&self, k: usize) -> [i16; 8] {
        self.join(|p| p.axis[k])
    }
    #[inline(always)]
    fn cos_o(&self) -> [i16; 8] {
        self.join(|p| p.cos_o)
    }
    #[inline(always)]
    fn cos_e(&self) -> [i16; 8] {
        self.join(|p| p.cos_e)
    }
    #[inline(always)]
    fn power(&self) -> [f32; 8] {
        self.join(|p| p.power)
    }
    #[inline(always)]
    fn flags(&self) -> [u8; 8] {
        self.join(|p| p.flags)
    }
}

/// The compact importances of two pairs at once, `[a.left, a.right, b.left, b.right]`.
#[inline(always)]
pub(crate) fn quad_importance<L: Lanes<4>>(
    a: &NodePair,
    b: &NodePair,
    q: &Quant,
    x: Vec3,
    n: Vec3,
) -> [f32; 4] {
    slots_importance::<4, L, _>(&TwoPairs(a, b), q, x, n)
}

impl LightTree {
    /// Compact importances `[left, right]` of pair `pair` on the fast lanes.
    #[inline(always)]
    pub(crate) fn pair_importances(&self, pair: u32, x: Vec3, n: Vec3) -> [f32; 2] {
        let c = &self.compact;
        pair_importance::<Fast>(&c.pairs[pair as usize], &c.quant, x, n)
    }

    /// Compact importances of two pairs at once (see [`quad_importance`]).
    #[inline(always)]
    pub(crate) fn quad_importances(&self, a: u32, b: u32, x: Vec3, n: Vec3) -> [f32; 4] {
        let c = &self.compact;
        quad_importance::<Fast>(&c.pairs[a as usize], &c.pairs[b as usize], &c.quant, x, n)
    }

    /// What a caller's weight of quad `quad`'s four nodes can reuse at `x` (see
    /// [`crate::QuadView`]).
    pub fn quad_view(&self, quad: u32, x: Vec3) -> crate::QuadView {
        let c = &self.compact;
        let e = slots_evaluated::<4, Fast, _>(&c.quads[quad as usize].0, &c.quant, x, Vec3::ZERO);
        crate::QuadView {
            to_centre: e.to_centre,
            radius_sq: e.radius_sq,
            emit: e.importance,
        }
    }

    /// Index of the pair that holds `node`'s children; `None` for a leaf.
    #[inline]
    pub(crate) fn children_pair(&self, node: u32) -> Option<u32> {
        let s = self.compact.slot_of[node as usize];
        let code = self.compact.pairs[(s >> 1) as usize].child[(s & 1) as usize];
        (code & LEAF_BIT == 0).then_some(code)
    }

    /// The pair that holds `node`'s children (`None` for a leaf), for callers that keep it
    /// beside their own per-node data and skip the two lookups of
    /// [`LightTree::child_importances`].
    #[inline]
    pub fn children_pair_of(&self, node: u32) -> Option<u32> {
        self.children_pair(node)
    }

    /// [`LightTree::child_importances`] of the node whose children pair `pair` holds (from
    /// [`LightTree::children_pair_of`]): the same bits.
    #[inline]
    pub fn pair_child_importances(&self, pair: u32, x: Vec3, n: Vec3) -> [f32; 2] {
        self.pair_importances(pair, x, n)
    }

    /// [`LightTree::pair_child_importances`] of `pair` and, from the same eight-lane pass
    /// (one AVX2 pass where the CPU has it, two four-lane ones otherwise), of the pairs below
    /// it: the children's importances of each of `pair`'s two nodes, `None` for a leaf. A
    /// descent that takes one child at a time evaluates every other level; the values are
    /// the same bits as one call per pair.
    pub fn pair_child_importances_ahead(
        &self,
        pair: u32,
        x: Vec3,
        n: Vec3,
    ) -> ([f32; 2], [Option<[f32; 2]>; 2]) {
        let c = &self.compact;
        let p = &c.pairs[pair as usize];
        // A leaf's lanes hold a copy of `pair` (valid bounds, discarded).
        let below = p.child.map(|code| (code & LEAF_BIT == 0).then_some(code));
        let slots = FourPairs([
            p,
            below[0].map_or(p, |q| &c.pairs[q as usize]),
            below[1].map_or(p, |q| &c.pairs[q as usize]),
            p,
        ]);
        let v = self.eight_lanes(&slots, x, n);
        let lanes = |k: usize| [v[2 * k], v[2 * k + 1]];
        (
            lanes(0),
            [below[0].map(|_| lanes(1)), below[1].map(|_| lanes(2))],
        )
    }

    /// The compact importances of eight slots on the best lanes.
    #[inline(always)]
    fn eight_lanes(&self, slots: &FourPairs<'_>, x: Vec3, n: Vec3) -> [f32; 8] {
        #[cfg(target_arch = "x86_64")]
        if self.compact.simd == DescentSimd::Avx2 {
            // SAFETY: `simd` is `Avx2` only where the CPU was found to have AVX2.
            return unsafe { self.eight_lanes_avx2(slots, x, n) };
        }
        slots_importance::<8, crate::lanes::Fast8, _>(slots, &self.compact.quant, x, n)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn eight_lanes_avx2(&self, slots: &FourPairs<'_>, x: Vec3, n: Vec3) -> [f32; 8] {
        slots_importance::<8, crate::lanes::Avx8, _>(slots, &self.compact.quant, x, n)
    }

    /// Starts loading the pairs of the grandchildren under pair `pair` (the next step of a
    /// descent, whichever child it takes), so that their cache misses overlap the work on
    /// `pair` itself (a hint).
    #[inline(always)]
    pub fn prefetch_next_pairs(&self, pair: u32) {
        #[cfg(target_arch = "x86_64")]
        if let Some(p) = self.compact.pairs.get(pair as usize) {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let base = self.compact.pairs.as_ptr();
            for code in p.child {
                if code & LEAF_BIT == 0 {
                    // SAFETY: a prefetch never faults; interior codes are valid pair indices.
                    unsafe { _mm_prefetch::<_MM_HINT_T0>(base.add(code as usize) as *const i8) };
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = pair;
    }
}

#[cfg(test)]
impl Compact {
    /// Decoded box, cos θo and cos θe of the slot holding `node` (tests).
    pub(crate) fn decoded(&self, node: u32) -> (Vec3, Vec3, f32, f32) {
        let s = self.slot_of[node as usize];
        let (p, side) = (&self.pairs[(s >> 1) as usize], (s & 1) as usize);
        let q = &self.quant;
        let lo = Vec3::from_array([0, 1, 2].map(|k| q.decode(k, p.qbox[k][side])));
        let hi = Vec3::from_array([0, 1, 2].map(|k| q.decode(k, p.qbox[k + 3][side])));
        (lo, hi, decode_cos(p.cos_o[side]), decode_cos(p.cos_e[side]))
    }
}
