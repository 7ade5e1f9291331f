//! The BRDF-oriented light cut (method.md §1.3): from the root, split a node when x lies inside
//! its bounding sphere or when the glossy lobe's integral over the node's cap exceeds δ. Every
//! cut node keeps its BO importance and its cap integral (the allocation's UB reuses them).
//! Under `--bo-importance sg` the cut is made the same way and each cut node's importance is
//! then its SG importance ([`super::sg_importance`]).
use super::importance::{BoRecord, LobeDensity, NodeTerms};
use super::sg_importance::SgImportance;
use brdf_integrals::LobeIntegral;
use light_tree::{Cut, LightTree, NodeId};
use std::collections::VecDeque;

/// Buffers of [`BoCut::build_into`].
#[derive(Clone, Debug, Default)]
pub struct BoCutScratch {
    out: Vec<(NodeId, NodeTerms)>,
    queue: VecDeque<NodeId>,
}

/// A BO cut: node ids sorted by DFS id with their terms and the cumulative importance.
#[derive(Clone, Debug, Default)]
pub struct BoCut {
    /// The cut's nodes (sorted by DFS id).
    pub cut: Cut,
    /// Each node's BO terms (I_BO and cap integral), in the cut's order.
    pub terms: Vec<NodeTerms>,
    /// `cdf[k]` = Σ_{j ≤ k} I_BO(cut node j).
    pub cdf: Vec<f32>,
}

impl BoCut {
    /// Builds the BO cut of the shading point of `rec` (at most `max_size` nodes).
    pub fn build<L: LobeIntegral + LobeDensity>(
        tree: &LightTree,
        rec: &BoRecord<L>,
        delta: f32,
        max_size: usize,
    ) -> BoCut {
        let mut cut = BoCut::default();
        cut.build_into(tree, rec, delta, max_size, &mut BoCutScratch::default());
        cut
    }

    /// [`BoCut::build`] into `self`, reusing its buffers and the caller's scratch.
    pub fn build_into<L: LobeIntegral + LobeDensity>(
        &mut self,
        tree: &LightTree,
        rec: &BoRecord<L>,
        delta: f32,
        max_size: usize,
        scratch: &mut BoCutScratch,
    ) {
        self.build_weighted_into(tree, rec, None, delta, max_size, scratch);
    }

    /// [`BoCut::build_into`] with the cut nodes' importances taken from `sg` when given: the
    /// split test and the cached cap integrals (UB) stay the method's.
    pub fn build_weighted_into<L: LobeIntegral + LobeDensity>(
        &mut self,
        tree: &LightTree,
        rec: &BoRecord<L>,
        sg: Option<&SgImportance>,
        delta: f32,
        max_size: usize,
        scratch: &mut BoCutScratch,
    ) {
        let BoCutScratch { out, queue } = scratch;
        out.clear();
        queue.clear();
        queue.push_back(tree.root());
        let mut size = 1usize;
        while let Some(id) = queue.pop_front() {
            let node = tree.node(id);
            let can_split = !node.is_leaf() && size < max_size.max(1);
            // Inside the bounding sphere: split before computing anything (as the authors do).
            if can_split
                && node.contains(rec.x)
                && node.importance(rec.x, render_core::Vec3::ZERO) > 0.0
            {
                let r = node.right_child().unwrap();
                queue.push_back(id + 1);
                queue.push_back(r);
                size += 1;
                continue;
            }
            let t = rec.terms(node);
            if can_split && t.importance > 0.0 && t.glossy > delta {
                queue.push_back(id + 1);
                queue.push_back(node.right_child().unwrap());
                size += 1;
            } else {
                out.push((id, t));
            }
        }
        out.sort_unstable_by_key(|&(id, _)| id);
        if let Some(sg) = sg {
            // Only the nodes kept: the split nodes' SG importance would never be read.
            for (id, t) in out.iter_mut() {
                t.importance = sg.importance(tree, *id);
            }
        }
        self.cut.nodes.clear();
        self.terms.clear();
        self.cdf.clear();
        let mut acc = 0.0f32;
        for &(id, t) in out.iter() {
            acc += t.importance;
            self.cut.nodes.push(id);
            self.terms.push(t);
            self.cdf.push(acc);
        }
    }

    /// Σ I_BO over the cut (0: BO cannot sample here).
    pub fn total(&self) -> f32 {
        self.cdf.last().copied().unwrap_or(0.0)
    }

    /// Probability of picking cluster `k`: the width of its interval of the (f32) cdf over
    /// the total, exactly what [`BoCut::pick`] realises (not I_k/total, which differs from the
    /// interval width by rounding for clusters far below the total).
    pub fn cluster_pmf(&self, k: usize) -> f32 {
        let total = self.total();
        if total > 0.0 {
            let lo = if k > 0 { self.cdf[k - 1] } else { 0.0 };
            (self.cdf[k] - lo) / total
        } else {
            0.0
        }
    }

    /// Picks a cluster for `u` ∈ [0, 1): `(index, pmf, u rescaled into the cluster's interval)`.
    pub fn pick(&self, u: f32) -> Option<(usize, f32, f32)> {
        let total = self.total();
        if !(total > 0.0) {
            return None;
        }
        let target = u * total;
        let mut k = self.cdf.partition_point(|&c| c <= target);
        // Stay in range (u·total can round up to total), skipping zero-width intervals.
        k = k.min(self.cdf.len() - 1);
        while k > 0 && self.cdf[k] <= self.cdf[k - 1] {
            k -= 1;
        }
        let lo = if k > 0 { self.cdf[k - 1] } else { 0.0 };
        let width = self.cdf[k] - lo;
        if !(width > 0.0) {
            return None;
        }
        let rest = ((target - lo) / width).clamp(0.0, 1.0 - f32::EPSILON / 2.0);
        Some((k, width / total, rest))
    }

    /// UB = clamp(max over the cut of the cached glossy cap integrals, 0, 1) (heuristic 1).
    pub fn upper_bound(&self) -> f32 {
        self.terms
            .iter()
            .map(|t| t.glossy)
            .fold(0.0f32, f32::max)
            .clamp(0.0, 1.0)
    }
}
