//! Adaptive sample allocation between BRDF-oriented light sampling and BRDF sampling
//! (method.md §1.7).
//!
//! * Heuristic 1: N = floor(N_max · UB) BRDF-aware samples beyond one forced sample of each,
//!   UB = clamp(max over the BO cut of the cached glossy cap integrals, 0, 1).
//! * Heuristic 2: P(BO) = n_nohit / (n_nohit + λ·n_hit), with the authors' counters (both start
//!   at 1; a BRDF sample that reaches an emitter adds λ to the hit counter, any other adds 1 to
//!   the miss counter), i.e. P = (1 + misses) / (2 + misses + λ·hits).
//!
//! Unbiased default: the counts that weight a shading point's samples are fixed before any of
//! them is drawn. The hit/miss tallies come from the BRDF samples of *earlier* samples of the
//! same pixel (kept in `SampleContext::pixel_memory`, which the renderer carries in sample order,
//! deterministically for any thread count); with fixed counts the multi-sample MIS estimator
//! is unbiased. `reproduce` instead runs the authors' in-sample loop, where the outcome of each
//! BRDF sample changes the probability of the next choice and the final counts weight all
//! samples (slightly biased).

use render_core::estimator::PIXEL_MEMORY;

use super::importance::LobeDensity;
use super::ls_technique::LsTechnique;
use super::pixel_memory::{GLOSSY, REST, SAMPLES, SUM, SUM_SQ, UB, UNIT, WITHIN};
use super::three_techniques::{PointTechniques, TECHNIQUE_BO, TECHNIQUE_BSDF};
use crate::point_sets::lattice_sum_variance;
use brdf_integrals::LobeIntegral;
use render_core::Vec3;
use render_core::colour::luminance;
use render_core::estimator::SampleContext;

/// The N_max values [`EfficiencyTally::best_n_max`] chooses from (about √2 apart).
pub const N_MAX_CANDIDATES: [f32; 16] = [
    0.0, 1.0, 2.0, 3.0, 5.0, 7.0, 10.0, 14.0, 20.0, 28.0, 40.0, 56.0, 80.0, 113.0, 160.0, 226.0,
];

/// What a render's samples so far say about the worth of BRDF-aware samples, for choosing
/// heuristic 1's N_max by variance × cost (`--efficient-n`). Each pixel keeps, in its pixel
/// memory (sample order, so deterministic for any thread count):
///
/// * the luminance y of each sample's estimate (its variance across the pixel's samples);
/// * at glossy points, W, the variance the K BRDF-aware samples added (from the spread of
///   their own terms), W·K, and UB;
/// * the cost of the rest of the sample in units of one BRDF-aware sample.
///
/// The model: a pixel's variance is V_rest + S/K (V_rest: LS, the camera sample, diffuse
/// points; S/K: the BRDF-aware part) with K = 2 + N_max·UB, and a pass costs
/// Σ (c_rest + K). After each pass [`EfficiencyTally::best_n_max`] picks the N_max that
/// minimises (Σ relMSE weight × variance) × (Σ cost): the error reached in a given time.
pub struct EfficiencyTally;

impl EfficiencyTally {
    /// Records one sample: `y` the luminance of its estimate, `rest_cost` the cost of all but
    /// its BRDF-aware samples, and at a glossy point `(W, K, UB)`.
    pub fn record(memory: &mut [f32], y: f32, rest_cost: f32, glossy: Option<(f32, u32, f32)>) {
        if !y.is_finite() {
            return;
        }
        let (within, k, ub) = glossy.unwrap_or((0.0, 0, 0.0));
        if !within.is_finite() {
            return;
        }
        memory[SAMPLES] += 1.0;
        memory[SUM] += y;
        memory[SUM_SQ] += y * y;
        memory[REST] += rest_cost;
        if glossy.is_some() {
            memory[WITHIN] += within;
            memory[UNIT] += within * k as f32;
            memory[UB] += ub;
            memory[GLOSSY] += 1.0;
        }
    }

