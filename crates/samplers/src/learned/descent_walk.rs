//! The learned descent's walk down the light tree, eight lanes (three levels) at a time on the
//! tree's own eight-wide nodes ([`LightTree::oct_importances`]): a lane's learned weight is
//! its importance times its factor, the factor chained from the region's tallies of the three
//! pairs above it; the nodes between weigh as the sum of their lanes, as in the tree's own
//! eight-wide descent. Sampling and the pmf replay run the same arithmetic, so they agree bit
//! for bit.
use super::descent_table::{LEVELS, NodeTally};
use light_tree::{LightTree, NO_NODE, NodeId, Rescaled};
use render_core::Vec3;

/// What a step from one oct reads besides its importances: its lanes' nodes, how far below
/// the oct's node each lies (1–3; 0 for an empty lane), and the learnt pairs above them: the
/// oct node's, its two children's, its four grandchildren's (`u32::MAX` where not learnt or
/// not there).
#[derive(Clone, Copy, Debug)]
pub(crate) struct OctPlan {
    lanes: [NodeId; 8],
    below: [u8; 8],
    pairs: [u32; 7],
}

/// One plan per oct of `tree` (in its oct order), from `pair_of`: per node, its children's
/// learnt pair.
pub(crate) fn oct_plans(tree: &LightTree, pair_of: &[u32]) -> Vec<OctPlan> {
    let mut plans = Vec::new();
    for id in 0..tree.nodes().len() as NodeId {
        let Some(oct) = tree.oct_of(id) else { continue };
        let mut plan = OctPlan {
            lanes: [NO_NODE; 8],
            below: [0; 8],
            pairs: [u32::MAX; 7],
        };
        plan.pairs[0] = pair_of[id as usize];
        let children = |n: NodeId| tree.node(n).children(n);
        let (l, r) = children(id).expect("octs are of interior nodes");
        for (h, half) in [l, r].into_iter().enumerate() {
            let Some((hl, hr)) = children(half) else {
                (plan.lanes[4 * h], plan.below[4 * h]) = (half, 1);
                continue;
            };
            plan.pairs[1 + h] = pair_of[half as usize];
            for (s, quarter) in [hl, hr].into_iter().enumerate() {
                let q = 2 * h + s;
                let Some((ql, qr)) = children(quarter) else {
                    (plan.lanes[2 * q], plan.below[2 * q]) = (quarter, 2);
                    continue;
                };
                plan.pairs[3 + q] = pair_of[quarter as usize];
                plan.lanes[2 * q] = ql;
                plan.lanes[2 * q + 1] = qr;
                plan.below[2 * q] = 3;
                plan.below[2 * q + 1] = 3;
            }
        }
        if plans.len() <= oct as usize {
            plans.resize(oct as usize + 1, plan);
        }
        plans[oct as usize] = plan;
    }
    plans
}

/// How a walk chooses: by a uniform number in [0, 1) (with the learned weights or the tree's),
/// or along a light's trail.
pub(crate) enum Steer {
    Draw { learned: bool, u: f64 },
    Trail { light: usize, bits: u64 },
}

/// What a walk found: the light, its pmf, and per level below the root P(n)/I_n (0 past its
/// leaf).
pub(crate) struct Walk {
    pub light: usize,
    pub pmf: f32,
    pub scales: [f32; LEVELS],
}

/// What a walk needs besides its steering.
pub(crate) struct WalkInput<'a> {
    pub tree: &'a LightTree,
    pub plans: &'a [OctPlan],
    /// The region's tallies, if it has been seen.
    pub tallies: Option<&'a [[NodeTally; 2]]>,
    /// The root's factor in the region.
    pub root_factor: f32,
    pub x: Vec3,
    pub n: Vec3,
    /// Share α of the tree's own descent.
    pub defensive: f32,
    /// Prior strength a.
    pub prior: f32,
}

