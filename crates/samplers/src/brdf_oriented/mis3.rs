//! The strategies of Liu, Xu & Yan 2019: BO alone, and three-technique MIS (tree-splitting light
//! sampling LS + BRDF-oriented light sampling BO + BRDF sampling) with equal or adaptive counts.
use super::allocation::{
    EfficiencyTally, InSampleCounters, SLOT_HITS, SLOT_MISSES, fixed_counts, probability_bo,
    total_brdf_aware,
};
use super::importance::{BoRecord, LobeDensity};
use super::pivot_sphere::PivotSphere;
use super::technique::BoState;
use super::{BoConfig, LobePivot};
use crate::bsdf_sampling::{sample_bsdf, sample_bsdf_at};
use crate::light_strategy::sample_pick;
use crate::mis::power_heuristic;
use crate::point_sets::{lattice_1d, lattice_sum_variance, r3_point};
use crate::scratch::Pooled;
use crate::selection::LightSelection;
use crate::tree_selection::TreeSelection;
use brdf_integrals::CapIntegral;
use render_core::colour::luminance;
use render_core::estimator::{DirectLighting, PIXEL_MEMORY, SampleContext, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::{Vec2, Vec3};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};

pub const TECHNIQUE_LS: usize = 0;
pub const TECHNIQUE_BO: usize = 1;
pub const TECHNIQUE_BSDF: usize = 2;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mis3Mode {
    /// BO alone: one BO sample. **Not a complete estimator**: the SPTD/LTC approximation (and,
    /// in `reproduce`, the glossy-only importance) can give zero importance to a light that
    /// contributes, so it is biased there; kept out of the unbiasedness tests.
    BoOnly,
    /// LS + BO + BRDF with one sample each.
    Equal,
    /// The full method: N = floor(N_max·UB) extra BRDF-aware samples split by P(BO).
    Adaptive,
}

pub struct Mis3<C: CapIntegral> {
    pub name: String,
    pub mode: Mis3Mode,
    pub ls: TreeSelection,
    pub integral: C,
    pub config: BoConfig,
    /// Heuristic 1's N_max for the next pass (f32 bits): `config.n_max`, or with
    /// `efficient_total` what [`EfficiencyTally::best_n_max`] chose after the last pass.
    pub n_max_now: AtomicU32,
    /// The N_max of each pass (`efficient_total`), for the render's JSON.
    pub n_max_log: Mutex<NMaxLog>,
}

/// Passes completed and the N_max in force from each change on: `(first pass, N_max)`, the
/// first pass counted from 1 (a render of thousands of passes logs a few entries).
#[derive(Default)]
pub struct NMaxLog {
    passes: u32,
    changes: Vec<(u32, f32)>,
}

/// Per-thread buffers of one shading point: the LS picks and the samples taken.
#[derive(Default)]
pub struct Mis3Scratch {
    taken: Vec<Taken>,
    picks: Vec<(u32, f32)>,
    /// The luminance of each BO sample's term in stratum order (zeros included).
    bo_terms: Vec<f32>,
}
crate::scratch_pool!(Mis3Scratch, |s| {
    s.taken.clear();
    s.picks.clear();
    s.bo_terms.clear();
});

/// A sample with a non-zero unweighted contribution: technique, f·L (shadowed), and the densities
/// of the three techniques at its light point.
#[derive(Clone, Copy, Debug)]
struct Taken {
    tech: usize,
    /// The sample's index among its technique's samples at this shading point.
    index: u32,
    f: Vec3,
    p: [f32; 3],
}

impl<C: CapIntegral> Mis3<C>
where
    C::Lobe: LobePivot + LobeDensity,
{
    fn bo_state(&self, sp: &ShadingPoint) -> Option<BoState<C::Lobe>> {
        let tree = self.ls.tree.as_ref()?;
        let wo_local = sp.bsdf.frame.to_local(sp.wo);
        let lobe = self.integral.lobe(wo_local, sp.bsdf.params.alpha);
        let pivot = if self.config.pivot_sphere {
            lobe.pivot().map(|pivot| PivotSphere { pivot })
        } else {
            None
        };
        let rec = BoRecord::new(sp, lobe, !self.config.reproduce, self.config.reproduce);
        Some(BoState::new(
            tree,
            rec,
            self.config.delta,
            self.config.max_cut_bo,
            pivot,
        ))
    }
}

