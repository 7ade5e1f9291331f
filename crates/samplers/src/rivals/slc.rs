//! Stochastic lightcuts (Yuksel, HPG 2019; real-time form Lin & Yuksel, I3D 2020): strategies
//! `slc` (lights only) and `slc+bsdf` (with one BSDF sample, combined by MIS); `slc-bo+bsdf`,
//! the descent weighed by the BRDF-oriented importance at glossy points, is in [`super::slc_bo`].
//!
//! # The estimator at a shading point x (receiver normal n)
//!
//! 1. **Cut.** Starting from {root}, the cut node with the largest error bound B is replaced by
//!    its two children, until the cut holds K nodes (default [`DEFAULT_CUT_SIZE`] = 32) or no
//!    node with B > 0 is left to refine. Leaves are never refined, nor nodes with B = 0 (every
//!    light below is provably dark at x). Ties go to the smaller node id. The cut depends on
//!    (x, n) alone, no random number, so its pmfs can be evaluated again for MIS.
//! 2. **One light per cut node.** From each cut node C one light ℓ is drawn down C's subtree by
//!    the tree's own descent ([`LightTree::sample_from`], E&K importance, one fresh 64-bit
//!    number per cut node, rescaled down the subtree), with probability P(ℓ | C) =
//!    [`LightTree::pmf_from`]`(C, ℓ)`.
//! 3. **Shadow ray per node.** A point y on ℓ is sampled by the light's own shape sampling
//!    (solid-angle density p_pt(y)), and the node's estimate is f(y)·L(y)·V(y) / (P(ℓ | C)·p_pt(y)).
//!    The image is the sum over the cut: the cut's subtrees partition the lights, each node's
//!    estimate is unbiased for its own lights, so the sum is unbiased for all of them.
//!
//! # The error bound B (what we use, and where it differs from the paper)
//!
//! B(C) = Φ_C · cos θ′ · cos θ′ᵢ / max(d_box², (ε·R)²), with
//! * Φ_C the node's total power (the tree's power units),
//! * cos θ′ the emitter bound of the node's orientation cone and cos θ′ᵢ the receiver bound on the
//!   geometric normal, both as the tree's importance computes them (E&K, the cone of the
//!   node's bounding sphere seen from x; both 1 inside the sphere; 0 behind the receiver's
//!   tangent plane or behind a one-sided half-space emitter set): [`Node::importance`] × its
//!   clamped squared centre distance,
//! * d_box the distance from x to the node's box (0 inside it) and ε·R a floor, ε =
//!   [`DISTANCE_FLOOR`] of the root's bounding radius R, so a node holding x gets a large
//!   finite bound and is refined first.
//!
//! This is an upper bound, up to a constant factor, on the node's unshadowed contribution
//! to a diffuse receiver: the cosines are bounds over the node, d_box is no longer than the
//! distance to any of its lights, and radiant intensity ≤ Φ/π in any direction.
//! Differences from the papers:
//! * Lightcuts' bound (the 2019 paper builds on lightcuts' cut selection) has a material
//!   term, a bound on the BSDF over the node's box. We leave it out: the BSDF counts as a constant, i.e. the
//!   bound is that of a diffuse receiver, and glossy points get the same cut as diffuse ones.
//!   That is also what Lin & Yuksel's public code does: intensity × receiver-cosine bound ×
//!   cone bound / clamped box distance², its floor a user parameter × the lights' bounding
//!   radius (ours fixed at ε = 10⁻³).
//! * Both cosines come from the tree's cones through the node's bounding sphere, not from its
//!   box as in lightcuts and Lin & Yuksel.
//! * Lightcuts also stops refining once every node's bound is below 2 % of the estimate; that
//!   needs the estimate, which is random here, so the cut would be too. Only the size K and
//!   B = 0 stop it, as in the real-time form's fixed cut size.
//! * The descent inside a cut node weighs the two children by the tree's E&K importance
//!   Φ·cos θ′·cos θ′ᵢ / d², d the distance to the bounding-sphere centre, clamped at r/2. Lin
//!   & Yuksel's public code (the variant it marks as the paper's) instead averages two
//!   normalised weights, intensity × receiver-cosine bound / (nearest box distance)² and the
//!   same over the farthest box distance, the nearest-distance term replaced by the plain
//!   shares of intensity × cosine bound when x lies in both boxes. Their weights are not a ratio of per-node importances, so the tree's descent
//!   cannot run them; [`SlcDescent::MinMax`] ([`super::slc_minmax`]) is that descent on our
//!   cones, for comparison (not our default).
//!
//! # MIS with BSDF sampling (`slc+bsdf`)
//!
//! The 2019 paper, as far as its public text shows, estimates direct lighting from the lights
//! alone and has no BSDF sampling to combine with. We add one BSDF sample and combine it as
//! `tree-split+bsdf` does (the power heuristic), with the light technique's density derived
//! below for the K samples of a cut.
//!
//! Let Y_C be the light points under cut node C. The Y_C are disjoint and their union is every
//! light point. The K light samples are one sample per stratum: the sample of node C has
//! density p_C(y) = P(ℓ(y) | C) · p_pt(y) on Y_C and 0 elsewhere. The BSDF sample y_b has
//! density p_b over all of them. With weights w_C, w_b the estimator
//!
//!   F = Σ_C w_C(y_C) f(y_C) / p_C(y_C) + w_b(y_b) f(y_b) / p_b(y_b)
//!
//! has expectation Σ_C ∫_{Y_C} w_C f + ∫ w_b f = Σ_C ∫_{Y_C} (w_C + w_b) f, and that is ∫ f
//! whenever w_C(y) + w_b(y) = 1 on Y_C, i.e. for every y, where C = C(y) is the one cut node
//! whose subtree holds y's light. The other nodes' samples can never produce y: their
//! densities at y are 0 and do not enter. Restricted to Y_C, this is two techniques with one
//! sample each, C's light sample and the BSDF sample, so the power heuristic with counts
//! (1, 1),
//!
//!   w_C(y) = p_C(y)² / (p_C(y)² + p_b(y)²),   w_b(y) = p_b(y)² / (p_C(y)² + p_b(y)²),
//!
//! is a valid pair. The light technique's density of a BSDF hit y is therefore
//! p_light(y) = P(ℓ(y) | C(y)) · p_pt(y). It is not 1/K of it, and not the root descent's
//! pmf: [`SlcSelection::pmf`] returns P(ℓ | C(ℓ)) from the cut of the same (x, n). Summing
//! every node's density (Σ_C p_C(y)) gives the same value, because only C(y)'s term is
//! non-zero. A BSDF hit on a light that C's descent cannot reach (a dead end, density 0) keeps
//! weight 1, which is right because no light sample covers it. Delta lights cannot be hit, so
//! their light samples keep weight 1. [`LightStrategy`] computes exactly these weights,
//! because a selection's `pmf` is the pick's probability within its part.
use super::slc_bo::BoWeight;
pub use super::slc_minmax::SlcDescent;
use crate::light_strategy::LightStrategy;
use crate::scratch::Pooled;
use crate::selection::LightSelection;
use crate::shared_tree::SharedTree;
use crate::shared_tree::shared_tree;
use crate::strategy::Strategy;
use crate::tree_selection::{PowerUnits, light_bounds};
use brdf_integrals::Sptd;
use light_tree::{Cut, LightTree, MIN_DIST_SQ, Node, NodeId, Rescaled};
use render_core::Vec3;
use render_core::estimator::{DirectLighting, SampleContext, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

pub use crate::options::DEFAULT_CUT_SIZE;
/// The largest cut size accepted (one shadow ray per node).
pub const MAX_CUT_SIZE: usize = 1 << 16;
/// Floor of the box distance in the error bound, as a fraction of the root's bounding radius.
pub const DISTANCE_FLOOR: f32 = 1e-3;

/// Lightcuts-style bound on node `node`'s unshadowed contribution at (`x`, `n`), up to a
/// constant factor (module docs): Φ · cos θ′ · cos θ′ᵢ / max(d_box², `floor_sq`), in f64.
pub fn error_bound(node: &Node, x: Vec3, n: Vec3, floor_sq: f32) -> f64 {
    let importance = node.importance(x, n);
    if !(importance > 0.0) {
        return 0.0;
    }
    // The importance divides Φ·cos·cos by this clamped squared centre distance.
    let d2 = (node.center() - x).length_squared();
    let r2 = node.radius() * node.radius();
    let d2c = d2.max(0.25 * r2).max(MIN_DIST_SQ);
    let (lo, hi) = node.aabb();
    let d_box2 = (x.clamp(lo, hi) - x).length_squared().max(floor_sq);
    importance as f64 * d2c as f64 / d_box2 as f64
}

/// A node waiting in the cut to be refined, ordered by its bound (then the smaller id first).
#[derive(Clone, Copy, Debug)]
pub struct Candidate {
    bound: f64,
    node: NodeId,
}

impl PartialEq for Candidate {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> Ordering {
        self.bound
            .total_cmp(&other.bound)
            .then_with(|| other.node.cmp(&self.node))
    }
}

/// The cut of at most `max_size` nodes at (`x`, `n`), refined by largest [`error_bound`]
/// (module docs), into `out` (sorted by DFS id); `heap` is scratch.
pub fn cut_into(
    tree: &LightTree,
    (x, n): (Vec3, Vec3),
    max_size: usize,
    floor_sq: f32,
    out: &mut Cut,
    heap: &mut BinaryHeap<Candidate>,
) {
    out.nodes.clear();
    heap.clear();
    let place = |id: NodeId, out: &mut Cut, heap: &mut BinaryHeap<Candidate>| {
        let node = tree.node(id);
        let bound = if node.is_leaf() {
            0.0
        } else {
            error_bound(node, x, n, floor_sq)
        };
        if bound > 0.0 {
            heap.push(Candidate { bound, node: id });
        } else {
            out.nodes.push(id);
        }
    };
    place(tree.root(), out, heap);
    let mut size = 1;
    while size < max_size {
        let Some(worst) = heap.pop() else { break };
        let (left, right) = tree
            .node(worst.node)
            .children(worst.node)
            .expect("only interior nodes wait to be refined");
        place(left, out, heap);
        place(right, out, heap);
        size += 1;
    }
    out.nodes.extend(heap.drain().map(|c| c.node));
    out.nodes.sort_unstable();
}

/// The selection of stochastic lightcuts: the cut of a shading point, one light per cut node.
pub struct SlcSelection {
    /// The tree over the scene's lights (None without lights).
    pub tree: Option<SharedTree>,
    /// Most nodes in a cut (K).
    pub cut_size: usize,
    /// Squared floor of the box distance in the error bound, in scene units².
    floor_sq: f32,
    /// The cap integrals of `slc-bo`'s descent at glossy points (None: the tree's descent).
    bo: Option<Sptd>,
    /// The descent inside a cut node (where `bo` does not apply).
    descent: SlcDescent,
}

impl SlcSelection {
    /// The tree over `scene`'s lights in `units` of power, cuts of at most `cut_size` nodes.
    /// A bad cut size is a [`crate::StrategyError::BadOption`], lights that make no tree a
    /// [`crate::StrategyError::Scene`].
    pub fn new(
        scene: &Scene,
        cut_size: usize,
        units: PowerUnits,
    ) -> Result<Self, crate::StrategyError> {
        check_cut_size(cut_size).map_err(crate::StrategyError::BadOption)?;
        let bounds = light_bounds(scene, units);
        let tree = if bounds.is_empty() {
            None
        } else {
            Some(shared_tree(scene, bounds).map_err(crate::StrategyError::Scene)?)
        };
        let radius = tree.as_ref().map_or(0.0, |t| t.node(t.root()).radius());
        let floor = DISTANCE_FLOOR * radius;
        Ok(SlcSelection {
            tree,
            cut_size,
            floor_sq: (floor * floor).max(MIN_DIST_SQ),
            bo: None,
            descent: SlcDescent::Tree,
        })
    }

    /// The same selection drawing each cut node's light by `descent`.
    pub fn with_descent(mut self, descent: SlcDescent) -> Self {
        self.descent = descent;
        self
    }

    /// The same selection descending by the BRDF-oriented weight at glossy points when `bo`
    /// ([`super::slc_bo`]).
    pub fn with_bo(mut self, bo: bool) -> Self {
        self.bo = bo.then(Sptd::default);
        self
    }

    /// The cut at (`x`, `n`) (empty without lights), for tests and tools.
    pub fn cut(&self, x: Vec3, n: Vec3) -> Cut {
        let mut out = Cut::default();
        if let Some(tree) = &self.tree {
            let heap = &mut BinaryHeap::new();
            cut_into(tree, (x, n), self.cut_size, self.floor_sq, &mut out, heap);
        }
        out
    }
}

fn check_cut_size(cut_size: usize) -> Result<(), String> {
    if (1..=MAX_CUT_SIZE).contains(&cut_size) {
        Ok(())
    } else {
        Err(format!(
            "slc: the cut size K must be in 1..={MAX_CUT_SIZE}, got {cut_size}"
        ))
    }
}

/// Per-thread buffers of one shading point's cut.
#[derive(Default)]
pub struct SlcScratch {
    cut: Cut,
    heap: BinaryHeap<Candidate>,
}

crate::scratch_pool!(SlcScratch, |s| {
    s.cut.nodes.clear();
    s.heap.clear();
});

/// The cut of one shading point (in per-thread scratch) and the receiver it was made for.
pub struct SlcState {
    scratch: Option<Pooled<SlcScratch>>,
    x: Vec3,
    n: Vec3,
    /// `slc-bo`'s node weight at a glossy point.
    bo: Option<BoWeight>,
}

impl SlcState {
    /// The cut's nodes (sorted DFS ids); `None` without lights.
    pub fn cut(&self) -> Option<&Cut> {
        self.scratch.as_ref().map(|s| &s.cut)
    }
}

impl LightSelection for SlcSelection {
    type State = SlcState;

    fn prepare(&self, _: &Scene, sp: &ShadingPoint) -> SlcState {
        let (x, n) = (sp.point(), sp.cull_normal());
        let scratch = self.tree.as_ref().map(|tree| {
            let mut s = Pooled::<SlcScratch>::take();
            let SlcScratch { cut, heap } = &mut *s;
            cut_into(tree, (x, n), self.cut_size, self.floor_sq, cut, heap);
            s
        });
        let bo = self
            .bo
            .as_ref()
            .and_then(|integral| BoWeight::at(sp, integral));
        SlcState { scratch, x, n, bo }
    }

    fn clusters(&self, state: &SlcState) -> usize {
        state.cut().map_or(0, Cut::len)
    }

    fn pick(
        &self,
        state: &SlcState,
        _: &ShadingPoint,
        rng: &mut SampleStream,
        picks: &mut Vec<(u32, f32)>,
    ) {
        let (Some(tree), Some(cut)) = (&self.tree, state.cut()) else {
            return;
        };
        if let Some(bo) = &state.bo {
            let weight = |id| bo.weight(tree.node(id));
            for &node in &cut.nodes {
                let mut u = Rescaled(rng.next_u64());
                if let Some((light, pmf)) = tree.sample_subtree(node, weight, &mut u) {
                    picks.push((light as u32, pmf));
                }
            }
            return;
        }
        let (x, n) = (state.x, state.n);
        if self.descent == SlcDescent::MinMax {
            for &node in &cut.nodes {
                let mut u = Rescaled(rng.next_u64());
                if let Some((light, pmf)) = super::slc_minmax::sample(tree, node, (x, n), &mut u) {
                    picks.push((light as u32, pmf));
                }
            }
            return;
        }
        // One fresh number per cut node, in cut order; two descents side by side.
        let mut pairs = cut.nodes.chunks_exact(2);
        for pair in &mut pairs {
            let (mut ua, mut ub) = (Rescaled(rng.next_u64()), Rescaled(rng.next_u64()));
            let found =
                tree.sample_pair_from([pair[0], pair[1]], [x; 2], [n; 2], [&mut ua, &mut ub]);
            for (light, pmf) in found.into_iter().flatten() {
                picks.push((light as u32, pmf));
            }
        }
        for &node in pairs.remainder() {
            let mut u = Rescaled(rng.next_u64());
            if let Some((light, pmf)) = tree.sample_from(node, x, n, &mut u) {
                picks.push((light as u32, pmf));
            }
        }
    }

    /// P(ℓ | C(ℓ)): the probability that the sample of the cut node holding `light` is it.
    fn pmf(&self, state: &SlcState, _: &ShadingPoint, light: u32) -> f32 {
        let (Some(tree), Some(cut)) = (&self.tree, state.cut()) else {
            return 0.0;
        };
        let light = light as usize;
        let Some(k) = cut.cluster_of(tree, light) else {
            return 0.0;
        };
        let (node, xn) = (cut.nodes[k], (state.x, state.n));
        match (&state.bo, self.descent) {
            (Some(bo), _) => tree.pmf_subtree(node, |id| bo.weight(tree.node(id)), light),
            (None, SlcDescent::Tree) => tree.pmf_from(node, xn.0, xn.1, light),
            (None, SlcDescent::MinMax) => super::slc_minmax::pmf(tree, node, xn, light),
        }
    }
}

/// What an `slc` strategy is built with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlcConfig {
    /// Most nodes in a cut (K), one shadow ray each.
    pub cut_size: usize,
    /// Add one BSDF sample, combined by the power heuristic (`slc+bsdf`).
    pub with_bsdf: bool,
    /// At glossy points, descend by the BRDF-oriented weight (`slc-bo+bsdf`, [`super::slc_bo`]).
    pub bo: bool,
    /// The descent inside a cut node elsewhere (default: the tree's).
    pub descent: SlcDescent,
    /// The tree's power units (the authors' `LeWithArea` under `--reproduce`, as every tree
    /// strategy).
    pub units: PowerUnits,
}

