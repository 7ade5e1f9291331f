//! BRDF-oriented light sampling (BO) at one shading point: pick a cluster of the BO cut by
//! I_BO, descend inside it by I_BO, sample a point on the light; and the pdf of any light point.
//! Under `--bo-importance sg` the cluster choice and the descent use the SG importance instead.
use super::cut::{BoCut, BoCutScratch};
use super::importance::{BoRecord, LobeDensity};
use super::ltc_triangle::LtcTriangle;
use super::pivot_sphere::PivotSphere;
use super::sg_importance::SgImportance;
use crate::memo::{NodeMemo, QuadMemo};
use crate::scratch::Pooled;
use brdf_integrals::LobeIntegral;
use light_tree::{DescentRandom, Fresh, LightTree, NO_NODE, NodeId, Rescaled};
use render_core::Vec3;
use render_core::light::{Light, LightSample, LightShape};
use render_core::light_points::LightPoints;
use render_core::rng::SampleStream;
use std::cell::RefCell;

/// 64 fresh random bits for every second decision, rescaled ([`Rescaled`]) for the one
/// between: the four-wide descent's two decisions per step take one fresh number. After a
/// decision the rescaled number is uniform again given that decision, so any sequence of
/// decisions stays exact. A decision of probability p uses log₂(1/p) of the 64 bits, so the
/// second one keeps at least 24 (what an f32 pmf resolves) unless the first had p < 2⁻⁴⁰.
struct FreshPerStep<F: FnMut() -> u64> {
    next: F,
    u: Rescaled,
    left: u8,
}

impl<F: FnMut() -> u64> FreshPerStep<F> {
    fn new(next: F) -> Self {
        FreshPerStep {
            next,
            u: Rescaled(0),
            left: 0,
        }
    }
}

impl<F: FnMut() -> u64> DescentRandom for FreshPerStep<F> {
    #[inline]
    fn go_left(&mut self, p_left: f32) -> bool {
        if self.left == 0 {
            self.u = Rescaled((self.next)());
            self.left = 2;
        }
        self.left -= 1;
        self.u.go_left(p_left)
    }
    // The BO descent steps by binary decisions only (the quads'); a many-way choice takes a
    // fresh number of its own.
    #[inline]
    fn draw(&mut self) -> u64 {
        (self.next)()
    }
    #[inline]
    fn chose(&mut self, _: u64, _: u64) {}
}

/// Per-thread buffers of one shading point's BO state: the cut, its build scratch and the
/// importance memos (per node for the binary descent and the pair steps, per quad for the
/// four-wide descent).
#[derive(Default)]
pub struct BoScratch {
    cut: BoCut,
    build: BoCutScratch,
    memo: RefCell<NodeMemo>,
    quads: RefCell<QuadMemo>,
}

