//! The strategies of Liu, Xu & Yan 2019: BO alone, and three-technique MIS (tree-splitting light
//! sampling LS + BRDF-oriented light sampling BO + BRDF sampling) with equal or adaptive counts.
use super::allocation::{
    Counts, EfficiencyTally, fixed_counts, probability_bo, record_efficiency, total_brdf_aware,
};
use super::importance::{BoRecord, LobeDensity};
use super::in_sample::in_sample_allocation;
use super::ls_technique::LsTechnique;
use super::ltc_triangle::LtcTriangle;
use super::pivot_sphere::PivotSphere;
use super::pixel_memory::{HITS, MISSES};
use super::sg_importance::SgImportance;
use super::technique::BoState;
use super::three_techniques::{PointTechniques, Taken};
pub use super::three_techniques::{TECHNIQUE_BO, TECHNIQUE_BSDF, TECHNIQUE_LS};
use super::{BoConfig, LobePivot};
use crate::mis::power_heuristic;
use crate::point_sets::{lattice_1d, r3_point};
use crate::scratch::Pooled;
use crate::tree_selection::TreeSelection;
use brdf_integrals::{CapIntegral, LobeIntegral};
use light_tree::LightTree;
use render_core::Vec3;
use render_core::colour::luminance;
use render_core::estimator::{DirectLighting, PIXEL_MEMORY, SampleContext, ShadingPoint};
use render_core::pilot::Pilot;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use std::cell::RefCell;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};

/// The fewest pixels a pilot of N_max may have (a 64 × 64 image at one pixel in 16).
const MIN_PILOT_PIXELS: usize = 256;

/// Which of the method's strategies a [`Mis3`] is.
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

/// The strategies `brdf-oriented`, `mis3-equal` and `mis3-adaptive` (Liu, Xu & Yan 2019).
pub struct Mis3<C: CapIntegral, S: LsTechnique = TreeSelection> {
    /// The strategy's registered name.
    pub name: String,
    /// BO alone, equal counts, or the adaptive allocation.
    pub mode: Mis3Mode,
    /// The LS technique and the light tree both cuts are of: the tree's E&K cut or one
    /// descent, or (`mis3-adaptive-learned`) the learned cluster selection.
    pub ls: S,
    /// The cap-integral method behind BO.
    pub integral: C,
    /// The method's knobs.
    pub config: BoConfig,
    /// The tree's SG lights, under `--bo-importance sg` (see [`super::sg_importance`]).
    pub sg_nodes: Option<light_tree::SgNodes>,
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

impl<C: CapIntegral, S: LsTechnique> Mis3<C, S>
where
    C::Lobe: LobePivot + LobeDensity,
{
    fn bo_state(&self, scene: &Scene, sp: &ShadingPoint) -> Option<BoState<'_, C::Lobe>> {
        let tree = self.ls.tree()?;
        let wo_local = sp.bsdf.frame.to_local(sp.wo);
        let lobe = self.integral.lobe(wo_local, sp.bsdf.params.alpha);
        // The guided point samplers follow the reflection lobe alone: a transmitting point
        // draws its light points as every other technique does.
        let transmits = sp.bsdf.transmits();
        let pivot = if self.config.pivot_sphere && !transmits {
            lobe.pivot().map(|pivot| PivotSphere { pivot })
        } else {
            None
        };
        let rec = BoRecord::new(sp, lobe, !self.config.reproduce, self.config.reproduce)
            .with_transmission(sp, |view, alpha| self.integral.lobe(view, alpha));
        let sg = self.sg_nodes.as_ref().map(|n| SgImportance::new(n, sp));
        Some(
            BoState::with_importance(
                tree,
                rec,
                sg,
                self.config.delta,
                self.config.max_cut_bo,
                pivot,
            )
            .with_four_wide_descent(self.config.four_wide_bo_descent)
            .with_light_points(scene.light_points)
            .with_ltc_triangles(if self.config.ltc_triangles && !transmits {
                LtcTriangle::new(wo_local, sp.bsdf.params.alpha)
            } else {
                None
            }),
        )
    }
}

