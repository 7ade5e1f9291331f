//! What the learned descent keeps: per region, the tallies of every learnt pair of sibling
//! nodes, and the observation a light sample leaves in its pixel's memory until the merge
//! after its pass.
use super::regions::KeyHasher;
use light_tree::LightTree;
use render_core::estimator::PIXEL_MEMORY;
use std::collections::HashMap;
use std::hash::BuildHasherDefault;

/// Deepest tree level learnt: an observation keeps one scale per level below the root, two
/// to a pixel-memory float, beside its stamp, region key, light and contribution.
pub const LEVELS: usize = 2 * (PIXEL_MEMORY - 6);
/// Most learnt pairs per region: the top levels of larger trees, as many as fit.
pub const MAX_PAIRS: usize = 4096;
/// Most bytes the tallies of all regions may take (the region cap is lowered to fit).
pub const MAX_TABLE_BYTES: usize = 256 << 20;

/// What one region learnt of one node: the sum of the ratios observed through it and their
/// number (misses included, with ratio 0).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodeTally {
    /// Σ ρ_n.
    pub ratio_sum: f32,
    /// Samples that went through the node.
    pub rays: u32,
}

/// Region key → per learnt pair of siblings (the children of an interior node of the learnt
/// levels) their tallies side by side, which is all a step of the descent reads.
#[derive(Clone)]
pub struct DescentTable {
    pub(crate) index: HashMap<u64, u32, BuildHasherDefault<KeyHasher>>,
    pub(crate) tallies: Vec<[NodeTally; 2]>,
    pub(crate) pairs: usize,
    pub(crate) max_regions: usize,
    /// Complete passes merged so far (the stamp of the pass now running is `pass + 1`).
    pub pass: u32,
    /// Observations dropped because the table was full.
    pub dropped: u64,
}

impl DescentTable {
    pub(crate) fn new(pairs: usize, max_regions: usize) -> DescentTable {
        DescentTable {
            index: HashMap::default(),
            tallies: Vec::new(),
            pairs,
            max_regions,
            pass: 0,
            dropped: 0,
        }
    }

    /// The tallies of region `key`, if it has been seen: per learnt pair, left and right.
    pub fn region(&self, key: u64) -> Option<&[[NodeTally; 2]]> {
        let i = *self.index.get(&key)? as usize * self.pairs;
        Some(&self.tallies[i..i + self.pairs])
    }

    /// Regions stored.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// Whether no region is stored.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// Bytes of the tallies, the factors and the map's entries at their capacity.
    pub fn memory_bytes(&self) -> usize {
        self.tallies.capacity() * std::mem::size_of::<[NodeTally; 2]>()
            + self.index.capacity() * (std::mem::size_of::<(u64, u32)>() + 1)
    }

    /// The index of region `key`, added if new and there is room.
    pub(crate) fn region_index(&mut self, key: u64) -> Option<usize> {
        match self.index.get(&key) {
            Some(&i) => Some(i as usize),
            None if self.index.len() < self.max_regions => {
                let i = self.index.len();
                self.index.insert(key, i as u32);
                let k = self.pairs;
                self.tallies
                    .resize(self.tallies.len() + k, [NodeTally::default(); 2]);
                Some(i)
            }
            None => None,
        }
    }
}

/// The learnt pairs of `tree`: per node the index of its children's pair, in DFS order, for the
/// interior nodes above the deepest depth D ≤ [`LEVELS`] at which they number at most
/// [`MAX_PAIRS`] (`u32::MAX` for the others), and their number.
pub fn learnt_pairs(tree: &LightTree) -> (Vec<u32>, usize) {
    let mut per_depth = [0usize; LEVELS + 1];
    for node in tree.nodes() {
        if !node.is_leaf() && (node.depth() as usize) < LEVELS {
            per_depth[node.depth() as usize] += 1;
        }
    }
    let mut depth = 0;
    let mut total = 0;
    while depth < LEVELS && total + per_depth[depth] <= MAX_PAIRS {
        total += per_depth[depth];
        depth += 1;
    }
    let mut count = 0usize;
    let pair_of = tree
        .nodes()
        .iter()
        .map(|node| {
            if node.is_leaf() || node.depth() as usize >= depth {
                u32::MAX
            } else {
                count += 1;
                (count - 1) as u32
            }
        })
        .collect();
    (pair_of, count)
}

/// Bits of one level's code: a scale's f32 exponent, 7 bits of it (2⁻⁶³ to 2⁶⁴), and the top 5
/// bits of its mantissa, rounded to nearest (within 1.6 %); 0 for a zero scale.
const CODE_BITS: u32 = 12;
const MANTISSA_BITS: u32 = 5;
/// The f32 exponent of code exponent 1 (biased: 2⁻⁶³).
const LOWEST_EXPONENT: u32 = 127 - 63;

