//! The four-wide descent (`quad.rs`) under a caller's weight ([`LightTree::sample_quads`],
//! e.g. Liu et al.'s BRDF-oriented importance), with its pmf replay beside it. (The tree's own
//! E&K descent is eight-wide, `oct_descent.rs`: a caller's weight of four nodes at a time keeps
//! its per-node memo small.)
//!
//! A step weighs four nodes at once: an even-depth node's four grandchildren (a child that is
//! a leaf stands in its half beside an empty lane). It picks a half ∝ the sum of its two
//! lanes, then a lane ∝ its own weight: the binary descent in which an odd-depth interior node
//! weighs as the sum of its children's sanitised weights. An odd-depth start takes one binary
//! step between its two children first.

use crate::codes::LEAF_BIT;
use crate::descent_step::{DescentRandom, choose, chosen, sanitize};
use crate::{LightTree, NodeId};

/// A lane that holds no node (the second lane of a leaf's half, the pair step's lanes 2, 3).
pub const NO_NODE: NodeId = NodeId::MAX;

/// A quad's four nodes as its compact lanes bound them, seen from a point x: what a caller's
/// weight ([`QuadWeights`]) can take instead of reading the four full nodes (four more cache
/// lines). The bounds are the compact ones, rounded outward (`compact.rs`); an empty lane has
/// zero `emit`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadView {
    /// The decoded box centre − x, per axis (x, y, z), per lane.
    pub to_centre: [[f32; 4]; 3],
    /// The decoded box's half-diagonal squared: the bounding sphere's radius².
    pub radius_sq: [f32; 4],
    /// The compact E&K importance without a receiver term: Φ·cos θ′/max(d², r²/4), 0 where
    /// the emitters cannot reach x.
    pub emit: [f32; 4],
}

/// A caller's weight for [`LightTree::sample_quads`] / [`LightTree::pmf_quads`].
pub trait QuadWeights {
    /// Non-negative weights of the four `nodes` of one step; lanes holding [`NO_NODE`] must not
    /// be looked up, and whatever they return counts as 0. `quad` is the step's quad index
    /// (a key for a per-shading-point memo: a quad always holds the same four nodes), `None`
    /// for the binary step of an odd-depth start. It must be a deterministic function of the
    /// nodes, so that the replay sees the numbers the descent saw.
    fn weigh(&mut self, quad: Option<u32>, nodes: &[NodeId; 4]) -> [f32; 4];
}

impl<F: FnMut(Option<u32>, &[NodeId; 4]) -> [f32; 4]> QuadWeights for F {
    #[inline(always)]
    fn weigh(&mut self, quad: Option<u32>, nodes: &[NodeId; 4]) -> [f32; 4] {
        self(quad, nodes)
    }
}

/// A caller's [`QuadWeights`] as the descent reads it: a step's lanes by node id, empty lanes
/// weighing 0.
struct ByNode<'w, W: QuadWeights>(&'w mut W);

impl<W: QuadWeights> ByNode<'_, W> {
    /// The two children of interior odd-depth `node`.
    #[inline(always)]
    fn pair(&mut self, tree: &LightTree, node: NodeId) -> [f32; 2] {
        let right = tree.nodes[node as usize].child_or_light;
        let w = self.0.weigh(None, &[node + 1, right, NO_NODE, NO_NODE]);
        [w[0], w[1]]
    }
    /// The four lanes of quad `quad`.
    #[inline(always)]
    fn quad(&mut self, tree: &LightTree, quad: u32) -> [f32; 4] {
        let nodes = &tree.compact.quad_nodes[quad as usize];
        let w = self.0.weigh(Some(quad), nodes);
        std::array::from_fn(|k| if nodes[k] == NO_NODE { 0.0 } else { w[k] })
    }
}

impl LightTree {
    /// The number of quads (one per interior node at even depth).
    pub fn num_quads(&self) -> u32 {
        self.compact.quads.len() as u32
    }

    /// The four nodes in the lanes of quad `quad` ([`NO_NODE`] for an empty lane), in lane
    /// order: the left child's two children, then the right child's.
    pub fn quad_nodes(&self, quad: u32) -> &[NodeId; 4] {
        &self.compact.quad_nodes[quad as usize]
    }

    /// The four-wide descent from `start` under a caller's weight (see the module doc):
    /// `(light, pmf within the subtree)`, or `None` at a dead end. It is
    /// `sample_subtree(start, w, rng)` bit for bit, where `w` is the caller's weight at every
    /// node except interior odd-depth ones, which weigh the sum of their children's
    /// (sanitised); a leaf `start` returns its light with pmf 1.
    pub fn sample_quads<W: QuadWeights, R: DescentRandom>(
        &self,
        start: NodeId,
        weights: &mut W,
        rng: &mut R,
    ) -> Option<(usize, f32)> {
        self.descend(start, &mut ByNode(weights), rng)
    }

