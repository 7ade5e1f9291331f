//! BRDF-oriented light sampling (BO) at one shading point: pick a cluster of the BO cut by
//! I_BO, descend inside it by I_BO, sample a point on the light; and the pdf of any light point.
use super::cut::BoCut;
use super::importance::{BoRecord, LobeDensity};
use super::pivot_sphere::PivotSphere;
use brdf_integrals::LobeIntegral;
use light_tree::{Fresh, LightTree, NodeId, Rescaled};
use render_core::Vec3;
use render_core::light::{Light, LightSample};
use render_core::rng::SampleStream;
use std::cell::RefCell;

const MEMO_SIZE: usize = 4096;

/// Direct-mapped cache of node importances of one shading point. Importance is a pure function
/// of (node, shading point), so a cached value is bit-identical to a recomputed one and the
/// sampling and the pdf replay stay consistent.
struct Memo {
    slots: Box<[(NodeId, f32); MEMO_SIZE]>,
}

impl Memo {
    fn new() -> Memo {
        Memo {
            slots: Box::new([(NodeId::MAX, 0.0); MEMO_SIZE]),
        }
    }
}

/// Per-shading-point BO state.
pub struct BoState<L> {
    pub rec: BoRecord<L>,
    pub cut: BoCut,
    memo: RefCell<Memo>,
    /// Pivot-sphere point sampling (method.md §3.1), if enabled.
    pub pivot: Option<PivotSphere>,
}

impl<L: LobeIntegral + LobeDensity> BoState<L> {
    pub fn new(
        tree: &LightTree,
        rec: BoRecord<L>,
        delta: f32,
        max_cut: usize,
        pivot: Option<PivotSphere>,
    ) -> Self {
        let cut = BoCut::build(tree, &rec, delta, max_cut);
        BoState {
            rec,
            cut,
            memo: RefCell::new(Memo::new()),
            pivot,
        }
    }

    /// I_BO of `id` (memoised).
    pub fn importance(&self, tree: &LightTree, id: NodeId) -> f32 {
        let slot = (id.wrapping_mul(0x9E37_79B1) >> 20) as usize % MEMO_SIZE;
        {
            let m = self.memo.borrow();
            if m.slots[slot].0 == id {
                return m.slots[slot].1;
            }
        }
        let v = self.rec.terms(tree.node(id)).importance;
        self.memo.borrow_mut().slots[slot] = (id, v);
        v
    }

    /// Chooses a light: `(light, selection probability)`. `fresh`: a fresh random number per
    /// tree level (default); otherwise the cluster's `u` is rescaled down the tree (authors).
    pub fn select(
        &self,
        tree: &LightTree,
        rng: &mut SampleStream,
        fresh: bool,
    ) -> Option<(usize, f32)> {
        let (k, p_cl, rest) = self.cut.pick(rng.next_f32())?;
        let start = self.cut.cut.nodes[k];
        let imp = |c| self.importance(tree, c);
        let (light, p) = if fresh {
            tree.sample_subtree(start, imp, &mut Fresh(|| rng.next_f32()))?
        } else {
            tree.sample_subtree(start, imp, &mut Rescaled(rest))?
        };
        Some((light, p_cl * p))
    }

    /// Probability that [`BoState::select`] returns `light`.
    pub fn selection_pmf(&self, tree: &LightTree, light: usize) -> f32 {
        let Some(k) = self.cut.cut.cluster_of(tree, light) else {
            return 0.0;
        };
        let p_cl = self.cut.cluster_pmf(k);
        if !(p_cl > 0.0) {
            return 0.0;
        }
        p_cl * tree.pmf_subtree(self.cut.cut.nodes[k], |c| self.importance(tree, c), light)
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
