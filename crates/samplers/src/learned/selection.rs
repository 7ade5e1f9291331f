//! The learned cluster selection at one shading point: a cluster of the fixed cut by the
//! weight w_c = prior_c · r̂_c (r̂_c the region's learnt contribution ratio or hit rate of the
//! cluster) mixed with the prior alone, then the tree's descent
//! inside the cluster. `pick` and `pmf` read the same per-point probabilities, so a light's
//! probability at sampling and at any replay is the same number.
use super::regions::{RegionGrid, RegionTable};
use super::{LearnTarget, LearnedConfig, Learner};
use crate::selection::LightSelection;
use crate::tree_selection::{PowerUnits, TreeMode, TreeSelection, TreeState};
use light_tree::{Cut, LightTree, Rescaled};
use render_core::estimator::PIXEL_MEMORY;
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use std::sync::RwLock;

/// Most clusters a fixed cut may have (the per-point probabilities live on the stack).
pub const MAX_CLUSTERS: usize = 256;

/// Learned cluster selection over a fixed cut of the light tree.
pub struct LearnedSelection {
    /// The light tree, used by single descent for its memoised node importances.
    pub tree: TreeSelection,
    /// The fixed cut (breadth-first from the root to `config.clusters` nodes), built once.
    pub cut: Cut,
    /// Shading point → region.
    pub grid: RegionGrid,
    /// Its parameters.
    pub config: LearnedConfig,
    /// What earlier passes taught, frozen during a pass.
    pub table: RwLock<RegionTable>,
}

impl LearnedSelection {
    /// The selection for `scene` (tree in `units` of power).
    pub fn new(
        scene: &Scene,
        units: PowerUnits,
        config: LearnedConfig,
    ) -> Result<LearnedSelection, String> {
        if !(1..=MAX_CLUSTERS).contains(&config.clusters) {
            return Err(format!(
                "learned selection: clusters must be in 1..={MAX_CLUSTERS}, got {}",
                config.clusters
            ));
        }
        check_config(&config)?;
        let tree = TreeSelection::new(scene, TreeMode::Single, units)?;
        // Breadth-first: clusters of about equal depth, which the SAOH build keeps compact
        // in space (a room's lights, a lamp's bulbs), the unit visibility is learnt for.
        let cut = tree
            .tree
            .as_ref()
            .map_or_else(Cut::default, |t| t.cut(config.clusters, |_| true));
        let (lo, _) = scene.bounds;
        let grid = RegionGrid::new(lo, scene.diagonal(), config.cells_per_diagonal);
        Ok(LearnedSelection {
            tree,
            table: RwLock::new(RegionTable::new(cut.len(), config.max_regions)),
            cut,
            grid,
            config,
        })
    }

    fn light_tree(&self) -> Option<&LightTree> {
        self.tree.tree.as_deref()
    }
}

/// Refuses parameters no learned selection can use (the defensive share, the prior strength,
/// the light samples per point, the cell size).
pub(crate) fn check_config(config: &LearnedConfig) -> Result<(), String> {
    if !(config.defensive > 0.0 && config.defensive <= 1.0) || !(config.prior_strength > 0.0) {
        return Err(format!(
            "learned selection: need defensive share in (0, 1] and prior strength > 0, got {} and {}",
            config.defensive, config.prior_strength
        ));
    }
    if !(1..=1024).contains(&config.light_samples) {
        return Err(format!(
            "learned selection: light samples per point must be in 1..=1024, got {}",
            config.light_samples
        ));
    }
    if !(config.cells_per_diagonal >= 1.0 && config.cells_per_diagonal <= 1e5) {
        return Err(format!(
            "learned selection: cells per scene diagonal must be in [1, 100000], got {}",
            config.cells_per_diagonal
        ));
    }
    Ok(())
}

/// One shading point: its region, the memoised importances and the cluster probabilities.
pub struct LearnedState {
    tree: TreeState,
    /// The region of the shading point.
    pub key: u64,
    /// The stamp of the pass being drawn (the passes merged into the table + 1).
    pub stamp: u32,
    /// Unnormalised probability of each cluster; `total` is their sum.
    q: [f32; MAX_CLUSTERS],
    total: f64,
    /// Each cluster's prior (unshadowed tree importance) at the point.
    prior: [f32; MAX_CLUSTERS],
}

impl LearnedState {
    /// Probability of choosing cluster `c`.
    pub fn cluster_pmf(&self, c: usize) -> f32 {
        if self.total > 0.0 {
            (self.q[c] as f64 / self.total) as f32
        } else {
            0.0
        }
    }
}

#[inline]
fn sanitize(x: f32) -> f32 {
    if x.is_finite() && x > 0.0 { x } else { 0.0 }
}

