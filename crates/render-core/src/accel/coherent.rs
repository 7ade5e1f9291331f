//! Coherent rays (a tile's camera rays) traced in packets of up to [`PACKET`] that share one
//! traversal: one stack whose entries carry the rays still bound for them, one visit of each
//! node for the whole packet. A visit tests each of its rays against the node's eight
//! children with the single-ray node test (so each ray finds exactly the children it would
//! find alone), and pushes every child some ray enters, with those rays, nearest entry on
//! top; a leaf is tested by each of its rays with the single-ray leaf code. What the rays
//! share is the stack work, the loop and the node's loads, which dominate a single ray's
//! visit (docs/notes/rays.md, "Packets").
//!
//! A ray visits its nodes in another order than alone, and may visit nodes it would skip (an
//! entry's distance is the least over its rays, so it is dropped only when beyond every ray's
//! `tmax`); the closest hit does not depend on the order of the visits
//! (`traverse::leaf_closest`: the nearest, ties to the lowest index), so each ray's hit is
//! [`super::Accel::intersect`]'s bit for bit, but for the rounding exception `leaf_closest`'s
//! rule names: at such a tie the packet may pick the other primitive at the same distance.
use super::collapse::Wide;
use super::node::{BoxRay, LEAF, NodeTest};
use super::packet::LaneRay;
use super::traverse::{insert_nearest_on_top, leaf_closest, pop_fetching_next};
use super::{Hit, StreamRay, positive_zeros};
use glam::Vec3;
use std::mem::MaybeUninit;

/// Rays that share a traversal: consecutive rays of the stream (a tile's neighbouring pixels).
pub const PACKET: usize = 8;

/// A stack entry: a child, the least distance at which one of its rays enters it, and those
/// rays (bit i: the packet's ray i).
#[derive(Clone, Copy)]
struct Entry {
    code: u32,
    t: f32,
    rays: u32,
}

/// A packet's rays as the node and leaf tests read them, their answers so far.
struct Rays {
    boxes: [BoxRay; PACKET],
    lanes: [LaneRay; PACKET],
    tmax: [f32; PACKET],
    best: [Option<Hit>; PACKET],
}

impl Rays {
    /// The packet's rays, and the bits of those that need a traversal (finite origin and
    /// direction, as `Accel::intersect` asks) with the least of their `tmin`.
    #[inline(always)]
    fn new(rays: &[StreamRay]) -> (Rays, u32, f32) {
        let units: [Option<(&StreamRay, Vec3)>; PACKET] = std::array::from_fn(|i| {
            let r = rays.get(i)?;
            (r.origin.is_finite() && r.dir.is_finite()).then(|| (r, positive_zeros(r.dir)))
        });
        let (mut live, mut tmin) = (0u32, f32::INFINITY);
        let mut tmax = [f32::NEG_INFINITY; PACKET];
        for (i, u) in units.iter().enumerate() {
            if let Some((r, _)) = u {
                live |= 1 << i;
                tmin = tmin.min(r.tmin);
                tmax[i] = r.tmax;
            }
        }
        let boxes = units.map(|u| match u {
            Some((r, d)) => BoxRay::new(r.origin, d, r.tmin),
            None => BoxRay::new(Vec3::ZERO, Vec3::ONE, 0.0),
        });
        let lanes = units.map(|u| match u {
            Some((r, d)) => LaneRay::new(r.origin, d, r.tmin),
            None => LaneRay::new(Vec3::ZERO, Vec3::ONE, 0.0),
        });
        let best = [None; PACKET];
        let rays = Rays {
            boxes,
            lanes,
            tmax,
            best,
        };
        (rays, live, tmin)
    }

    /// Those of `rays` that have not yet found a hit nearer than `t` (as the single-ray
    /// loop's `e.t > tmax` skip; all eight lanes compared at once).
    #[inline(always)]
    fn bound_for(&self, rays: u32, t: f32) -> u32 {
        let mut keep = 0;
        for (i, &tmax) in self.tmax.iter().enumerate() {
            keep |= ((!(t > tmax)) as u32) << i;
        }
        rays & keep
    }
}

/// `Accel::intersect` of each ray into `hits`, [`PACKET`] consecutive rays at a time.
#[inline(always)]
pub fn closest_packets<N: NodeTest>(
    w: &Wide,
    need: usize,
    rays: &[StreamRay],
    hits: &mut [Option<Hit>],
) {
    let mut stack = vec![MaybeUninit::<Entry>::uninit(); need];
    for (rays, hits) in rays.chunks(PACKET).zip(hits.chunks_mut(PACKET)) {
        let (mut r, live, tmin) = Rays::new(rays);
        if live != 0 {
            closest_packet::<N>(w, &mut r, (live, tmin), &mut stack);
        }
        hits.copy_from_slice(&r.best[..hits.len()]);
    }
}

/// One packet's traversal from the root with rays `live`, least `tmin` given.
#[inline(always)]
fn closest_packet<N: NodeTest>(
    w: &Wide,
    r: &mut Rays,
    (live, tmin): (u32, f32),
    stack: &mut [MaybeUninit<Entry>],
) {
    stack[0] = MaybeUninit::new(Entry {
        code: 0,
        t: tmin,
        rays: live,
    });
    let mut sp = 1;
    while sp > 0 {
        let e = pop_fetching_next(w, stack, &mut sp, |e| e.code);
        let mut rays = r.bound_for(e.rays, e.t);
        if rays == 0 {
            continue;
        }
        if e.code & LEAF != 0 {
            while rays != 0 {
                let i = rays.trailing_zeros() as usize;
                rays &= rays - 1;
                leaf_closest(w, e.code, &r.lanes[i], &mut r.tmax[i], &mut r.best[i]);
            }
            continue;
        }
        let node = &w.nodes[e.code as usize];
        // Per child: the rays that enter it and the least entry distance among them.
        let mut entered = [0u32; 8];
        let mut near = [f32::INFINITY; 8];
        while rays != 0 {
            let i = rays.trailing_zeros() as usize;
            rays &= rays - 1;
            N::test_into(
                node,
                &r.boxes[i],
                r.tmax[i],
                1 << i,
                (&mut entered, &mut near),
            );
        }
        push_nearest_on_top(node.child, (&entered, &near), stack, &mut sp);
    }
}

/// Pushes the children some ray enters, the nearest on top (an insertion sort over this
/// node's entries, as the single-ray traversal does).
#[inline(always)]
fn push_nearest_on_top(
    child: [u32; 8],
    (entered, near): (&[u32; 8], &[f32; 8]),
    stack: &mut [MaybeUninit<Entry>],
    sp: &mut usize,
) {
    let base = *sp;
    let mut children = 0u32;
    for (k, &rays) in entered.iter().enumerate() {
        children |= ((rays != 0) as u32) << k;
    }
    while children != 0 {
        let k = children.trailing_zeros() as usize;
        children &= children - 1;
        let x = Entry {
            code: child[k],
            t: near[k],
            rays: entered[k],
        };
        insert_nearest_on_top(stack, (base, sp), x, |e| e.t);
    }
}
