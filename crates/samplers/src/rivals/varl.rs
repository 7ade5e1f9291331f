//! Learning to cluster (Wang, Wu, Li & Chuang, SIGGRAPH Asia 2021; "VARL" in the comparison
//! harnesses): strategies `varl` and `varl+bsdf`. Per region of space (position cell × normal
//! bucket), a cut of the light tree refined coarse to fine from the light samples'
//! observed contributions (visibility included), and a distribution over that cut moved from
//! the tree's prior towards the observed contributions by stochastic successive approximation
//! ([`super::varl_table`]).
//!
//! # The selection at a shading point x (region R, pass learnt from k passes with a target)
//!
//! With the cut C_R of R (the initial breadth-first cut of [`INITIAL_CUT`] nodes before R
//! was observed), prior_c the tree's E&K importance of node c at x, π_c = prior_c / Σ prior,
//! T_c R's learnt share and β = k/(k + 1):
//!
//!   q_c = (1 − α)·(β·T_c + (1 − β)·π_c) + α·π_c,   α the defensive share (`--varl-defensive`),
//!
//! then one light drawn down c's subtree by the tree's descent. Every light the tree can reach
//! keeps a positive probability (the α·π term), and q is a function of x and of the table frozen
//! before the pass, so each pass is unbiased and, merged in pixel order, the same for any
//! thread count (the pass machinery of `learned`, [`crate::learned::strategy::LearnedStrategy`]).
//!
//! # Where we differ from the paper (parameters with our defaults)
//!
//! * `--varl-cells` 16 regions per scene diagonal (× 6 normal buckets): the paper clusters
//!   shading points its own way; we reuse `learned`'s grid, coarser, since a cut needs
//!   [`super::varl_table::SPLIT_SAMPLES`] observations per node before it refines.
//! * `--varl-max-cut` 64 nodes per region, from [`INITIAL_CUT`] = 8; a node is split when its
//!   observations' squared coefficient of variation exceeds 1: our stand-in for the paper's
//!   refinement test, which we could not read.
//! * The update is the running mean of each pass's normalised contributions (step 1/k) and the
//!   pmf moves from the prior to it as k/(k + 1); the paper's own step sizes we could not read.
//! * One light sample per shading point, one BSDF sample by MIS in `varl+bsdf` (the power
//!   heuristic, as `learned+bsdf`).
//!
//! `learned` differs: its cut is one fixed breadth-first cut shared by every region, and it
//! learns a per-cluster factor (contribution over prior, or hit rate) that multiplies the
//! prior at each point; `varl` refines each region's cut and learns the distribution itself.
use super::varl_table::{Observation, VarlTable, node_of};
use crate::learned::regions::RegionGrid;
use crate::learned::strategy::LearnedStrategy;
use crate::learned::{Learner, PassWeights};
use crate::selection::LightSelection;
use crate::shared_tree::SharedTree;
use crate::shared_tree::shared_tree;
use crate::strategy::Strategy;
use crate::tree_selection::{PowerUnits, light_bounds};
use light_tree::{NodeId, Rescaled};
use render_core::Vec3;
use render_core::estimator::{PIXEL_MEMORY, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use std::sync::RwLock;

pub use super::varl_options::{INITIAL_CUT, MAX_CUT, VarlOptions};

/// The selection of `varl`: per-region learnt cuts and distributions.
pub struct VarlSelection {
    /// The light tree (None without lights).
    pub tree: Option<SharedTree>,
    /// Shading point → region.
    pub grid: RegionGrid,
    /// Its parameters.
    pub opts: VarlOptions,
    /// What earlier passes taught, frozen during a pass.
    pub table: RwLock<VarlTable>,
}

/// One shading point: its region, its cut and the probability of each cut node.
pub struct VarlState {
    /// The region.
    pub key: u64,
    /// The stamp of the pass being drawn.
    pub stamp: u32,
    x: Vec3,
    n: Vec3,
    k: usize,
    nodes: [NodeId; MAX_CUT],
    q: [f32; MAX_CUT],
    total: f64,
}

impl VarlState {
    /// The cut's nodes at this point.
    pub fn cut(&self) -> &[NodeId] {
        &self.nodes[..self.k]
    }

    /// The probability of cut node `c`.
    pub fn node_pmf(&self, c: usize) -> f32 {
        if self.total > 0.0 {
            (self.q[c] as f64 / self.total) as f32
        } else {
            0.0
        }
    }
}

fn sanitize(x: f32) -> f32 {
    if x.is_finite() && x > 0.0 { x } else { 0.0 }
}

impl VarlSelection {
    /// The selection for `scene` (tree in `units` of power).
    /// Bad options are a [`crate::StrategyError::BadOption`], lights that make no tree a
    /// [`crate::StrategyError::Scene`].
    pub fn new(
        scene: &Scene,
        units: PowerUnits,
        opts: VarlOptions,
    ) -> Result<Self, crate::StrategyError> {
        opts.check().map_err(crate::StrategyError::BadOption)?;
        let bounds = light_bounds(scene, units);
        let tree = if bounds.is_empty() {
            None
        } else {
            Some(shared_tree(scene, bounds).map_err(crate::StrategyError::Scene)?)
        };
        let table = VarlTable::new(tree.as_deref(), opts.max_cut, opts.max_regions);
        let (lo, _) = scene.bounds;
        Ok(VarlSelection {
            grid: RegionGrid::new(lo, scene.diagonal(), opts.cells_per_diagonal),
            tree,
            opts,
            table: RwLock::new(table),
        })
    }

    /// The state at `sp` under `table`.
    pub fn prepare_with(&self, sp: &ShadingPoint, table: &VarlTable) -> VarlState {
        let (x, n) = (sp.point(), sp.cull_normal());
        let key = self.grid.key(x, n);
        let mut s = VarlState {
            key,
            stamp: table.pass + 1,
            x,
            n,
            k: 0,
            nodes: [0; MAX_CUT],
            q: [0.0; MAX_CUT],
            total: 0.0,
        };
        let Some(tree) = &self.tree else { return s };
        let mut shares = [0.0f32; MAX_CUT];
        let passes = match table.region(key) {
            Some(r) => {
                for (i, node) in r.nodes.iter().enumerate() {
                    s.nodes[i] = node.id;
                    shares[i] = sanitize(node.share);
                }
                s.k = r.nodes.len();
                r.passes
            }
            None => {
                s.k = table.initial.len();
                s.nodes[..s.k].copy_from_slice(&table.initial);
                0
            }
        };
        let k = s.k;
        let mut prior = [0.0f32; MAX_CUT];
        tree.importances(&s.nodes[..k], x, n, &mut prior[..k]);
        let sum_prior: f64 = prior[..k].iter().map(|&p| sanitize(p) as f64).sum();
        if !(sum_prior > 0.0) {
            return s;
        }
        let sum_share: f64 = shares[..k].iter().map(|&t| t as f64).sum();
        let beta = if passes > 0 && sum_share > 0.0 {
            passes as f64 / (passes as f64 + 1.0)
        } else {
            0.0
        };
        let alpha = self.opts.defensive as f64;
        let mut total = 0.0f64;
        for c in 0..k {
            let pi = sanitize(prior[c]) as f64 / sum_prior;
            let t = if beta > 0.0 {
                shares[c] as f64 / sum_share
            } else {
                0.0
            };
            let q = (1.0 - alpha) * (beta * t + (1.0 - beta) * pi) + alpha * pi;
            s.q[c] = q as f32;
            total += s.q[c] as f64;
        }
        s.total = total;
        s
    }

    fn pick_node(&self, state: &VarlState, bits: u64) -> Option<(usize, f32)> {
        if !(state.total > 0.0) {
            return None;
        }
        let t = (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64) * state.total;
        let (mut cum, mut last) = (0.0f64, None);
        for c in 0..state.k {
            if state.q[c] > 0.0 {
                cum += state.q[c] as f64;
                last = Some(c);
                if t < cum {
                    break;
                }
            }
        }
        last.map(|c| (c, state.node_pmf(c)))
    }
}

impl LightSelection for VarlSelection {
    type State = VarlState;

    fn prepare(&self, _: &Scene, sp: &ShadingPoint) -> VarlState {
        let table = self.table.read().unwrap_or_else(|e| e.into_inner());
        self.prepare_with(sp, &table)
    }

    fn clusters(&self, state: &VarlState) -> usize {
        state.k
    }

    fn pick(
        &self,
        state: &VarlState,
        _: &ShadingPoint,
        rng: &mut SampleStream,
        picks: &mut Vec<(u32, f32)>,
    ) {
        let Some(tree) = &self.tree else { return };
        let node = self.pick_node(state, rng.next_u64());
        // Drawn whether or not a node was, so that later draws keep their dimensions.
        let mut u = Rescaled(rng.next_u64());
        let Some((c, pc)) = node else { return };
        if let Some((light, p)) = tree.sample_from(state.nodes[c], state.x, state.n, &mut u) {
            picks.push((light as u32, pc * p));
        }
    }

    fn pmf(&self, state: &VarlState, _: &ShadingPoint, light: u32) -> f32 {
        let Some(tree) = &self.tree else { return 0.0 };
        let cut = state.cut().iter().copied();
        let Some(c) = node_of(tree, cut, light as usize) else {
            return 0.0;
        };
        let pc = state.node_pmf(c);
        if !(pc > 0.0) {
            return 0.0;
        }
        pc * tree.pmf_from(state.nodes[c], state.x, state.n, light as usize)
    }
}

impl Learner for VarlSelection {
    fn observe(&self, state: &VarlState, light: u32, lum_f: f32, p: f32, hit: bool, m: &mut [f32]) {
        let y = if hit && p > 0.0 {
            sanitize(lum_f / p)
        } else {
            0.0
        };
        Observation {
            key: state.key,
            light,
            y,
        }
        .write(m, state.stamp);
    }

    fn clear_observation(&self, memory: &mut [f32]) {
        memory[0] = 0.0;
    }

    fn forget(&self) {
        self.table
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
    }

    fn merge(&self, pixels: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
        let Some(tree) = &self.tree else { return };
        let mut table = self.table.write().unwrap_or_else(|e| e.into_inner());
        table.merge_pass(tree, pixels, 0);
    }

    fn describe(&self) -> serde_json::Value {
        let t = self.table.read().unwrap_or_else(|e| e.into_inner());
        let mut p = resolved(&self.opts);
        p["cell_size"] = serde_json::json!(self.grid.cell);
        p["regions"] = serde_json::json!(t.len());
        p["cut_nodes"] = serde_json::json!(t.nodes());
        p["dropped_observations"] = serde_json::json!(t.dropped);
        p["passes_learnt"] = serde_json::json!(t.pass);
        p
    }
}

/// The parameters every `varl` render records.
fn resolved(opts: &VarlOptions) -> serde_json::Value {
    serde_json::json!({
        "options": opts,
        "initial_cut": INITIAL_CUT,
        "split_samples": super::varl_table::SPLIT_SAMPLES,
        "split_cv2": super::varl_table::SPLIT_CV2,
        "update": "running mean of the passes' normalised contributions; pmf from prior to it as k/(k+1)",
    })
}

fn resolve(_: &str, opts: &crate::StrategyOptions) -> serde_json::Value {
    let mut p = resolved(&opts.varl);
    p["power_units"] = serde_json::json!(crate::resolve::units(opts));
    p
}

fn build(
    name: &str,
    scene: &Scene,
    opts: &crate::StrategyOptions,
) -> Result<Box<dyn render_core::estimator::DirectLighting>, crate::StrategyError> {
    let selection = VarlSelection::new(scene, opts.power_units(), opts.varl)?;
    Ok(Box::new(LearnedStrategy {
        name: name.into(),
        selection,
        with_bsdf: name == VARL_BSDF.name,
        light_samples: 1,
        pass_weights: PassWeights::Equal,
    }))
}

const KNOBS: &[&str] = &["varl-max-cut", "varl-cells", "varl-defensive"];

/// `varl`.
pub const VARL: Strategy = Strategy {
    knobs: KNOBS,
    ..Strategy::new(
        "varl",
        "learning to cluster (Wang, Wu, Li & Chuang 2021): per region a light-tree cut refined from the samples' contributions with visibility and a distribution over it learnt between passes",
        resolve,
        build,
    )
};

/// `varl+bsdf`.
pub const VARL_BSDF: Strategy = Strategy {
    knobs: KNOBS,
    ..Strategy::new("varl+bsdf", "varl + BSDF sampling, MIS", resolve, build)
};
