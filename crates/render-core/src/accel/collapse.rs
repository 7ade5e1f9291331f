//! The eight-wide tree from obvhs's binary one: each wide node takes a binary node's two
//! children and keeps opening the child of largest surface area that is an inner node until
//! it has eight (or only leaves are left); obvhs's leaves, chosen by its surface-area
//! collapse, become our leaves, their primitives packed four to a packet.
use super::Primitive;
use super::node::{MAX_SPHERE_PACKETS, MAX_TRI_PACKETS, Node8, leaf_code};
use super::packet::Packet;
use glam::Vec3;
use obvhs::bvh2::Bvh2;

/// Nodes (the root first), packets, and the deepest path in nodes.
pub struct Wide {
    pub nodes: Vec<Node8>,
    pub packets: Vec<Packet>,
    pub depth: usize,
}

/// The wide tree over `prims` from obvhs's binary tree of them (at least one primitive).
pub fn collapse(bvh2: &Bvh2, prims: &[Primitive]) -> Wide {
    let mut w = Wide {
        nodes: vec![Node8::empty()],
        packets: Vec::new(),
        depth: 1,
    };
    // (binary node whose children fill wide node `slot`, that wide node's depth), breadth first.
    let mut queue = std::collections::VecDeque::new();
    let root = &bvh2.nodes[0];
    if root.is_leaf() {
        let code = leaf(&mut w.packets, bvh2, 0, prims);
        w.nodes[0].set(0, root.aabb().min.into(), root.aabb().max.into(), code);
        return w;
    }
    queue.push_back((0usize, 0usize, 1usize));
    while let Some((b, slot, depth)) = queue.pop_front() {
        w.depth = w.depth.max(depth);
        let mut kids = children(bvh2, b).to_vec();
        while kids.len() < 8 {
            let widest = kids
                .iter()
                .enumerate()
                .filter(|(_, k)| !bvh2.nodes[**k].is_leaf())
                .max_by(|a, b| half_area(bvh2, *a.1).total_cmp(&half_area(bvh2, *b.1)))
                .map(|(i, _)| i);
            let Some(i) = widest else { break };
            let k = kids.swap_remove(i);
            kids.extend(children(bvh2, k));
        }
        for (s, &k) in kids.iter().enumerate() {
            let node = &bvh2.nodes[k];
            let code = if node.is_leaf() {
                leaf(&mut w.packets, bvh2, k, prims)
            } else {
                w.nodes.push(Node8::empty());
                let index = (w.nodes.len() - 1) as u32;
                queue.push_back((k, index as usize, depth + 1));
                index
            };
            let (lo, hi): (Vec3, Vec3) = (node.aabb().min.into(), node.aabb().max.into());
            w.nodes[slot].set(s, lo, hi, code);
        }
    }
    w
}

fn children(bvh2: &Bvh2, b: usize) -> [usize; 2] {
    let first = bvh2.nodes[b].first_index as usize;
    [first, first + 1]
}

fn half_area(bvh2: &Bvh2, b: usize) -> f32 {
    bvh2.nodes[b].aabb().half_area()
}

/// Packs binary leaf `b`'s primitives (triangles first, then spheres) and returns its code.
fn leaf(packets: &mut Vec<Packet>, bvh2: &Bvh2, b: usize, prims: &[Primitive]) -> u32 {
    let node = &bvh2.nodes[b];
    let range = node.first_index as usize..(node.first_index + node.prim_count) as usize;
    let (mut tris, mut spheres) = (Vec::new(), Vec::new());
    for &id in &bvh2.primitive_indices[range] {
        match prims[id as usize] {
            Primitive::Triangle { v0, v1, v2 } => tris.push((id, v0, v1, v2)),
            Primitive::Sphere { center, radius } => spheres.push((id, center, radius)),
        }
    }
    let first = packets.len() as u32;
    let (nt, ns) = (tris.len().div_ceil(4), spheres.len().div_ceil(4));
    assert!(
        nt as u32 <= MAX_TRI_PACKETS && ns as u32 <= MAX_SPHERE_PACKETS,
        "a leaf of {} primitives",
        node.prim_count
    );
    packets.extend(tris.chunks(4).map(Packet::triangles));
    packets.extend(spheres.chunks(4).map(Packet::spheres));
    leaf_code(first, nt as u32, ns as u32)
}