    /// The candidate N_max with the least predicted error × cost, from every pixel with two
    /// samples or more; `None` before any has.
    pub fn best_n_max<'a>(memories: impl Iterator<Item = &'a [f32; PIXEL_MEMORY]>) -> Option<f32> {
        // Per pixel i: weight w (relMSE's 1/(mean² + 0.01)), V_rest, S, UB and glossy share.
        let (mut rest_var, mut total_var, mut pixels) = (0.0f64, 0.0f64, 0usize);
        let mut error_at = [0.0f64; N_MAX_CANDIDATES.len()];
        let mut cost_at = [0.0f64; N_MAX_CANDIDATES.len()];
        for m in memories {
            let n = m[SAMPLES] as f64;
            if n < 2.0 {
                continue;
            }
            pixels += 1;
            let mean = m[SUM] as f64 / n;
            let total = ((m[SUM_SQ] as f64 - n * mean * mean) / (n - 1.0)).max(0.0);
            let w = 1.0 / (mean * mean + 0.01);
            rest_var += w * (total - m[WITHIN] as f64 / n);
            total_var += w * total;
            let glossy = m[GLOSSY] as f64 / n;
            let unit = m[UNIT] as f64 / n;
            let ub = if m[GLOSSY] > 0.0 {
                (m[UB] / m[GLOSSY]) as f64
            } else {
                0.0
            };
            let rest_cost = m[REST] as f64 / n;
            for (j, &n_max) in N_MAX_CANDIDATES.iter().enumerate() {
                let k = 2.0 + (n_max as f64) * ub;
                error_at[j] += w * unit / k;
                // A diffuse point takes one BRDF sample, a glossy one K.
                cost_at[j] += rest_cost + (1.0 - glossy) + glossy * k;
            }
        }
        if pixels == 0 {
            return None;
        }
        // A few samples can put the total below the BRDF-aware part alone.
        let rest_var = rest_var.max(0.1 * total_var);
        let score = |j: usize| (rest_var + error_at[j]) * cost_at[j];
        (0..N_MAX_CANDIDATES.len())
            .min_by(|&a, &b| score(a).total_cmp(&score(b)))
            .map(|j| N_MAX_CANDIDATES[j])
    }
}

/// Heuristic 1: BRDF-aware samples beyond the forced two. With `adaptive` off, N_max/2.
pub fn total_brdf_aware(upper_bound: f32, n_max: f32, adaptive: bool) -> u32 {
    if adaptive {
        (n_max * upper_bound.clamp(0.0, 1.0)).floor() as u32
    } else {
        (n_max as u32) / 2
    }
}

/// Heuristic 2 from tallies of BRDF samples that hit / missed an emitter.
pub fn probability_bo(hits: f32, misses: f32, lambda: f32) -> f32 {
    let f = 1.0 + misses.max(0.0);
    let s = 1.0 + lambda * hits.max(0.0);
    f / (f + s)
}

/// Fixed counts (n_BO, n_BRDF) for N extra samples split with probability `p_bo`.
pub fn fixed_counts(n: u32, p_bo: f32) -> (u32, u32) {
    let k = ((n as f32) * p_bo.clamp(0.0, 1.0)).round() as u32;
    let k = k.min(n);
    (1 + k, 1 + n - k)
}

/// How many samples each BRDF-aware technique took at a shading point.
pub struct Counts {
    /// BO samples.
    pub n_bo: u32,
    /// BRDF samples.
    pub n_brdf: u32,
    /// Heuristic 1's N, the samples beyond the forced ones (the `n_brdf_aware` channel).
    pub n_extra: u32,
    /// Whether the samples were stratified sets (`point_sets`).
    pub stratified: bool,
}

