//! Queries: node importance, stochastic descent and its pmf replay, cuts.

use crate::codes::{LEAF_BIT, MIN_DIST_SQ, MIN_EMIT_COS};
use crate::descent_step::{DescentRandom, Rescaled, choose, sanitize};
use crate::{LightTree, Node, NodeId};
use glam::Vec3;
use std::collections::VecDeque;

/// cos(max(θa − θb, 0)) from cosines and sines, with θa, θb ∈ [0, π].
#[inline]
fn cos_sub_clamped(cos_a: f32, sin_a: f32, cos_b: f32, sin_b: f32) -> f32 {
    if cos_a >= cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// sin(max(θa − θb, 0)).
#[inline]
fn sin_sub_clamped(cos_a: f32, sin_a: f32, cos_b: f32, sin_b: f32) -> f32 {
    if cos_a >= cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

impl Node {
    /// E&K importance of this node for a receiver at `x` with normal `n`; see
    /// [`LightTree::importance`].
    #[inline]
    pub fn importance(&self, x: Vec3, n: Vec3) -> f32 {
        let center = self.center();
        let half = (self.aabb_max - self.aabb_min) * 0.5;
        let to_c = center - x;
        // Box–plane tests (conservative, monotone under the box union): the whole box behind
        // the receiver's tangent plane, or the receiver behind the whole box of a one-sided
        // emitter set whose emission stays within π/2 of the axis.
        let has_n = n != Vec3::ZERO;
        if has_n && n.dot(to_c) + n.abs().dot(half) <= 0.0 {
            return 0.0;
        }
        if self.flags & crate::FLAG_HALF_SPACE != 0
            && self.axis.dot(-to_c) + self.axis.abs().dot(half) <= 0.0
        {
            return 0.0;
        }
        let d2 = to_c.length_squared();
        let r2 = self.radius * self.radius;
        let d2c = d2.max(0.25 * r2).max(MIN_DIST_SQ);
        if d2 <= r2 {
            // x inside the bounding sphere: the cone bounds give nothing.
            return self.power / d2c;
        }
        let inv_d = d2.sqrt().recip();
        let w = to_c * inv_d; // unit, from x towards the centre
        let sin_u = (self.radius * inv_d).min(1.0);
        let cos_u = (1.0 - sin_u * sin_u).max(0.0).sqrt();

        // Emitter: θ = angle between the axis and x − c.
        let mut cos_t = -self.axis.dot(w);
        if self.flags & crate::FLAG_TWO_SIDED != 0 {
            cos_t = cos_t.abs();
        }
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let cos_o = self.cos_theta_o;
        let sin_o = (1.0 - cos_o * cos_o).max(0.0).sqrt();
        let cos_x = cos_sub_clamped(cos_t, sin_t, cos_o, sin_o);
        let sin_x = sin_sub_clamped(cos_t, sin_t, cos_o, sin_o);
        let cos_p = cos_sub_clamped(cos_x, sin_x, cos_u, sin_u);
        if cos_p <= self.cos_theta_e {
            return 0.0;
        }
        let emit = cos_p.max(MIN_EMIT_COS);

        // Receiver: θi = angle between n and c − x; n = 0 means no receiver cosine.
        let recv = if has_n {
            let cos_i = n.dot(w);
            let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
            cos_sub_clamped(cos_i, sin_i, cos_u, sin_u)
        } else {
            1.0
        };
        if recv <= 0.0 {
            return 0.0;
        }
        self.power * emit * recv / d2c
    }

    /// `true` when `x` lies in the closed bounding sphere.
    #[inline]
    pub fn contains(&self, x: Vec3) -> bool {
        (self.center() - x).length_squared() <= self.radius * self.radius
    }
}

/// A cut through the tree: node ids sorted by DFS id, whose subtrees partition the lights.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Cut {
    /// The cut's nodes in increasing [`NodeId`] order; every light lies under exactly one of
    /// them (for cuts made by [`LightTree::cut`] and friends).
    pub nodes: Vec<NodeId>,
}

impl Cut {
    /// Number of nodes (clusters) in the cut.
    #[inline]
    pub fn len(&self) -> usize {
        self.nodes.len()
    }
    /// Whether the cut has no node (only the [`Default`] value; real cuts hold at least the
    /// root).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
    /// Index into `nodes` of the cut node whose subtree holds `light` (binary search over
    /// the DFS ids); `None` if no cut node covers it.
    pub fn cluster_of(&self, tree: &LightTree, light: usize) -> Option<usize> {
        let leaf = tree.leaf_of(light);
        let i = self.nodes.partition_point(|&id| id <= leaf);
        if i == 0 {
            return None;
        }
        let c = self.nodes[i - 1];
        (leaf <= tree.subtree_range(c).1).then_some(i - 1)
    }
}

impl LightTree {
    /// Starts loading the children of node `id` (the next level of a descent), so that their
    /// cache misses overlap the importance evaluations of the current level.
    #[inline(always)]
    fn prefetch_children(&self, id: NodeId) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let node = &self.nodes[id as usize];
            if !node.is_leaf() {
                let base = self.nodes.as_ptr();
                // SAFETY: prefetching is a hint that never faults; both ids are valid
                // node indices (children of an interior node), so the pointers are in bounds.
                unsafe {
                    _mm_prefetch::<_MM_HINT_T0>(base.add(id as usize + 1) as *const i8);
                    _mm_prefetch::<_MM_HINT_T0>(base.add(node.child_or_light as usize) as *const i8);
                }
            }
        }
    }

    /// Starts loading the quads `codes` (leaf codes are skipped), both lines of each: the
    /// candidates for the next step of a four-wide descent.
    #[inline(always)]
    pub(crate) fn prefetch_quads(&self, codes: [u32; 4]) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let base = self.compact.quads.as_ptr();
            for c in codes {
                if c & LEAF_BIT == 0 {
                    // SAFETY: a prefetch never faults; interior codes are valid quad indices.
                    unsafe {
                        let p = base.add(c as usize) as *const i8;
                        _mm_prefetch::<_MM_HINT_T0>(p);
                        _mm_prefetch::<_MM_HINT_T0>(p.add(64));
                    }
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = codes;
    }

    /// E&K's normalised variance measure ρ = (1/(1 + σ))^{1/4} ∈ (0, 1] of `node` seen from
    /// `x` under `criterion` (σ from [`LightTree::split_sigma`]): low ρ = high variance.
    /// Leaves return 1.
    pub fn split_metric(&self, node: NodeId, x: Vec3, criterion: SplitCriterion) -> f32 {
        (1.0 / (1.0 + self.split_sigma(node, x, criterion))).powf(0.25) as f32
    }

    /// The σ behind E&K's splitting (their eqs. 8–10), for a node of N lights whose bounding
    /// sphere (c, r) lies at distance d from `x`: distances uniform in [a, b] = [d − r, d + r]
    /// give the geometric term g = 1/dist² the mean E\[g\] = 1/(ab) and the variance
    /// V\[g\] = (b³ − a³)/(3(b − a)a³b³) − 1/(a²b²); the lights' powers give E\[e\] = Φ/N and
    /// V\[e\].
    ///
    /// * [`SplitCriterion::Authors`]: σ = N·√(V\[e\]V\[g\] + V\[e\]E\[g\]² + E\[e\]²V\[g\]) in
    ///   scene units (power / length²), with the authors' V\[e\] = ⌊1/(N − 1)⌋·(ΣΦ² − N·E\[e\]²):
    ///   their integer division makes it 0 for N ≥ 3; a = max(d − r, 1e-9).
    /// * [`SplitCriterion::UnitFree`]: the same σ over the node's expected contribution
    ///   N·E\[e\]·E\[g\], i.e. the coefficient of variation of a one-light estimate of the node,
    ///   √((1 + V\[e\]/E\[e\]²)(1 + V\[g\]/E\[g\]²) − 1) with V\[g\]/E\[g\]² = 4r²/(3(d² − r²)):
    ///   scaling every power or every length leaves it unchanged. Infinite inside the sphere.
    ///
    /// Leaves return 0.
    pub fn split_sigma(&self, node: NodeId, x: Vec3, criterion: SplitCriterion) -> f64 {
        let nd = &self.nodes[node as usize];
        let n = nd.num_lights;
        if n <= 1 {
            return 0.0;
        }
        let ex = &self.extra[node as usize];
        match criterion {
            SplitCriterion::UnitFree => {
                let d2 = (nd.center() - x).length_squared() as f64;
                let r2 = (nd.radius * nd.radius) as f64;
                if d2 <= r2 {
                    return f64::INFINITY;
                }
                let cg = 4.0 * r2 / (3.0 * (d2 - r2));
                ((1.0 + ex.power_cv2 as f64) * (1.0 + cg) - 1.0)
                    .max(0.0)
                    .sqrt()
            }
            SplitCriterion::Authors => {
                let nf = n as f64;
                let d = ((nd.center() - x).length()) as f64;
                let r = nd.radius as f64;
                let a = (d - r).max(1e-9);
                let b = d + r;
                let e_g = 1.0 / (a * b);
                // (b³ − a³)/(b − a) = a² + ab + b².
                let ab = a * b;
                let v_g = ((a * a + ab + b * b) / (3.0 * ab * ab * ab) - 1.0 / (ab * ab)).max(0.0);
                let e_e = nd.power as f64 / nf;
                // 1 / (N − 1) in integers: 1 for two lights, 0 from three on.
                let v_e = if n == 2 {
                    (ex.power_sq_sum as f64 - nf * e_e * e_e).max(0.0)
                } else {
                    0.0
                };
                (v_e * v_g + v_e * e_g * e_g + e_e * e_e * v_g).sqrt() * nf
            }
        }
    }

    /// `true` when E&K's ρ < τ, i.e. σ > τ⁻⁴ − 1 (`sigma_min`), without powf or, for the
    /// unit-free criterion, any square root: compared as squares.
    #[inline]
    fn split_by_variance(
        &self,
        node: NodeId,
        x: Vec3,
        criterion: SplitCriterion,
        sigma_min: f32,
    ) -> bool {
        let nd = &self.nodes[node as usize];
        if nd.num_lights <= 1 {
            return false;
        }
        match criterion {
            SplitCriterion::UnitFree => {
                let d2 = (nd.center() - x).length_squared();
                let r2 = nd.radius * nd.radius;
                if d2 <= r2 {
                    return true;
                }
                let cg = 4.0 * r2 / (3.0 * (d2 - r2));
                let cv2 = (1.0 + self.extra[node as usize].power_cv2) * (1.0 + cg) - 1.0;
                cv2 > sigma_min * sigma_min
            }
            SplitCriterion::Authors => self.split_sigma(node, x, criterion) > sigma_min as f64,
        }
    }

    /// Conty Estevez & Kulla importance Φ · cos θ′ · cos θ′ᵢ / d² of node `node` for a receiver
    /// at `x` with normal `n`, on the node's compact bounds (the ones the descent reads; see
    /// below). [`Node::importance`] is the same formula on the exact f32 bounds.
    /// * d = distance from `x` to the node's bounding-sphere centre, θu = half-angle the
    ///   sphere subtends (sin θu = r/d);
    /// * θ′ = max(θ − θo − θu, 0) with θ the angle between the cone axis and x − c (|cos θ|
    ///   for two-sided nodes); the importance is 0 when θ′ ≥ θe;
    /// * θ′ᵢ = max(θi − θu, 0) with θi the angle between `n` and c − x; 0 when cos θ′ᵢ ≤ 0
    ///   (one-sided receiver: pass `n` flipped to the side of interest). `n == Vec3::ZERO`
    ///   drops the receiver term (volumes, transmissive BSDFs).
    /// * inside the bounding sphere (d² ≤ r²) both cosines are 1; the squared distance is
    ///   always max(d², r²/4, 1e-12), the same clamp everywhere;
    /// * in addition (Cycles-style, conservative, also inside the sphere) the importance is 0
    ///   when the node's box lies wholly behind the receiver's tangent plane, or when the node
    ///   is one-sided with θo + θe ≤ π/2 and `x` lies behind the box along the axis;
    /// * for θe > π/2 an emitter cosine ≤ 0 inside the emission range is floored at 1e-3.
    ///
    /// The compact bounds (16-bit box, axis and cosines, rounded outward: `compact.rs`)
    /// contain the exact ones, so this importance is positive wherever the exact one is. A
    /// node is evaluated together with its sibling, so this costs two nodes' arithmetic; the
    /// descents evaluate both children with one call.
    ///
    /// `x` and `n` are in the same space as the light bounds; `n` is unit length or zero. The
    /// result is ≥ 0, in power / length² (only ratios between nodes matter to the descent).
    #[inline]
    pub fn importance(&self, node: NodeId, x: Vec3, n: Vec3) -> f32 {
        let s = self.compact.slot_of[node as usize];
        self.pair_importances(s >> 1, x, n)[(s & 1) as usize]
    }

    /// [`LightTree::importance`] of each of `nodes`, into `out` (as long as `nodes`): the same
    /// bits as one call per node, from a quarter of the evaluations when siblings come next to
    /// each other (as in a cut sorted by DFS id, where a node's sibling, if also in the cut,
    /// follows it): the pairs holding consecutive nodes are evaluated two at a time.
    pub fn importances(&self, nodes: &[NodeId], x: Vec3, n: Vec3, out: &mut [f32]) {
        assert_eq!(nodes.len(), out.len(), "one output per node");
        let slot = |i: usize| self.compact.slot_of[nodes[i] as usize];
        // The end of the run of nodes from `i` on that sit in `i`'s pair.
        let run = |i: usize| {
            let pair = slot(i) >> 1;
            (i + 1..nodes.len())
                .find(|&j| slot(j) >> 1 != pair)
                .unwrap_or(nodes.len())
        };
        let mut i = 0;
        while i < nodes.len() {
            let j = run(i);
            let k = if j < nodes.len() { run(j) } else { j };
            let b = if j < nodes.len() {
                slot(j) >> 1
            } else {
                slot(i) >> 1
            };
            let v = self.quad_importances(slot(i) >> 1, b, x, n);
            for t in i..j {
                out[t] = v[(slot(t) & 1) as usize];
            }
            for t in j..k {
                out[t] = v[2 + (slot(t) & 1) as usize];
            }
            i = k;
        }
    }

    /// [`LightTree::importance`] of `node` and, from the same evaluation, of its sibling
    /// (`None` for the root): for memos that can keep both.
    #[inline]
    pub fn importance_and_sibling(
        &self,
        node: NodeId,
        x: Vec3,
        n: Vec3,
    ) -> (f32, Option<(NodeId, f32)>) {
        let s = self.compact.slot_of[node as usize];
        let (pair, side) = (s >> 1, (s & 1) as usize);
        let v = self.pair_importances(pair, x, n);
        let parent = self.compact.parent[pair as usize];
        if parent == u32::MAX {
            return (v[0], None);
        }
        let sibling = if side == 0 {
            self.nodes[parent as usize].child_or_light
        } else {
            parent + 1
        };
        (v[side], Some((sibling, v[1 - side])))
    }

    /// The importances [`LightTree::importance`] of the two children of `node` (`None` for
    /// a leaf), from one evaluation of their pair.
    #[inline]
    pub fn child_importances(&self, node: NodeId, x: Vec3, n: Vec3) -> Option<[f32; 2]> {
        self.children_pair(node)
            .map(|p| self.pair_importances(p, x, n))
    }

    /// Samples one light by a single descent from the root with one rescaled 64-bit uniform
    /// `u` (see [`Rescaled`]).
    /// Returns `(light, pmf)`, or `None` when the descent reaches a node whose children
    /// both have zero importance (with conservative bounds those lights cannot reach `x`).
    ///
    /// `light` indexes the slice given to [`LightTree::build`]; `pmf` ∈ (0, 1] is the discrete
    /// probability of that choice (not a density), equal to [`LightTree::pmf`] for it. `x` and
    /// `n` are as in [`LightTree::importance`].
    #[inline]
    pub fn sample(&self, x: Vec3, n: Vec3, u: u64) -> Option<(usize, f32)> {
        self.sample_from(self.root(), x, n, &mut Rescaled(u))
    }

    /// Probability that [`LightTree::sample`] returns `light`, replayed along its bit trail
    /// with the same floating-point operations. Summed over all lights it is 1, minus the
    /// mass of dead ends (see `sample`); 0 when every importance is 0.
    #[inline]
    pub fn pmf(&self, x: Vec3, n: Vec3, light: usize) -> f32 {
        self.pmf_from(self.root(), x, n, light)
    }

    /// Generic descent from `start`: at each interior node go left with probability
    /// I(left)/(I(left)+I(right)) (NaN/negative importances count as 0). Returns
    /// `(light, pmf within the subtree)`, or `None` at a dead end (both children 0).
    ///
    /// `importance` maps a node id to any non-negative weight (e.g. [`LightTree::importance`]
    /// or a BRDF-aware one); it is called for both children at each level. `rng` makes the
    /// left/right decisions. A leaf `start` returns its light with pmf 1.
    pub fn sample_subtree<I, R>(
        &self,
        start: NodeId,
        importance: I,
        rng: &mut R,
    ) -> Option<(usize, f32)>
    where
        I: Fn(NodeId) -> f32,
        R: DescentRandom,
    {
        let mut id = start;
        let mut pmf = 1.0f32;
        loop {
            let node = &self.nodes[id as usize];
            if node.is_leaf() {
                return Some((node.child_or_light as usize, pmf));
            }
            let (l, r) = (id + 1, node.child_or_light);
            self.prefetch_children(l);
            self.prefetch_children(r);
            let il = sanitize(importance(l));
            let ir = sanitize(importance(r));
            let (left, f) = choose(il, ir, rng)?;
            pmf *= f;
            id = if left { l } else { r };
        }
    }

    /// Probability that [`LightTree::sample_subtree`] from `start` with the same importance
    /// returns `light`; 0 if `light` is not under `start`.
    pub fn pmf_subtree<I>(&self, start: NodeId, importance: I, light: usize) -> f32
    where
        I: Fn(NodeId) -> f32,
    {
        let leaf = self.leaf_of[light];
        let (first, last) = self.subtree_range(start);
        if leaf < first || leaf > last {
            return 0.0;
        }
        let mut id = start;
        let start_depth = self.nodes[id as usize].depth();
        // Leaves may sit at depth 64; only interior nodes (depth < 64) shift here.
        let mut bits = if start_depth < 64 {
            self.trails[light] >> start_depth
        } else {
            0
        };
        let mut pmf = 1.0f32;
        while id != leaf {
            let node = &self.nodes[id as usize];
            let (l, r) = (id + 1, node.child_or_light);
            // Only the next node on the trail matters here.
            self.prefetch_children(if bits & 1 == 0 { l } else { r });
            let il = sanitize(importance(l));
            let ir = sanitize(importance(r));
            let sum = il + ir;
            if sum == 0.0 {
                return 0.0;
            }
            if bits & 1 == 0 {
                pmf *= il / sum;
                id = l;
            } else {
                pmf *= ir / sum;
                id = r;
            }
            bits >>= 1;
        }
        pmf
    }

    /// Generic cut: starting from `{root}`, nodes are visited breadth-first and an interior
    /// node is replaced by its two children when `should_split(node)` holds and the cut has
    /// fewer than `max_size` nodes. Leaves are never split. The result is sorted by DFS id
    /// and has at most `max(max_size, 1)` nodes.
    pub fn cut<S: FnMut(NodeId) -> bool>(&self, max_size: usize, should_split: S) -> Cut {
        let mut out = Cut::default();
        self.cut_into(&mut out, &mut VecDeque::new(), max_size, should_split);
        out
    }

    /// [`LightTree::cut`] reusing the caller's buffers (`queue` is scratch), so that a cut per
    /// shading point allocates nothing.
    pub fn cut_into<S: FnMut(NodeId) -> bool>(
        &self,
        out: &mut Cut,
        queue: &mut VecDeque<NodeId>,
        max_size: usize,
        mut should_split: S,
    ) {
        out.nodes.clear();
        queue.clear();
        queue.push_back(self.root());
        let mut size = 1usize;
        while let Some(id) = queue.pop_front() {
            let node = &self.nodes[id as usize];
            if !node.is_leaf() && size < max_size && should_split(id) {
                queue.push_back(id + 1);
                queue.push_back(node.child_or_light);
                size += 1;
            } else {
                out.nodes.push(id);
            }
        }
        out.nodes.sort_unstable();
    }

    /// E&K adaptive cut for a receiver at (`x`, `n`): split a node when `x` lies inside its
    /// bounding sphere or its [`LightTree::split_metric`] is below `params.tau`, at most
    /// `params.max_size` nodes. With the unit-free criterion nodes of zero importance are never
    /// split (all their lights are provably dark at `x`); the authors' cut splits them too.
    pub fn adaptive_cut(&self, x: Vec3, n: Vec3, params: &SplitParams) -> Cut {
        let mut out = Cut::default();
        self.adaptive_cut_into(&mut out, &mut VecDeque::new(), x, n, params);
        out
    }

    /// [`LightTree::adaptive_cut`] reusing the caller's buffers (`queue` is scratch).
    pub fn adaptive_cut_into(
        &self,
        out: &mut Cut,
        queue: &mut VecDeque<NodeId>,
        x: Vec3,
        n: Vec3,
        params: &SplitParams,
    ) {
        let sigma_min = params.sigma_min();
        let criterion = params.criterion;
        self.cut_into(out, queue, params.max_size, |id| {
            let node = &self.nodes[id as usize];
            let split = node.contains(x) || self.split_by_variance(id, x, criterion, sigma_min);
            match criterion {
                SplitCriterion::Authors => split,
                SplitCriterion::UnitFree => split && node.importance(x, n) > 0.0,
            }
        })
    }
}

/// Which σ E&K splitting compares with τ (see [`LightTree::split_sigma`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SplitCriterion {
    /// The coefficient of variation of the node's one-light estimate: no units, so a scene's
    /// scale or brightness changes no cut (our default).
    #[default]
    UnitFree,
    /// bisml's σ in scene units with its zeroed V\[e\] (`--reproduce`).
    Authors,
}

/// Parameters of an adaptive cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitParams {
    /// Split when ρ = (1/(1 + σ))^{1/4} < τ (τ ∈ [0, 1]; the authors use 0.85).
    pub tau: f32,
    /// Most nodes in the cut (`usize::MAX`: no cap, as in the authors' code).
    pub max_size: usize,
    /// Which σ is compared with τ.
    pub criterion: SplitCriterion,
}

impl SplitParams {
    /// σ above which ρ < τ: τ⁻⁴ − 1 (infinite for τ = 0: never split by variance).
    #[inline]
    pub fn sigma_min(&self) -> f32 {
        let t2 = self.tau * self.tau;
        1.0 / (t2 * t2) - 1.0
    }
}
