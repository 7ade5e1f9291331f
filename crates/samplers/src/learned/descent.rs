//! The learned descent: per region, a factor learnt for every node of the light tree's top
//! levels (all of them up to 4,096 learnt pairs and depth [`LEVELS`]), which multiplies the
//! node's unshadowed importance at each step of the descent (after Pantaleoni 2019,
//! *Importance sampling of many lights with reinforcement lightcuts learning*, and in the role
//! of Vévoda et al. 2018's per-region cut). The cluster selection learns one level (its cut);
//! this one learns down to single lights, so it also corrects the tree's bounds inside what the
//! cluster selection treats as one unit.
//!
//! What is learnt: a sample of light l, drawn with probability P(l) through node n (reached
//! with probability P(n)), estimates n's shadowed contribution T_n at the point as
//! Y · P(n), Y = lum(f·L·V)/(P(l) p_point); its ratio to n's importance I_n,
//! ρ_n = Y · P(n)/I_n, has mean T_n/I_n given that the sample went through n. A region's
//! factor of n is ρ̄_n shrunk towards its parent's, r̂_n = (Σρ_n + a·r̂_parent)/(rays_n + a),
//! the root's the mean of its children's ratios (1 before any), so a node not yet observed
//! keeps its parent's factor and the tree's own split below it.
//!
//! Sampling (`descent_walk.rs`): with probability 1 − α the walk chooses among a step's eight
//! lanes ∝ importance × factor, otherwise ∝ the importances alone (the tree's descent); the
//! pmf of a light is (1 − α)·Q(l) + α·T(l), both products replayed along its trail with the
//! same operations, so every light the tree reaches keeps at least α times its tree
//! probability.
use super::descent_table::{
    DescentObservation, DescentTable, LEVELS, MAX_TABLE_BYTES, NodeTally, learnt_pairs,
};
use super::descent_walk::{OctPlan, Steer, WalkInput, oct_plans, sanitize};
use super::regions::RegionGrid;
use super::{LearnedConfig, Learner};
use crate::selection::LightSelection;
use crate::tree_selection::{PowerUnits, TreeMode, TreeSelection};
use light_tree::LightTree;
use render_core::Vec3;
use render_core::estimator::{PIXEL_MEMORY, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use std::cell::Cell;
use std::sync::{Arc, RwLock};

/// Most lights an observation can name (a light index is stored exactly in an f32).
const MAX_LIGHTS: usize = 1 << 24;

/// The learned descent over the scene's light tree.
pub struct DescentSelection {
    /// The light tree (single descent) and the receiver convention.
    pub tree: TreeSelection,
    /// Per node: the index of the learnt pair of its children, `u32::MAX` for leaves and nodes
    /// below the learnt levels.
    pair_of: Vec<u32>,
    /// Per oct of the tree: what a step of the walk reads.
    plans: Vec<OctPlan>,
    /// Shading point → region.
    pub grid: RegionGrid,
    /// Its parameters (`clusters` and `target` are the cluster selection's and unused here).
    pub config: LearnedConfig,
    /// What earlier passes taught, frozen during a pass (shared with the points of a pass).
    pub table: RwLock<Arc<DescentTable>>,
}

impl DescentSelection {
    /// The learned descent for `scene` (tree in `units` of power).
    pub fn new(
        scene: &Scene,
        units: PowerUnits,
        config: LearnedConfig,
    ) -> Result<DescentSelection, String> {
        super::selection::check_config(&config)?;
        if scene.lights.len() > MAX_LIGHTS {
            return Err(format!(
                "learned descent: at most {MAX_LIGHTS} lights, the scene has {}",
                scene.lights.len()
            ));
        }
        let tree = TreeSelection::new(scene, TreeMode::Single, units)?;
        let (pair_of, pair_count) = tree
            .tree
            .as_deref()
            .map_or_else(Default::default, learnt_pairs);
        let per_region = pair_count.max(1) * std::mem::size_of::<[NodeTally; 2]>();
        let max_regions = config.max_regions.min(MAX_TABLE_BYTES / per_region).max(1);
        let (lo, _) = scene.bounds;
        let plans = tree
            .tree
            .as_ref()
            .map_or_else(Vec::new, |t| oct_plans(t, &pair_of));
        Ok(DescentSelection {
            plans,
            tree,
            table: RwLock::new(Arc::new(DescentTable::new(pair_count, max_regions))),
            pair_of,
            grid: RegionGrid::new(lo, scene.diagonal(), config.cells_per_diagonal),
            config,
        })
    }

    fn light_tree(&self) -> Option<&LightTree> {
        self.tree.tree.as_deref()
    }

    /// The depth of the deepest learnt nodes (the children of the deepest learnt pairs).
    pub fn learnt_depth(&self) -> u32 {
        self.light_tree().map_or(0, |lt| {
            lt.nodes()
                .iter()
                .zip(&self.pair_of)
                .filter(|&(_, &p)| p != u32::MAX)
                .map(|(n, _)| n.depth() + 1)
                .max()
                .unwrap_or(0)
        })
    }
}

/// The root's factor in a region: the mean ratio its children's observations found (1 before
/// any).
fn root_factor(tallies: &[[NodeTally; 2]]) -> f32 {
    tallies.first().map_or(1.0, |[l, r]| {
        let (sum, rays) = (l.ratio_sum + r.ratio_sum, l.rays + r.rays);
        if rays > 0 && sum > 0.0 {
            sum / rays as f32
        } else {
            1.0
        }
    })
}

/// One shading point: its region and receiver, and the per-level scales of its first pick
/// (for its observation).
pub struct DescentState {
    table: Arc<DescentTable>,
    /// The first of the region's pairs in the table, if the region has been seen.
    region: Option<usize>,
    /// The region of the shading point.
    pub key: u64,
    /// The stamp of the pass being drawn.
    pub stamp: u32,
    x: Vec3,
    n: Vec3,
    /// The first pick's light and, per level of its path below the root, P(n)/I_n (0 past
    /// its leaf).
    last: Cell<(u32, [f32; LEVELS])>,
}

impl DescentState {
    /// Whether the point's region has been seen in earlier passes.
    pub fn learnt(&self) -> bool {
        self.region.is_some()
    }
}

impl DescentSelection {
    /// The walk's inputs at the point of `state`.
    fn walk_input<'a>(&'a self, lt: &'a LightTree, state: &'a DescentState) -> WalkInput<'a> {
        let tallies = state
            .region
            .map(|i| &state.table.tallies[i..i + state.table.pairs]);
        WalkInput {
            tree: lt,
            plans: &self.plans,
            tallies,
            root_factor: tallies.map_or(1.0, root_factor),
            x: state.x,
            n: state.n,
            defensive: self.config.defensive,
            prior: self.config.prior_strength,
        }
    }
}