impl WalkInput<'_> {
    /// r̂ of the node on `side` of learnt pair `pair`, its parent's being `parent`.
    #[inline(always)]
    fn chain(&self, pair: u32, side: usize, parent: f32) -> f32 {
        match self.tallies {
            Some(t) if pair != u32::MAX => {
                let t = t[pair as usize][side];
                (t.ratio_sum + self.prior * parent) / (t.rays as f32 + self.prior)
            }
            _ => parent,
        }
    }

    /// The pmf of a light reached with products `q` (learned) and `t` (tree).
    #[inline(always)]
    fn mix(&self, q: f32, t: f32) -> f32 {
        (1.0 - self.defensive) * q + self.defensive * t
    }

    /// Walks from the root to a leaf (`None` at a dead end: every lane of zero importance).
    /// Below the learnt levels every node inherits its factor, so both products take the
    /// tree's probabilities and its own eight-wide descent finishes the walk.
    pub(crate) fn walk(&self, mut steer: Steer) -> Option<Walk> {
        let lt = self.tree;
        let mut id = lt.root();
        let mut factor = self.root_factor;
        let (mut q, mut t) = (1.0f32, 1.0f32);
        let mut scales = [0.0f32; LEVELS];
        let mut depth = 0usize;
        // Only a drawn pick is observed: a pmf replay (a trail) leaves its scales at 0.
        let observed = matches!(steer, Steer::Draw { .. });
        loop {
            let node = lt.node(id);
            if let Some(light) = node.light() {
                let pmf = self.mix(q, t);
                return Some(Walk { light, pmf, scales });
            }
            let oct = lt.oct_of(id)?;
            let plan = &self.plans[oct as usize];
            if plan.pairs[0] == u32::MAX {
                let (light, sub) = match steer {
                    Steer::Draw { u, .. } => {
                        let mut r = Rescaled((u * 18_446_744_073_709_551_616.0) as u64);
                        lt.sample_from(id, self.x, self.n, &mut r)?
                    }
                    Steer::Trail { light, .. } => (light, lt.pmf_from(id, self.x, self.n, light)),
                };
                let pmf = self.mix(q, t) * sub;
                return Some(Walk { light, pmf, scales });
            }
            if let Some(tallies) = self.tallies {
                for &p in &plan.pairs {
                    if let Some(pair) = tallies.get(p as usize) {
                        prefetch(pair);
                    }
                }
            }
            let g = lt.oct_importances(oct, self.x, self.n).map(sanitize);
            let half = [0, 1].map(|h| self.chain(plan.pairs[0], h, factor));
            let quarter: [f32; 4] =
                std::array::from_fn(|k| self.chain(plan.pairs[1 + k / 2], k % 2, half[k / 2]));
            let lane: [f32; 8] =
                std::array::from_fn(|k| self.chain(plan.pairs[3 + k / 2], k % 2, quarter[k / 2]));
            let w: [f32; 8] = std::array::from_fn(|k| g[k] * lane[k]);
            let (sum_g, sum_w) = (sum(&g), sum(&w));
            if sum_g == 0.0 {
                return None;
            }
            // The learned weights, or the tree's where they all underflowed.
            let w = if sum_w > 0.0 { w } else { g };
            let sum_w = if sum_w > 0.0 { sum_w } else { sum_g };
            let k = match &mut steer {
                Steer::Draw { learned, u } => {
                    let (v, total) = if *learned { (&w, sum_w) } else { (&g, sum_g) };
                    choose_lane(v, total, u)
                }
                Steer::Trail { bits, .. } => {
                    let mut k = 4 * (*bits >> depth & 1) as usize;
                    if plan.below[k] > 1 {
                        k += 2 * (*bits >> (depth + 1) & 1) as usize;
                        if plan.below[k] > 2 {
                            k += (*bits >> (depth + 2) & 1) as usize;
                        }
                    }
                    k
                }
            };
            // The levels passed: the half, the quarter and the lane (as far as the lane's node
            // lies below), each weighing the sum of its lanes.
            let below = plan.below[k] as usize;
            for level in (1..=below).filter(|_| observed) {
                let span = 8 >> level;
                let first = k / span * span;
                let i = range_sum(&g, first, span);
                let p = self.mix(q * (range_sum(&w, first, span) / sum_w), t * (i / sum_g));
                if depth + level <= LEVELS && i > 0.0 {
                    scales[depth + level - 1] = p / i;
                }
            }
            q *= w[k] / sum_w;
            t *= g[k] / sum_g;
            factor = lane[k];
            id = plan.lanes[k];
            depth += below;
            if id == NO_NODE {
                return None;
            }
        }
    }
}

/// The lane that `u` ∈ [0, 1) falls in, in proportion to `v` (whose sum is `total` > 0): never
/// a lane of weight 0. `u` becomes the uniform number within that lane.
fn choose_lane(v: &[f32; 8], total: f32, u: &mut f64) -> usize {
    let target = *u * total as f64;
    let mut cum = 0.0f64;
    let mut last = 0;
    for (k, &vk) in v.iter().enumerate() {
        if vk > 0.0 {
            last = k;
            if target < cum + vk as f64 {
                *u = ((target - cum) / vk as f64).clamp(0.0, 1.0 - f64::EPSILON);
                return k;
            }
            cum += vk as f64;
        }
    }
    *u = 1.0 - f64::EPSILON;
    last
}

/// The sum of the lanes in lane order.
#[inline(always)]
fn sum(v: &[f32; 8]) -> f32 {
    range_sum(v, 0, 8)
}

/// The sum of `span` lanes from `first`, in lane order.
#[inline(always)]
fn range_sum(v: &[f32; 8], first: usize, span: usize) -> f32 {
    v[first..first + span].iter().sum()
}

/// A hint to bring `x`'s cache line in (nothing off x86-64).
#[inline(always)]
fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults, and the pointer comes from a reference.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(x as *const T as *const i8);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// Non-finite and negative importances count as 0.
#[inline]
pub(crate) fn sanitize(x: f32) -> f32 {
    if x.is_finite() && x > 0.0 { x } else { 0.0 }
}
