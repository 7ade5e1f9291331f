//! The oracle selection (a measuring stick, not a production technique): at each shading point,
//! every light's unshadowed contribution f·L·G is estimated, O(N) per point, and one light is
//! chosen in proportion to it. Point lights are evaluated exactly; area and sphere lights at the
//! midpoints of a fixed k×k grid of strata of their own point sampling, so the weights are a
//! deterministic function of the shading point (sampling and `pmf` agree bit for bit); a sphere
//! light that looks small from the point gets one point instead of k².
//!
//! **Defensive mix.** The stratified estimate can be zero for a light that does contribute: a
//! triangle straddling the horizon whose k² points all fall below it, a light whose points all
//! face away while the rest of it does not, a textured emitter dark at the midpoints, a sphere
//! light the point is inside of. Choosing ∝ the estimate alone would then never sample such a
//! light and the image would be biased. So the selection is the mixture
//! (1 − ε)·c_i/Σc + ε·Φ_i/ΣΦ with power sampling, ε = [`DEFENSIVE`]: every light that emits
//! (Φ_i > 0) has a non-zero probability, while the lights that matter lose at most a factor
//! 1 − ε of theirs (variance at most 1/(1 − ε) ≈ 1.05× the pure oracle's on them).
use crate::selection::LightSelection;
use crate::strategy::Strategy;
use render_core::colour::luminance;
use render_core::estimator::ShadingPoint;
use render_core::light::Light;
use render_core::rng::SampleStream;
use render_core::scene::Scene;

/// Fraction of power sampling mixed into the oracle's distribution.
pub const DEFENSIVE: f64 = 0.05;
/// Strata per side of an area light's stratified estimate (k×k points).
pub const STRATA_PER_SIDE: u32 = 2;

/// The oracle light selection: each light ∝ its estimated contribution at the shading point,
/// unshadowed or (the `shadowed` variant) with the visibility of each stratum midpoint, mixed with
/// a defensive power fraction ([`DEFENSIVE`]).
pub struct OracleSelection {
    /// Φ_i / ΣΦ, or `None` when no light emits.
    power_pmf: Option<Vec<f64>>,
    /// Trace a shadow ray to each stratum midpoint and drop the occluded ones (issue 25's bound:
    /// what a selection that knew visibility exactly would reach).
    shadowed: bool,
}

/// The oracle's distribution at one shading point: `cdf[i]` = Σ_{j ≤ i} weight_j (f64, so that a
/// light with a tiny weight keeps a non-zero interval next to bright ones).
pub struct OracleState {
    cdf: Vec<f64>,
}

impl OracleState {
    fn total(&self) -> f64 {
        self.cdf.last().copied().unwrap_or(0.0)
    }
}

impl OracleSelection {
    /// The unshadowed oracle over `scene`'s lights.
    pub fn new(scene: &Scene) -> OracleSelection {
        let power: Vec<f64> = scene.lights.iter().map(|l| l.power() as f64).collect();
        let total: f64 = power.iter().sum();
        OracleSelection {
            power_pmf: (total > 0.0).then(|| power.iter().map(|p| p / total).collect()),
            shadowed: false,
        }
    }

    /// The shadowed oracle: one shadow ray per stratum midpoint of every light at every shading
    /// point (O(lights · k²) rays per point, uncounted in the render's ray totals).
    pub fn shadowed(scene: &Scene) -> OracleSelection {
        OracleSelection {
            shadowed: true,
            ..OracleSelection::new(scene)
        }
    }
}

/// Luminance of the unshadowed f·L·G of `light` at `sp`, integrated over the light's solid
/// angle: exact for point lights, the k×k stratum midpoints of the light's own sampling otherwise.
pub fn unshadowed_contribution(light: &Light, sp: &ShadingPoint) -> f64 {
    contribution(light, sp, None)
}

/// [`unshadowed_contribution`] with each stratum midpoint's term kept only where a shadow ray
/// from `sp` reaches it in `scene`.
pub fn shadowed_contribution(light: &Light, sp: &ShadingPoint, scene: &Scene) -> f64 {
    contribution(light, sp, Some(scene))
}

fn contribution(light: &Light, sp: &ShadingPoint, occluders: Option<&Scene>) -> f64 {
    let x = sp.point();
    let lum = |s: &render_core::light::LightSample| {
        let f = sp.bsdf.eval_cos(sp.wo, s.wi) * s.radiance;
        let blocked = |scene: &Scene| {
            let o = sp.origin_towards(s.wi);
            scene.occluded(o, s.wi, (s.point - o).length())
        };
        if f == render_core::Vec3::ZERO || occluders.is_some_and(blocked) {
            0.0
        } else {
            luminance(f) as f64
        }
    };
    if light.is_delta() {
        return light
            .sample(x, render_core::Vec2::splat(0.5))
            .map_or(0.0, |s| lum(&s));
    }
    let k = strata_per_side(light, x);
    let mut sum = 0.0f64;
    for i in 0..k {
        for j in 0..k {
            let u =
                render_core::Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
            if let Some(s) = light.sample(x, u)
                && s.pdf > 0.0
            {
                sum += lum(&s) / s.pdf as f64;
            }
        }
    }
    let v = sum / (k * k) as f64;
    if v.is_finite() { v.max(0.0) } else { 0.0 }
}