impl LearnedSelection {
    /// The selection's state at `sp` with the statistics in `table`.
    pub fn prepare_with(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        table: &RegionTable,
    ) -> LearnedState {
        let tree = self.tree.prepare(scene, sp);
        let key = self.grid.key(sp.point(), sp.bsdf.ng);
        let mut state = LearnedState {
            tree,
            key,
            stamp: table.pass + 1,
            q: [0.0; MAX_CLUSTERS],
            total: 0.0,
            prior: [0.0; MAX_CLUSTERS],
        };
        let Some(lt) = self.light_tree() else {
            return state;
        };
        let k = self.cut.len();
        let region = table.region(key);
        let a = self.config.prior_strength;
        let (mut sum_prior, mut sum_w) = (0.0f64, 0.0f64);
        let mut w = [0.0f32; MAX_CLUSTERS];
        // The cut's importances in one batch: its nodes are sorted by DFS id, so siblings sit
        // side by side and two pairs (four nodes) go through each evaluation.
        let (x, n) = state.tree.receiver();
        lt.importances(&self.cut.nodes[..k], x, n, &mut state.prior[..k]);
        let contribution = self.config.target == LearnTarget::Contribution;
        // The region's mean ratio over every cluster: what a cluster not yet observed there is
        // expected to have (1 before any ray, which leaves the prior as it is).
        let mean_ratio = match region {
            Some(r) if contribution => {
                let (sum, rays) = r.iter().fold((0.0f64, 0u64), |(s, n), t| {
                    (s + t.ratio_sum as f64, n + t.rays as u64)
                });
                if rays > 0 && sum > 0.0 {
                    (sum / rays as f64) as f32
                } else {
                    1.0
                }
            }
            _ => 1.0,
        };
        for c in 0..k {
            let prior = sanitize(state.prior[c]);
            state.prior[c] = prior;
            let v = match region {
                None => 1.0,
                // (Σ ratio + a·r̄)/(rays + a): r̄ before any ray, the mean ratio after many.
                Some(r) if contribution => {
                    (r[c].ratio_sum + a * mean_ratio) / (r[c].rays as f32 + a)
                }
                // V̂ = (hits + a)/(rays + a): 1 before any ray, the hit rate after many.
                Some(r) => (r[c].hits as f32 + a) / (r[c].rays as f32 + a),
            };
            w[c] = prior * v;
            sum_prior += prior as f64;
            sum_w += w[c] as f64;
        }
        if !(sum_prior > 0.0) {
            // No cluster reachable: every q stays 0 and `total` 0.
            return state;
        }
        let alpha = self.config.defensive as f64;
        let mut total = 0.0f64;
        for c in 0..k {
            let learned = if sum_w > 0.0 {
                w[c] as f64 / sum_w
            } else {
                0.0
            };
            let q = (1.0 - alpha) * learned + alpha * state.prior[c] as f64 / sum_prior;
            state.q[c] = q as f32;
            total += state.q[c] as f64;
        }
        state.total = total;
        state
    }

    /// Chooses a cluster from 64 random bits: (cluster, its probability).
    pub fn pick_cluster(&self, state: &LearnedState, bits: u64) -> Option<(usize, f32)> {
        if !(state.total > 0.0) {
            return None;
        }
        let t = (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64) * state.total;
        let k = self.cut.len();
        let mut cum = 0.0f64;
        let mut last = None;
        for c in 0..k {
            let q = state.q[c];
            if q > 0.0 {
                cum += q as f64;
                last = Some(c);
                if t < cum {
                    break;
                }
            }
        }
        last.map(|c| (c, state.cluster_pmf(c)))
    }

    /// The cluster (index into the cut) holding `light`.
    pub fn cluster_of(&self, light: u32) -> Option<usize> {
        self.cut.cluster_of(self.light_tree()?, light as usize)
    }
}

impl LightSelection for LearnedSelection {
    type State = LearnedState;

    fn prepare(&self, scene: &Scene, sp: &ShadingPoint) -> LearnedState {
        let table = self.table.read().unwrap_or_else(|e| e.into_inner());
        self.prepare_with(scene, sp, &table)
    }

    fn pick(
        &self,
        state: &LearnedState,
        _: &ShadingPoint,
        rng: &mut SampleStream,
        picks: &mut Vec<(u32, f32)>,
    ) {
        let Some(lt) = self.light_tree() else { return };
        let cluster = self.pick_cluster(state, rng.next_u64());
        // The descent's number is drawn whether or not a cluster was, so later draws keep
        // their dimensions.
        let mut u = Rescaled(rng.next_u64());
        let Some((c, pc)) = cluster else { return };
        let (x, n) = state.tree.receiver();
        if let Some((light, p)) = lt.sample_from(self.cut.nodes[c], x, n, &mut u) {
            picks.push((light as u32, pc * p));
        }
    }

    fn pmf(&self, state: &LearnedState, _: &ShadingPoint, light: u32) -> f32 {
        let Some(lt) = self.light_tree() else {
            return 0.0;
        };
        let Some(c) = self.cluster_of(light) else {
            return 0.0;
        };
        let pc = state.cluster_pmf(c);
        if !(pc > 0.0) {
            return 0.0;
        }
        let (x, n) = state.tree.receiver();
        pc * lt.pmf_from(self.cut.nodes[c], x, n, light as usize)
    }
}

