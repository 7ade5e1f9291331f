//! What the RHT gathering ([`super::rht_gather`]) reads of a node, in one 32-byte record per
//! node: the tree's topology, the handle of the children's compact pair (their importances)
//! and the inputs of the split measure.
//!
//! The gathering visits tens of nodes per shading point, most of them once on a single path
//! down, and at each it read the node (is it a leaf, where are its children), the node's slot
//! and its parent's pair (where its children's pair is), the children's pair, and the node's
//! extra data (the power spread of the split measure): four or five dependent cache lines
//! from four arrays. Here one record holds all but the pair, the records of both children are
//! requested while the current node is worked on, and the split probability is computed
//! inline with the same operations as [`LightTree::split_sigma`], so every value, and so the
//! image, stays the same bit for bit.
use super::slc_bo::BoWeight;
use light_tree::{LightTree, NodeId};
use render_core::Vec3;

/// `pair` of a leaf.
const LEAF: u32 = u32::MAX;

/// One node's record.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct Record {
    /// Centre of the bounding sphere, as [`light_tree::Node::center`].
    centre: Vec3,
    /// radius², rounded to f32 as `split_sigma` rounds it.
    r2: f32,
    /// The power spread V\[Φ\]/E\[Φ\]² of the node's lights.
    power_cv2: f32,
    /// Handle of the children's compact pair ([`LightTree::children_pair_of`]); [`LEAF`].
    pair: u32,
    /// Interior: the right child's id (the left one is id + 1). Leaf: the light.
    code: u32,
}

/// What a node is to the gathering.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A leaf holding this light.
    Leaf(u32),
    /// An interior node: its children (left, right) and their compact pair.
    Interior {
        /// Left child.
        left: NodeId,
        /// Right child.
        right: NodeId,
        /// Handle of the children's pair.
        pair: u32,
    },
}

/// The records of every node of a tree, indexed by [`NodeId`].
#[derive(Clone, Debug, Default)]
pub struct RhtNodes {
    records: Vec<Record>,
}

impl RhtNodes {
    /// The records of `tree`'s nodes.
    pub fn new(tree: &LightTree) -> RhtNodes {
        let records = (0..tree.nodes().len() as NodeId)
            .map(|id| {
                let node = tree.node(id);
                let (pair, code) = match (node.light(), node.children(id)) {
                    (Some(light), _) => (LEAF, light as u32),
                    (None, Some((_, right))) => (tree.children_pair_of(id).unwrap_or(LEAF), right),
                    (None, None) => (LEAF, u32::MAX),
                };
                Record {
                    centre: node.center(),
                    r2: node.radius() * node.radius(),
                    power_cv2: tree.node_extra(id).power_cv2,
                    pair,
                    code,
                }
            })
            .collect();
        RhtNodes { records }
    }

    /// What node `id` is.
    #[inline]
    pub fn kind(&self, id: NodeId) -> Kind {
        let r = &self.records[id as usize];
        if r.pair == LEAF {
            Kind::Leaf(r.code)
        } else {
            Kind::Interior {
                left: id + 1,
                right: r.code,
                pair: r.pair,
            }
        }
    }

