//! Closest hit and occlusion through the eight-wide tree, generic over the node test so the
//! AVX2 and SSE2 paths are one loop. Closest hit visits the children a node test finds in
//! order of entry distance, nearest first (an insertion sort on the stack); occlusion takes
//! them as they come and stops at the first primitive in the segment.
use super::Hit;
use super::collapse::Wide;
use super::lanes::F4;
use super::node::{BoxRay, LEAF, Node8, NodeTest, leaf_parts, prefetch};
use super::packet::LaneRay;
use glam::Vec3;
use std::mem::MaybeUninit;

/// A stack entry: a child code and the distance at which the ray enters its box.
#[derive(Clone, Copy)]
pub struct Entry {
    pub code: u32,
    pub t: f32,
}

/// Stack entries kept on the call stack; deeper trees take a heap stack.
const INLINE_STACK: usize = 128;

/// Stack entries a traversal of a tree `depth` nodes deep may hold at once (a popped node
/// pushes at most eight children).
pub fn stack_need(depth: usize) -> usize {
    8 * depth + 1
}

/// Runs `f` with an uninitialised stack of at least `need` entries.
#[inline(always)]
pub fn with_stack<R>(need: usize, f: impl FnOnce(&mut [MaybeUninit<Entry>]) -> R) -> R {
    if need <= INLINE_STACK {
        let mut s = [MaybeUninit::<Entry>::uninit(); INLINE_STACK];
        f(&mut s)
    } else {
        f(&mut vec![MaybeUninit::uninit(); need])
    }
}

/// Nearest primitive with t in [tmin, tmax); of several at exactly the same distance, the
/// lowest primitive index ([`leaf_closest`]), so the answer does not depend on the order in
/// which the traversal meets them (but for the rounding exception `replaces` names).
#[inline(always)]
pub fn closest<N: NodeTest>(
    w: &Wide,
    o: Vec3,
    d: Vec3,
    tmin: f32,
    mut tmax: f32,
    stack: &mut [MaybeUninit<Entry>],
) -> Option<Hit> {
    let br = BoxRay::new(o, d, tmin);
    let lr = LaneRay::new(o, d, tmin);
    let mut best = None;
    stack[0] = MaybeUninit::new(Entry { code: 0, t: tmin });
    let mut sp = 1;
    while sp > 0 {
        let e = pop_fetching_next(w, stack, &mut sp, |e| e.code);
        if e.t > tmax {
            continue;
        }
        if e.code & LEAF == 0 {
            let node = &w.nodes[e.code as usize];
            let (mask, tnear) = N::test(node, &br, tmax);
            push_nearest_on_top(node, mask, &tnear, stack, &mut sp);
        } else {
            leaf_closest(w, e.code, &lr, &mut tmax, &mut best);
        }
    }
    best
}

/// Pushes the children of `node` in `mask` with their entry distances, keeping the entries
/// pushed here in decreasing distance (the nearest on top). Entries below `*sp` must be written.
#[inline(always)]
pub fn push_nearest_on_top(
    node: &Node8,
    mut mask: u32,
    tnear: &[f32; 8],
    stack: &mut [MaybeUninit<Entry>],
    sp: &mut usize,
) {
    let base = *sp;
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let x = Entry {
            code: node.child[i],
            t: tnear[i],
        };
        insert_nearest_on_top(stack, (base, sp), x, |e| e.t);
    }
}

/// Whether a hit of primitive `id` at `t` replaces `best` (whose distance `tmax` is, once
/// there is one): nearer, or as near with a lower index. Entries are dropped only when beyond
/// `tmax`, and a box's entry distance is as a rule no later than the hits inside it, so every
/// primitive at the final distance is tested whatever the order of the visits and the closest
/// hit is the same for any order: the nearest, ties to the lowest index. The exception is a
/// tie whose other primitive lies on its box's face where the entry distance rounds beyond the
/// hit's (seen on a ray from 1e30 away): a traversal that met the tie first skips it.
#[inline(always)]
fn replaces(t: f32, id: u32, tmax: f32, best: &Option<Hit>) -> bool {
    t < tmax || (t == tmax && best.is_some_and(|b| id < b.prim))
}

/// Pushes `x`, moving it below the entries from `base` up that are nearer (by `t`), so that
/// those entries stay in decreasing distance with the nearest on top (an insertion sort step).
/// Entries below `*sp` must be written.
#[inline(always)]
pub fn insert_nearest_on_top<E: Copy>(
    stack: &mut [MaybeUninit<E>],
    (base, sp): (usize, &mut usize),
    x: E,
    t: impl Fn(&E) -> f32,
) {
    let mut j = *sp;
    // SAFETY: entries below `sp` were written.
    while j > base && t(&unsafe { stack[j - 1].assume_init() }) < t(&x) {
        stack[j] = stack[j - 1];
        j -= 1;
    }
    stack[j] = MaybeUninit::new(x);
    *sp += 1;
}