    /// Probability that [`LightTree::sample_quads`] from `start` with the same weight returns
    /// `light` (0 if `light` is not under `start`), replayed with the same operations.
    pub fn pmf_quads<W: QuadWeights>(&self, start: NodeId, weights: &mut W, light: usize) -> f32 {
        self.replay(start, &mut ByNode(weights), light)
    }

    /// The descent of [`LightTree::sample_quads`].
    #[inline(always)]
    fn descend<W: QuadWeights, R: DescentRandom>(
        &self,
        start: NodeId,
        weights: &mut ByNode<W>,
        rng: &mut R,
    ) -> Option<(usize, f32)> {
        let node = &self.nodes[start as usize];
        if node.is_leaf() {
            return Some((node.child_or_light as usize, 1.0));
        }
        let mut pmf = 1.0f32;
        let mut quad = if node.depth() % 2 == 0 {
            self.compact.quad_of[start as usize]
        } else {
            let [il, ir] = weights.pair(self, start).map(sanitize);
            let (left, f) = choose(il, ir, rng)?;
            pmf *= f;
            let child = if left { start + 1 } else { node.child_or_light };
            let c = &self.nodes[child as usize];
            if c.is_leaf() {
                return Some((c.child_or_light as usize, pmf));
            }
            self.compact.quad_of[child as usize]
        };
        let quads = &self.compact.quads;
        loop {
            let q = &quads[quad as usize];
            self.prefetch_quads(q.child);
            let g = weights.quad(self, quad).map(sanitize);
            let (ia, ib) = (sanitize(g[0] + g[1]), sanitize(g[2] + g[3]));
            let (left, f) = choose(ia, ib, rng)?;
            pmf *= f;
            let h = if left { 0 } else { 2 };
            // A half of non-zero weight has a lane of non-zero weight. A leaf's half is
            // (leaf, empty): its second choice is certain (1.0) and draws nothing. (Both
            // decisions as nested intervals of the one number, rescaled once, measured 3-8 %
            // slower than two rescales: the division is not what the step waits for.)
            let (first, f) = choose(g[h], g[h + 1], rng)?;
            pmf *= f;
            let code = q.child[h + if first { 0 } else { 1 }];
            if code & LEAF_BIT != 0 {
                return Some(((code & !LEAF_BIT) as usize, pmf));
            }
            quad = code;
        }
    }

    /// The pmf replay of [`LightTree::descend`] along `light`'s bit trail.
    #[inline(always)]
    fn replay<W: QuadWeights>(&self, start: NodeId, weights: &mut ByNode<W>, light: usize) -> f32 {
        let leaf = self.leaf_of[light];
        let (first, last) = self.subtree_range(start);
        if leaf < first || leaf > last {
            return 0.0;
        }
        let node = &self.nodes[start as usize];
        if node.is_leaf() {
            return 1.0;
        }
        let leaf_depth = self.nodes[leaf as usize].depth();
        let mut depth = node.depth();
        // `start` is interior here, so its depth is below 64.
        let mut bits = self.trails[light] >> depth;
        let mut pmf = 1.0f32;
        let mut quad = if depth % 2 == 0 {
            self.compact.quad_of[start as usize]
        } else {
            let [il, ir] = weights.pair(self, start).map(sanitize);
            let Some(f) = chosen(il, ir, bits & 1 == 1) else {
                return 0.0;
            };
            pmf *= f;
            let child = if bits & 1 == 0 {
                start + 1
            } else {
                node.child_or_light
            };
            if depth + 1 == leaf_depth {
                return pmf;
            }
            bits >>= 1;
            depth += 1;
            self.compact.quad_of[child as usize]
        };
        let quads = &self.compact.quads;
        loop {
            let q = &quads[quad as usize];
            let g = weights.quad(self, quad).map(sanitize);
            let (ia, ib) = (sanitize(g[0] + g[1]), sanitize(g[2] + g[3]));
            let Some(f) = chosen(ia, ib, bits & 1 == 1) else {
                return 0.0;
            };
            pmf *= f;
            let h = 2 * (bits & 1) as usize;
            // The leaf is the child itself (first lane of its half) or one of its children.
            let lane = if depth + 1 == leaf_depth {
                0
            } else {
                (bits >> 1) & 1
            };
            let Some(f) = chosen(g[h], g[h + 1], lane == 1) else {
                return 0.0;
            };
            pmf *= f;
            if depth + 2 >= leaf_depth {
                return pmf;
            }
            quad = q.child[h + lane as usize];
            bits >>= 2;
            depth += 2;
        }
    }
}
