//! The candidate gathering of the resampled hierarchical tree ([`super::rht`]): a stochastic
//! traversal of the light tree that, at each node, either splits (goes on into both children)
//! or descends into one child, and the probability that a light ends up among the candidates.
//!
//! At an interior node N with child weights w_a, w_b (both > 0) and p_a = w_a/(w_a + w_b):
//!
//! * N splits with probability s(N) = clamp(1 − ρ(N)/τ, 0, 1), ρ the E&K variance measure
//!   ([`LightTree::split_metric`], unit-free: 1 for a node that looks like one light, 0 when x
//!   is inside its bounding sphere), τ the `--rht-tau` knob;
//! * otherwise it descends into a with probability p_a, into b with p_b = 1 − p_a.
//!
//! One uniform number decides both (split when u < s, else the child by (u − s)/(1 − s)).
//! A child of weight 0 is never visited (its lights are provably dark at x): N then passes to
//! the other child with probability 1 and draws no number; both 0 is a dead end.
//!
//! **The gathering probability.** Child a is visited, given that N is, with probability
//! q_a = s + (1 − s)·p_a, and the decisions at different nodes are independent given the
//! nodes visited, so light ℓ is a candidate with probability π(ℓ) = Π q over the nodes on its
//! path ([`RhtTraversal::Corrected`]). π is a function of (x, n, ℓ) alone; [`inclusion`]
//! replays it, and Σ_{ℓ in the set} g(ℓ)/π(ℓ) is unbiased for Σ_ℓ g(ℓ) (Horvitz–Thompson).
//!
//! [`RhtTraversal::Biased`] is the defect the issue reports of the published pseudo-code: the
//! running probability is multiplied by q only on a single-child step and left unchanged (× 1)
//! where N split. Each of the two bookkeepings alone would be unbiased (the marginal q at every
//! node, or the conditional 1 | 1/p of the step actually taken); mixing them gives a child the
//! expected weight s + (1 − s)·p_a / q_a < 1 per level where 0 < s < 1, so the image is dark.
//! We could not read the talk's own pseudo-code: this is our reading of the reported defect,
//! kept to show the bias in a test (`tests/rht.rs`), not to be used.
//!
//! **Cost.** Most visited nodes lie on a single path down, so the per-node work is what
//! counts (none of it changes a value, so the images are those of the plain form bit for
//! bit):
//!
//! * the tree's importance is evaluated every other level: one eight-lane pass gives a node's
//!   children's weights and those of both children's children, whichever child comes next
//!   ([`LightTree::pair_child_importances_ahead`]; a pair alone fills two of four lanes);
//! * the node's topology, the handle of its children's compact pair and the inputs of the
//!   split measure come from one record ([`super::rht_nodes`]), the records of both children
//!   and the pairs of the next level requested ahead; the split probability skips its square
//!   roots where it is surely 0 or 1;
//! * the child a step goes on into is kept out of the stack (only a split's right child is
//!   pushed);
//! * each candidate carries its single-descent pmf (Π p on its path), which the MIS weight of
//!   the picked candidate needs, multiplied up with the same operations as
//!   [`Traversal::descent_pmf`], so it equals that replay bit for bit without a second walk.
use super::rht_nodes::NodeWeights;
use super::rht_nodes::{Kind, RhtNodes};
use light_tree::{LightTree, NodeId};
use render_core::rng::SampleStream;

pub use super::rht_options::RhtTraversal;

/// A weight of 0 for anything not positive, finite weights kept below overflow (as the
/// tree's own descent sanitises them, so that replays agree).
fn sanitize(w: f32) -> f32 {
    if w > 0.0 { w.min(f32::MAX / 4.0) } else { 0.0 }
}

/// What the traversal at one shading point reads: the tree and its records, the child weights
/// of an interior node, the split threshold τ and the receiver for the split measure.
pub struct Traversal<'a> {
    /// The tree over the scene's lights.
    pub tree: &'a LightTree,
    /// The gathering's records of the tree's nodes.
    pub nodes: &'a RhtNodes,
    /// The weights of an interior node's two children (e.g. their E&K importances).
    pub weights: &'a NodeWeights,
    /// τ of the split probability (0: never split, a single descent).
    pub tau: f32,
    /// [`super::rht_nodes::zero_split_bound`] of τ.
    pub zero_below: f64,
    /// The receiver position.
    pub x: render_core::Vec3,
}

/// A gathered candidate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gathered {
    /// The light.
    pub light: u32,
    /// π(light): the probability that the gathering reaches it.
    pub pi: f32,
    /// Its pmf under a single descent by the same weights ([`Traversal::descent_pmf`]).
    pub descent: f32,
}

/// A node on the traversal's stack, with the probabilities of the path that reached it and,
/// when its parent's evaluation already gave them, its children's weights.
#[derive(Clone, Copy, Debug)]
pub struct Visit {
    id: NodeId,
    pi: f32,
    descent: f32,
    weights: Option<[f32; 2]>,
}

/// One interior node's step: the children's sanitised weights and the split probability.
struct Step {
    w: [f32; 2],
    split: f32,
}

