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

use crate::compact::{LEAF_BIT, Slot, Slots};
use crate::{NO_NODE, Node, NodeId};

/// Eight slots, structure-of-arrays, lanes in branch-bit order; 256 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(256))]
pub(crate) struct OctNode {
    qbox: [[u16; 8]; 6],
    axis: [[i16; 8]; 3],
    cos_o: [i16; 8],
    cos_e: [i16; 8],
    power: [f32; 8],
    /// Interior slot (at a depth divisible by 3): index of its own oct. Leaf: `LEAF_BIT |
    /// light`. Empty: `LEAF_BIT` with zero power, never chosen.
    pub(crate) child: [u32; 8],
    flags: [u8; 8],
}

impl OctNode {
    fn set(&mut self, lane: usize, s: &Slot, child: u32) {
        for k in 0..6 {
            self.qbox[k][lane] = s.qbox[k];
        }
        for k in 0..3 {
            self.axis[k][lane] = s.axis[k];
        }
        self.cos_o[lane] = s.cos_o;
        self.cos_e[lane] = s.cos_e;
        self.power[lane] = s.power;
        self.flags[lane] = s.flags;
        self.child[lane] = child;
    }

    /// A lane of zero power (importance 0; a valid axis keeps NaN out of it).
    fn set_empty(&mut self, lane: usize) {
        self.axis[2][lane] = i16::MAX;
        self.child[lane] = LEAF_BIT;
    }
}

impl Slots<8> for OctNode {
    #[inline(always)]
    fn qbox(&self, k: usize) -> [u16; 8] {
        self.qbox[k]
    }
    #[inline(always)]
    fn axis(&self, k: usize) -> [i16; 8] {
        self.axis[k]
    }
    #[inline(always)]
    fn cos_o(&self) -> [i16; 8] {
        self.cos_o
    }
    #[inline(always)]
    fn cos_e(&self) -> [i16; 8] {
        self.cos_e
    }
    #[inline(always)]
    fn power(&self) -> [f32; 8] {
        self.power
    }
    #[inline(always)]
    fn flags(&self) -> [u8; 8] {
        self.flags
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
                    octs[o as usize].set(first, &slots[n as usize], code(n));
                    lanes[o as usize][first] = n;
                    for lane in first + 1..first + span {
                        octs[o as usize].set_empty(lane);
                    }
                }
            }
        }
    }
    (octs, oct_of, lanes)
}
