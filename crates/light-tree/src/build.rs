//! SAOH build (12 buckets, 3 axes), depth-first flattening, bit trails.
//!
//! A subtree with k lights has exactly 2k − 1 nodes, so every node's DFS id is known as
//! soon as its split is chosen: the two subtrees are built into disjoint slices of the
//! node array, in parallel (rayon) for large subtrees.

use crate::cone::Cone;
use crate::{
    BuildError, FLAG_HALF_SPACE, FLAG_LEAF, FLAG_TWO_SIDED, LightBounds, LightTree, MAX_DEPTH,
    Node, NodeExtra,
};
use glam::{Vec3, Vec3A};
use rayon::prelude::*;
use std::f32::consts::{FRAC_PI_2, PI};

const NUM_BUCKETS: usize = 12;
/// Nodes with at most this many lights evaluate every sorted split instead of binning.
const SMALL: usize = NUM_BUCKETS;
/// Subtrees at least this large are built with `rayon::join`.
const PAR_SUBTREE: usize = 2048;
/// Nodes at least this large bin their lights in parallel chunks.
const PAR_BIN: usize = 1 << 16;
const BIN_CHUNK: usize = 1 << 14;
/// Box extents are padded to this fraction of the parent's longest extent in the surface
/// area term, so that buckets of collinear or coincident lights (area 0) do not all cost 0.
const AREA_PAD: f32 = 1e-3;

#[derive(Clone, Copy, Debug)]
struct Prim {
    min: Vec3A,
    max: Vec3A,
    cone: Cone,
    power: f32,
    light: u32,
    two_sided: bool,
}

impl Prim {
    #[inline]
    fn centroid(&self) -> Vec3A {
        (self.min + self.max) * 0.5
    }
}

/// Aggregate bounds of a set of lights.
#[derive(Clone, Copy, Debug)]
struct Agg {
    min: Vec3A,
    max: Vec3A,
    cmin: Vec3A,
    cmax: Vec3A,
    cone: Cone,
    power: f64,
    power_sq: f64,
    count: u32,
    two_sided: bool,
}

impl Agg {
    const EMPTY: Agg = Agg {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
        cmin: Vec3A::INFINITY,
        cmax: Vec3A::NEG_INFINITY,
        cone: Cone::EMPTY,
        power: 0.0,
        power_sq: 0.0,
        count: 0,
        two_sided: false,
    };

    #[inline]
    fn add(&mut self, p: &Prim) {
        let c = p.centroid();
        self.min = self.min.min(p.min);
        self.max = self.max.max(p.max);
        self.cmin = self.cmin.min(c);
        self.cmax = self.cmax.max(c);
        self.cone = Cone::union(self.cone, p.cone);
        let pw = p.power as f64;
        self.power += pw;
        self.power_sq += pw * pw;
        self.count += 1;
        self.two_sided |= p.two_sided;
    }

    #[inline]
    fn merge(&mut self, o: &Agg) {
        if o.count == 0 {
            return;
        }
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
        self.cmin = self.cmin.min(o.cmin);
        self.cmax = self.cmax.max(o.cmax);
        self.cone = Cone::union(self.cone, o.cone);
        self.power += o.power;
        self.power_sq += o.power_sq;
        self.count += o.count;
        self.two_sided |= o.two_sided;
    }

    fn of(prims: &[Prim]) -> Agg {
        let mut a = Agg::EMPTY;
        for p in prims {
            a.add(p);
        }
        a
    }

    /// SAOH cost term Φ · M_A · M_Ω (surface area with padded extents).
    #[inline]
    fn cost(&self, pad: f32) -> f64 {
        let e = (self.max - self.min).max(Vec3A::splat(pad)).as_dvec3();
        let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
        self.power * area * self.cone.measure() as f64
    }
}

fn validate(i: usize, l: &LightBounds) -> Result<Prim, BuildError> {
    let finite = l.aabb_min.is_finite()
        && l.aabb_max.is_finite()
        && l.axis.is_finite()
        && l.theta_o.is_finite()
        && l.theta_e.is_finite()
        && l.power.is_finite();
    if !finite {
        return Err(BuildError::NonFinite { light: i });
    }
    if l.power < 0.0 {
        return Err(BuildError::NegativePower {
            light: i,
            power: l.power,
        });
    }
    if l.aabb_min.cmpgt(l.aabb_max).any() {
        return Err(BuildError::InvertedBounds { light: i });
    }
    if !(0.0..=PI).contains(&l.theta_o) || !(0.0..=PI).contains(&l.theta_e) {
        return Err(BuildError::AngleOutOfRange { light: i });
    }
    let len = l.axis.length();
    let axis = if len > 1e-20 {
        l.axis / len
    } else if l.theta_o >= PI {
        Vec3::Z
    } else {
        return Err(BuildError::ZeroAxis { light: i });
    };
    Ok(Prim {
        min: l.aabb_min.into(),
        max: l.aabb_max.into(),
        cone: Cone {
            axis,
            theta_o: l.theta_o,
            theta_e: l.theta_e,
        },
        power: l.power,
        light: i as u32,
        two_sided: l.two_sided,
    })
}

