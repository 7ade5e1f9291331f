//! Light-tree selection (Conty Estevez & Kulla 2018): a single stochastic descent, or
//! adaptive splitting into a cut with one light drawn per cluster.
use crate::light_strategy::LightStrategy;
use crate::memo::OctMemo;
use crate::scratch::Pooled;
use crate::selection::LightSelection;
use crate::shared_tree::{SharedTree, shared_tree};
use crate::strategy::Strategy;
use crate::{StrategyError, StrategyOptions, resolve};
use light_tree::{Cut, LightBounds, LightTree, NodeId, Rescaled, SplitParams};
use render_core::Vec3;
use render_core::estimator::DirectLighting;
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use std::cell::RefCell;
use std::collections::VecDeque;

pub use crate::options::PowerUnits;

/// The bounds the tree is built over, one per scene light, in scene order.
pub fn light_bounds(scene: &Scene, units: PowerUnits) -> Vec<LightBounds> {
    scene
        .lights
        .iter()
        .map(|l| {
            let (lo, hi) = l.bounds();
            let (axis, theta_o, theta_e) = l.orientation();
            LightBounds {
                aabb_min: lo,
                aabb_max: hi,
                axis,
                theta_o,
                theta_e,
                power: match units {
                    PowerUnits::Watts => l.power(),
                    PowerUnits::Authors => l.power_authors(),
                },
                two_sided: l.two_sided,
            }
        })
        .collect()
}

/// How the tree is used at a shading point.
#[derive(Clone, Copy, Debug)]
pub enum TreeMode {
    /// One descent from the root.
    Single,
    /// Split nodes whose importance estimate is unreliable (E&K's normalised variance below
    /// τ, or the point inside the node's bounds); see [`LightTree::adaptive_cut`].
    Split(SplitParams),
}

/// Light-tree selection: one descent, or an E&K adaptive cut with one light per cluster.
pub struct TreeSelection {
    /// The tree over the scene's lights (None without lights).
    pub tree: Option<SharedTree>,
    /// Single descent or adaptive splitting.
    pub mode: TreeMode,
}

impl TreeSelection {
    /// The tree over `scene`'s lights in `units` of power.
    pub fn new(scene: &Scene, mode: TreeMode, units: PowerUnits) -> Result<TreeSelection, String> {
        let bounds = light_bounds(scene, units);
        let tree = if bounds.is_empty() {
            None
        } else {
            Some(shared_tree(scene, bounds)?)
        };
        Ok(TreeSelection { tree, mode })
    }
}

/// The per-thread buffers of one shading point: the adaptive cut, and the oct lanes its pmf
/// replays read when the state caches them ([`TreeState::with_cached_pmf`]).
#[derive(Default)]
pub struct TreeScratch {
    cut: Cut,
    queue: VecDeque<NodeId>,
    lanes: RefCell<OctMemo>,
}

crate::scratch_pool!(TreeScratch, |s| {
    s.cut.nodes.clear();
    s.queue.clear();
    s.lanes.get_mut().invalidate();
});

/// The E&K cut of one shading point (none for a single descent), in per-thread scratch.
///
/// The picks and pmf replays descend the tree's eight-wide octs
/// ([`LightTree::sample_from`] / [`LightTree::pmf_from`]), one evaluation per three levels. No memo
/// by default: on `builtin:emissive-mesh` only 338 of 9,724 shading points of `tree+bsdf`
/// replayed a pmf (callgrind, docs/notes/light-tree.md), so its lookups cost more than they saved.
/// The method replays one per BRDF-aware sample and asks for the memo
/// ([`TreeState::with_cached_pmf`]).
pub struct TreeState {
    /// The cut and the lane memo; none for a single descent without the memo (which needs
    /// neither, and so skips the loan).
    scratch: Option<Pooled<TreeScratch>>,
    split: bool,
    cached_pmf: bool,
    x: Vec3,
    n: Vec3,
}

impl TreeState {
    /// The shading point's position and receiver normal the state was prepared for.
    pub fn receiver(&self) -> (Vec3, Vec3) {
        (self.x, self.n)
    }