crate::scratch_pool!(BoScratch, |s| {
    s.memo.get_mut().invalidate();
    s.quads.get_mut().invalidate();
});

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
    /// How points on triangle lights are drawn (pivot-sphere sampling aside).
    points: LightPoints,
    /// BRDF-aware points on triangle lights (mixed with `points`), if enabled.
    ltc: Option<LtcTriangle>,
    /// The descent below the cut is the tree's four-wide one (`LightTree::sample_quads`);
    /// off: the binary one (`LightTree::sample_subtree`).
    four_wide: bool,
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
            points: LightPoints::Area,
            ltc: None,
            four_wide: sg.is_none(),
            sg,
        }
    }

    /// Chooses the descent below the cut: four-wide (the default without the SG importance)
    /// or binary (the paper's, one level at a time). Sampling and every pmf replay use it.
    pub fn with_four_wide_descent(mut self, four_wide: bool) -> Self {
        self.four_wide = four_wide;
        self
    }

    /// Chooses how points on triangle lights are drawn (the scene's, for its render).
    pub fn with_light_points(mut self, points: LightPoints) -> Self {
        self.points = points;
        self
    }

    /// Chooses BRDF-aware points on triangle lights (`--ltc-triangles`), or none.
    pub fn with_ltc_triangles(mut self, ltc: Option<LtcTriangle>) -> Self {
        self.ltc = ltc;
        self
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

    /// The weights of one step of the four-wide descent: I_BO of the four nodes, in lanes
    /// where it takes its point form (`quad_importance.rs`) and by the scalar terms
    /// elsewhere (or the SG importance), memoised per quad (the pair step of an odd-depth
    /// cluster root per node).
    fn quad_lanes(&self, tree: &LightTree, quad: Option<u32>, nodes: &[NodeId; 4]) -> [f32; 4] {
        let lanes = |nodes: &[NodeId; 4]| {
            let point = match (&self.sg, quad) {
                (None, Some(q)) => self
                    .rec
                    .point_importances_view(&tree.quad_view(q, self.rec.x)),
                (None, None) => {
                    // An empty lane (always after a real one) borrows the first node.
                    let node = |id: NodeId| tree.node(if id == NO_NODE { nodes[0] } else { id });
                    self.rec.point_importances(nodes.map(node))
                }
                (Some(_), _) => [None; 4],
            };
            std::array::from_fn(|k| match (nodes[k], point[k]) {
                (NO_NODE, _) => 0.0,
                (_, Some(v)) => v,
                (id, None) => self.importance(tree, id),
            })
        };
        match quad {
            Some(q) => self.scratch.quads.borrow_mut().get_or(q, |_| lanes(nodes)),
            None => lanes(nodes),
        }
    }

    /// The descent below the cut from cluster root `start`, binary or four-wide.
    fn descend<R: DescentRandom>(
        &self,
        tree: &LightTree,
        start: NodeId,
        rng: &mut R,
    ) -> Option<(usize, f32)> {
        if self.four_wide {
            let mut lanes = |q: Option<u32>, nodes: &[NodeId; 4]| self.quad_lanes(tree, q, nodes);
            tree.sample_quads(start, &mut lanes, rng)
        } else {
            tree.sample_subtree(start, |c| self.importance(tree, c), rng)
        }
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
            let (light, p) = self.descend(tree, cut.cut.nodes[k], &mut Rescaled(rng.next_u64()))?;
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
        let start = cut.cut.nodes[k];
        let (light, p) = if self.four_wide {
            self.descend(tree, start, &mut FreshPerStep::new(next))?
        } else {
            self.descend(tree, start, &mut Fresh(next))?
        };
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
        let start = cut.cut.nodes[k];
        let p = if self.four_wide {
            let mut lanes = |q: Option<u32>, nodes: &[NodeId; 4]| self.quad_lanes(tree, q, nodes);
            tree.pmf_quads(start, &mut lanes, light)
        } else {
            tree.pmf_subtree(start, |c| self.importance(tree, c), light)
        };
        p_cl * p
    }

    /// Samples a point on `light` (its own shape sampling, or the pivot-sphere mixture).
    pub fn sample_point(&self, light: &Light, rng: &mut SampleStream) -> Option<LightSample> {
        match &self.pivot {
            Some(p) if is_sphere(light) => p.sample(&self.rec, light, rng),
            _ if self.ltc.is_some() && !is_sphere(light) => {
                let ltc = self.ltc.as_ref()?;
                ltc.sample(&self.rec, light, self.points, rng)
            }
            _ => self
                .points
                .sample(light, self.rec.x, self.rec.frame.z, rng.next_2d()),
        }
    }

    /// Solid-angle density of [`BoState::sample_point`] at `point` (1 for delta lights).
    pub fn point_pdf(&self, light: &Light, point: Vec3, normal: Vec3, wi: Vec3) -> f32 {
        if light.is_delta() {
            return 1.0;
        }
        match &self.pivot {
            Some(p) if is_sphere(light) => p.pdf(&self.rec, light, point, normal, wi),
            _ => match &self.ltc {
                Some(t) => t.pdf(&self.rec, light, self.points, point, normal),
                None => self
                    .points
                    .pdf(light, self.rec.x, self.rec.frame.z, point, normal),
            },
        }
    }
}

fn is_sphere(light: &Light) -> bool {
    matches!(light.shape, LightShape::Sphere { .. })
}
