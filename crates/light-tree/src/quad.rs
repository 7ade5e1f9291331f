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

use crate::codes::{LEAF_BIT, Slot};
use crate::lane_slots::LaneSlots;
use crate::{NO_NODE, Node, NodeId};

/// Four slots, lanes `[left.l, left.r, right.l, right.r]`, in two cache lines.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(128))]
pub(crate) struct QuadNode(pub(crate) LaneSlots<4>);

impl std::ops::Deref for QuadNode {
    type Target = LaneSlots<4>;
    #[inline(always)]
    fn deref(&self) -> &LaneSlots<4> {
        &self.0
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
                    quad.0.set(2 * half, &slots[cl as usize], code(cl));
                    quad.0.set(2 * half + 1, &slots[cr as usize], code(cr));
                    lanes[q as usize][2 * half] = cl;
                    lanes[q as usize][2 * half + 1] = cr;
                }
                None => {
                    quad.0.set(2 * half, &slots[c as usize], code(c));
                    quad.0.set_empty(2 * half + 1);
                    lanes[q as usize][2 * half] = c;
                }
            }
        }
    }
    (quads, quad_of, lanes)
}