impl<C: CapIntegral> Mis3<C> {
    pub fn new(
        name: String,
        mode: Mis3Mode,
        ls: TreeSelection,
        integral: C,
        config: BoConfig,
    ) -> Self {
        let n_max_now = AtomicU32::new((config.n_max as f32).to_bits());
        Mis3 {
            name,
            mode,
            ls,
            integral,
            config,
            n_max_now,
            n_max_log: Mutex::new(NMaxLog::default()),
        }
    }

    /// Whether heuristic 1's N_max is learnt between passes (`efficient_total`; never under
    /// `reproduce`, which `create` turns it off for).
    fn learns_n_max(&self) -> bool {
        self.config.efficient_total && self.config.adaptive_total && self.mode == Mis3Mode::Adaptive
    }

    fn n_max_now(&self) -> f32 {
        f32::from_bits(self.n_max_now.load(Ordering::Relaxed))
    }

    /// P(BO) of the default allocation, fixed before drawing from the hit/miss tallies of the
    /// pixel's earlier samples (heuristic 2), or 1/2 with the heuristic off.
    fn planned_p_bo(&self, ctx: &SampleContext) -> f32 {
        if self.config.adaptive_split {
            probability_bo(
                ctx.pixel_memory[SLOT_HITS],
                ctx.pixel_memory[SLOT_MISSES],
                self.config.lambda,
            )
        } else {
            0.5
        }
    }
}