    /// The cut's nodes (sorted DFS ids), if the selection splits.
    pub fn cut(&self) -> Option<&Cut> {
        match (&self.scratch, self.split) {
            (Some(s), true) => Some(&s.cut),
            _ => None,
        }
    }

    /// This state's pmf replays keep the oct lanes they evaluate for the next replay (bit for
    /// bit the same pmfs): for a caller that replays many at one shading point.
    pub fn with_cached_pmf(mut self) -> Self {
        self.cached_pmf = true;
        self.scratch.get_or_insert_with(Pooled::take);
        self
    }

    /// [`LightTree::pmf_from`] from `start`, through the lane memo if the state keeps one.
    fn pmf_from(&self, tree: &LightTree, start: NodeId, light: usize) -> f32 {
        let (x, n) = (self.x, self.n);
        match (&self.scratch, self.cached_pmf) {
            (Some(s), true) => {
                let mut lanes = s.lanes.borrow_mut();
                tree.pmf_from_cached(start, x, n, light, &mut *lanes)
            }
            _ => tree.pmf_from(start, x, n, light),
        }
    }
}

impl TreeSelection {
    /// [`LightSelection::prepare`] with the adaptive cut held to at most `max_size` clusters.
    pub fn prepare_capped(&self, sp: &ShadingPoint, max_size: usize) -> TreeState {
        self.prepare_impl(sp, Some(max_size))
    }

    fn prepare_impl(&self, sp: &ShadingPoint, cap: Option<usize>) -> TreeState {
        let (x, n) = (sp.point(), sp.cull_normal());
        let (scratch, split) = match (&self.tree, self.mode) {
            (Some(t), TreeMode::Split(mut params)) => {
                if let Some(cap) = cap {
                    params.max_size = params.max_size.min(cap);
                }
                let mut scratch = Pooled::<TreeScratch>::take();
                let TreeScratch { cut, queue, .. } = &mut *scratch;
                t.adaptive_cut_into(cut, queue, x, n, &params);
                (Some(scratch), true)
            }
            _ => (None, false),
        };
        TreeState {
            scratch,
            split,
            cached_pmf: false,
            x,
            n,
        }
    }
}

impl LightSelection for TreeSelection {
    type State = TreeState;

    fn prepare(&self, _: &Scene, sp: &ShadingPoint) -> TreeState {
        self.prepare_impl(sp, None)
    }

    fn batch_group(&self) -> usize {
        match self.mode {
            TreeMode::Split(_) => 8,
            _ => 64,
        }
    }

    fn clusters(&self, state: &TreeState) -> usize {
        state.cut().map_or(0, Cut::len)
    }