fn make_node(agg: &Agg, depth: u32, child_or_light: u32, leaf: bool) -> (Node, NodeExtra) {
    let cone = agg.cone;
    let mut flags = 0;
    if leaf {
        flags |= FLAG_LEAF;
    }
    if agg.two_sided {
        flags |= FLAG_TWO_SIDED;
    } else if cone.theta_o + cone.theta_e <= FRAC_PI_2 {
        flags |= FLAG_HALF_SPACE;
    }
    (
        Node {
            aabb_min: agg.min.into(),
            aabb_max: agg.max.into(),
            radius: 0.5 * (agg.max - agg.min).length(),
            axis: cone.axis,
            power: agg.power as f32,
            cos_theta_o: cone.theta_o.cos(),
            cos_theta_e: cone.theta_e.cos(),
            num_lights: agg.count,
            child_or_light,
            depth: depth as u8,
            flags,
        },
        NodeExtra {
            theta_o: cone.theta_o,
            theta_e: cone.theta_e,
            power_sq_sum: agg.power_sq as f32,
            power_cv2: power_cv2(agg.count, agg.power, agg.power_sq) as f32,
        },
    )
}

/// V[Φ]/E[Φ]² of `n` lights of total power `sum` and Σ Φ² `sum_sq`, with the sample variance
/// (n − 1): n·(n·ΣΦ²/Φ² − 1)/(n − 1); 0 for one light or zero total power.
// `!(sum > 0.0)` is meant to be true for NaN as well as for sum ≤ 0.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn power_cv2(n: u32, sum: f64, sum_sq: f64) -> f64 {
    if n <= 1 || !(sum > 0.0) {
        return 0.0;
    }
    let n = n as f64;
    (n * (n * sum_sq / (sum * sum) - 1.0) / (n - 1.0)).max(0.0)
}

#[inline]
fn ceil_log2(n: usize) -> u32 {
    if n <= 1 {
        0
    } else {
        usize::BITS - (n - 1).leading_zeros()
    }
}

/// Bucket of centroid coordinate `c` on an axis with origin `o` and `scale` = 12 / extent.
#[inline]
fn bucket(c: f32, o: f32, scale: f32) -> usize {
    (((c - o) * scale) as usize).min(NUM_BUCKETS - 1)
}

type Bins = [[Agg; NUM_BUCKETS]; 3];

fn bin(prims: &[Prim], origin: Vec3A, scale: Vec3A, active: [bool; 3]) -> Bins {
    let mut bins = [[Agg::EMPTY; NUM_BUCKETS]; 3];
    for p in prims {
        let c = p.centroid();
        for a in 0..3 {
            if active[a] {
                bins[a][bucket(c[a], origin[a], scale[a])].add(p);
            }
        }
    }
    bins
}

fn merge_bins(mut x: Bins, y: Bins) -> Bins {
    for a in 0..3 {
        for b in 0..NUM_BUCKETS {
            x[a][b].merge(&y[a][b]);
        }
    }
    x
}