impl<C: CapIntegral, S: LsTechnique> Mis3<C, S> {
    /// The strategy `name` in `mode` over the light tree of `ls`.
    pub fn new(name: String, mode: Mis3Mode, ls: S, integral: C, config: BoConfig) -> Self {
        let n_max_now = AtomicU32::new((config.n_max as f32).to_bits());
        Mis3 {
            name,
            mode,
            ls,
            integral,
            config,
            sg_nodes: None,
            n_max_now,
            n_max_log: Mutex::new(NMaxLog::default()),
        }
    }

    /// Whether heuristic 1's N_max is learnt between passes (`efficient_total`; never under
    /// `reproduce`, which `create` turns it off for).
    fn learns_n_max(&self) -> bool {
        self.config.efficient_total && self.config.adaptive_total && self.mode == Mis3Mode::Adaptive
    }

    /// Heuristic 1's N_max for the next pass from the pass's efficiency tallies.
    fn learn_n_max(&self, pixel_memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
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

    fn n_max_now(&self) -> f32 {
        f32::from_bits(self.n_max_now.load(Ordering::Relaxed))
    }

    /// P(BO) of the default allocation, fixed before drawing from the hit/miss tallies of the
    /// pixel's earlier samples (heuristic 2), or 1/2 with the heuristic off.
    fn planned_p_bo(&self, ctx: &SampleContext) -> f32 {
        if self.config.adaptive_split {
            probability_bo(
                ctx.pixel_memory[HITS],
                ctx.pixel_memory[MISSES],
                self.config.lambda,
            )
        } else {
            0.5
        }
    }
}

impl<C: CapIntegral, S: LsTechnique> DirectLighting for Mis3<C, S>
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
        if let Some(d) = self.ls.describe()
            && let Some(map) = v.as_object_mut()
        {
            map.insert("learned".into(), d);
        }
        v
    }

    fn counters(&self) -> Vec<render_core::stats::StrategyCounter> {
        crate::work_counters::names()
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

    /// The allocation diagnostics as the talk shows them: the BRDF-aware count N (black → blue
    /// → green → yellow → white over 0..N_max) and the BO vs BRDF-sampling share (blue = BO,
    /// red = BRDF sampling).
    fn aux_colour(&self, channel: &str, v: f32) -> Option<Vec3> {
        match channel {
            "n_brdf_aware" => {
                let stops = [
                    Vec3::ZERO,
                    Vec3::new(0.0, 0.1, 1.0),
                    Vec3::new(0.0, 0.8, 0.1),
                    Vec3::new(1.0, 0.9, 0.0),
                    Vec3::ONE,
                ];
                let t = (v / self.config.n_max.max(1) as f32).clamp(0.0, 1.0)
                    * (stops.len() - 1) as f32;
                let i = (t as usize).min(stops.len() - 2);
                Some(stops[i].lerp(stops[i + 1], t - i as f32))
            }
            "bo_share" => {
                let s = v.clamp(0.0, 1.0);
                Some(Vec3::new(1.0 - s, 0.0, s))
            }
            _ => None,
        }
    }

    fn begin_render(&self) {
        self.ls.begin_render();
        self.n_max_now
            .store((self.config.n_max as f32).to_bits(), Ordering::Relaxed);
        let mut log = self.n_max_log.lock().unwrap_or_else(|e| e.into_inner());
        log.passes = 0;
        log.changes.clear();
        log.changes.push((1, self.config.n_max as f32));
    }

    /// Heuristic 1's N_max learnt from a pilot, so that the first passes of a short render
    /// already use it: one pixel in 4 × 4, two samples each (an eighth of a pass). Not on
    /// images below 64 × 64, where so few pixels would make a noisier choice than the one
    /// after pass 2.
    fn pilot(&self, width: usize, height: usize) -> Option<Pilot> {
        let pilot = Pilot {
            stride: 4,
            samples: 2,
        };
        let enough = pilot.pixels(width, height).len() >= MIN_PILOT_PIXELS;
        (self.learns_n_max() && self.config.pilot && enough).then_some(pilot)
    }

    fn end_pilot(&self, pixel_memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
        if !self.learns_n_max() {
            return;
        }
        if let Some(n_max) = EfficiencyTally::best_n_max(pixel_memory) {
            self.n_max_now.store(n_max.to_bits(), Ordering::Relaxed);
        }
        // What pass 1 uses replaces the log's first entry.
        let mut log = self.n_max_log.lock().unwrap_or_else(|e| e.into_inner());
        log.changes = vec![(1, self.n_max_now())];
    }

    fn end_pass(&self, pixel_memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
        // Both learners read every pixel, in pixel order.
        let pixels: Vec<&[f32; PIXEL_MEMORY]> = pixel_memory.collect();
        self.ls.end_pass(&pixels);
        self.learn_n_max(&mut pixels.iter().copied());
    }

    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        let Some(tree) = self.ls.tree() else {
            return Vec3::ZERO;
        };
        if self.mode == Mis3Mode::BoOnly {
            return self.estimate_bo_only(scene, sp, tree, rng, ctx);
        }
        let point = self.cuts(scene, sp, tree);
        let mut scratch = Pooled::<Mis3Scratch>::take();
        let Mis3Scratch {
            taken,
            picks,
            bo_terms,
        } = &mut *scratch;
        point.ls_samples(taken, picks, rng, ctx);
        let counts = self.brdf_aware_samples(&point, taken, rng, ctx);
        point.resolve_shadows(taken);
        record_counts(&point, &counts, ctx);
        let learns = self.learns_n_max();
        // Stratified BO terms are kept in stratum order for their variance (`record_efficiency`).
        let stratified_bo = learns && counts.stratified;
        if stratified_bo {
            bo_terms.resize(counts.n_bo as usize, 0.0);
        }
        let (l, moments) = mis_weighted_sum(taken, &counts, learns, stratified_bo, bo_terms);
        if learns {
            record_efficiency(&point, &counts, l, &moments, stratified_bo, bo_terms, ctx);
        }
        l
    }
}

