//! The RIS strategies: per shading point, M candidates from the LS + BO mixture, each weighted
//! by the unshadowed contribution over the candidates' source densities, one kept and
//! shadow-tested; plus one BSDF sample, combined by MIS.
//!
//! **Estimator.** With target p̂(y) = luminance of the unshadowed f·L·G and Σ_j p_{s(j)}(y) the
//! sum of the M slots' source densities ([`CandidateSource::pdf_sum`]), candidate i gets
//! w_i = p̂(y_i) / Σ_j p_{s(j)}(y_i) (RIS with balance-heuristic weights across the slots), one
//! is kept with probability w_i / W, W = Σ w_i, and the estimate of ∫ g is g(y)·W / p̂(y).
//! Given the candidates its expectation is Σ_i g(y_i) / Σ_j p_{s(j)}(y_i), whose expectation
//! over the independent y_i ~ p_{s(i)} is ∫ g over the union of the sources' supports — for any
//! g that is a fixed function of y and zero where p̂ is zero.
//!
//! **MIS with BSDF sampling.** RIS has no tractable density, so it is not weighed by its own
//! density. The two techniques estimate complementary parts of the integrand instead:
//! RIS estimates ∫ w_R·f and BSDF sampling ∫ w_B·f, with w_R(y) = power heuristic of the
//! candidate *mixture* density p_mix(y) = Σ_j p_{s(j)}(y)/M against the BSDF density, and
//! w_B = 1 − w_R (the same heuristic from the other side; delta lights: w_R = 1). Both weights
//! are fixed functions of y and the shading point (M is fixed per point before drawing), so
//! g = w_R·f is a valid RIS integrand and the two estimates sum to ∫ f wherever either
//! technique can reach y: where p_mix = 0, w_R = 0 and BSDF sampling takes it all. A weight
//! that used the candidates (e.g. a density estimated from W) would make g depend on them and
//! break the argument. p_mix understates how concentrated the kept candidate is, so the split
//! leans towards BSDF sampling on sharp lobes, which is where it is strong anyway.
use super::CandidateCount;
use super::candidates::CandidateSource;
use super::resample;
use crate::brdf_oriented::LobePivot;
use crate::brdf_oriented::importance::{BoRecord, LobeDensity};
use crate::brdf_oriented::technique::BoState;
use crate::bsdf_sampling::sample_bsdf;
use crate::mis::power2;
use crate::scratch::Pooled;
use crate::shared_tree::SharedTree;
use crate::strategy::Strategy;
use brdf_integrals::CapIntegral;
use render_core::Vec3;
use render_core::colour::luminance;
use render_core::estimator::{DirectLighting, SampleContext, ShadingPoint};
use render_core::light::LightSample;
use render_core::rng::SampleStream;
use render_core::scene::Scene;

/// Index of the candidates drawn in the technique counters.
pub const TECHNIQUE_CANDIDATES: usize = 0;
/// Index of the resampled light sample.
pub const TECHNIQUE_RIS: usize = 1;
/// Index of BSDF sampling.
pub const TECHNIQUE_BSDF: usize = 2;

/// The strategies `ris`, `ris-N`, `ris-adaptive`: resampled importance sampling of light
/// candidates, combined with BSDF sampling.
pub struct Ris<C: CapIntegral> {
    /// The strategy's registered name.
    pub name: String,
    /// The light tree (None without lights).
    pub tree: Option<SharedTree>,
    /// The cap-integral method behind the BO candidates.
    pub integral: C,
    /// How many candidates.
    pub count: CandidateCount,
    /// BO cut: split threshold δ and most clusters.
    pub delta: f32,
    /// Most clusters of the BO cut.
    pub max_cut: usize,
}

struct Candidate {
    light: u32,
    sample: LightSample,
    target: f32,
}

/// The candidates of one shading point and their resampling weights, in per-thread scratch
/// (no heap allocation per shading point).
#[derive(Default)]
struct RisScratch {
    candidates: Vec<Candidate>,
    weights: Vec<f32>,
}

crate::scratch_pool!(RisScratch, |s| {
    s.candidates.clear();
    s.weights.clear();
});

impl<C: CapIntegral> Ris<C>
where
    C::Lobe: LobePivot + LobeDensity,
{
    /// The BO state of a point (none on pure diffuse points, as in `mis3`).
    pub fn bo_state(&self, scene: &Scene, sp: &ShadingPoint) -> Option<BoState<'_, C::Lobe>> {
        let tree = self.tree.as_ref()?;
        if sp.bsdf.is_pure_diffuse() {
            return None;
        }
        let lobe = self
            .integral
            .lobe(sp.bsdf.frame.to_local(sp.wo), sp.bsdf.params.alpha);
        let rec = BoRecord::new(sp, lobe, true, false)
            .with_transmission(sp, |view, alpha| self.integral.lobe(view, alpha));
        Some(
            BoState::new(tree, rec, self.delta, self.max_cut, None)
                .with_light_points(scene.light_points),
        )
    }
}

