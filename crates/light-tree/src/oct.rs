//! Eight-wide descent nodes (issue 22): a node's eight great-grandchildren side by side in
//! four cache lines, evaluated in one eight-lane pass (AVX where the CPU has it), so that the
//! E&K descent takes one step, one dependent load and one choice per three levels of the
//! binary tree.
//!
//! An oct exists for every interior node at a depth divisible by 3 (the root's is oct 0).
//! Lane `4·b₀ + 2·b₁ + b₂` holds the node reached by the branch bits b₀, b₁, b₂ (0 = left);
//! a descendant that is a leaf above that depth takes the first lane of its range, beside
//! empty lanes of zero power. The descent picks a lane ∝ its importance
//! (`oct_descent.rs`): the binary descent in which interior nodes at the two depths between
//! weigh as the sum of their lanes.

use crate::codes::{LEAF_BIT, Slot, Slots};
use crate::lane_slots::LaneSlots;
use crate::{NO_NODE, Node, NodeId};

/// Eight slots in branch-bit order, in four cache lines.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(256))]
pub(crate) struct OctNode(pub(crate) LaneSlots<8>);

impl std::ops::Deref for OctNode {
    type Target = LaneSlots<8>;
    #[inline(always)]
    fn deref(&self) -> &LaneSlots<8> {
        &self.0
    }
}

/// The octs of a tree, per node the index of its oct (`u32::MAX`: none, i.e. a leaf or a
/// depth not divisible by 3), and per oct the nodes in its lanes (`NO_NODE` where empty).
pub(crate) fn build(nodes: &[Node], slots: &[Slot]) -> (Vec<OctNode>, Vec<u32>, Vec<[NodeId; 8]>) {
    let mut oct_of = vec![u32::MAX; nodes.len()];
    let mut count = 0u32;
    for (id, node) in nodes.iter().enumerate() {
        if !node.is_leaf() && node.depth() % 3 == 0 {
            oct_of[id] = count;
            count += 1;
        }
    }
    let code = |id: NodeId| match nodes[id as usize].light() {
        Some(light) => LEAF_BIT | light as u32,
        None => oct_of[id as usize],
    };
    let mut octs = vec![OctNode::default(); count as usize];
    let mut lanes = vec![[NO_NODE; 8]; count as usize];
    for (id, node) in nodes.iter().enumerate() {
        let o = oct_of[id];
        if o == u32::MAX {
            continue;
        }
        let (l, r) = node
            .children(id as NodeId)
            .expect("octs are of interior nodes");
        // (node, its first lane, the lanes it spans), down to the great-grandchildren.
        let mut stack = vec![(l, 0usize, 4usize), (r, 4, 4)];
        while let Some((n, first, span)) = stack.pop() {
            match nodes[n as usize].children(n) {
                Some((a, b)) if span > 1 => {
                    stack.push((a, first, span / 2));
                    stack.push((b, first + span / 2, span / 2));
                }
                _ => {
                    octs[o as usize].0.set(first, &slots[n as usize], code(n));
                    lanes[o as usize][first] = n;
                    for lane in first + 1..first + span {
                        octs[o as usize].0.set_empty(lane);
                    }
                }
            }
        }
    }
    (octs, oct_of, lanes)
}

/// Two octs as sixteen slots, `a`'s eight lanes then `b`'s: two descents evaluated side by
/// side in one pass (`LightTree::sample_pair_from`).
pub(crate) struct TwoOcts<'a>(pub(crate) &'a OctNode, pub(crate) &'a OctNode);

#[inline(always)]
fn join<T: Copy + Default>(a: [T; 8], b: [T; 8]) -> [T; 16] {
    let mut v = [T::default(); 16];
    v[..8].copy_from_slice(&a);
    v[8..].copy_from_slice(&b);
    v
}

impl Slots<16> for TwoOcts<'_> {
    #[inline(always)]
    fn qbox(&self, k: usize) -> [u16; 16] {
        join(self.0.qbox(k), self.1.qbox(k))
    }
    #[inline(always)]
    fn axis(&self, k: usize) -> [i16; 16] {
        join(self.0.axis(k), self.1.axis(k))
    }
    #[inline(always)]
    fn cos_o(&self) -> [i16; 16] {
        join(self.0.cos_o(), self.1.cos_o())
    }
    #[inline(always)]
    fn cos_e(&self) -> [i16; 16] {
        join(self.0.cos_e(), self.1.cos_e())
    }
    #[inline(always)]
    fn power(&self) -> [f32; 16] {
        join(self.0.power(), self.1.power())
    }
    #[inline(always)]
    fn flags(&self) -> [u8; 16] {
        join(self.0.flags(), self.1.flags())
    }
}
