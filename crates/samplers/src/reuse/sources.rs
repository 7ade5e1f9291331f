//! Where a pixel's first reservoir comes from: a light selection's candidates (`restir`), or
//! the paper's techniques (`restir-bo`: light-tree and BRDF-oriented candidates at glossy
//! points, the mixture of `ris`).
use super::initial::{Candidates, SelectionCandidates, initial_reservoir};
use super::light_point::{LightPoint, Seen};
use super::reservoir::Reservoir;
use crate::baselines::selection::LightSelection;
use crate::brdf_oriented::LobePivot;
use crate::brdf_oriented::importance::LobeDensity;
use crate::ris::candidates::CandidateSource;
use crate::ris::strategy::Ris;
use brdf_integrals::{CapIntegral, LobeIntegral};
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::stats::Counters;
use std::cell::RefCell;

/// Draws a pixel's first reservoir from `m` light candidates and one BSDF candidate.
pub trait InitialSource: Send + Sync {
    /// The reservoir of shading point `sp`.
    fn initial(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        m: u32,
        rng: &mut SampleStream,
        c: &mut Counters,
    ) -> Reservoir;
}

/// Candidates from a light selection (power, one tree descent).
pub struct FromSelection<S>(pub S);

impl<S: LightSelection> InitialSource for FromSelection<S> {
    fn initial(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        m: u32,
        rng: &mut SampleStream,
        c: &mut Counters,
    ) -> Reservoir {
        let source = SelectionCandidates {
            scene,
            sp,
            selection: &self.0,
            state: self.0.prepare(scene, sp),
            m,
            picks: RefCell::new(Vec::with_capacity(1)),
        };
        initial_reservoir(scene, sp, &source, true, rng, c)
    }
}

/// The paper's techniques as candidates: at glossy points half from BRDF-oriented sampling
/// (the BO cut of `mis3`), half from one light-tree descent; all from the descent elsewhere.
/// `Ris` holds the tree, the cap integral and the BO cut's parameters.
pub struct FromBo<C: CapIntegral>(pub Ris<C>);

impl<C: CapIntegral> InitialSource for FromBo<C>
where
    C::Lobe: LobePivot + LobeDensity,
{
    fn initial(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        m: u32,
        rng: &mut SampleStream,
        c: &mut Counters,
    ) -> Reservoir {
        let Some(tree) = self.0.tree.as_ref() else {
            return Reservoir::default();
        };
        let bo = self.0.bo_state(scene, sp);
        let source = CandidateSource::new(scene, tree, sp, bo.as_ref(), m);
        initial_reservoir(scene, sp, &source, true, rng, c)
    }
}

impl<L: LobeIntegral + LobeDensity> Candidates for CandidateSource<'_, L> {
    fn count(&self) -> u32 {
        CandidateSource::count(self)
    }

    fn draw(&self, j: u32, rng: &mut SampleStream) -> Option<LightPoint> {
        let d = self.sample(j, rng)?;
        Some(LightPoint {
            light: d.light,
            point: d.sample.point,
            normal: d.sample.normal,
        })
    }

    fn density_sum(&self, y: &LightPoint, seen: &Seen) -> f32 {
        self.pdf_sum(y.light, y.point, y.normal, seen.wi, seen.is_delta)
    }
}
