//! Light selection: which light(s) a shading point samples, and with what probability.
use crate::alias::AliasTable;
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::Scene;

/// Chooses lights for a shading point. A selection may split the lights into disjoint parts
/// and pick one light in each (Conty Estevez & Kulla's splitting); single-sample selection
/// has one part. Each pick is an independent estimate of its part's contribution.
pub trait LightSelection: Send + Sync {
    /// Per-shading-point state (e.g. a light cut), computed once and shared by `pick` and `pmf`.
    type State;
    /// The state of shading point `sp`.
    fn prepare(&self, scene: &Scene, sp: &ShadingPoint) -> Self::State;
    /// Number of parts (clusters) the selection splits the lights into at this shading point;
    /// 0 for single-sample selection.
    fn clusters(&self, _state: &Self::State) -> usize {
        0
    }
    /// Appends (light, probability of choosing it within its part).
    fn pick(
        &self,
        state: &Self::State,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        picks: &mut Vec<(u32, f32)>,
    );
    /// Probability with which the pick of the part containing `light` chooses it.
    fn pmf(&self, state: &Self::State, sp: &ShadingPoint, light: u32) -> f32;
}

/// Every light equally likely.
pub struct UniformSelection {
    count: u32,
}

impl UniformSelection {
    /// Over `scene`'s lights.
    pub fn new(scene: &Scene) -> Self {
        UniformSelection {
            count: scene.lights.len() as u32,
        }
    }
}

impl LightSelection for UniformSelection {
    type State = ();
    fn prepare(&self, _: &Scene, _: &ShadingPoint) {}
    fn pick(&self, _: &(), _: &ShadingPoint, rng: &mut SampleStream, picks: &mut Vec<(u32, f32)>) {
        if self.count > 0 {
            let i = ((rng.next_f32() * self.count as f32) as u32).min(self.count - 1);
            picks.push((i, 1.0 / self.count as f32));
        }
    }
    fn pmf(&self, _: &(), _: &ShadingPoint, _: u32) -> f32 {
        if self.count > 0 {
            1.0 / self.count as f32
        } else {
            0.0
        }
    }
}

/// Lights in proportion to their emitted power, through an alias table.
pub struct PowerSelection {
    table: Option<AliasTable>,
}

impl PowerSelection {
    /// Over `scene`'s lights, ∝ their power.
    pub fn new(scene: &Scene) -> Self {
        let powers: Vec<f32> = scene.lights.iter().map(|l| l.power()).collect();
        PowerSelection {
            table: AliasTable::new(&powers),
        }
    }
}

impl LightSelection for PowerSelection {
    type State = ();
    fn prepare(&self, _: &Scene, _: &ShadingPoint) {}
    fn pick(&self, _: &(), _: &ShadingPoint, rng: &mut SampleStream, picks: &mut Vec<(u32, f32)>) {
        if let Some(t) = &self.table {
            let (i, p) = t.sample(rng.next_u64());
            picks.push((i as u32, p));
        }
    }
    fn pmf(&self, _: &(), _: &ShadingPoint, light: u32) -> f32 {
        self.table.as_ref().map_or(0.0, |t| t.pmf(light as usize))
    }
}