/// Chooses the split of `prims` (described by `agg`) and partitions them in place.
/// Returns (number of lights on the left, left aggregate, right aggregate).
fn split(prims: &mut [Prim], agg: &Agg, depth: u32, max_depth: u32) -> (usize, Agg, Agg) {
    let n = prims.len();
    let cext = agg.cmax - agg.cmin;
    let ext = agg.max - agg.min;
    let longest = ext.max_element();
    let active = [cext.x > 0.0, cext.y > 0.0, cext.z > 0.0];
    // Children sit at depth + 1 and need ceil_log2(k) more levels for k lights.
    let budget = max_depth - (depth + 1);
    if active.iter().any(|&a| a) && n > 2 {
        let scale = Vec3A::select(
            cext.cmpgt(Vec3A::ZERO),
            Vec3A::splat(NUM_BUCKETS as f32) / cext,
            Vec3A::ZERO,
        );
        let pad = AREA_PAD * longest;
        if n <= SMALL {
            return split_small(prims, cext, longest, ext, pad, budget);
        }
        let bins = if n >= PAR_BIN {
            // Collected in chunk order and folded sequentially: the cone union is not
            // associative, and a fixed order keeps the build deterministic.
            let parts: Vec<Bins> = prims
                .par_chunks(BIN_CHUNK)
                .map(|ch| bin(ch, agg.cmin, scale, active))
                .collect();
            parts
                .into_iter()
                .fold([[Agg::EMPTY; NUM_BUCKETS]; 3], merge_bins)
        } else {
            bin(prims, agg.cmin, scale, active)
        };
        let mut best: Option<(f64, usize, usize, Agg, Agg)> = None;
        for a in 0..3 {
            if !active[a] {
                continue;
            }
            let kr = (longest / ext[a]) as f64;
            let b = &bins[a];
            let mut right = [Agg::EMPTY; NUM_BUCKETS];
            let mut acc = Agg::EMPTY;
            for i in (1..NUM_BUCKETS).rev() {
                acc.merge(&b[i]);
                right[i] = acc;
            }
            let mut left = Agg::EMPTY;
            for i in 0..NUM_BUCKETS - 1 {
                // An empty bucket repeats the previous candidate's partition.
                if b[i].count == 0 {
                    continue;
                }
                left.merge(&b[i]);
                let r = &right[i + 1];
                if r.count == 0 {
                    break;
                }
                let cost = kr * (left.cost(pad) + r.cost(pad));
                if cost.is_finite() && best.as_ref().is_none_or(|bst| cost < bst.0) {
                    best = Some((cost, a, i, left, *r));
                }
            }
        }
        if let Some((cost, a, i, l, r)) = best {
            let deep = ceil_log2(l.count.max(r.count) as usize);
            if cost > 0.0 && deep <= budget {
                let (o, s) = (agg.cmin[a], scale[a]);
                let mid = partition(prims, |p| bucket(p.centroid()[a], o, s) <= i);
                debug_assert_eq!(mid, l.count as usize);
                return (mid, l, r);
            }
        }
    }
    median_split(prims, cext)
}

/// Orders lights by centroid along `axis`, ties by light index (deterministic).
#[inline]
fn by_axis(axis: usize) -> impl Fn(&Prim, &Prim) -> std::cmp::Ordering {
    move |p, q| {
        p.centroid()[axis]
            .total_cmp(&q.centroid()[axis])
            .then(p.light.cmp(&q.light))
    }
}

/// SAOH for nodes of at most `SMALL` lights: every split of the centroid-sorted order is a
/// candidate on each axis. That is a superset of the 12 bucket boundaries, and it avoids
/// setting up 36 buckets for a handful of lights (the bulk of all nodes).
fn split_small(
    prims: &mut [Prim],
    cext: Vec3A,
    longest: f32,
    ext: Vec3A,
    pad: f32,
    budget: u32,
) -> (usize, Agg, Agg) {
    let n = prims.len();
    let active = [cext.x > 0.0, cext.y > 0.0, cext.z > 0.0];
    let mut suffix = [Agg::EMPTY; SMALL];
    // Sort small index arrays rather than the 64-byte lights themselves.
    let mut order = [[0u8; SMALL]; 3];
    let mut best: Option<(f64, usize, usize, Agg, Agg)> = None;
    for a in 0..3 {
        if !active[a] {
            continue;
        }
        let idx = &mut order[a][..n];
        for (k, v) in idx.iter_mut().enumerate() {
            *v = k as u8;
        }
        let cmp = by_axis(a);
        idx.sort_unstable_by(|&i, &j| cmp(&prims[i as usize], &prims[j as usize]));
        let kr = (longest / ext[a]) as f64;
        let mut acc = Agg::EMPTY;
        for i in (1..n).rev() {
            acc.add(&prims[idx[i] as usize]);
            suffix[i] = acc;
        }
        let mut left = Agg::EMPTY;
        for i in 0..n - 1 {
            left.add(&prims[idx[i] as usize]);
            let cost = kr * (left.cost(pad) + suffix[i + 1].cost(pad));
            if cost.is_finite() && best.as_ref().is_none_or(|b| cost < b.0) {
                best = Some((cost, a, i + 1, left, suffix[i + 1]));
            }
        }
    }
    match best {
        Some((cost, a, mid, l, r)) if cost > 0.0 && ceil_log2(mid.max(n - mid)) <= budget => {
            let mut tmp = [prims[0]; SMALL];
            tmp[..n].copy_from_slice(prims);
            for (dst, &src) in prims.iter_mut().zip(&order[a][..n]) {
                *dst = tmp[src as usize];
            }
            (mid, l, r)
        }
        _ => median_split(prims, cext),
    }
}