impl SlcConfig {
    /// The configuration of strategy `name` (`slc`, `slc+bsdf`, `slc-bo+bsdf`) under `opts`: K is
    /// `opts.slc_cut_size` (the paper's [`DEFAULT_CUT_SIZE`] by default; `opts.max_cut` is the
    /// E&K cut's).
    pub fn for_name(name: &str, opts: &crate::StrategyOptions) -> Result<SlcConfig, String> {
        let (with_bsdf, bo) = match name {
            "slc" => (false, false),
            "slc+bsdf" => (true, false),
            "slc-bo+bsdf" => (true, true),
            other => return Err(format!("not a stochastic-lightcuts strategy: `{other}`")),
        };
        Ok(SlcConfig {
            cut_size: opts.slc_cut_size,
            with_bsdf,
            bo,
            descent: opts.slc_descent,
            units: opts.power_units(),
        })
    }

    /// The strategy's name.
    pub fn name(&self) -> &'static str {
        match (self.bo, self.with_bsdf) {
            (true, true) => "slc-bo+bsdf",
            (true, false) => "slc-bo",
            (false, true) => "slc+bsdf",
            (false, false) => "slc",
        }
    }
}

/// Every parameter an `slc` strategy renders with, as the render's JSON records it.
pub fn resolved_parameters(config: &SlcConfig) -> serde_json::Value {
    serde_json::json!({
        "cut_size": config.cut_size,
        "error_bound": "power x emitter and receiver cone cosines / max(box distance, floor)^2",
        "distance_floor": DISTANCE_FLOOR,
        "descent": match config.descent {
            SlcDescent::Tree => "tree importance (E&K)",
            SlcDescent::MinMax => "mean of nearest- and farthest-box-distance weights (Lin & Yuksel)",
        },
        "glossy_descent": config.bo.then(|| {
            format!(
                "I_BO (SPTD, diffuse term) + {} x (ks + kd)/pi x E&K importance",
                super::slc_bo::EK_FLOOR
            )
        }),
        "power_units": match config.units {
            PowerUnits::Watts => "watts",
            PowerUnits::Authors => "authors",
        },
        "bsdf_mis": config.with_bsdf.then_some("power heuristic, one BSDF sample"),
    })
}

