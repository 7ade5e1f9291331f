//! The RIS candidate source at one shading point: `n_ls` candidates from a single light-tree
//! descent (LS) and `n_bo` from BRDF-oriented sampling (BO), each a light point drawn by the
//! technique's own point sampling; and, side by side, the density of any light point under
//! every candidate slot, Σ_j p_{s(j)}(y) = n_ls·p_LS(y) + n_bo·p_BO(y).
//!
//! Cost: the tree importances of LS are memoised per shading point like BO's, so the second
//! technique's density at a candidate (a replay down the same few tree levels) costs lookups.
use crate::brdf_oriented::importance::LobeDensity;
use crate::brdf_oriented::technique::BoState;
use crate::memo::NodeMemo;
use crate::scratch::Pooled;
use brdf_integrals::LobeIntegral;
use light_tree::{LightTree, NodeId, Rescaled};
use render_core::Vec3;
use render_core::estimator::ShadingPoint;
use render_core::light::LightSample;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use std::cell::RefCell;

/// The candidates of one shading point: how many of each technique, and what drawing and
/// evaluating them needs.
pub struct CandidateSource<'a, L> {
    scene: &'a Scene,
    tree: &'a LightTree,
    x: Vec3,
    n: Vec3,
    /// The shading normal, the receiver's of the scene's light point sampler.
    ns: Vec3,
    /// The tree importances of this shading point, memoised (shared by draws and replays).
    memo: RefCell<Pooled<NodeMemo>>,
    bo: Option<&'a BoState<'a, L>>,
    /// Candidates drawn by LS.
    pub n_ls: u32,
    /// Candidates drawn by BO.
    pub n_bo: u32,
}

/// A drawn light point and the technique's selection probability of its light.
pub struct Drawn {
    /// The light's index in the scene.
    pub light: u32,
    /// The point on it.
    pub sample: LightSample,
}

impl<'a, L: LobeIntegral + LobeDensity> CandidateSource<'a, L> {
    /// `m` candidates: half (rounded down) from BO when the point has a BO state, the rest LS.
    pub fn new(
        scene: &'a Scene,
        tree: &'a LightTree,
        sp: &ShadingPoint,
        bo: Option<&'a BoState<'a, L>>,
        m: u32,
    ) -> Self {
        let n_bo = if bo.is_some() { m / 2 } else { 0 };
        CandidateSource {
            scene,
            tree,
            x: sp.point(),
            n: sp.cull_normal(),
            ns: sp.normal(),
            memo: RefCell::new(Pooled::take()),
            bo,
            n_ls: m - n_bo,
            n_bo,
        }
    }

    /// Candidates in all (M).
    pub fn count(&self) -> u32 {
        self.n_ls + self.n_bo
    }

    /// The tree importance of `id`, memoised; a miss stores its sibling's too, since the
    /// compact tree evaluates the two together and the descents ask for both.
    fn tree_importance(&self, id: NodeId) -> f32 {
        let mut memo = self.memo.borrow_mut();
        if let Some(v) = memo.get(id) {
            return v;
        }
        let (v, sibling) = self.tree.importance_and_sibling(id, self.x, self.n);
        memo.insert(id, v);
        if let Some((s, sv)) = sibling {
            memo.insert(s, sv);
        }
        v
    }

    /// LS selection probability of `light` (a single descent under the tree importance).
    pub fn ls_pmf(&self, light: u32) -> f32 {
        self.tree.pmf_subtree(
            self.tree.root(),
            |c| self.tree_importance(c),
            light as usize,
        )
    }

    /// Draws candidate slot `j` (LS for j < n_ls, BO after); `None` when the technique finds
    /// nothing (a dead end, or a point that emits nothing towards x): a candidate of weight 0.
    pub fn sample(&self, j: u32, rng: &mut SampleStream) -> Option<Drawn> {
        if j < self.n_ls {
            let u = rng.next_u64();
            let (light, _) = self.tree.sample_subtree(
                self.tree.root(),
                |c| self.tree_importance(c),
                &mut Rescaled(u),
            )?;
            let sample = self
                .scene
                .sample_light(light as u32, self.x, self.ns, rng.next_2d())?;
            Some(Drawn {
                light: light as u32,
                sample,
            })
        } else {
            let bo = self.bo?;
            let (light, _) = bo.select(self.tree, rng, true)?;
            let sample = bo.sample_point(&self.scene.lights[light], rng)?;
            Some(Drawn {
                light: light as u32,
                sample,
            })
        }
    }

    /// LS density of a light point (solid angle; the selection probability alone for a delta light).
    pub fn ls_pdf(&self, light: u32, point: Vec3, normal: Vec3, delta: bool) -> f32 {
        let p_sel = self.ls_pmf(light);
        if delta || !(p_sel > 0.0) {
            return p_sel;
        }
        p_sel * self.scene.light_pdf(light, self.x, self.ns, point, normal)
    }

    /// BO density of a light point (0 without a BO state).
    pub fn bo_pdf(&self, light: u32, point: Vec3, normal: Vec3, wi: Vec3) -> f32 {
        let Some(bo) = self.bo else { return 0.0 };
        let p_sel = bo.selection_pmf(self.tree, light as usize);
        if !(p_sel > 0.0) {
            return 0.0;
        }
        p_sel * bo.point_pdf(&self.scene.lights[light as usize], point, normal, wi)
    }

    /// Σ over the candidate slots of their source densities at a light point:
    /// n_ls·p_LS + n_bo·p_BO. The mixture density is this over [`CandidateSource::count`].
    pub fn pdf_sum(&self, light: u32, point: Vec3, normal: Vec3, wi: Vec3, delta: bool) -> f32 {
        let ls = self.ls_pdf(light, point, normal, delta);
        let bo = if self.n_bo > 0 {
            self.bo_pdf(light, point, normal, wi)
        } else {
            0.0
        };
        self.n_ls as f32 * ls + self.n_bo as f32 * bo
    }

    /// The mixture density of one candidate slot drawn at random among all slots.
    pub fn mixture_pdf(&self, light: u32, point: Vec3, normal: Vec3, wi: Vec3, delta: bool) -> f32 {
        let m = self.count();
        if m == 0 {
            return 0.0;
        }
        self.pdf_sum(light, point, normal, wi, delta) / m as f32
    }
}