/// The code of `scale` (≥ 0), from its bits: no logarithm on a sample's path.
fn encode(scale: f32) -> u32 {
    if !(scale > 0.0 && scale.is_finite()) {
        return 0;
    }
    let drop = 23 - MANTISSA_BITS;
    // Round the mantissa to its top bits (a carry moves into the exponent, as it should).
    let bits = scale.to_bits() + (1 << (drop - 1));
    let exponent = (bits >> 23) as i64 - LOWEST_EXPONENT as i64 + 1;
    let top = (1i64 << (CODE_BITS - MANTISSA_BITS)) - 1;
    if exponent < 1 {
        return 1 << MANTISSA_BITS;
    }
    if exponent > top {
        return (1 << CODE_BITS) - 1;
    }
    (exponent as u32) << MANTISSA_BITS | ((bits >> drop) & ((1 << MANTISSA_BITS) - 1))
}

/// The scale of `code`.
fn decode(code: u32) -> f32 {
    if code == 0 {
        return 0.0;
    }
    let exponent = (code >> MANTISSA_BITS) + LOWEST_EXPONENT - 1;
    let mantissa = code & ((1 << MANTISSA_BITS) - 1);
    f32::from_bits(exponent << 23 | mantissa << (23 - MANTISSA_BITS))
}

/// What one light sample taught: its region, its light, its contribution
/// Y = lum(f·L·V)/(P(l) p_point) (0 when occluded) and, per level of its path below the root
/// (depth 1 on), the scale P(n)/I_n that makes Y the node's ratio ρ_n = Y·P(n)/I_n (0 past
/// its leaf).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DescentObservation {
    /// The region of the shading point.
    pub key: u64,
    /// The light sampled.
    pub light: u32,
    /// Its contribution Y.
    pub y: f32,
    /// P(n)/I_n per level.
    pub scales: [f32; LEVELS],
}

impl DescentObservation {
    /// Writes it into a pixel's `memory` under pass `stamp`: the stamp, the key in three
    /// 21-bit parts, the light and Y, then the scales as 12-bit codes two to a float (every
    /// value but Y an integer an f32 holds exactly). The scales come back within 1.6 %.
    pub fn write(&self, memory: &mut [f32], stamp: u32) {
        let mask = (1u64 << 21) - 1;
        memory[0] = stamp as f32;
        for j in 0..3 {
            memory[1 + j] = ((self.key >> (21 * j as u32)) & mask) as f32;
        }
        memory[4] = self.light as f32;
        memory[5] = self.y;
        for (slot, pair) in memory[6..PIXEL_MEMORY]
            .iter_mut()
            .zip(self.scales.chunks(2))
        {
            *slot = (encode(pair[0]) | encode(pair[1]) << CODE_BITS) as f32;
        }
    }

    /// Marks `memory` as holding no observation (its stamp 0, which no pass has).
    pub fn clear(memory: &mut [f32]) {
        memory[0] = 0.0;
    }

    /// The observation of pass `stamp` in `memory`, if it holds one.
    pub fn read(memory: &[f32; PIXEL_MEMORY], stamp: u32) -> Option<DescentObservation> {
        if memory[0] != stamp as f32 {
            return None;
        }
        let key = (0..3).fold(0u64, |k, j| k | ((memory[1 + j] as u64) << (21 * j as u32)));
        let mut scales = [0.0f32; LEVELS];
        for (pair, &slot) in scales.chunks_mut(2).zip(&memory[6..PIXEL_MEMORY]) {
            let code = slot as u32;
            pair[0] = decode(code & ((1 << CODE_BITS) - 1));
            pair[1] = decode(code >> CODE_BITS);
        }
        Some(DescentObservation {
            key,
            light: memory[4] as u32,
            y: memory[5],
            scales,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn observations_round_trip_through_pixel_memory() {
        let mut scales = [0.0f32; LEVELS];
        for (d, s) in scales.iter_mut().enumerate().take(LEVELS - 3) {
            *s = 1.7f32.powi(d as i32 * 3 - 20);
        }
        scales[2] = 1.0;
        let o = DescentObservation {
            key: (1 << 62) | 12_345,
            light: (1 << 24) - 1,
            y: 0.375,
            scales,
        };
        let mut m = [0.0f32; PIXEL_MEMORY];
        o.write(&mut m, 7);
        assert!(DescentObservation::read(&m, 8).is_none());
        let back = DescentObservation::read(&m, 7).unwrap();
        assert_eq!((back.key, back.light, back.y), (o.key, o.light, o.y));
        assert_eq!(back.scales[2], 1.0, "a scale of 1 is exact");
        for (a, b) in back.scales.iter().zip(&o.scales) {
            if *b == 0.0 {
                assert_eq!(*a, 0.0);
            } else {
                assert!((a / b - 1.0).abs() < 0.016, "{a} vs {b}");
            }
        }
    }
}