/// A light sample of a learned pick, shaded with its shadow ray, whose outcome is left in the
/// pixel's memory from `memory[0]` on for the merge after the pass: `(sample, pmf × point pdf,
/// f·L, the BSDF's density of its direction)` when the light is visible, `None` otherwise.
/// `u`: the point's random numbers.
#[allow(clippy::too_many_arguments)]
pub(crate) fn sample_observed<L: Learner>(
    scene: &Scene,
    sp: &ShadingPoint,
    light: u32,
    pmf: f32,
    u: glam::Vec2,
    counters: &mut render_core::stats::Counters,
    memory: &mut [f32],
    sel: &L,
    state: &L::State,
) -> Option<(render_core::light::LightSample, f32, render_core::Vec3, f32)> {
    let s = scene.sample_light(light, sp.point(), sp.normal(), u)?;
    let p = pmf * s.pdf;
    if !(p > 0.0) {
        return None;
    }
    let v = sp.bsdf.eval(sp.wo, s.wi);
    let f = v.f_cos * s.radiance;
    if f == render_core::Vec3::ZERO {
        return None;
    }
    counters.shadow_rays += 1;
    let o = sp.origin_towards(s.wi);
    let hit = !scene.occluded(o, s.wi, (s.point - o).length());
    sel.observe(
        state,
        light,
        render_core::colour::luminance(f),
        p,
        hit,
        memory,
    );
    hit.then_some((s, p, f, v.pdf))
}

impl Learner for LearnedSelection {
    fn observe(
        &self,
        state: &LearnedState,
        light: u32,
        lum_f: f32,
        p: f32,
        hit: bool,
        memory: &mut [f32],
    ) {
        let Some(cluster) = self.cluster_of(light) else {
            return;
        };
        // The contribution f/p of the light within its cluster, over the cluster's prior.
        let pc = state.cluster_pmf(cluster);
        let prior = state.prior[cluster];
        let ratio = if hit && pc > 0.0 && prior > 0.0 {
            let y = lum_f * pc / p;
            sanitize(y / prior)
        } else {
            0.0
        };
        super::regions::Observation {
            key: state.key,
            cluster,
            hit,
            ratio,
        }
        .write(memory, state.stamp);
    }

    fn clear_observation(&self, memory: &mut [f32]) {
        super::regions::Observation::clear(memory);
    }

    fn forget(&self) {
        self.table
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
    }

    fn merge(&self, pixels: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
        self.table
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .merge_pass(pixels, 0);
    }

    fn describe(&self) -> serde_json::Value {
        let t = self.table.read().unwrap_or_else(|e| e.into_inner());
        serde_json::json!({
            "config": self.config,
            "clusters": self.cut.len(),
            "cell_size": self.grid.cell,
            "regions": t.len(),
            "region_memory_bytes": t.memory_bytes(),
            "dropped_observations": t.dropped,
            "passes_learnt": t.pass,
        })
    }
}

/// `mis3-adaptive-learned`: the learned selection as the method's LS technique at every point,
/// its observation in the method's pixel memory from
/// [`crate::brdf_oriented::pixel_memory::LEARNED`] on.
impl crate::brdf_oriented::ls_technique::LsTechnique for LearnedSelection {
    fn tree(&self) -> Option<&LightTree> {
        self.tree.tree.as_deref()
    }

    fn prepare_ls(&self, scene: &Scene, sp: &ShadingPoint, _: bool) -> LearnedState {
        let table = self.table.read().unwrap_or_else(|e| e.into_inner());
        self.prepare_with(scene, sp, &table)
    }

    fn sample_ls(
        &self,
        state: &LearnedState,
        scene: &Scene,
        sp: &ShadingPoint,
        light: u32,
        pmf: f32,
        rng: &mut render_core::rng::SampleStream,
        ctx: &mut render_core::estimator::SampleContext,
    ) -> Option<(render_core::light::LightSample, f32, render_core::Vec3, f32)> {
        let u = rng.next_2d();
        let memory = &mut ctx.pixel_memory[crate::brdf_oriented::pixel_memory::LEARNED..];
        sample_observed(scene, sp, light, pmf, u, ctx.counters, memory, self, state)
    }

    fn begin_render(&self) {
        Learner::forget(self);
    }

    fn end_pass(&self, pixels: &[&[f32; render_core::estimator::PIXEL_MEMORY]]) {
        self.table
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .merge_pass(
                &mut pixels.iter().copied(),
                crate::brdf_oriented::pixel_memory::LEARNED,
            );
    }

    fn describe(&self) -> Option<serde_json::Value> {
        let t = self.table.read().unwrap_or_else(|e| e.into_inner());
        Some(serde_json::json!({
            "config": self.config,
            "clusters": self.cut.len(),
            "cell_size": self.grid.cell,
            "regions": t.len(),
            "region_memory_bytes": t.memory_bytes(),
            "dropped_observations": t.dropped,
        }))
    }
}
