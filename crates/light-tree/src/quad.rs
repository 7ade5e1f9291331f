//! Four-wide descent nodes (issue 22): a node's four grandchildren side by side in two cache
//! lines, evaluated in one four-lane pass, so that a descent takes one step, one dependent
//! load and one evaluation per two levels of the binary tree.
//!
//! A quad exists for every interior node at even depth (the root's is quad 0). Its lanes hold,
//! for the left child then the right one, that child's two children; a child that is a leaf
//! takes the first lane of its half itself, beside an empty lane of zero power. The descent
//! picks a half with probability (I(l) + I(r)) / Σ over the four lanes, then a lane within it
//! by its own importance: the binary descent in which an odd-depth interior node weighs as
//! the sum of its children's importances (see `compact_tests.rs`).

use crate::compact::{LEAF_BIT, Slot, Slots};
use crate::{NO_NODE, Node, NodeId};

/// Four slots, structure-of-arrays, lanes `[left.l, left.r, right.l, right.r]`; 128 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(128))]
pub(crate) struct QuadNode {
    qbox: [[u16; 4]; 6],
    axis: [[i16; 4]; 3],
    cos_o: [i16; 4],
    cos_e: [i16; 4],
    power: [f32; 4],
    /// Interior (even-depth) slot: index of its own quad. Leaf: `LEAF_BIT | light`. Empty:
    /// `LEAF_BIT` with zero power, never chosen.
    pub(crate) child: [u32; 4],
    flags: [u8; 4],
}

impl QuadNode {
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

impl Slots<4> for QuadNode {
    #[inline(always)]
    fn qbox(&self, k: usize) -> [u16; 4] {
        self.qbox[k]
    }
    #[inline(always)]
    fn axis(&self, k: usize) -> [i16; 4] {
        self.axis[k]
    }
    #[inline(always)]
    fn cos_o(&self) -> [i16; 4] {
        self.cos_o
    }
    #[inline(always)]
    fn cos_e(&self) -> [i16; 4] {
        self.cos_e
    }
    #[inline(always)]
    fn power(&self) -> [f32; 4] {
        self.power
    }
    #[inline(always)]
    fn flags(&self) -> [u8; 4] {
        self.flags
    }
}

/// The quads of a tree, per node the index of its quad (`u32::MAX`: none, i.e. a leaf or an
/// odd-depth node), and per quad the nodes in its lanes (`NO_NODE` where empty).
pub(crate) fn build(nodes: &[Node], slots: &[Slot]) -> (Vec<QuadNode>, Vec<u32>, Vec<[NodeId; 4]>) {
    let mut quad_of = vec![u32::MAX; nodes.len()];
    let mut count = 0u32;
    for (id, node) in nodes.iter().enumerate() {
        if !node.is_leaf() && node.depth() % 2 == 0 {
            quad_of[id] = count;
            count += 1;
        }
    }
    let code = |id: NodeId| match nodes[id as usize].light() {
        Some(light) => LEAF_BIT | light as u32,
        None => quad_of[id as usize],
    };
    let mut quads = vec![QuadNode::default(); count as usize];
    let mut lanes = vec![[NO_NODE; 4]; count as usize];
    for (id, node) in nodes.iter().enumerate() {
        let q = quad_of[id];
        if q == u32::MAX {
            continue;
        }
        let quad = &mut quads[q as usize];
        let (l, r) = node
            .children(id as NodeId)
            .expect("quads are of interior nodes");
        for (half, c) in [(0, l), (1, r)] {
            match nodes[c as usize].children(c) {
                Some((cl, cr)) => {
                    quad.set(2 * half, &slots[cl as usize], code(cl));
                    quad.set(2 * half + 1, &slots[cr as usize], code(cr));
                    lanes[q as usize][2 * half] = cl;
                    lanes[q as usize][2 * half + 1] = cr;
                }
                None => {
                    quad.set(2 * half, &slots[c as usize], code(c));
                    quad.set_empty(2 * half + 1);
                    lanes[q as usize][2 * half] = c;
                }
            }
        }
    }
    (quads, quad_of, lanes)
}
