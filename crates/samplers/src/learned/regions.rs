//! Regions of shading points and what was learnt in each: a hash grid over positions (cells of
//! a fixed size) × six normal buckets (the normal's major axis and its sign), and per region
//! the tallies of every cluster of the fixed cut (visibility and contribution), capped in
//! number.
//!
//! The table is written only between passes (`merge_pass`, pixels in order) and read only
//! during them, so what a sample sees is fixed before it is drawn and is the same for any
//! thread count.
use render_core::Vec3;
use render_core::estimator::PIXEL_MEMORY;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Bits of one cell coordinate in a region key (cells beyond are clamped to the border).
const COORD_BITS: u32 = 20;
/// Bits of each of the three pixel-memory floats the key is stored in (exact in an f32).
const KEY_PART_BITS: u32 = 21;

/// Which region a shading point falls in.
#[derive(Clone, Copy, Debug)]
pub struct RegionGrid {
    /// Lower corner of the grid (the scene's bounds).
    pub origin: Vec3,
    /// Edge length of a cell.
    pub cell: f32,
}

impl RegionGrid {
    /// Cells of `diagonal / cells_per_diagonal` from the scene's lower corner.
    pub fn new(lo: Vec3, diagonal: f32, cells_per_diagonal: f32) -> RegionGrid {
        let cell = if diagonal > 0.0 && diagonal.is_finite() {
            diagonal / cells_per_diagonal
        } else {
            1.0
        };
        RegionGrid { origin: lo, cell }
    }

    /// The region key of position `x` with normal `n`: cell coordinates (20 bits each) and the
    /// normal bucket (3 bits), 63 bits, one key per region (no hash collisions).
    pub fn key(&self, x: Vec3, n: Vec3) -> u64 {
        let max = ((1u32 << COORD_BITS) - 1) as f32;
        let c = ((x - self.origin) / self.cell)
            .floor()
            .clamp(Vec3::ZERO, Vec3::splat(max));
        let a = n.abs();
        let (axis, v) = if a.x >= a.y && a.x >= a.z {
            (0, n.x)
        } else if a.y >= a.z {
            (1, n.y)
        } else {
            (2, n.z)
        };
        let bucket = 2 * axis + (v < 0.0) as u64;
        ((c.x as u64) << (2 * COORD_BITS + 3))
            | ((c.y as u64) << (COORD_BITS + 3))
            | ((c.z as u64) << 3)
            | bucket
    }
}

/// Tallies of one cluster in one region: shadow rays traced towards it, how many of them
/// reached the light, and the sum of the contribution ratios they observed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tally {
    /// Shadow rays that reached the light.
    pub hits: u32,
    /// Shadow rays traced.
    pub rays: u32,
    /// Sum of the observed contribution ratios (0 for an occluded ray).
    pub ratio_sum: f32,
}

/// A splitmix64 finaliser as the map's hash: keys are already unique 63-bit values.
#[derive(Default)]
pub struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        let mut z = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 << 8) | b as u64;
        }
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = i;
    }
}

/// The learnt statistics: region key → one tally per cluster of the fixed cut.
pub struct RegionTable {
    index: HashMap<u64, u32, BuildHasherDefault<KeyHasher>>,
    tallies: Vec<Tally>,
    clusters: usize,
    max_regions: usize,
    /// Complete passes merged so far (the stamp of the pass now running is `pass + 1`).
    pub pass: u32,
    /// Observations dropped because the table was full.
    pub dropped: u64,
}

impl RegionTable {
    /// An empty table for `clusters` clusters, holding at most `max_regions` regions.
    pub fn new(clusters: usize, max_regions: usize) -> RegionTable {
        RegionTable {
            index: HashMap::default(),
            tallies: Vec::new(),
            clusters,
            max_regions,
            pass: 0,
            dropped: 0,
        }
    }

    /// Forgets everything (a new render).
    pub fn clear(&mut self) {
        self.index.clear();
        self.tallies.clear();
        self.pass = 0;
        self.dropped = 0;
    }

    /// The tallies of region `key`, if it has been seen.
    #[inline]
    pub fn region(&self, key: u64) -> Option<&[Tally]> {
        let i = *self.index.get(&key)? as usize * self.clusters;
        Some(&self.tallies[i..i + self.clusters])
    }

    /// Number of regions stored.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// Whether no region is stored.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// Bytes the table holds: the tallies and the map's entries (key, index and control
    /// byte per bucket, at its capacity).
    pub fn memory_bytes(&self) -> usize {
        self.tallies.capacity() * std::mem::size_of::<Tally>()
            + self.index.capacity() * (std::mem::size_of::<(u64, u32)>() + 1)
    }

    /// Adds one observation: a shadow ray towards cluster `cluster` from region `key`.
    /// `ratio`: its observed contribution over the cluster's prior (0 when occluded).
    pub fn add(&mut self, key: u64, cluster: usize, hit: bool, ratio: f32) {
        let k = self.clusters;
        let i = match self.index.get(&key) {
            Some(&i) => i as usize,
            None if self.index.len() < self.max_regions => {
                let i = self.index.len();
                self.index.insert(key, i as u32);
                self.tallies
                    .resize(self.tallies.len() + k, Tally::default());
                i
            }
            None => {
                self.dropped += 1;
                return;
            }
        };
        let t = &mut self.tallies[i * k + cluster];
        t.rays += 1;
        t.hits += hit as u32;
        t.ratio_sum += ratio;
    }