/// Stochastic lightcuts as a strategy: the cut's light samples through [`LightStrategy`]
/// (its light-point sampling, shadow rays, BSDF sample and MIS weights).
pub struct Slc(LightStrategy<SlcSelection>);

impl Slc {
    /// The strategy `config` describes, over `scene`'s lights.
    pub fn new(scene: &Scene, config: SlcConfig) -> Result<Slc, crate::StrategyError> {
        Ok(Slc(LightStrategy {
            name: config.name().into(),
            selection: SlcSelection::new(scene, config.cut_size, config.units)?
                .with_bo(config.bo)
                .with_descent(config.descent),
            with_bsdf: config.with_bsdf,
            parameters: resolved_parameters(&config),
        }))
    }

    /// Its selection (the tree and the cuts).
    pub fn selection(&self) -> &SlcSelection {
        &self.0.selection
    }
}

impl DirectLighting for Slc {
    fn name(&self) -> String {
        self.0.name()
    }
    fn parameters(&self) -> serde_json::Value {
        self.0.parameters()
    }
    fn techniques(&self) -> Vec<&'static str> {
        self.0.techniques()
    }
    fn counters(&self) -> Vec<render_core::stats::StrategyCounter> {
        self.0.counters()
    }
    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        self.0.estimate(scene, sp, rng, ctx)
    }
}

