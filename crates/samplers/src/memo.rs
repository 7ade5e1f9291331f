//! A direct-mapped cache of per-node values (importances) of one shading point.
//!
//! A node's importance is a pure function of (node, shading point), so a cached value is
//! bit-identical to a recomputed one: sampling and every pdf replay see the same numbers
//! whether or not a slot was evicted. A slot is valid only under the current stamp, so moving
//! to the next shading point invalidates the cache without clearing it.
use light_tree::NodeId;

const SLOTS: usize = 1024;

#[derive(Clone, Copy)]
struct Slot {
    node: NodeId,
    stamp: u32,
    value: f32,
}

pub struct NodeMemo {
    slots: Box<[Slot]>,
    stamp: u32,
}

impl Default for NodeMemo {
    fn default() -> NodeMemo {
        NodeMemo {
            slots: vec![
                Slot {
                    node: NodeId::MAX,
                    stamp: 0,
                    value: 0.0
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

impl NodeMemo {
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
    pub fn get(&self, node: NodeId) -> Option<f32> {
        let s = &self.slots[Self::slot(node)];
        (s.node == node && s.stamp == self.stamp).then_some(s.value)
    }

    /// Stores `value` for `node` (which must be what `compute` would give it).
    #[inline]
    pub fn insert(&mut self, node: NodeId, value: f32) {
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
    pub fn get_or(&mut self, node: NodeId, compute: impl FnOnce(NodeId) -> f32) -> f32 {
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
