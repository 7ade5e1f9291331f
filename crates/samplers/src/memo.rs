//! A direct-mapped cache of per-node values (importances) of one shading point, or of
//! per-quad or per-oct values (the lanes of a four- or eight-wide descent step, keyed by quad
//! or oct index).
//!
//! A node's importance is a pure function of (node, shading point), so a cached value is
//! bit-identical to a recomputed one: sampling and every pdf replay see the same numbers
//! whether or not a slot was evicted. A slot is valid only under the current stamp, so moving
//! to the next shading point invalidates the cache without clearing it.
use light_tree::{LaneCache, NodeId};

const SLOTS: usize = 1024;

#[derive(Clone, Copy)]
struct Slot<V> {
    node: NodeId,
    stamp: u32,
    value: V,
}

/// The cache, of values `V` keyed by a node id (or a quad index).
pub struct Memo<V> {
    slots: Box<[Slot<V>]>,
    stamp: u32,
}

/// Node importances.
pub type NodeMemo = Memo<f32>;
/// The four lanes of a quad (`light_tree::LightTree::quad_nodes`), keyed by quad index.
pub type QuadMemo = Memo<[f32; 4]>;
/// The eight E&K lanes of an oct (`light_tree::LightTree::pmf_from_cached`), keyed by oct
/// index.
pub type OctMemo = Memo<[f32; 8]>;

impl<V: Copy + Default> Default for Memo<V> {
    fn default() -> Memo<V> {
        Memo {
            slots: vec![
                Slot {
                    node: NodeId::MAX,
                    stamp: 0,
                    value: V::default()
                };
                SLOTS
            ]
            .into_boxed_slice(),
            stamp: 1,
        }
    }
}

// A memo on its own (for users without a scratch struct of their own) comes from a per-thread
// pool too, so taking one does not allocate per shading point.
crate::scratch_pool!(NodeMemo, |m| m.invalidate());

impl<V: Copy> Memo<V> {
    /// Forgets every cached value (a new shading point).
    pub fn invalidate(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.slots.iter_mut().for_each(|s| s.stamp = 0);
            self.stamp = 1;
        }
    }

    /// The cached value of `node`, if any.
    #[inline]
    pub fn get(&self, node: NodeId) -> Option<V> {
        let s = &self.slots[Self::slot(node)];
        (s.node == node && s.stamp == self.stamp).then_some(s.value)
    }

    /// Stores `value` for `node` (which must be what `compute` would give it).
    #[inline]
    pub fn insert(&mut self, node: NodeId, value: V) {
        let stamp = self.stamp;
        self.slots[Self::slot(node)] = Slot { node, stamp, value };
    }

    #[inline]
    fn slot(node: NodeId) -> usize {
        // Fibonacci hashing: the top 10 bits of the product.
        (node.wrapping_mul(0x9E37_79B1) >> 22) as usize
    }

    /// The cached value of `node`, or `compute(node)` stored for next time.
    #[inline]
    pub fn get_or(&mut self, node: NodeId, compute: impl FnOnce(NodeId) -> V) -> V {
        let slot = Self::slot(node);
        let stamp = self.stamp;
        let s = &mut self.slots[slot];
        if s.node == node && s.stamp == stamp {
            return s.value;
        }
        let value = compute(node);
        *s = Slot { node, stamp, value };
        value
    }
}

/// The E&K lanes of a shading point's LS pmf replays (`TreeState::with_cached_pmf`).
impl LaneCache for OctMemo {
    #[inline]
    fn get(&mut self, oct: u32) -> Option<[f32; 8]> {
        Memo::get(self, oct)
    }
    #[inline]
    fn put(&mut self, oct: u32, lanes: [f32; 8]) {
        self.insert(oct, lanes);
    }
}
