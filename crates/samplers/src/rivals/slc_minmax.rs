//! The descent inside a cut node as Lin & Yuksel's public real-time code runs it (the variant
//! it marks as the paper's), on our tree's bounds: [`SlcDescent::MinMax`]. `slc`'s default is
//! the tree's own descent ([`SlcDescent::Tree`]); this one is there to measure the difference.
//!
//! At an interior node with children a and b, let g = Φ · cos θ′ · cos θ′ᵢ (the tree's cone
//! bounds, as in [`super::slc::error_bound`]) and l²_min, l²_max the squared distances from x to
//! the nearest and the farthest point of each child's box. The left child is taken with
//!
//!   p_a = ½ · (n(g_a/l²_min,a , g_b/l²_min,b) + n(g_a/l²_max,a , g_b/l²_max,b)),
//!   n(u, v) = u / (u + v),
//!
//! where the near term is g_a/(g_a + g_b) when x lies in both boxes, a child with g = 0 is never
//! taken and both g = 0 is a dead end (no sample). The code weighs g by its own box-based
//! cosine bounds; we use the tree's cones. Sampling and replay multiply the same f32 factors, so
//! the pmf replays bit for bit.
use light_tree::{DescentRandom, LightTree, Node, NodeId};
use render_core::Vec3;

/// How the light of a cut node is drawn down its subtree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SlcDescent {
    /// The tree's descent by E&K importance (our default).
    #[default]
    Tree,
    /// The mean of the nearest- and farthest-distance weights (Lin & Yuksel's code).
    MinMax,
}

impl SlcDescent {
    /// Every descent, in `--slc-descent`'s order.
    pub const ALL: [SlcDescent; 2] = [SlcDescent::Tree, SlcDescent::MinMax];

    /// The name `--slc-descent` takes.
    pub fn name(self) -> &'static str {
        match self {
            SlcDescent::Tree => "tree",
            SlcDescent::MinMax => "minmax",
        }
    }

    /// The descent called `name`.
    pub fn from_name(name: &str) -> Option<SlcDescent> {
        SlcDescent::ALL.into_iter().find(|d| d.name() == name)
    }
}

/// Φ · cos θ′ · cos θ′ᵢ of `node` at (x, n): the tree's importance times its clamped squared
/// centre distance (0 where the node is provably dark).
fn cone_power(node: &Node, x: Vec3, n: Vec3) -> f32 {
    let importance = node.importance(x, n);
    if !(importance > 0.0) {
        return 0.0;
    }
    let d2 = (node.center() - x).length_squared();
    let r2 = node.radius() * node.radius();
    importance * d2.max(0.25 * r2).max(light_tree::MIN_DIST_SQ)
}

/// Squared distances from `x` to the nearest and the farthest point of `node`'s box.
fn box_distances(node: &Node, x: Vec3) -> (f32, f32) {
    let (lo, hi) = node.aabb();
    let near = (x.clamp(lo, hi) - x).length_squared();
    let far = (x - lo).abs().max((hi - x).abs()).length_squared();
    (near, far)
}

/// u / (u + v) for u = g_a / l_a, v = g_b / l_b, as (l_b g_a) / (l_b g_a + l_a g_b): a child at
/// distance 0 takes all of it; `None` when both products are 0.
fn normalized(l_a: f32, l_b: f32, g_a: f32, g_b: f32) -> Option<f32> {
    let (u, v) = (l_b * g_a, l_a * g_b);
    let sum = u + v;
    (sum > 0.0 && sum.is_finite()).then(|| u / sum)
}

/// The probability of taking the left child of interior node `id` at (x, n); `None` at a
/// dead end.
fn left_probability(tree: &LightTree, id: NodeId, x: Vec3, n: Vec3) -> Option<f32> {
    let (l, r) = tree.node(id).children(id)?;
    let (a, b) = (tree.node(l), tree.node(r));
    let (g_a, g_b) = (cone_power(a, x, n), cone_power(b, x, n));
    if g_a == 0.0 && g_b == 0.0 {
        return None;
    }
    if g_a == 0.0 || g_b == 0.0 {
        return Some(if g_a > 0.0 { 1.0 } else { 0.0 });
    }
    let share = g_a / (g_a + g_b);
    let ((near_a, far_a), (near_b, far_b)) = (box_distances(a, x), box_distances(b, x));
    let near = if near_a == 0.0 && near_b == 0.0 {
        share
    } else {
        normalized(near_a, near_b, g_a, g_b).unwrap_or(share)
    };
    let far = normalized(far_a, far_b, g_a, g_b).unwrap_or(share);
    Some((0.5 * (near + far)).clamp(0.0, 1.0))
}

/// One light drawn from the subtree of `start` by the min-max weights, with its pmf within the
/// subtree; `None` at a dead end.
pub fn sample<R: DescentRandom>(
    tree: &LightTree,
    start: NodeId,
    (x, n): (Vec3, Vec3),
    rng: &mut R,
) -> Option<(usize, f32)> {
    let mut id = start;
    let mut pmf = 1.0f32;
    loop {
        let node = tree.node(id);
        if let Some(light) = node.light() {
            return Some((light, pmf));
        }
        let p = left_probability(tree, id, x, n)?;
        let left = p >= 1.0 || (p > 0.0 && rng.go_left(p));
        pmf *= if left { p } else { 1.0 - p };
        let (l, r) = node.children(id)?;
        id = if left { l } else { r };
    }
}

/// The probability that [`sample`] from `start` returns `light` (0 if it is not below `start`).
pub fn pmf(tree: &LightTree, start: NodeId, (x, n): (Vec3, Vec3), light: usize) -> f32 {
    let leaf = tree.leaf_of(light);
    let (first, last) = tree.subtree_range(start);
    if leaf < first || leaf > last {
        return 0.0;
    }
    let depth = tree.node(start).depth();
    let mut bits = if depth < 64 {
        tree.bit_trail(light) >> depth
    } else {
        0
    };
    let (mut id, mut pmf) = (start, 1.0f32);
    while id != leaf {
        let Some(p) = left_probability(tree, id, x, n) else {
            return 0.0;
        };
        let Some((l, r)) = tree.node(id).children(id) else {
            return 0.0;
        };
        let left = bits & 1 == 0;
        pmf *= if left { p } else { 1.0 - p };
        id = if left { l } else { r };
        bits >>= 1;
    }
    pmf
}