impl OracleSelection {
    /// Probability that `pick` chooses `light`: its interval of the cdf over the total.
    pub fn pmf_of(&self, state: &OracleState, light: u32) -> f32 {
        let total = state.total();
        let i = light as usize;
        if !(total > 0.0) || i >= state.cdf.len() {
            return 0.0;
        }
        let lo = if i > 0 { state.cdf[i - 1] } else { 0.0 };
        ((state.cdf[i] - lo) / total) as f32
    }
}

/// k×k strata for triangles and for sphere lights that look large from `x`; one point (the
/// middle of the cone) for a sphere light whose radius is under 5 % of its distance, where the
/// 2×2 points would see nearly the same direction (a quarter of the cost on scenes of thousands
/// of small bulbs). A function of the light and `x` only, so still deterministic per point.
fn strata_per_side(light: &Light, x: render_core::Vec3) -> u32 {
    match light.shape {
        render_core::light::LightShape::Sphere { center, radius }
            if radius < 0.05 * (center - x).length() =>
        {
            1
        }
        _ => STRATA_PER_SIDE,
    }
}

impl LightSelection for OracleSelection {
    type State = OracleState;

    fn prepare(&self, scene: &Scene, sp: &ShadingPoint) -> OracleState {
        let Some(power) = &self.power_pmf else {
            return OracleState { cdf: Vec::new() };
        };
        let c: Vec<f64> = scene
            .lights
            .iter()
            .map(|l| contribution(l, sp, self.shadowed.then_some(scene)))
            .collect();
        let sum_c: f64 = c.iter().sum();
        // Without any estimated contribution, power sampling alone (still complete).
        let a = if sum_c > 0.0 { 1.0 - DEFENSIVE } else { 0.0 };
        let mut acc = 0.0f64;
        let cdf = c
            .iter()
            .zip(power)
            .map(|(&ci, &pi)| {
                let contribution = if sum_c > 0.0 { ci / sum_c } else { 0.0 };
                acc += a * contribution + (1.0 - a) * pi;
                acc
            })
            .collect();
        OracleState { cdf }
    }

    fn pick(
        &self,
        state: &OracleState,
        _: &ShadingPoint,
        rng: &mut SampleStream,
        picks: &mut Vec<(u32, f32)>,
    ) {
        let total = state.total();
        if !(total > 0.0) {
            return;
        }
        // 48 random bits: with 24, a light whose interval is below 2⁻²⁴ of the total could be
        // unreachable although its pmf is not zero.
        let u = rng.next_f32() as f64 + rng.next_f32() as f64 / 16_777_216.0;
        let target = u * total;
        let mut k = state.cdf.partition_point(|&c| c <= target);
        k = k.min(state.cdf.len() - 1);
        // Never land on a zero-width interval (u·total rounding up to a flat tail).
        while k > 0 && state.cdf[k] <= state.cdf[k - 1] {
            k -= 1;
        }
        let p = self.pmf_of(state, k as u32);
        if p > 0.0 {
            picks.push((k as u32, p));
        }
    }

    fn pmf(&self, state: &OracleState, _: &ShadingPoint, light: u32) -> f32 {
        self.pmf_of(state, light)
    }
}

fn resolve_oracle(name: &str, _: &crate::StrategyOptions) -> serde_json::Value {
    let mut p = serde_json::json!({
        "defensive_power_fraction": DEFENSIVE,
        "strata_per_side": STRATA_PER_SIDE,
    });
    // Only the new variant names it, so that the oracle's parameters stay as they were.
    if name == ORACLE_SHADOWED.name {
        p["shadowed"] = serde_json::json!(true);
    }
    p
}

fn build_oracle(
    name: &str,
    scene: &Scene,
    opts: &crate::StrategyOptions,
) -> Result<Box<dyn render_core::estimator::DirectLighting>, crate::StrategyError> {
    Ok(Box::new(crate::light_strategy::LightStrategy {
        name: name.into(),
        selection: if name == ORACLE_SHADOWED.name {
            OracleSelection::shadowed(scene)
        } else {
            OracleSelection::new(scene)
        },
        with_bsdf: true,
        parameters: resolve_oracle(name, opts),
    }))
}

/// `oracle`.
pub const ORACLE: Strategy = Strategy::new(
    "oracle",
    "every light's unshadowed contribution per point, one light chosen ∝ it (+5 % power), + BSDF sampling, MIS: a floor, O(lights) per point",
    resolve_oracle,
    build_oracle,
);

/// `oracle-shadowed`.
pub const ORACLE_SHADOWED: Strategy = Strategy::new(
    "oracle-shadowed",
    "oracle with a shadow ray to each of its points per light: a visibility-exact floor (issue 25's bound), O(lights) rays per point",
    resolve_oracle,
    build_oracle,
);