impl<C: CapIntegral> DirectLighting for Ris<C>
where
    C::Lobe: LobePivot + LobeDensity,
{
    fn name(&self) -> String {
        self.name.clone()
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::json!({
            "candidates": self.count,
            "delta": self.delta,
            "max_cut": self.max_cut,
        })
    }

    fn techniques(&self) -> Vec<&'static str> {
        vec!["candidates", "ris", "bsdf"]
    }

    fn aux_channels(&self) -> Vec<&'static str> {
        vec!["candidates"]
    }

    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        let Some(tree) = self.tree.as_ref() else {
            return Vec3::ZERO;
        };
        let bo = self.bo_state(scene, sp);
        let m = self
            .count
            .at(bo.as_ref().map_or(0.0, |b| b.cut().upper_bound()));
        let source = CandidateSource::new(scene, tree, sp, bo.as_ref(), m);
        ctx.aux[0] = m as f32;

        // Candidates and their resampling weights.
        let mut scratch = Pooled::<RisScratch>::take();
        let RisScratch {
            candidates,
            weights,
        } = &mut *scratch;
        for j in 0..m {
            ctx.counters.technique_samples[TECHNIQUE_CANDIDATES] += 1;
            let Some(d) = source.sample(j, rng) else {
                continue;
            };
            let s = d.sample;
            let target = luminance(sp.bsdf.eval_cos(sp.wo, s.wi) * s.radiance);
            if !(target > 0.0) || !target.is_finite() {
                continue;
            }
            let den = source.pdf_sum(d.light, s.point, s.normal, s.wi, s.is_delta);
            if !(den > 0.0) {
                continue;
            }
            let w = target / den;
            if w.is_finite() {
                candidates.push(Candidate {
                    light: d.light,
                    sample: s,
                    target,
                });
                weights.push(w);
            }
        }

        let mut l = Vec3::ZERO;
        // The kept candidate: one shadow ray.
        let u = rng.next_f32();
        if let Some((k, total)) = resample::pick(weights, u) {
            ctx.counters.technique_samples[TECHNIQUE_RIS] += 1;
            let c = &candidates[k];
            let s = &c.sample;
            let f = sp.shade(scene, s, ctx.counters);
            if f != Vec3::ZERO {
                let w_ris = if s.is_delta {
                    1.0
                } else {
                    let p_mix = source.mixture_pdf(c.light, s.point, s.normal, s.wi, false);
                    power2(p_mix, sp.bsdf.pdf(sp.wo, s.wi))
                };
                l += f * (w_ris * total / c.target);
            }
        }

        // BSDF sampling, weighted by the complement of the RIS weight at the point it finds.
        ctx.counters.technique_samples[TECHNIQUE_BSDF] += 1;
        if let Some(b) = sample_bsdf(scene, sp, rng, ctx.counters)
            && b.found_light()
        {
            let p_mix = source.mixture_pdf(b.light, b.point, b.normal, b.wi, false);
            l += b.f_cos * b.radiance * (power2(b.pdf, p_mix) / b.pdf);
        }
        l
    }
}

/// Candidate count of a `ris` strategy name: `ris` (8), `ris-N` (1 ≤ N ≤ 1024), `ris-adaptive`.
pub fn ris_count(name: &str) -> Option<CandidateCount> {
    match name {
        "ris" => Some(CandidateCount::Fixed(8)),
        "ris-adaptive" => Some(CandidateCount::Adaptive { min: 4, max: 32 }),
        _ => {
            let m: u32 = name.strip_prefix("ris-")?.parse().ok()?;
            (1..=1024).contains(&m).then_some(CandidateCount::Fixed(m))
        }
    }
}

fn resolve_ris(name: &str, opts: &crate::StrategyOptions) -> serde_json::Value {
    serde_json::json!({
        "candidates": ris_count(name),
        "delta": opts.delta,
        "max_cut": opts.max_cut,
        "power_units": crate::resolve::units(opts),
        // RIS builds its integral with the default options, `reproduce` or not.
        "integral": crate::resolve::integral(&crate::StrategyOptions {
            reproduce: false,
            ..opts.clone()
        }),
    })
}

/// The RIS strategies; the BO candidates use the BO cut of `mis3` with its options.
fn build_ris(
    name: &str,
    scene: &Scene,
    opts: &crate::StrategyOptions,
) -> Result<Box<dyn DirectLighting>, crate::StrategyError> {
    use crate::brdf_oriented::BrdfIntegral;
    use crate::tree_selection::{TreeMode, TreeSelection};
    let count = ris_count(name)
        .ok_or_else(|| crate::StrategyError::BadOption(format!("`{name}`: no candidate count")))?;
    let tree = TreeSelection::new(scene, TreeMode::Single, opts.power_units())
        .map_err(crate::StrategyError::Scene)?
        .tree;
    Ok(match opts.brdf_integral {
        BrdfIntegral::Sptd => Box::new(Ris {
            name: name.into(),
            tree,
            integral: brdf_integrals::Sptd::default(),
            count,
            delta: opts.delta,
            max_cut: opts.max_cut,
        }),
        BrdfIntegral::Ltc => Box::new(Ris {
            name: name.into(),
            tree,
            integral: brdf_integrals::Ltc::default(),
            count,
            delta: opts.delta,
            max_cut: opts.max_cut,
        }),
    })
}

const RIS_KNOBS: &[&str] = &["delta", "max-cut", "brdf-integral"];

/// A RIS strategy value.
const fn ris(name: &'static str, description: &'static str) -> Strategy {
    Strategy {
        knobs: RIS_KNOBS,
        ..Strategy::new(name, description, resolve_ris, build_ris)
    }
}

/// `ris`, and every `ris-N`.
pub const RIS: Strategy = Strategy {
    other_names: Some(|name| name.starts_with("ris-") && ris_count(name).is_some()),
    ..ris(
        "ris",
        "resampled importance sampling: 8 light-tree + BO candidates, one kept, + BSDF sampling, MIS (ris-N: N candidates)",
    )
};
/// `ris-4`.
pub const RIS_4: Strategy = ris("ris-4", "ris with 4 candidates");
/// `ris-32`.
pub const RIS_32: Strategy = ris("ris-32", "ris with 32 candidates");
/// `ris-adaptive`.
pub const RIS_ADAPTIVE: Strategy = Strategy {
    golden_variants: &["ltc", "pivot-independent"],
    ..ris(
        "ris-adaptive",
        "ris with 4 + round(28·UB) candidates (UB of the BO cut, the paper's heuristic 1)",
    )
};