fn resolve(name: &str, opts: &crate::StrategyOptions) -> serde_json::Value {
    SlcConfig::for_name(name, opts).map_or(serde_json::Value::Null, |c| resolved_parameters(&c))
}

fn build(
    name: &str,
    scene: &Scene,
    opts: &crate::StrategyOptions,
) -> Result<Box<dyn render_core::estimator::DirectLighting>, crate::StrategyError> {
    let config = SlcConfig::for_name(name, opts).map_err(crate::StrategyError::BadOption)?;
    Ok(Box::new(Slc::new(scene, config)?))
}

const KNOBS: &[&str] = &["slc-cut-size", "slc-descent"];

/// `slc`.
pub const SLC: Strategy = Strategy {
    knobs: KNOBS,
    ..Strategy::new(
        "slc",
        "stochastic lightcuts (Yuksel 2019): an error-bound cut of at most K = 32 tree nodes, one light drawn down each, one shadow ray each",
        resolve,
        build,
    )
};

/// `slc+bsdf`.
pub const SLC_BSDF: Strategy = Strategy {
    knobs: KNOBS,
    ..Strategy::new("slc+bsdf", "slc + BSDF sampling, MIS", resolve, build)
};

/// `slc-bo+bsdf`: beyond the paper, the descent in each cut node by the BRDF-oriented importance
/// at glossy points.
pub const SLC_BO_BSDF: Strategy = Strategy {
    knobs: KNOBS,
    ..Strategy::new(
        "slc-bo+bsdf",
        "slc+bsdf with each cut node's descent by the paper's BRDF-oriented importance at glossy points (ours)",
        resolve,
        build,
    )
};