impl Traversal<'_> {
    /// s(N) where both children have weight, else 0 (module docs); `raw` are the children's
    /// weights.
    #[inline]
    fn step(&self, id: NodeId, raw: [f32; 2]) -> Step {
        let w = [sanitize(raw[0]), sanitize(raw[1])];
        let split = if w[0] > 0.0 && w[1] > 0.0 && self.tau > 0.0 {
            self.nodes.split(id, self.x, self.tau, self.zero_below)
        } else {
            0.0
        };
        Step { w, split }
    }

    /// Gathers the candidates into `out`, in depth-first order (left child first); `stack` is
    /// scratch.
    pub fn gather(
        &self,
        form: RhtTraversal,
        rng: &mut SampleStream,
        stack: &mut Vec<Visit>,
        out: &mut Vec<Gathered>,
    ) {
        stack.clear();
        // The node to visit next: the child a step went on into, kept out of the stack (a
        // store and a reload per level), or else the right child a split left there.
        let mut next = Some(Visit {
            id: self.tree.root(),
            pi: 1.0,
            descent: 1.0,
            weights: None,
        });
        while let Some(visit) = next.take().or_else(|| stack.pop()) {
            let (l, r, pair) = match self.nodes.kind(visit.id) {
                Kind::Leaf(light) => {
                    let (pi, descent) = (visit.pi, visit.descent);
                    out.push(Gathered { light, pi, descent });
                    continue;
                }
                Kind::Interior { left, right, pair } => (left, right, pair),
            };
            self.nodes.prefetch(l, r);
            self.tree.prefetch_next_pairs(pair);
            // The weights of this node's children, and where they come from an evaluation
            // here, those of its grandchildren too (for the next level, whichever it is).
            let (raw, below) = match visit.weights {
                Some(w) => (w, [None; 2]),
                None => self.weights.children_ahead(self.tree, visit.id, pair),
            };
            next = self.step_down(form, rng, &visit, [l, r], raw, below, stack);
        }
    }

    /// The decision at an interior node (`visit`, children `lr` with weights `raw`): the child
    /// it goes on into (the left one where it splits, the right one then pushed on `stack`),
    /// with its path probabilities and any known weights `below`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn step_down(
        &self,
        form: RhtTraversal,
        rng: &mut SampleStream,
        visit: &Visit,
        lr: [NodeId; 2],
        raw: [f32; 2],
        below: [Option<[f32; 2]>; 2],
        stack: &mut Vec<Visit>,
    ) -> Option<Visit> {
        let Step { w, split } = self.step(visit.id, raw);
        let sum = w[0] + w[1];
        if sum == 0.0 {
            return None;
        }
        let (pi, descent) = (visit.pi, visit.descent);
        if w[0] == 0.0 || w[1] == 0.0 {
            let side = (w[0] == 0.0) as usize;
            let (id, weights) = (lr[side], below[side]);
            return Some(Visit {
                id,
                pi,
                descent,
                weights,
            });
        }
        let p = [w[0] / sum, w[1] / sum];
        let q = [split + (1.0 - split) * p[0], split + (1.0 - split) * p[1]];
        let child = |side: usize, q: f32| Visit {
            id: lr[side],
            pi: pi * q,
            descent: descent * p[side],
            weights: below[side],
        };
        let u = rng.next_f32();
        if u < split {
            let (ql, qr) = match form {
                RhtTraversal::Corrected => (q[0], q[1]),
                RhtTraversal::Biased => (1.0, 1.0),
            };
            stack.push(child(1, qr));
            Some(child(0, ql))
        } else {
            let v = (u - split) / (1.0 - split);
            let side = (v >= p[0]) as usize;
            Some(child(side, q[side]))
        }
    }

    /// The pmf of `light` under a single descent by the same weights (Π p along its path, 0 at
    /// a dead end): [`Traversal::inclusion`]'s second value without the split probabilities.
    pub fn descent_pmf(&self, light: usize) -> f32 {
        let tree = self.tree;
        let leaf = tree.leaf_of(light);
        let mut bits = tree.bit_trail(light);
        let (mut id, mut pmf) = (tree.root(), 1.0f32);
        while id != leaf {
            let Kind::Interior { left, right, pair } = self.nodes.kind(id) else {
                return 0.0;
            };
            let raw = self.weights.children(tree, id, pair);
            let w = [sanitize(raw[0]), sanitize(raw[1])];
            let side = (bits & 1) as usize;
            if w[side] == 0.0 {
                return 0.0;
            }
            if w[1 - side] > 0.0 {
                pmf *= w[side] / (w[0] + w[1]);
            }
            id = if side == 0 { left } else { right };
            bits >>= 1;
        }
        pmf
    }

    /// (π(`light`), its pmf under a single descent by the same weights): the probability that
    /// [`Traversal::gather`] (corrected) gathers it, and Π p along its path (0 at a dead end).
    pub fn inclusion(&self, light: usize) -> (f32, f32) {
        let tree = self.tree;
        let leaf = tree.leaf_of(light);
        let mut bits = tree.bit_trail(light);
        let (mut id, mut pi, mut descent) = (tree.root(), 1.0f32, 1.0f32);
        while id != leaf {
            let Kind::Interior { left, right, pair } = self.nodes.kind(id) else {
                return (0.0, 0.0);
            };
            let Step { w, split } = self.step(id, self.weights.children(tree, id, pair));
            let side = (bits & 1) as usize;
            let sum = w[0] + w[1];
            if w[side] == 0.0 {
                return (0.0, 0.0);
            }
            if w[1 - side] > 0.0 {
                let p = w[side] / sum;
                pi *= split + (1.0 - split) * p;
                descent *= p;
            }
            id = if side == 0 { left } else { right };
            bits >>= 1;
        }
        (pi, descent)
    }
}
