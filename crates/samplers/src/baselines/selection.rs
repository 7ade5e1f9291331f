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
    /// Shading points that go through the batched engine's phases together. A point's state
    /// lives from its first phase to its last, so a selection with a large state (an E&K cut
    /// and its memo) asks for small groups, to keep the states in cache; a stateless one
    /// takes longer ray streams. (`power+bsdf` on `builtin:emissive-mesh` costs the same from
    /// 16 to 256 points; E&K 1.5–1.6 s at 4–16 against 2.4–2.7 s at 256, 128², 16 spp.)
    fn batch_group(&self) -> usize {
        64
    }
    /// A hint before a batch's picks: start loading what the pick from `rng` (left as it is)
    /// will read. Changes nothing but when memory arrives.
    fn prefetch_pick(&self, _rng: &SampleStream) {}
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
            let i = uniform_index(rng.next_u64(), self.count);
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

/// The light a uniform pick among `count` makes of 64 random bits: ⌊bits · count / 2⁶⁴⌋, a
/// widening multiply, so that every light has probability 1/count to within 2⁻⁶⁴ (from an
/// f32's 24 bits, at 10⁶ lights some were picked 4.6 % less often than claimed).
#[inline]
pub fn uniform_index(bits: u64, count: u32) -> u32 {
    ((bits as u128 * count as u128) >> 64) as u32
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
    fn prefetch_pick(&self, rng: &SampleStream) {
        if let Some(t) = &self.table {
            t.prefetch(rng.clone().next_u64());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::uniform_index;
    use chi2_test::chi2_test;
    use render_core::rng::SampleStream;

    /// At 10⁶ lights every light is picked 1/10⁶ of the time: 2²⁴ picks, a chi-square test
    /// over the lights must not reject at 0.1 %. (From an f32's 24 bits, each light got 16 or
    /// 17 of the 2²⁴ values, i.e. 4.6 % less or 1.3 % more often than claimed: p = 2·10⁻¹³.)
    #[test]
    fn uniform_picks_are_uniform_at_a_million_lights() {
        let count = 1_000_000u32;
        let samples = 1u64 << 24;
        let mut observed = vec![0.0f64; count as usize];
        for k in 0..samples {
            let bits = SampleStream::new(3, k, 0).next_u64();
            let i = uniform_index(bits, count);
            assert!(i < count);
            observed[i as usize] += 1.0;
        }
        assert_eq!(uniform_index(u64::MAX, count), count - 1);
        assert_eq!(uniform_index(0, count), 0);
        assert_eq!(uniform_index(u64::MAX, 1), 0);
        let expected = vec![samples as f64 / count as f64; count as usize];
        let r = chi2_test(&observed, &expected);
        eprintln!(
            "uniform at 10^6 lights: chi2 {} dof {} p {}",
            r.statistic, r.dof, r.p_value
        );
        assert!(
            r.p_value > 1e-3,
            "chi2 {} dof {} p {}",
            r.statistic,
            r.dof,
            r.p_value
        );
    }
}