fn median_split(prims: &mut [Prim], cext: Vec3A) -> (usize, Agg, Agg) {
    let mid = prims.len() / 2;
    if cext.max_element() > 0.0 {
        prims.select_nth_unstable_by(mid, by_axis(cext.max_position()));
    }
    let (l, r) = prims.split_at(mid);
    (mid, Agg::of(l), Agg::of(r))
}

/// In-place partition; returns the number of elements satisfying `pred` (moved to the front).
fn partition(v: &mut [Prim], pred: impl Fn(&Prim) -> bool) -> usize {
    let mut i = 0;
    let mut j = v.len();
    loop {
        while i < j && pred(&v[i]) {
            i += 1;
        }
        while i < j && !pred(&v[j - 1]) {
            j -= 1;
        }
        if i >= j {
            return i;
        }
        v.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

fn build_rec(
    prims: &mut [Prim],
    nodes: &mut [Node],
    extra: &mut [NodeExtra],
    agg: Agg,
    depth: u32,
    max_depth: u32,
    base: u32,
) {
    let n = prims.len();
    debug_assert_eq!(nodes.len(), 2 * n - 1);
    debug_assert!(depth <= max_depth);
    if n == 1 {
        let (node, bb) = make_node(&agg, depth, prims[0].light, true);
        nodes[0] = node;
        extra[0] = bb;
        return;
    }
    let (mid, lagg, ragg) = split(prims, &agg, depth, max_depth);
    let right_id = base + 2 * mid as u32;
    let (node, bb) = make_node(&agg, depth, right_id, false);
    nodes[0] = node;
    extra[0] = bb;
    let (lp, rp) = prims.split_at_mut(mid);
    let (ln, rn) = nodes[1..].split_at_mut(2 * mid - 1);
    let (lb, rb) = extra[1..].split_at_mut(2 * mid - 1);
    if n >= PAR_SUBTREE {
        rayon::join(
            || build_rec(lp, ln, lb, lagg, depth + 1, max_depth, base + 1),
            || build_rec(rp, rn, rb, ragg, depth + 1, max_depth, right_id),
        );
    } else {
        build_rec(lp, ln, lb, lagg, depth + 1, max_depth, base + 1);
        build_rec(rp, rn, rb, ragg, depth + 1, max_depth, right_id);
    }
}

impl LightTree {
    /// Builds the tree. Errors on an empty list, more than 2³¹ − 1 lights, non-finite fields,
    /// negative power, inverted boxes, angles outside [0, π] or a zero axis with θo < π.
    pub fn build(lights: &[LightBounds]) -> Result<LightTree, BuildError> {
        Self::build_with_max_depth(lights, MAX_DEPTH)
    }

    /// `build` with a smaller depth limit (tests of the median-split fallback).
    pub(crate) fn build_with_max_depth(
        lights: &[LightBounds],
        max_depth: u32,
    ) -> Result<LightTree, BuildError> {
        let n = lights.len();
        assert!(max_depth <= MAX_DEPTH && ceil_log2(n) <= max_depth);
        if n == 0 {
            return Err(BuildError::NoLights);
        }
        if n > (i32::MAX as usize) {
            return Err(BuildError::TooManyLights(n));
        }
        let mut prims: Vec<Prim> = lights
            .par_iter()
            .enumerate()
            .map(|(i, l)| validate(i, l))
            .collect::<Result<_, _>>()?;
        let num_nodes = 2 * n - 1;
        let root_agg = if n >= PAR_BIN {
            let parts: Vec<Agg> = prims.par_chunks(BIN_CHUNK).map(Agg::of).collect();
            parts.iter().fold(Agg::EMPTY, |mut a, b| {
                a.merge(b);
                a
            })
        } else {
            Agg::of(&prims)
        };
        let dummy = make_node(&Agg::EMPTY, 0, 0, true);
        let mut nodes = vec![dummy.0; num_nodes];
        let mut extra = vec![dummy.1; num_nodes];
        build_rec(
            &mut prims, &mut nodes, &mut extra, root_agg, 0, max_depth, 0,
        );
        drop(prims);

        // Bit trails: children follow their parent in DFS order, so one forward pass works.
        let mut node_trail = vec![0u64; num_nodes];
        let mut leaf_of = vec![0u32; n];
        let mut trails = vec![0u64; n];
        for (id, node) in nodes.iter().enumerate() {
            let t = node_trail[id];
            if let Some(light) = node.light() {
                leaf_of[light] = id as u32;
                trails[light] = t;
            } else {
                node_trail[id + 1] = t;
                node_trail[node.child_or_light as usize] = t | (1u64 << node.depth());
            }
        }
        let compact = crate::compact::Compact::build(&nodes, &extra)?;
        Ok(LightTree {
            nodes,
            extra,
            leaf_of,
            trails,
            compact,
        })
    }
}