    fn pick(
        &self,
        state: &TreeState,
        _: &ShadingPoint,
        rng: &mut SampleStream,
        picks: &mut Vec<(u32, f32)>,
    ) {
        let Some(tree) = &self.tree else { return };
        let (x, n) = (state.x, state.n);
        match state.cut() {
            None => {
                let root = tree.root();
                if let Some((light, pmf)) =
                    tree.sample_from(root, x, n, &mut Rescaled(rng.next_u64()))
                {
                    picks.push((light as u32, pmf));
                }
            }
            Some(cut) => {
                // One fresh random number per cluster, rescaled down its subtree (as E&K and
                // the authors' code); the clusters two by two, their descents side by side.
                let mut pairs = cut.nodes.chunks_exact(2);
                for pair in &mut pairs {
                    let (mut ua, mut ub) = (Rescaled(rng.next_u64()), Rescaled(rng.next_u64()));
                    let found = tree.sample_pair_from(
                        [pair[0], pair[1]],
                        [x; 2],
                        [n; 2],
                        [&mut ua, &mut ub],
                    );
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
        }
    }

    fn pmf(&self, state: &TreeState, _: &ShadingPoint, light: u32) -> f32 {
        let Some(tree) = &self.tree else { return 0.0 };
        match state.cut() {
            None => state.pmf_from(tree, tree.root(), light as usize),
            Some(cut) => match cut.cluster_of(tree, light as usize) {
                Some(k) => state.pmf_from(tree, cut.nodes[k], light as usize),
                None => 0.0,
            },
        }
    }
}

/// A tree strategy's estimator: the tree in `mode`, with or without BSDF sampling.
fn tree_strategy(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
    split: bool,
    with_bsdf: bool,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    let (mode, parameters) = if split {
        let p = opts.split_params();
        let parameters = serde_json::json!({
            "tau": p.tau,
            "max_cut": opts.max_cut,
            "split_criterion": format!("{:?}", p.criterion).to_lowercase(),
            "reproduce": opts.reproduce,
        });
        (TreeMode::Split(p), parameters)
    } else {
        let parameters = serde_json::json!({ "reproduce": opts.reproduce });
        (TreeMode::Single, parameters)
    };
    let selection =
        TreeSelection::new(scene, mode, opts.power_units()).map_err(StrategyError::Scene)?;
    Ok(Box::new(LightStrategy {
        name: name.into(),
        selection,
        with_bsdf,
        parameters,
    }))
}

fn resolve_single(_: &str, opts: &StrategyOptions) -> serde_json::Value {
    serde_json::json!({ "tree": "single", "power_units": resolve::units(opts) })
}

fn resolve_split(_: &str, opts: &StrategyOptions) -> serde_json::Value {
    serde_json::json!({
        "tree": "split",
        "power_units": resolve::units(opts),
        "split": resolve::split(opts.split_params()),
    })
}

/// The knobs of the split tree strategies.
const SPLIT_KNOBS: &[&str] = &["tau", "max-cut"];

/// `tree`.
pub const TREE: Strategy = Strategy {
    golden_variants: &["reproduce"],
    ..Strategy::new(
        "tree",
        "light tree, single descent (Conty Estevez & Kulla 2018)",
        resolve_single,
        |name, scene, opts| tree_strategy(name, scene, opts, false, false),
    )
};

/// `tree+bsdf`.
pub const TREE_BSDF: Strategy = Strategy {
    golden_variants: &["reproduce"],
    ..Strategy::new(
        "tree+bsdf",
        "light tree single descent + BSDF sampling, MIS",
        resolve_single,
        |name, scene, opts| tree_strategy(name, scene, opts, false, true),
    )
};

/// `tree-split`.
pub const TREE_SPLIT: Strategy = Strategy {
    knobs: SPLIT_KNOBS,
    golden_variants: &["reproduce"],
    ..Strategy::new(
        "tree-split",
        "light tree with adaptive splitting",
        resolve_split,
        |name, scene, opts| tree_strategy(name, scene, opts, true, false),
    )
};

/// `tree-split+bsdf`: the paper's E&K baseline.
pub const TREE_SPLIT_BSDF: Strategy = Strategy {
    knobs: SPLIT_KNOBS,
    golden_variants: &["reproduce"],
    ..Strategy::new(
        "tree-split+bsdf",
        "adaptive tree splitting + BSDF sampling, MIS (the paper's E&K baseline)",
        resolve_split,
        |name, scene, opts| tree_strategy(name, scene, opts, true, true),
    )
};

impl crate::brdf_oriented::ls_technique::LsTechnique for TreeSelection {
    fn tree(&self) -> Option<&LightTree> {
        self.tree.as_deref()
    }

    fn prepare_ls(&self, scene: &Scene, sp: &ShadingPoint, one_descent: bool) -> TreeState {
        if one_descent {
            self.prepare_capped(sp, 1).with_cached_pmf()
        } else {
            LightSelection::prepare(self, scene, sp)
        }
    }

    fn defers_visibility(&self) -> bool {
        true
    }

    fn sample_ls(
        &self,
        _: &TreeState,
        scene: &Scene,
        sp: &ShadingPoint,
        light: u32,
        pmf: f32,
        rng: &mut SampleStream,
        ctx: &mut render_core::estimator::SampleContext,
    ) -> Option<(render_core::light::LightSample, f32, Vec3, f32)> {
        crate::light_strategy::sample_pick(scene, sp, light, pmf, rng, ctx.counters)
    }
}