impl<C: CapIntegral, S: LsTechnique> Mis3<C, S>
where
    C::Lobe: LobePivot + LobeDensity,
{
    /// `brdf-oriented`: one BO sample, no MIS.
    fn estimate_bo_only(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        tree: &LightTree,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        let Some(bo) = self.bo_state(scene, sp) else {
            return Vec3::ZERO;
        };
        ctx.counters.technique_samples[0] += 1;
        crate::work_counters::record(
            ctx.counters,
            !sp.bsdf.is_pure_diffuse(),
            0,
            bo.cut().cut.len(),
            1,
        );
        let Some((light, p_sel)) = bo.select(tree, rng, !self.config.reproduce) else {
            return Vec3::ZERO;
        };
        let Some(s) = bo.sample_point(&scene.lights[light], rng) else {
            return Vec3::ZERO;
        };
        let p = p_sel * s.pdf;
        if !(p > 0.0) {
            return Vec3::ZERO;
        }
        sp.shade(scene, &s, ctx.counters) / p
    }

    /// Step 1, the cuts: the BO cut at a glossy point, and the LS cut. At a glossy point BO and
    /// BRDF sampling cover the lobe and LS is the defensive technique: by default one descent
    /// from the root there, not the E&K cut's one light per cluster (`single_ls_at_glossy`).
    fn cuts<'a>(
        &'a self,
        scene: &'a Scene,
        sp: &'a ShadingPoint,
        tree: &'a LightTree,
    ) -> PointTechniques<'a, C::Lobe, S> {
        let bo = if sp.bsdf.is_pure_diffuse() {
            None
        } else {
            self.bo_state(scene, sp)
        };
        let one_descent = bo.is_some() && self.config.single_ls_at_glossy;
        let ls_state = self.ls.prepare_ls(scene, sp, one_descent);
        PointTechniques {
            scene,
            sp,
            tree,
            ls: &self.ls,
            ls_state,
            bo,
            fresh: !self.config.reproduce,
            // The authors' in-sample allocation looks at samples' values as it draws them.
            shadows: (!self.config.reproduce).then(|| RefCell::new(Pooled::take())),
        }
    }

    /// Steps 2 and 3, allocation and the BRDF-aware samples: one BRDF sample at a diffuse
    /// point, one of each under `mis3-equal`, otherwise heuristic 1's N split by heuristic 2.
    fn brdf_aware_samples(
        &self,
        point: &PointTechniques<C::Lobe, S>,
        taken: &mut Vec<Taken>,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Counts {
        let counts = |n_bo, n_brdf| Counts {
            n_bo,
            n_brdf,
            n_extra: 0,
            stratified: false,
        };
        match (&point.bo, self.mode) {
            (None, _) => {
                point.bsdf_sample(taken, rng, ctx, None);
                counts(0, 1)
            }
            (Some(_), Mis3Mode::Equal) => {
                point.bo_sample(taken, rng, ctx, 0, None);
                point.bsdf_sample(taken, rng, ctx, None);
                counts(1, 1)
            }
            (Some(b), _) => {
                let n = self.total_brdf_aware(b);
                if self.config.reproduce {
                    in_sample_allocation(
                        point,
                        n,
                        self.config.lambda,
                        self.config.adaptive_split,
                        taken,
                        rng,
                        ctx,
                    )
                } else {
                    self.fixed_allocation(point, n, taken, rng, ctx)
                }
            }
        }
    }

    /// Heuristic 1: N = floor(N_max·UB), UB optionally times the glossy lobe's weight (Ks·F;
    /// off by default until it wins at equal time), N_max learnt per pass or the constant.
    fn total_brdf_aware(&self, b: &BoState<C::Lobe>) -> u32 {
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
        total_brdf_aware(ub, n_max, self.config.adaptive_total)
    }

    /// Our default: counts fixed before drawing, from earlier samples of this pixel, then the
    /// samples, stratified by default (one random shift per technique and shading point; each
    /// sample stays uniform on its own, so the fixed-count MIS estimator stays unbiased); the
    /// BRDF samples' hits and misses go to the pixel's tallies for its next samples.
    fn fixed_allocation(
        &self,
        point: &PointTechniques<C::Lobe, S>,
        n: u32,
        taken: &mut Vec<Taken>,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Counts {
        let (n_bo, n_brdf) = fixed_counts(n, self.planned_p_bo(ctx));
        let strata = self
            .config
            .stratified
            .then(|| (rng.next_f32(), rng.next_f32(), rng.next_2d()));
        for i in 0..n_bo {
            let u = strata.map(|(shift, ..)| lattice_1d(shift, i, n_bo));
            point.bo_sample(taken, rng, ctx, i, u);
        }
        let mut hits = 0u32;
        for i in 0..n_brdf {
            let u = strata.map(|(_, lobe, dir)| r3_point(lobe, dir, i));
            hits += point.bsdf_sample(taken, rng, ctx, u) as u32;
        }
        ctx.pixel_memory[HITS] += hits as f32;
        ctx.pixel_memory[MISSES] += (n_brdf - hits) as f32;
        Counts {
            n_bo,
            n_brdf,
            n_extra: n,
            stratified: strata.is_some(),
        }
    }
}

/// The cut sizes and counts for the render's statistics, and the two diagnostic channels.
fn record_counts<L: LobeIntegral + LobeDensity, S: LsTechnique>(
    point: &PointTechniques<L, S>,
    counts: &Counts,
    ctx: &mut SampleContext,
) {
    let (ls_clusters, bo_clusters) = point.cluster_counts();
    let (n_bo, n_brdf) = (counts.n_bo, counts.n_brdf);
    crate::work_counters::record(
        ctx.counters,
        point.bo.is_some(),
        ls_clusters,
        bo_clusters,
        (n_bo + n_brdf) as usize,
    );
    ctx.aux[0] = counts.n_extra as f32;
    ctx.aux[1] = if n_bo + n_brdf > 0 {
        n_bo as f32 / (n_bo + n_brdf) as f32
    } else {
        0.0
    };
}

/// Step 4, the weights: the power heuristic with counts (n_LS = 1, n_BO, n_BRDF) over every
/// sample taken. With `learns`, also Σz and Σz² per technique of the luminance z of each
/// sample's term, and (`stratified_bo`) the BO terms in stratum order.
fn mis_weighted_sum(
    taken: &[Taken],
    counts: &Counts,
    learns: bool,
    stratified_bo: bool,
    bo_terms: &mut [f32],
) -> (Vec3, [[f32; 2]; 3]) {
    let counts = [1.0f32, counts.n_bo as f32, counts.n_brdf as f32];
    let mut l = Vec3::ZERO;
    let mut moments = [[0.0f32; 2]; 3];
    for t in taken {
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
    (l, moments)
}
