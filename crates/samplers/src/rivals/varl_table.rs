//! What `varl` learns per region (position cell × normal bucket, the grid of `learned`): its
//! own cut of the light tree, refined coarse to fine between passes, and a distribution over
//! that cut learnt by stochastic approximation from the passes' observed contributions.
//!
//! After each pass, for every region with observations (merged in pixel order):
//!
//! 1. **Target.** t_c = Y_c / Σ Y, Y_c the sum over the pass's observations in the region of
//!    the light sample's estimate lum(f·V)/p whose light lies under cut node c (shadowed, so
//!    visibility is in it).
//! 2. **Successive approximation.** T ← T + (t − T)/k, k the region's passes with a target
//!    (step 1/k: T is the running mean of the targets, which converges to the region's
//!    contribution distribution over its cut); the sampling pmf moves from the prior to T as
//!    k/(k + 1) ([`super::varl`]).
//! 3. **Refinement.** A node c with at least [`SPLIT_SAMPLES`] observations since it entered the
//!    cut, a share T_c ≥ 1/(2K) (K the cut's size) and a squared coefficient of variation of its
//!    observations above [`SPLIT_CV2`] (its lights are not sampled in proportion to their
//!    contributions: the descent inside it is wrong or they are partly occluded) is replaced by
//!    its two children, T_c shared between them in proportion to what each one's observations
//!    carried; the largest T_c first, until the cut has `max_cut` nodes.
use super::varl::{INITIAL_CUT, MAX_CUT};
use light_tree::{LightTree, NodeId};
use render_core::estimator::PIXEL_MEMORY;
use std::collections::HashMap;

/// Observations a node needs before it may be split.
pub const SPLIT_SAMPLES: u32 = 32;
/// Squared coefficient of variation of a node's observations above which it is split.
pub const SPLIT_CV2: f64 = 1.0;
/// Memory slots of one observation.
pub const SLOTS: usize = 7;
const _: () = assert!(SLOTS <= PIXEL_MEMORY);
const KEY_PART_BITS: u32 = 21;

/// One node of a region's cut and what was observed of it.
#[derive(Clone, Copy, Debug, Default)]
pub struct CutNode {
    /// The tree node.
    pub id: NodeId,
    /// Its learnt share T_c of the region's contribution.
    pub share: f32,
    n: u32,
    sum: f64,
    sum_sq: f64,
    /// What the observations under its left and right child carried.
    sides: [f64; 2],
    /// The current pass's Σ y.
    pass_sum: f64,
}

/// One region: its cut (sorted by DFS id) and its passes with a target.
#[derive(Clone, Debug, Default)]
pub struct Region {
    /// The cut's nodes.
    pub nodes: Vec<CutNode>,
    /// Passes that brought a target.
    pub passes: u32,
}

impl Region {
    fn initial(cut: &[NodeId]) -> Region {
        Region {
            nodes: cut
                .iter()
                .map(|&id| CutNode {
                    id,
                    ..Default::default()
                })
                .collect(),
            passes: 0,
        }
    }

    /// The index of the cut node holding `light` (the cut partitions the lights).
    pub fn node_of(&self, tree: &LightTree, light: usize) -> Option<usize> {
        node_of(tree, self.nodes.iter().map(|n| n.id), light)
    }
}

/// The index in `cut` (sorted by DFS id, a partition of the lights) of the node holding `light`.
pub fn node_of(
    tree: &LightTree,
    cut: impl ExactSizeIterator<Item = NodeId> + Clone,
    light: usize,
) -> Option<usize> {
    let leaf = tree.leaf_of(light);
    let k = cut.clone().take_while(|&id| id <= leaf).count();
    let i = k.checked_sub(1)?;
    let id = cut.clone().nth(i)?;
    let (first, last) = tree.subtree_range(id);
    (first..=last).contains(&leaf).then_some(i)
}

/// One light sample's observation, left in its pixel's memory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    /// The region of the shading point.
    pub key: u64,
    /// The light sampled.
    pub light: u32,
    /// lum(f·V)/p: the sample's estimate (0 when occluded).
    pub y: f32,
}

impl Observation {
    /// Writes it under pass stamp `stamp` (all but `y` exact integers in f32).
    pub fn write(&self, memory: &mut [f32], stamp: u32) {
        let mask = (1u64 << KEY_PART_BITS) - 1;
        memory[0] = stamp as f32;
        for j in 0..3 {
            memory[1 + j] = ((self.key >> (KEY_PART_BITS * j as u32)) & mask) as f32;
        }
        memory[4] = (self.light & 0xffff) as f32;
        memory[5] = (self.light >> 16) as f32;
        memory[6] = self.y;
    }

    /// The observation written under `stamp`, if any.
    pub fn read(memory: &[f32], stamp: u32) -> Option<Observation> {
        if memory[0] != stamp as f32 {
            return None;
        }
        let key = (0..3).fold(0u64, |k, j| {
            k | ((memory[1 + j] as u64) << (KEY_PART_BITS * j as u32))
        });
        Some(Observation {
            key,
            light: memory[4] as u32 | ((memory[5] as u32) << 16),
            y: memory[6],
        })
    }
}

/// Every region's cut and distribution, frozen during a pass.
#[derive(Debug, Default)]
pub struct VarlTable {
    regions: HashMap<u64, Region>,
    /// The cut a region starts from (breadth-first, [`INITIAL_CUT`] nodes).
    pub initial: Vec<NodeId>,
    /// Most nodes in a region's cut.
    pub max_cut: usize,
    /// Most regions kept.
    pub max_regions: usize,
    /// Passes merged.
    pub pass: u32,
    /// Observations dropped for want of a region.
    pub dropped: u64,
}