impl<C: CapIntegral> DirectLighting for Mis3<C>
where
    C::Lobe: LobePivot + LobeDensity,
{
    fn name(&self) -> String {
        self.name.clone()
    }

    fn parameters(&self) -> serde_json::Value {
        let mut v = serde_json::to_value(&self.config).unwrap_or(serde_json::Value::Null);
        if self.config.efficient_total
            && let Some(map) = v.as_object_mut()
        {
            let log = self.n_max_log.lock().unwrap_or_else(|e| e.into_inner());
            map.insert("n_max_by_pass".into(), serde_json::json!(log.changes));
        }
        v
    }

    fn techniques(&self) -> Vec<&'static str> {
        match self.mode {
            Mis3Mode::BoOnly => vec!["bo"],
            _ => vec!["ls", "bo", "bsdf"],
        }
    }

    fn aux_channels(&self) -> Vec<&'static str> {
        match self.mode {
            Mis3Mode::BoOnly => vec![],
            _ => vec!["n_brdf_aware", "bo_share"],
        }
    }

    fn begin_render(&self) {
        self.n_max_now
            .store((self.config.n_max as f32).to_bits(), Ordering::Relaxed);
        let mut log = self.n_max_log.lock().unwrap_or_else(|e| e.into_inner());
        log.passes = 0;
        log.changes.clear();
        log.changes.push((1, self.config.n_max as f32));
    }

    fn end_pass(&self, pixel_memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
        if !self.learns_n_max() {
            return;
        }
        let mut log = self.n_max_log.lock().unwrap_or_else(|e| e.into_inner());
        log.passes += 1;
        if let Some(n_max) = EfficiencyTally::best_n_max(pixel_memory) {
            self.n_max_now.store(n_max.to_bits(), Ordering::Relaxed);
            if log.changes.last().map(|c| c.1) != Some(n_max) {
                let next = log.passes + 1;
                log.changes.push((next, n_max));
            }
        }
    }

    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        let Some(tree) = self.ls.tree.as_ref() else {
            return Vec3::ZERO;
        };
        let x = sp.point();
        let fresh = !self.config.reproduce;

        if self.mode == Mis3Mode::BoOnly {
            let Some(bo) = self.bo_state(sp) else {
                return Vec3::ZERO;
            };
            ctx.counters.technique_samples[0] += 1;
            ctx.counters
                .record_selection(!sp.bsdf.is_pure_diffuse(), 0, bo.cut().cut.len(), 1);
            let Some((light, p_sel)) = bo.select(tree, rng, fresh) else {
                return Vec3::ZERO;
            };
            let Some(s) = bo.sample_point(&scene.lights[light], rng) else {
                return Vec3::ZERO;
            };
            let p = p_sel * s.pdf;
            if !(p > 0.0) {
                return Vec3::ZERO;
            }
            return sp.shade(scene, &s, ctx.counters) / p;
        }

        let bo = if sp.bsdf.is_pure_diffuse() {
            None
        } else {
            self.bo_state(sp)
        };
        // At a glossy point BO and BRDF sampling cover the lobe and LS is the defensive
        // technique: by default one descent from the root, not the E&K cut's one light per
        // cluster (README, "one LS descent at glossy points").
        let ls_state = if bo.is_some() && self.config.single_ls_at_glossy {
            self.ls.prepare_capped(sp, 1)
        } else {
            self.ls.prepare(scene, sp)
        };

        // Densities of the three techniques at a light point (solid angle; delta lights use
        // the discrete selection probabilities and no BRDF density).
        // `own` is the sampling technique, whose density the caller already has.
        let densities =
            |light: usize, point: Vec3, normal: Vec3, wi: Vec3, delta: bool, own: usize| {
                let l = &scene.lights[light];
                let p_ls = if own == TECHNIQUE_LS {
                    0.0
                } else {
                    let p_pt = if delta { 1.0 } else { l.pdf(x, point, normal) };
                    self.ls.pmf(&ls_state, sp, light as u32) * p_pt
                };
                let p_bo = match &bo {
                    Some(b) if own != TECHNIQUE_BO || cfg!(debug_assertions) => {
                        b.selection_pmf(tree, light) * b.point_pdf(l, point, normal, wi)
                    }
                    _ => 0.0,
                };
                let p_bsdf = if delta || own == TECHNIQUE_BSDF {
                    0.0
                } else {
                    sp.bsdf.pdf(sp.wo, wi)
                };
                [p_ls, p_bo, p_bsdf]
            };
        let mut scratch = Pooled::<Mis3Scratch>::take();
        let Mis3Scratch {
            taken,
            picks,
            bo_terms,
        } = &mut *scratch;

        // LS: one light per cluster of the E&K cut (a splitting technique counts as one sample).
        self.ls.pick(&ls_state, sp, rng, picks);
        for &(light, pmf) in picks.iter() {
            ctx.counters.technique_samples[TECHNIQUE_LS] += 1;
            let Some((s, p_ls, f)) = sample_pick(scene, sp, light, pmf, rng, ctx.counters) else {
                continue;
            };
            let mut p = densities(
                light as usize,
                s.point,
                s.normal,
                s.wi,
                s.is_delta,
                TECHNIQUE_LS,
            );
            debug_assert!(
                {
                    let replay = self.ls.pmf(&ls_state, sp, light)
                        * scene.lights[light as usize].pdf(x, s.point, s.normal);
                    s.is_delta || (replay - p_ls).abs() <= 1e-3 * p_ls
                },
                "LS pdf at sampling vs replay"
            );
            p[TECHNIQUE_LS] = p_ls;
            taken.push(Taken {
                tech: TECHNIQUE_LS,
                index: 0,
                f,
                p,
            });
        }

        // One BO sample.
        // `u_cluster`: the cluster choice's number when the caller stratifies them.
        let bo_sample = |taken: &mut Vec<Taken>,
                         rng: &mut SampleStream,
                         ctx: &mut SampleContext,
                         index: u32,
                         u_cluster: Option<f32>| {
            let Some(b) = bo.as_ref() else { return };
            ctx.counters.technique_samples[TECHNIQUE_BO] += 1;
            let picked = match u_cluster {
                Some(u) => b.select_with(tree, u, rng, fresh),
                None => b.select(tree, rng, fresh),
            };
            let Some((light, p_sel)) = picked else {
                return;
            };
            let Some(s) = b.sample_point(&scene.lights[light], rng) else {
                return;
            };
            let p_bo = p_sel * s.pdf;
            if !(p_bo > 0.0) {
                return;
            }
            let f = sp.shade(scene, &s, ctx.counters);
            if f == Vec3::ZERO {
                return;
            }
            let mut p = densities(light, s.point, s.normal, s.wi, s.is_delta, TECHNIQUE_BO);
            debug_assert!(
                (p[TECHNIQUE_BO] - p_bo).abs() <= 1e-3 * p_bo,
                "BO pdf at sampling {p_bo} vs replay {}",
                p[TECHNIQUE_BO]
            );
            p[TECHNIQUE_BO] = p_bo;
            taken.push(Taken {
                tech: TECHNIQUE_BO,
                index,
                f,
                p,
            });
        };
        // One BRDF sample; returns whether it reached an emitter.
        // `u`: the lobe choice's and the direction's numbers when the caller stratifies them.
        let bsdf_sample = |taken: &mut Vec<Taken>,
                           rng: &mut SampleStream,
                           ctx: &mut SampleContext,
                           u: Option<(f32, Vec2)>| {
            ctx.counters.technique_samples[TECHNIQUE_BSDF] += 1;
            let drawn = match u {
                Some((u_lobe, u_dir)) => sample_bsdf_at(scene, sp, u_lobe, u_dir, ctx.counters),
                None => sample_bsdf(scene, sp, rng, ctx.counters),
            };
            let Some(b) = drawn else {
                return false;
            };
            if !b.found_light() {
                return false;
            }
            let mut p = densities(
                b.light as usize,
                b.point,
                b.normal,
                b.wi,
                false,
                TECHNIQUE_BSDF,
            );
            p[TECHNIQUE_BSDF] = b.pdf;
            taken.push(Taken {
                tech: TECHNIQUE_BSDF,
                index: 0,
                f: b.f_cos * b.radiance,
                p,
            });
            true
        };

        let (n_bo, n_brdf, n_extra, stratified) = match (&bo, self.mode) {
            (None, _) => {
                bsdf_sample(taken, rng, ctx, None);
                (0, 1, 0, false)
            }
            (Some(_), Mis3Mode::Equal) => {
                bo_sample(taken, rng, ctx, 0, None);
                bsdf_sample(taken, rng, ctx, None);
                (1, 1, 0, false)
            }
            (Some(b), _) => {
                // Heuristic 1's UB, optionally times the glossy lobe's weight (Ks·F), as the
                // fidelity issue asks; off by default until it wins at equal time.
                let ub = if self.config.weighted_ub {
                    b.cut().upper_bound() * b.rec.ks.min(1.0)
                } else {
                    b.cut().upper_bound()
                };
                let n_max = if self.learns_n_max() {
                    self.n_max_now()
                } else {
                    self.config.n_max as f32
                };
                let n = total_brdf_aware(ub, n_max, self.config.adaptive_total);
                if self.config.reproduce {
                    // The authors' in-sample loop (biased: the outcomes pick the counts), with
                    // their one random number rescaled at every step.
                    let mut c = InSampleCounters::new(self.config.lambda);
                    bo_sample(taken, rng, ctx, 0, None);
                    c.record(bsdf_sample(taken, rng, ctx, None));
                    let (mut n_bo, mut n_brdf) = (1, 1);
                    let mut u = rng.next_f32();
                    for _ in 0..n {
                        let p = if self.config.adaptive_split {
                            c.p_bo()
                        } else {
                            0.5
                        };
                        if u < p {
                            bo_sample(taken, rng, ctx, 0, None);
                            n_bo += 1;
                            u /= p;
                        } else {
                            c.record(bsdf_sample(taken, rng, ctx, None));
                            n_brdf += 1;
                            u = (u - p) / (1.0 - p);
                        }
                    }
                    (n_bo, n_brdf, n, false)
                } else {
                    // Counts fixed before drawing, from earlier samples of this pixel.
                    let (n_bo, n_brdf) = fixed_counts(n, self.planned_p_bo(ctx));
                    // Stratified by default: one random shift per technique and shading point
                    // (see `stratified`); each sample stays uniform on its own, so the fixed-count
                    // MIS estimator stays unbiased.
                    let strata = self
                        .config
                        .stratified
                        .then(|| (rng.next_f32(), rng.next_f32(), rng.next_2d()));
                    for i in 0..n_bo {
                        let u = strata.map(|(shift, ..)| lattice_1d(shift, i, n_bo));
                        bo_sample(taken, rng, ctx, i, u);
                    }
                    let mut hits = 0u32;
                    for i in 0..n_brdf {
                        let u = strata.map(|(_, lobe, dir)| r3_point(lobe, dir, i));
                        hits += bsdf_sample(taken, rng, ctx, u) as u32;
                    }
                    ctx.pixel_memory[SLOT_HITS] += hits as f32;
                    ctx.pixel_memory[SLOT_MISSES] += (n_brdf - hits) as f32;
                    (n_bo, n_brdf, n, strata.is_some())
                }
            }
        };
        ctx.counters.record_selection(
            bo.is_some(),
            self.ls.clusters(&ls_state),
            bo.as_ref().map_or(0, |b| b.cut().cut.len()),
            (n_bo + n_brdf) as usize,
        );
        ctx.aux[0] = n_extra as f32;
        ctx.aux[1] = if n_bo + n_brdf > 0 {
            n_bo as f32 / (n_bo + n_brdf) as f32
        } else {
            0.0
        };

        let counts = [1.0f32, n_bo as f32, n_brdf as f32];
        let mut l = Vec3::ZERO;
        let learns = self.learns_n_max();
        // Per BRDF-aware technique: Σz and Σz² of the luminance z of each sample's term.
        let mut moments = [[0.0f32; 2]; 3];
        // Stratified BO terms, in stratum order, for their variance (below).
        let stratified_bo = learns && stratified;
        if stratified_bo {
            bo_terms.resize(n_bo as usize, 0.0);
        }
        for t in taken.iter() {
            let techniques = [
                (counts[0], t.p[0]),
                (counts[1], t.p[1]),
                (counts[2], t.p[2]),
            ];
            let w = power_heuristic(t.tech, &techniques);
            debug_assert!(
                {
                    let sum: f32 = (0..3).map(|k| power_heuristic(k, &techniques)).sum();
                    (sum - 1.0).abs() < 1e-4
                },
                "MIS weights do not sum to one: {techniques:?}"
            );
            let np = counts[t.tech] * t.p[t.tech];
            if np > 0.0 && w > 0.0 {
                let term = t.f * (w / np);
                l += term;
                if learns {
                    let z = luminance(term);
                    moments[t.tech][0] += z;
                    moments[t.tech][1] += z * z;
                    if stratified_bo && t.tech == TECHNIQUE_BO {
                        bo_terms[t.index as usize] = z;
                    }
                }
            }
        }
        if learns {
            // In units of one BRDF-aware sample (a ray, a descent, the other techniques'
            // densities), the rest costs about two for the camera ray and shading, one per LS
            // cluster and a quarter per BO cluster (measured: ARCHITECTURE.md, "N_max chosen
            // by variance × cost").
            let ls_clusters = self.ls.clusters(&ls_state) as f32;
            let bo_clusters = bo.as_ref().map_or(0, |b| b.cut().cut.len()) as f32;
            let rest_cost = 2.0 + ls_clusters + 0.25 * bo_clusters;
            let glossy = bo.as_ref().map(|b| {
                // The variance the BRDF-aware samples added: n_t times the spread of one term
                // of technique t (its samples without contribution count as zeros). Stratified
                // BO samples: collapsed strata (`lattice_sum_variance`), as the spread over all
                // strata would count the differences between them; the R3 set of BRDF samples
                // has no such neighbours, and keeps the spread (an overestimate).
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
        l
    }
}