/// Step 5, learning N_max: the sample's luminance, the rest of its cost and, at a glossy
/// point, the variance its BRDF-aware samples added, into the pixel's efficiency tally.
pub fn record_efficiency<L: LobeIntegral + LobeDensity, S: LsTechnique>(
    point: &PointTechniques<L, S>,
    counts: &Counts,
    l: Vec3,
    moments: &[[f32; 2]; 3],
    stratified_bo: bool,
    bo_terms: &[f32],
    ctx: &mut SampleContext,
) {
    let (n_bo, n_brdf) = (counts.n_bo, counts.n_brdf);
    // In units of one BRDF-aware sample (a ray, a descent, the other techniques' densities),
    // the rest costs about two for the camera ray and shading, one per LS cluster and a
    // quarter per BO cluster (measured: docs/notes/defaults.md).
    let (ls_clusters, bo_clusters) = point.cluster_counts();
    let rest_cost = 2.0 + ls_clusters as f32 + 0.25 * bo_clusters as f32;
    let glossy = point.bo.as_ref().map(|b| {
        // The variance the BRDF-aware samples added: n_t times the spread of one term of
        // technique t (its samples without contribution count as zeros). Stratified BO
        // samples: collapsed strata (`lattice_sum_variance`), as the spread over all strata
        // would count the differences between them; the R3 set of BRDF samples has no such
        // neighbours, and keeps the spread (an overestimate).
        let mut within = 0.0;
        if stratified_bo {
            within += lattice_sum_variance(bo_terms);
        }
        for (t, n_t) in [(TECHNIQUE_BO, n_bo), (TECHNIQUE_BSDF, n_brdf)] {
            if t == TECHNIQUE_BO && stratified_bo {
                continue;
            }
            let [sum, sum_sq] = moments[t];
            let var = if n_t >= 2 {
                ((sum_sq - sum * sum / n_t as f32) / (n_t - 1) as f32).max(0.0)
            } else {
                sum_sq
            };
            within += n_t as f32 * var;
        }
        (within, n_bo + n_brdf, b.cut().upper_bound())
    });
    EfficiencyTally::record(&mut ctx.pixel_memory[..], luminance(l), rest_cost, glossy);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heuristics() {
        assert_eq!(total_brdf_aware(0.999, 50.0, true), 49);
        assert_eq!(total_brdf_aware(2.0, 50.0, true), 50);
        assert_eq!(total_brdf_aware(0.0, 50.0, true), 0);
        assert_eq!(total_brdf_aware(0.0, 50.0, false), 25);
        assert_eq!(probability_bo(0.0, 0.0, 10.0), 0.5);
        assert!((probability_bo(1.0, 3.0, 10.0) - 4.0 / 15.0).abs() < 1e-6);
        assert_eq!(fixed_counts(10, 0.26), (4, 8));
        assert_eq!(fixed_counts(0, 0.9), (1, 1));
    }

    #[test]
    fn best_n_max_follows_the_variance_split() {
        let mut pixels = vec![[0.0f32; PIXEL_MEMORY]; 4];
        assert_eq!(EfficiencyTally::best_n_max(pixels.iter()), None);
        // Samples y = 1 and 3 (variance 2), with UB 1 and a rest costing 10 BRDF-aware samples.
        let tally = |within: f32, k: u32| {
            let mut m = [0.0f32; PIXEL_MEMORY];
            EfficiencyTally::record(&mut m, 1.0, 10.0, Some((within, k, 1.0)));
            EfficiencyTally::record(&mut m, 3.0, 10.0, Some((within, k, 1.0)));
            m
        };
        // All the variance from 12 BRDF-aware samples: more of them pay (V_rest floored at
        // a tenth: K* = sqrt(10 · 24 / 0.2) ≈ 35, N_max ≈ 33).
        pixels.fill(tally(2.0, 12));
        assert_eq!(EfficiencyTally::best_n_max(pixels.iter()), Some(28.0));
        // None of it: the forced two are enough.
        pixels.fill(tally(0.0, 12));
        assert_eq!(EfficiencyTally::best_n_max(pixels.iter()), Some(0.0));
        // Half of it from 12 samples: K* = sqrt(10 · 12 / 1) ≈ 11, N_max ≈ 9.
        pixels.fill(tally(1.0, 12));
        assert_eq!(EfficiencyTally::best_n_max(pixels.iter()), Some(10.0));
        // Non-finite values are not recorded.
        let mut m = [0.0f32; PIXEL_MEMORY];
        EfficiencyTally::record(&mut m, f32::NAN, 1.0, None);
        EfficiencyTally::record(&mut m, 1.0, 1.0, Some((f32::INFINITY, 2, 1.0)));
        assert_eq!(m[SAMPLES], 0.0);
    }
}