    /// Merges the observations the pass just finished left in the pixels' memory (in pixel
    /// order), then counts the pass as merged.
    /// `base`: the first of the observation's slots in the pixel memory.
    pub fn merge_pass<'a>(
        &mut self,
        pixels: &mut dyn Iterator<Item = &'a [f32; PIXEL_MEMORY]>,
        base: usize,
    ) {
        let stamp = self.pass + 1;
        for m in pixels {
            if let Some(o) = Observation::read(&m[base..], stamp)
                && o.cluster < self.clusters
            {
                self.add(o.key, o.cluster, o.hit, o.ratio);
            }
        }
        self.pass = stamp;
    }
}

/// One sample's observation, kept in its pixel's memory until the pass ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    /// The region of the shading point.
    pub key: u64,
    /// The cluster of the light sampled.
    pub cluster: usize,
    /// Whether its shadow ray reached the light.
    pub hit: bool,
    /// Observed contribution over the cluster's prior importance (0 when occluded).
    pub ratio: f32,
}

/// Pixel-memory slots: the pass stamp, three 21-bit parts of the key, the cluster, and the
/// ratio (0 for a miss, at least the smallest normal f32 for a hit).
pub const SLOTS: usize = 6;
const _: () = assert!(SLOTS <= PIXEL_MEMORY);

impl Observation {
    /// Writes the observation under pass stamp `stamp` (every value but the ratio an exact
    /// integer).
    pub fn write(&self, memory: &mut [f32], stamp: u32) {
        let mask = (1u64 << KEY_PART_BITS) - 1;
        memory[0] = stamp as f32;
        for j in 0..3 {
            memory[1 + j] = ((self.key >> (KEY_PART_BITS * j as u32)) & mask) as f32;
        }
        memory[4] = self.cluster as f32;
        memory[5] = if self.hit {
            self.ratio.max(f32::MIN_POSITIVE)
        } else {
            0.0
        };
    }

    /// Marks the pixel as having no observation in this pass.
    pub fn clear(memory: &mut [f32]) {
        memory[0] = 0.0;
    }

    /// The observation written under `stamp`, if any (older passes' are ignored).
    pub fn read(memory: &[f32], stamp: u32) -> Option<Observation> {
        if memory[0] != stamp as f32 {
            return None;
        }
        let key = (0..3).fold(0u64, |k, j| {
            k | ((memory[1 + j] as u64) << (KEY_PART_BITS * j as u32))
        });
        Some(Observation {
            key,
            cluster: memory[4] as usize,
            hit: memory[5] != 0.0,
            ratio: memory[5],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_separate_cells_and_normal_buckets_and_round_trip_through_memory() {
        let g = RegionGrid::new(Vec3::splat(-1.0), 64.0, 64.0);
        let k = g.key(Vec3::new(0.5, 0.5, 0.5), Vec3::Y);
        assert_eq!(k, g.key(Vec3::new(0.9, 0.1, 0.2), Vec3::new(0.1, 0.9, 0.0)));
        assert_ne!(k, g.key(Vec3::new(1.5, 0.5, 0.5), Vec3::Y));
        assert_ne!(k, g.key(Vec3::new(0.5, 0.5, 0.5), Vec3::NEG_Y));
        assert_ne!(k, g.key(Vec3::new(0.5, 0.5, 0.5), Vec3::X));
        let far = g.key(Vec3::splat(1e9), Vec3::Z);
        assert!(far < 1 << 63);
        let mut m = [0.0; PIXEL_MEMORY];
        let o = Observation {
            key: far,
            cluster: 63,
            hit: true,
            ratio: 0.375,
        };
        o.write(&mut m, 5);
        assert_eq!(Observation::read(&m, 5), Some(o));
        // A hit with a zero ratio still reads as a hit; a miss keeps no ratio.
        let zero = Observation { ratio: 0.0, ..o };
        zero.write(&mut m, 5);
        assert!(Observation::read(&m, 5).unwrap().hit);
        let miss = Observation { hit: false, ..o };
        miss.write(&mut m, 5);
        assert_eq!(Observation::read(&m, 5).unwrap().ratio, 0.0);
        assert_eq!(Observation::read(&m, 6), None);
        Observation::clear(&mut m);
        assert_eq!(Observation::read(&m, 5), None);
    }

    #[test]
    fn the_table_tallies_in_order_and_stops_at_its_cap() {
        let mut t = RegionTable::new(4, 2);
        t.add(10, 1, true, 0.5);
        t.add(10, 1, false, 0.0);
        t.add(20, 3, true, 2.0);
        t.add(30, 0, true, 1.0);
        assert_eq!(t.len(), 2);
        assert_eq!(t.dropped, 1);
        let tally = |hits, rays, ratio_sum| Tally {
            hits,
            rays,
            ratio_sum,
        };
        assert_eq!(t.region(10).unwrap()[1], tally(1, 2, 0.5));
        assert_eq!(t.region(20).unwrap()[3], tally(1, 1, 2.0));
        assert!(t.region(30).is_none());
        assert!(t.memory_bytes() >= 2 * 4 * 12);
        t.clear();
        assert!(t.is_empty() && t.pass == 0);
    }
}
