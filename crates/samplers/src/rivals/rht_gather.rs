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
use light_tree::{LightTree, NodeId, SplitCriterion};
use render_core::rng::SampleStream;

pub use super::rht_options::RhtTraversal;

/// A weight of 0 for anything not positive, finite weights kept below overflow (as the
/// tree's own descent sanitises them, so that replays agree).
fn sanitize(w: f32) -> f32 {
    if w > 0.0 { w.min(f32::MAX / 4.0) } else { 0.0 }
}

/// What the traversal at one shading point reads: the tree, the child weights of an interior
/// node, the split threshold τ and the receiver for the split measure.
pub struct Traversal<'a, W: Fn(NodeId) -> [f32; 2]> {
    /// The tree over the scene's lights.
    pub tree: &'a LightTree,
    /// Weights of the two children of an interior node (e.g. their E&K importances).
    pub child_weights: W,
    /// τ of the split probability (0: never split, a single descent).
    pub tau: f32,
    /// The receiver position.
    pub x: render_core::Vec3,
}

/// One interior node's step: the children's sanitised weights and the split probability.
struct Step {
    w: [f32; 2],
    split: f32,
}

impl<W: Fn(NodeId) -> [f32; 2]> Traversal<'_, W> {
    /// s(N) where both children have weight, else 0 (module docs).
    fn step(&self, id: NodeId) -> Step {
        let raw = (self.child_weights)(id);
        let w = [sanitize(raw[0]), sanitize(raw[1])];
        let split = if w[0] > 0.0 && w[1] > 0.0 && self.tau > 0.0 {
            // ρ = (1 + σ)^(−1/4), as `split_metric`, by two square roots instead of powf.
            let sigma = self.tree.split_sigma(id, self.x, SplitCriterion::UnitFree);
            let rho = (1.0 / (1.0 + sigma).sqrt().sqrt()) as f32;
            (1.0 - rho / self.tau).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Step { w, split }
    }

    /// Gathers the candidates into `out` as (light, gathering probability), in depth-first
    /// order (left child first); `stack` is scratch.
    pub fn gather(
        &self,
        form: RhtTraversal,
        rng: &mut SampleStream,
        stack: &mut Vec<(NodeId, f32)>,
        out: &mut Vec<(u32, f32)>,
    ) {
        stack.clear();
        stack.push((self.tree.root(), 1.0));
        while let Some((id, prob)) = stack.pop() {
            let node = self.tree.node(id);
            if let Some(light) = node.light() {
                out.push((light as u32, prob));
                continue;
            }
            let Some((l, r)) = node.children(id) else {
                continue;
            };
            let Step { w, split } = self.step(id);
            let sum = w[0] + w[1];
            if sum == 0.0 {
                continue;
            }
            if w[0] == 0.0 || w[1] == 0.0 {
                stack.push((if w[0] > 0.0 { l } else { r }, prob));
                continue;
            }
            let p_left = w[0] / sum;
            let q = [
                split + (1.0 - split) * p_left,
                split + (1.0 - split) * (w[1] / sum),
            ];
            let u = rng.next_f32();
            if u < split {
                let (ql, qr) = match form {
                    RhtTraversal::Corrected => (q[0], q[1]),
                    RhtTraversal::Biased => (1.0, 1.0),
                };
                stack.push((r, prob * qr));
                stack.push((l, prob * ql));
            } else {
                let v = (u - split) / (1.0 - split);
                let (child, qc) = if v < p_left { (l, q[0]) } else { (r, q[1]) };
                stack.push((child, prob * qc));
            }
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
            let Some((l, r)) = tree.node(id).children(id) else {
                return 0.0;
            };
            let raw = (self.child_weights)(id);
            let w = [sanitize(raw[0]), sanitize(raw[1])];
            let side = (bits & 1) as usize;
            if w[side] == 0.0 {
                return 0.0;
            }
            if w[1 - side] > 0.0 {
                pmf *= w[side] / (w[0] + w[1]);
            }
            id = if side == 0 { l } else { r };
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
            let Some((l, r)) = tree.node(id).children(id) else {
                return (0.0, 0.0);
            };
            let Step { w, split } = self.step(id);
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
            id = if side == 0 { l } else { r };
            bits >>= 1;
        }
        (pi, descent)
    }
}