    /// Starts loading the records of `left` and `right` (a hint).
    #[inline(always)]
    pub fn prefetch(&self, left: NodeId, right: NodeId) {
        #[cfg(target_arch = "x86_64")]
        for id in [left, right] {
            if let Some(r) = self.records.get(id as usize) {
                use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
                // SAFETY: a prefetch never faults, and `r` is a live reference.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(r as *const Record as *const i8) };
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (left, right);
    }

    /// The split probability clamp(1 − ρ/τ, 0, 1) of interior node `id` seen from `x`, with
    /// ρ = (1 + σ)^(−1/4) and σ [`LightTree::split_sigma`]'s unit-free measure, in the same
    /// operations (so the same bits); `zero_below` is [`zero_split_bound`]`(τ)`.
    #[inline]
    pub fn split(&self, id: NodeId, x: Vec3, tau: f32, zero_below: f64) -> f32 {
        let r = &self.records[id as usize];
        let d2 = (r.centre - x).length_squared() as f64;
        let r2 = r.r2 as f64;
        if d2 <= r2 {
            // σ = ∞: ρ = 0, split for sure.
            return 1.0;
        }
        let cg = 4.0 * r2 / (3.0 * (d2 - r2));
        let cv2 = (1.0 + r.power_cv2 as f64) * (1.0 + cg) - 1.0;
        if cv2 <= zero_below {
            // ρ/τ ≥ 1.0001: the clamp gives 0 without the square roots.
            return 0.0;
        }
        let sigma = cv2.max(0.0).sqrt();
        let rho = (1.0 / (1.0 + sigma).sqrt().sqrt()) as f32;
        (1.0 - rho / tau).clamp(0.0, 1.0)
    }
}

/// The squared σ below which ρ/τ ≥ 1.0001, so that clamp(1 − ρ/τ, 0, 1) is 0 whatever the
/// rounding of ρ (f64 to f32, relative error 6e-8) and of the division (6e-8); −∞ (no shortcut)
/// where no σ ≥ 0 gives that.
pub fn zero_split_bound(tau: f32) -> f64 {
    let rho = tau as f64 * 1.0001;
    let sigma = rho.powi(-4) - 1.0;
    if sigma > 0.0 {
        sigma * sigma
    } else {
        f64::NEG_INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use light_tree::{LightBounds, SplitCriterion};
    use rand::{RngExt, SeedableRng};

    /// The split probability as the tree's own measure gives it, with no shortcut.
    fn reference(tree: &LightTree, id: NodeId, x: Vec3, tau: f32) -> f32 {
        let sigma = tree.split_sigma(id, x, SplitCriterion::UnitFree);
        let rho = (1.0 / (1.0 + sigma).sqrt().sqrt()) as f32;
        (1.0 - rho / tau).clamp(0.0, 1.0)
    }

    /// The records' split equals the reference bit for bit at every interior node, for
    /// receivers near and far and τ across its range, and each of the three outcomes (0, 1,
    /// in between) occurs; the records' topology is the tree's.
    #[test]
    fn split_and_topology_match_the_tree() {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(11);
        let lights: Vec<LightBounds> = (0..500)
            .map(|_| {
                let c = Vec3::new(
                    rng.random_range(-10.0..10.0),
                    rng.random_range(-10.0..10.0),
                    rng.random_range(0.0..5.0),
                );
                let e = Vec3::splat(rng.random_range(0.01..0.5));
                LightBounds {
                    aabb_min: c - e,
                    aabb_max: c + e,
                    axis: Vec3::Z,
                    theta_o: 0.5,
                    theta_e: std::f32::consts::FRAC_PI_2,
                    power: rng.random_range(0.1..10.0),
                    two_sided: false,
                }
            })
            .collect();
        let tree = LightTree::build(&lights).unwrap();
        let nodes = RhtNodes::new(&tree);
        let mut seen = [0usize; 3];
        for tau in [0.05, 0.3, 0.5, 0.85, 0.999_9, 1.0] {
            let zero_below = zero_split_bound(tau);
            for _ in 0..30 {
                let x = Vec3::new(
                    rng.random_range(-15.0..15.0),
                    rng.random_range(-15.0..15.0),
                    rng.random_range(-8.0..8.0),
                );
                for id in 0..tree.nodes().len() as NodeId {
                    let node = tree.node(id);
                    let Kind::Interior { left, right, pair } = nodes.kind(id) else {
                        assert_eq!(nodes.kind(id), Kind::Leaf(node.light().unwrap() as u32));
                        continue;
                    };
                    assert_eq!(Some((left, right)), node.children(id));
                    assert_eq!(Some(pair), tree.children_pair_of(id));
                    let got = nodes.split(id, x, tau, zero_below);
                    assert_eq!(got.to_bits(), reference(&tree, id, x, tau).to_bits());
                    seen[if got == 0.0 {
                        0
                    } else if got == 1.0 {
                        1
                    } else {
                        2
                    }] += 1;
                }
            }
        }
        assert!(
            seen.iter().all(|&k| k > 100),
            "outcomes 0, 1, between: {seen:?}"
        );
    }
}

/// The node weights of one shading point: the tree's importance, or the BO weight.
pub enum NodeWeights {
    /// E&K importance at (x, n), on the tree's compact bounds.
    Tree(Vec3, Vec3),
    /// `rht-bo`'s weight at a glossy point.
    Bo(BoWeight),
}

impl NodeWeights {
    /// The weights of the two children of interior node `id`, whose compact pair is `pair`.
    pub fn children(&self, tree: &LightTree, id: NodeId, pair: u32) -> [f32; 2] {
        match self {
            NodeWeights::Tree(x, n) => tree.pair_child_importances(pair, *x, *n),
            NodeWeights::Bo(bo) => match tree.node(id).children(id) {
                Some((l, r)) => [bo.weight(tree.node(l)), bo.weight(tree.node(r))],
                None => [0.0; 2],
            },
        }
    }

    /// [`NodeWeights::children`] and, where one evaluation gives them at no extra cost (the
    /// tree's importance, eight lanes at a time), the weights of the children's own children
    /// (`None` for a leaf or where not evaluated).
    #[inline]
    pub fn children_ahead(
        &self,
        tree: &LightTree,
        id: NodeId,
        pair: u32,
    ) -> ([f32; 2], [Option<[f32; 2]>; 2]) {
        match self {
            NodeWeights::Tree(x, n) => tree.pair_child_importances_ahead(pair, *x, *n),
            NodeWeights::Bo(_) => (self.children(tree, id, pair), [None; 2]),
        }
    }
}