impl LightSelection for DescentSelection {
    type State = DescentState;

    fn prepare(&self, scene: &Scene, sp: &ShadingPoint) -> DescentState {
        let (x, n) = self.tree.prepare(scene, sp).receiver();
        let key = self.grid.key(sp.point(), sp.bsdf.ng);
        let table = Arc::clone(&self.table.read().unwrap_or_else(|e| e.into_inner()));
        let region = table.index.get(&key).map(|&i| i as usize * table.pairs);
        DescentState {
            stamp: table.pass + 1,
            table,
            region,
            key,
            x,
            n,
            last: Cell::new((u32::MAX, [0.0; LEVELS])),
        }
    }

    fn pick(
        &self,
        state: &DescentState,
        _: &ShadingPoint,
        rng: &mut SampleStream,
        picks: &mut Vec<(u32, f32)>,
    ) {
        let Some(lt) = self.light_tree() else { return };
        let unit = |bits: u64| (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        let learned = unit(rng.next_u64()) >= self.config.defensive as f64;
        let u = unit(rng.next_u64());
        if let Some(w) = self.walk_input(lt, state).walk(Steer::Draw { learned, u })
            && w.pmf > 0.0
        {
            // Only a point's first light sample is learnt from (`LearnedStrategy`): its
            // scales are kept for the observation.
            if state.last.get().0 == u32::MAX {
                state.last.set((w.light as u32, w.scales));
            }
            picks.push((w.light as u32, w.pmf));
        }
    }

    fn pmf(&self, state: &DescentState, _: &ShadingPoint, light: u32) -> f32 {
        let Some(lt) = self.light_tree() else {
            return 0.0;
        };
        if light as usize >= lt.num_lights() {
            return 0.0;
        }
        let steer = Steer::Trail {
            light: light as usize,
            bits: lt.bit_trail(light as usize),
        };
        match self.walk_input(lt, state).walk(steer) {
            Some(w) if w.light == light as usize => w.pmf,
            _ => 0.0,
        }
    }
}

impl Learner for DescentSelection {
    fn observe(
        &self,
        state: &DescentState,
        light: u32,
        lum_f: f32,
        p: f32,
        hit: bool,
        memory: &mut [f32],
    ) {
        let (last, scales) = state.last.get();
        if last != light {
            return;
        }
        let y = if hit && p > 0.0 {
            sanitize(lum_f / p)
        } else {
            0.0
        };
        DescentObservation {
            key: state.key,
            light,
            y,
            scales,
        }
        .write(memory, state.stamp);
    }

    fn clear_observation(&self, memory: &mut [f32]) {
        DescentObservation::clear(memory);
    }

    fn forget(&self) {
        let mut guard = self.table.write().unwrap_or_else(|e| e.into_inner());
        let (pairs, max_regions) = (guard.pairs, guard.max_regions);
        *guard = Arc::new(DescentTable::new(pairs, max_regions));
    }

    fn merge(&self, pixels: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
        let mut guard = self.table.write().unwrap_or_else(|e| e.into_inner());
        let table = Arc::make_mut(&mut guard);
        let stamp = table.pass + 1;
        if let Some(lt) = self.light_tree() {
            for m in pixels {
                let Some(o) = DescentObservation::read(m, stamp) else {
                    continue;
                };
                let light = o.light as usize;
                if light >= lt.num_lights() {
                    continue;
                }
                let Some(i) = table.region_index(o.key) else {
                    table.dropped += 1;
                    continue;
                };
                let base = i * table.pairs;
                let mut trail = lt.bit_trail(light);
                let mut id = lt.root();
                for scale in o.scales {
                    let p = self.pair_of[id as usize];
                    let Some((l, r)) = lt.node(id).children(id) else {
                        break;
                    };
                    if p == u32::MAX {
                        break;
                    }
                    let side = (trail & 1) as usize;
                    let t = &mut table.tallies[base + p as usize][side];
                    t.ratio_sum += o.y * scale;
                    t.rays += 1;
                    id = if side == 0 { l } else { r };
                    trail >>= 1;
                }
            }
        }
        table.pass = stamp;
    }

    fn describe(&self) -> serde_json::Value {
        let t = self.table.read().unwrap_or_else(|e| e.into_inner());
        serde_json::json!({
            "config": self.config,
            "learnt_depth": self.learnt_depth(),
            "tree_depth": self.light_tree().map_or(0, LightTree::max_depth),
            "learnt_pairs": t.pairs,
            "cell_size": self.grid.cell,
            "regions": t.len(),
            "max_regions": t.max_regions,
            "region_memory_bytes": t.memory_bytes(),
            "dropped_observations": t.dropped,
            "passes_learnt": t.pass,
        })
    }
}
