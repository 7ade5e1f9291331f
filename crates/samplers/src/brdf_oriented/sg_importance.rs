//! The SG node importance inside the method (issue 24, `--bo-importance sg`): BO's cluster
//! distribution and its descent inside a cluster weigh nodes by the spherical-Gaussian
//! lighting integral of Tokuyoshi et al. 2024 ([`crate::sg::importance`]) instead of I_BO.
//!
//! Only the importance changes. The BO cut is still made by the method's test (split inside
//! the bounding sphere or while the glossy cap integral exceeds δ) and heuristic 1's UB is still
//! the largest cap integral of the cut: the paper defines both by the cap integrals, and they
//! decide how many BRDF-aware samples a point takes, not which light one of them picks.
//!
//! The SG importance is zero exactly where the tree's conservative E&K bound is (its floor), so
//! every light that can contribute keeps a non-zero BO probability: BO alone is then a
//! complete estimator, which cap-integral I_BO is not.
use crate::sg::SgShading;
use light_tree::{LightTree, NodeId, SgNodes};
use render_core::estimator::ShadingPoint;

/// One shading point's SG importance over the light tree's SG lights.
#[derive(Clone, Copy, Debug)]
pub struct SgImportance<'a> {
    nodes: &'a SgNodes,
    shading: SgShading,
}

impl<'a> SgImportance<'a> {
    /// The SG importance at `sp` over `nodes` (fitted to the tree BO descends).
    pub fn new(nodes: &'a SgNodes, sp: &ShadingPoint) -> SgImportance<'a> {
        SgImportance {
            nodes,
            shading: SgShading::new(sp),
        }
    }

    /// The SG importance of node `id` of `tree` (a pure function of the node and the shading
    /// point, so the pick and every pdf replay see the same value).
    #[inline]
    pub fn importance(&self, tree: &LightTree, id: NodeId) -> f32 {
        self.shading.importance(tree.node(id), self.nodes.node(id))
    }
}