impl VarlTable {
    /// An empty table over `tree` (None: no lights).
    pub fn new(tree: Option<&LightTree>, max_cut: usize, max_regions: usize) -> VarlTable {
        let initial = tree.map_or_else(Vec::new, |t| t.cut(INITIAL_CUT, |_| true).nodes);
        VarlTable {
            initial,
            max_cut: max_cut.min(MAX_CUT),
            max_regions,
            ..Default::default()
        }
    }

    /// Forgets everything learnt.
    pub fn clear(&mut self) {
        self.regions.clear();
        self.pass = 0;
        self.dropped = 0;
    }

    /// The region `key`, if anything was learnt there.
    pub fn region(&self, key: u64) -> Option<&Region> {
        self.regions.get(&key)
    }

    /// Regions held.
    pub fn len(&self) -> usize {
        self.regions.len()
    }

    /// Whether no region is held.
    pub fn is_empty(&self) -> bool {
        self.regions.is_empty()
    }

    /// Total cut nodes over all regions.
    pub fn nodes(&self) -> usize {
        self.regions.values().map(|r| r.nodes.len()).sum()
    }

    /// Merges the pass's observations (from `memory[base..]` of each pixel, in pixel order),
    /// then updates every region that observed something and refines its cut.
    pub fn merge_pass<'a>(
        &mut self,
        tree: &LightTree,
        pixels: &mut dyn Iterator<Item = &'a [f32; PIXEL_MEMORY]>,
        base: usize,
    ) {
        let stamp = self.pass + 1;
        let mut touched = Vec::new();
        for m in pixels {
            let Some(o) = Observation::read(&m[base..], stamp) else {
                continue;
            };
            if (o.light as usize) >= tree.num_lights() {
                continue;
            }
            if !self.regions.contains_key(&o.key) {
                if self.regions.len() >= self.max_regions {
                    self.dropped += 1;
                    continue;
                }
                self.regions.insert(o.key, Region::initial(&self.initial));
            }
            let region = self.regions.get_mut(&o.key).expect("inserted above");
            let Some(c) = region.node_of(tree, o.light as usize) else {
                continue;
            };
            observe(tree, &mut region.nodes[c], o);
            touched.push(o.key);
        }
        touched.sort_unstable();
        touched.dedup();
        for key in touched {
            let region = self.regions.get_mut(&key).expect("touched regions exist");
            update(region);
            refine(tree, region, self.max_cut);
        }
        self.pass = stamp;
    }
}

/// Adds observation `o` to cut node `node`.
fn observe(tree: &LightTree, node: &mut CutNode, o: Observation) {
    let y = if o.y.is_finite() && o.y > 0.0 {
        o.y as f64
    } else {
        0.0
    };
    node.n += 1;
    node.sum += y;
    node.sum_sq += y * y;
    node.pass_sum += y;
    if let Some((l, _)) = tree.node(node.id).children(node.id) {
        let leaf = tree.leaf_of(o.light as usize);
        let (first, last) = tree.subtree_range(l);
        let side = !(first..=last).contains(&leaf) as usize;
        node.sides[side] += y;
    }
}

/// Step 2 of the module docs: the pass's target into the running mean.
fn update(region: &mut Region) {
    let total: f64 = region.nodes.iter().map(|n| n.pass_sum).sum();
    if total > 0.0 {
        region.passes += 1;
        let step = 1.0 / region.passes as f64;
        for n in &mut region.nodes {
            let t = n.pass_sum / total;
            n.share = (n.share as f64 + (t - n.share as f64) * step) as f32;
        }
    }
    for n in &mut region.nodes {
        n.pass_sum = 0.0;
    }
}

/// Step 3 of the module docs.
fn refine(tree: &LightTree, region: &mut Region, max_cut: usize) {
    let k = region.nodes.len();
    let floor = 0.5 / k as f32;
    let mut wanted: Vec<usize> = (0..k)
        .filter(|&i| {
            let n = &region.nodes[i];
            let interior = !tree.node(n.id).is_leaf();
            interior && n.n >= SPLIT_SAMPLES && n.share >= floor && n.sum > 0.0 && {
                let cv2 = n.n as f64 * n.sum_sq / (n.sum * n.sum) - 1.0;
                cv2 > SPLIT_CV2
            }
        })
        .collect();
    wanted.sort_by(|&a, &b| {
        let (na, nb) = (&region.nodes[a], &region.nodes[b]);
        nb.share.total_cmp(&na.share).then(na.id.cmp(&nb.id))
    });
    wanted.truncate(max_cut.saturating_sub(k));
    if wanted.is_empty() {
        return;
    }
    let mut next = Vec::with_capacity(k + wanted.len());
    for (i, n) in region.nodes.iter().enumerate() {
        if !wanted.contains(&i) {
            next.push(*n);
            continue;
        }
        let (l, r) = tree.node(n.id).children(n.id).expect("interior");
        // A side with nothing observed keeps a small part of the share.
        let eps = 0.05 * (n.sides[0] + n.sides[1]);
        let left = (n.sides[0] + eps) / (n.sides[0] + n.sides[1] + 2.0 * eps);
        let child = |id, share: f64| CutNode {
            id,
            share: (n.share as f64 * share) as f32,
            ..Default::default()
        };
        next.push(child(l, left));
        next.push(child(r, 1.0 - left));
    }
    next.sort_by_key(|n| n.id);
    region.nodes = next;
}