/// Tests the primitives of leaf `code`, lowering `tmax` and replacing `best` at each hit that
/// [`replaces`] it (triangle packets first, lanes in order).
#[inline(always)]
pub fn leaf_closest(w: &Wide, code: u32, lr: &LaneRay, tmax: &mut f32, best: &mut Option<Hit>) {
    let (first, tris, spheres) = leaf_parts(code);
    let first = first as usize;
    for p in &w.packets[first..first + tris as usize] {
        let (mut ok, t, b1, b2) = p.intersect_triangles(lr, *tmax);
        if ok == 0 {
            continue;
        }
        let (t, b1, b2) = (t.to_array(), b1.to_array(), b2.to_array());
        while ok != 0 {
            let l = ok.trailing_zeros() as usize;
            ok &= ok - 1;
            if replaces(t[l], p.ids[l], *tmax, best) {
                *tmax = t[l];
                *best = Some(Hit {
                    prim: p.ids[l],
                    t: t[l],
                    b1: b1[l],
                    b2: b2[l],
                });
            }
        }
    }
    let s0 = first + tris as usize;
    for p in &w.packets[s0..s0 + spheres as usize] {
        let (mut ok, t) = p.intersect_spheres(lr, *tmax);
        let t = t.to_array();
        while ok != 0 {
            let l = ok.trailing_zeros() as usize;
            ok &= ok - 1;
            if replaces(t[l], p.ids[l], *tmax, best) {
                *tmax = t[l];
                *best = Some(Hit {
                    prim: p.ids[l],
                    t: t[l],
                    b1: 0.0,
                    b2: 0.0,
                });
            }
        }
    }
}

/// True when a primitive has t in [tmin, tmax).
#[inline(always)]
pub fn occluded<N: NodeTest>(
    w: &Wide,
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
    stack: &mut [MaybeUninit<Entry>],
) -> bool {
    let br = BoxRay::new(o, d, tmin);
    let lr = LaneRay::new(o, d, tmin);
    stack[0] = MaybeUninit::new(Entry { code: 0, t: tmin });
    let mut sp = 1;
    while sp > 0 {
        let e = pop_fetching_next(w, stack, &mut sp, |e| e.code);
        if e.code & LEAF == 0 {
            let node = &w.nodes[e.code as usize];
            let (mask, _) = N::test(node, &br, tmax);
            push_as_found(node, mask, stack, &mut sp);
        } else if leaf_blocks(w, e.code, &lr, tmax) {
            return true;
        }
    }
    false
}

/// Pushes the children of `node` in `mask` in slot order (occlusion needs no distances).
#[inline(always)]
pub fn push_as_found(
    node: &Node8,
    mut mask: u32,
    stack: &mut [MaybeUninit<Entry>],
    sp: &mut usize,
) {
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        stack[*sp] = MaybeUninit::new(Entry {
            code: node.child[i],
            t: 0.0,
        });
        *sp += 1;
    }
}

/// True when a primitive of leaf `code` has t in [tmin, tmax).
#[inline(always)]
pub fn leaf_blocks(w: &Wide, code: u32, lr: &LaneRay, tmax: f32) -> bool {
    let below = F4::splat(tmax);
    let (first, tris, spheres) = leaf_parts(code);
    let first = first as usize;
    for p in &w.packets[first..first + tris as usize] {
        let (ok, t, _, _) = p.intersect_triangles(lr, tmax);
        if ok & t.lt(below) != 0 {
            return true;
        }
    }
    let s0 = first + tris as usize;
    for p in &w.packets[s0..s0 + spheres as usize] {
        let (ok, t) = p.intersect_spheres(lr, tmax);
        if ok & t.lt(below) != 0 {
            return true;
        }
    }
    false
}

/// Pops the top entry (`*sp` > 0, entries below it written) and prefetches what the entry
/// below it names (`code`), so that its memory loads while the popped one is tested.
#[inline(always)]
pub fn pop_fetching_next<E: Copy>(
    w: &Wide,
    stack: &[MaybeUninit<E>],
    sp: &mut usize,
    code: impl Fn(&E) -> u32,
) -> E {
    *sp -= 1;
    // SAFETY: entries below the old `*sp` were written.
    let e = unsafe { stack[*sp].assume_init() };
    if *sp > 0 {
        // SAFETY: as above.
        fetch(w, code(&unsafe { stack[*sp - 1].assume_init() }));
    }
    e
}

/// Prefetches what `code` names: a node, or a leaf's first packet.
#[inline(always)]
pub fn fetch(w: &Wide, code: u32) {
    if code & LEAF == 0 {
        prefetch(&w.nodes[code as usize]);
    } else {
        prefetch(&w.packets[leaf_parts(code).0 as usize]);
    }
}
