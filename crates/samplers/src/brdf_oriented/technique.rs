//! BRDF-oriented light sampling (BO) at one shading point: pick a cluster of the BO cut by
//! I_BO, descend inside it by I_BO, sample a point on the light; and the pdf of any light point.
//! Under `--bo-importance sg` the cluster choice and the descent use the SG importance instead.
use super::cut::{BoCut, BoCutScratch};
use super::importance::{BoRecord, LobeDensity};
use super::pivot_sphere::PivotSphere;
use super::sg_importance::SgImportance;
use crate::memo::NodeMemo;
use crate::scratch::Pooled;
use brdf_integrals::LobeIntegral;
use light_tree::{Fresh, LightTree, NodeId, Rescaled};
use render_core::Vec3;
use render_core::light::{Light, LightSample};
use render_core::rng::SampleStream;
use std::cell::RefCell;

/// Per-thread buffers of one shading point's BO state: the cut, its build scratch and the
/// importance memo.
#[derive(Default)]
pub struct BoScratch {
    cut: BoCut,
    build: BoCutScratch,
    memo: RefCell<NodeMemo>,
}

crate::scratch_pool!(BoScratch, |s| s.memo.get_mut().invalidate());

/// Per-shading-point BO state: the record, the BO cut with its cluster distribution, and the
/// memoised node importances shared by sampling and pdf evaluation. Its buffers are on loan
/// from a per-thread pool (no allocation per shading point). `'a`: the SG lights it weighs
/// nodes by under `--bo-importance sg`.
pub struct BoState<'a, L> {
    /// The shading point's record.
    pub rec: BoRecord<L>,
    scratch: Pooled<BoScratch>,
    /// Pivot-sphere point sampling (method.md §3.1), if enabled.
    pub pivot: Option<PivotSphere>,
    /// The SG importance that replaces I_BO in the cluster choice and the descent, if chosen.
    sg: Option<SgImportance<'a>>,
}

impl<'a, L: LobeIntegral + LobeDensity> BoState<'a, L> {
    /// Builds the BO cut of the shading point of `rec` (split while the cap integral > `delta`,
    /// at most `max_cut` clusters).
    pub fn new(
        tree: &LightTree,
        rec: BoRecord<L>,
        delta: f32,
        max_cut: usize,
        pivot: Option<PivotSphere>,
    ) -> Self {
        Self::with_importance(tree, rec, None, delta, max_cut, pivot)
    }

    /// [`BoState::new`] with the clusters and the descent weighed by the SG importance `sg`
    /// when given (`--bo-importance sg`); the cut and its cap integrals (UB) are the same.
    pub fn with_importance(
        tree: &LightTree,
        rec: BoRecord<L>,
        sg: Option<SgImportance<'a>>,
        delta: f32,
        max_cut: usize,
        pivot: Option<PivotSphere>,
    ) -> Self {
        let mut scratch = Pooled::<BoScratch>::take();
        let BoScratch { cut, build, .. } = &mut *scratch;
        cut.build_weighted_into(tree, &rec, sg.as_ref(), delta, max_cut, build);
        BoState {
            rec,
            scratch,
            pivot,
            sg,
        }
    }

    /// The BO cut: clusters (sorted DFS ids), their terms and the cluster cdf.
    #[inline]
    pub fn cut(&self) -> &BoCut {
        &self.scratch.cut
    }

    /// The descent's importance of `id` (memoised): I_BO, or the SG importance.
    pub fn importance(&self, tree: &LightTree, id: NodeId) -> f32 {
        self.scratch
            .memo
            .borrow_mut()
            .get_or(id, |id| match &self.sg {
                Some(sg) => sg.importance(tree, id),
                None => self.rec.terms(tree.node(id)).importance,
            })
    }

    /// Chooses a light: `(light, selection probability)`: a cluster by I_BO, then a descent by
    /// I_BO. `fresh`: a fresh random number per tree level (default); otherwise one fresh
    /// number after the cluster choice, rescaled down the tree (the authors' code).
    pub fn select(
        &self,
        tree: &LightTree,
        rng: &mut SampleStream,
        fresh: bool,
    ) -> Option<(usize, f32)> {
        let u = rng.next_f32();
        self.select_with(tree, u, rng, fresh)
    }

    /// [`BoState::select`] with the cluster chosen by `u_cluster` (so that a shading point's
    /// BO samples can share one stratified set of cluster choices).
    pub fn select_with(
        &self,
        tree: &LightTree,
        u_cluster: f32,
        rng: &mut SampleStream,
        fresh: bool,
    ) -> Option<(usize, f32)> {
        if fresh {
            self.select_from(tree, u_cluster, || rng.next_u64())
        } else {
            let cut = self.cut();
            let (k, p_cl, _) = cut.pick(u_cluster)?;
            let imp = |c| self.importance(tree, c);
            let (light, p) =
                tree.sample_subtree(cut.cut.nodes[k], imp, &mut Rescaled(rng.next_u64()))?;
            Some((light, p_cl * p))
        }
    }

    /// [`BoState::select_with`] with 64 fresh uniform bits per tree level from `next`, any
    /// source of random numbers: `(light, selection probability)`, the
    /// probability [`BoState::selection_pmf`] gives for that light.
    pub fn select_from(
        &self,
        tree: &LightTree,
        u_cluster: f32,
        next: impl FnMut() -> u64,
    ) -> Option<(usize, f32)> {
        let cut = self.cut();
        let (k, p_cl, _) = cut.pick(u_cluster)?;
        let imp = |c| self.importance(tree, c);
        let (light, p) = tree.sample_subtree(cut.cut.nodes[k], imp, &mut Fresh(next))?;
        Some((light, p_cl * p))
    }

    /// Probability that [`BoState::select`] returns `light`.
    pub fn selection_pmf(&self, tree: &LightTree, light: usize) -> f32 {
        let cut = self.cut();
        let Some(k) = cut.cut.cluster_of(tree, light) else {
            return 0.0;
        };
        let p_cl = cut.cluster_pmf(k);
        if !(p_cl > 0.0) {
            return 0.0;
        }
        p_cl * tree.pmf_subtree(cut.cut.nodes[k], |c| self.importance(tree, c), light)
    }

    /// Samples a point on `light` (its own shape sampling, or the pivot-sphere mixture).
    pub fn sample_point(&self, light: &Light, rng: &mut SampleStream) -> Option<LightSample> {
        match &self.pivot {
            Some(p) => p.sample(&self.rec, light, rng),
            None => light.sample(self.rec.x, rng.next_2d()),
        }
    }

    /// Solid-angle density of [`BoState::sample_point`] at `point` (1 for delta lights).
    pub fn point_pdf(&self, light: &Light, point: Vec3, normal: Vec3, wi: Vec3) -> f32 {
        if light.is_delta() {
            return 1.0;
        }
        match &self.pivot {
            Some(p) => p.pdf(&self.rec, light, point, normal, wi),
            None => light.pdf(self.rec.x, point, normal),
        }
    }
}
