//! A stream of rays traversed several at a time on one thread. A few rays are in flight, each
//! with its own stack; they take turns, one node or one leaf per turn, and after its turn a
//! ray asks for the memory of the entry it will visit next. By the time its turn comes again
//! the others' tests have hidden that load, where one ray alone would wait for it.
//!
//! Each ray visits its own entries in exactly the order the single-ray traversal does (the
//! same node tests, the same leaf helpers of `traverse`), so its hit is the same bit for bit,
//! ties included. Entries beyond the ray's current `tmax` are dropped when they come to the
//! top instead of when popped: `tmax` only shrinks, so those would have been skipped anyway.
use super::collapse::Wide;
use super::node::{BoxRay, LEAF, NodeTest, leaf_parts, prefetch};
use super::packet::LaneRay;
use super::traverse::{Entry, leaf_blocks, leaf_closest, push_as_found, push_nearest_on_top};
use super::{Hit, StreamRay, positive_zeros};
use std::mem::MaybeUninit;

/// Rays in flight per thread: enough turns between a ray's request and its use for an L3
/// (or memory) load to arrive, few enough that the rays' states and stack tops stay in L1.
/// Chosen by measurement on the rays benchmark (docs/notes/rays.md, "Streams").
pub const IN_FLIGHT: usize = 8;

/// A ray in flight and where its stack lives.
struct Flight {
    br: BoxRay,
    lr: LaneRay,
    tmax: f32,
    best: Option<Hit>,
    /// The ray's index in the stream.
    ray: usize,
    /// Its stack: `need` entries from `base`, the top at `base + sp`.
    base: usize,
    sp: usize,
}

impl Flight {
    /// The ray's state with the root on its stack, or `None` for a ray that finds nothing
    /// without a traversal (a non-finite origin or direction, as in `Accel::intersect`).
    fn start(
        r: &StreamRay,
        ray: usize,
        base: usize,
        stack: &mut [MaybeUninit<Entry>],
    ) -> Option<Flight> {
        if !(r.origin.is_finite() && r.dir.is_finite()) {
            return None;
        }
        let d = positive_zeros(r.dir);
        stack[base] = MaybeUninit::new(Entry { code: 0, t: r.tmin });
        Some(Flight {
            br: BoxRay::new(r.origin, d, r.tmin),
            lr: LaneRay::new(r.origin, d, r.tmin),
            tmax: r.tmax,
            best: None,
            ray,
            base,
            sp: 1,
        })
    }

    /// One turn of closest hit: the next entry within `tmax`, tested; then the entry after
    /// it prefetched. True when the ray is done.
    #[inline(always)]
    fn closest_turn<N: NodeTest>(&mut self, w: &Wide, stack: &mut [MaybeUninit<Entry>]) -> bool {
        let s = &mut stack[self.base..];
        let Some(e) = self.pop::<true>(s) else {
            return true;
        };
        if e.code & LEAF == 0 {
            let node = &w.nodes[e.code as usize];
            let (mask, tnear) = N::test(node, &self.br, self.tmax);
            push_nearest_on_top(node, mask, &tnear, s, &mut self.sp);
        } else {
            leaf_closest(w, e.code, &self.lr, &mut self.tmax, &mut self.best);
        }
        self.ask_for_next::<true>(w, s)
    }

    /// One turn of occlusion: the next entry, tested. True when the ray is done (`best`
    /// then says nothing; the caller reads `blocked`).
    #[inline(always)]
    fn occluded_turn<N: NodeTest>(
        &mut self,
        w: &Wide,
        stack: &mut [MaybeUninit<Entry>],
        blocked: &mut bool,
    ) -> bool {
        let s = &mut stack[self.base..];
        let Some(e) = self.pop::<false>(s) else {
            return true;
        };
        if e.code & LEAF == 0 {
            let node = &w.nodes[e.code as usize];
            let (mask, _) = N::test(node, &self.br, self.tmax);
            push_as_found(node, mask, s, &mut self.sp);
        } else if leaf_blocks(w, e.code, &self.lr, self.tmax) {
            *blocked = true;
            return true;
        }
        self.ask_for_next::<false>(w, s)
    }

    /// The entry the single-ray traversal would test next, or `None` when the stack holds no
    /// more. Closest hit (`CULL`) skips entries beyond `tmax` as that traversal does;
    /// occlusion skips none.
    #[inline(always)]
    fn pop<const CULL: bool>(&mut self, s: &[MaybeUninit<Entry>]) -> Option<Entry> {
        while self.sp > 0 {
            self.sp -= 1;
            // SAFETY: entries below `sp` were written.
            let e = unsafe { s[self.sp].assume_init() };
            if !(CULL && e.t > self.tmax) {
                return Some(e);
            }
        }
        None
    }

    /// Prefetches what the ray visits next (dropping, for closest hit, the entries on top
    /// that it would skip); true when nothing is left.
    #[inline(always)]
    fn ask_for_next<const CULL: bool>(&mut self, w: &Wide, s: &[MaybeUninit<Entry>]) -> bool {
        while self.sp > 0 {
            // SAFETY: entries below `sp` were written.
            let e = unsafe { s[self.sp - 1].assume_init() };
            if !(CULL && e.t > self.tmax) {
                fetch_all(w, e.code);
                return false;
            }
            self.sp -= 1;
        }
        true
    }
}

/// Prefetches a node, or every cache line of a leaf's packets.
#[inline(always)]
fn fetch_all(w: &Wide, code: u32) {
    if code & LEAF == 0 {
        prefetch(&w.nodes[code as usize]);
        return;
    }
    let (first, tris, spheres) = leaf_parts(code);
    let first = first as usize;
    let leaf = &w.packets[first..first + (tris + spheres) as usize];
    let end = leaf.as_ptr_range().end as usize;
    // From the line holding the first byte: a packet need not start on a line.
    let mut line = leaf.as_ptr() as usize & !63;
    while line < end {
        prefetch_line(line);
        line += 64;
    }
}

#[inline(always)]
fn prefetch_line(addr: usize) {
    // SAFETY: a prefetch never faults; x86-64 always has SSE.
    #[cfg(target_arch = "x86_64")]
    unsafe {
        use std::arch::x86_64::*;
        _mm_prefetch::<_MM_HINT_T0>(addr as *const i8);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = addr;
}

/// Rays in flight and the stream's next ray to admit.
struct Flights<'a> {
    rays: &'a [StreamRay],
    next: usize,
    live: Vec<Flight>,
    stack: Vec<MaybeUninit<Entry>>,
}

impl<'a> Flights<'a> {
    /// Up to [`IN_FLIGHT`] rays started; `skipped` is told each ray that needs no traversal.
    fn new(rays: &'a [StreamRay], need: usize, mut skipped: impl FnMut(usize)) -> Flights<'a> {
        let n = IN_FLIGHT.min(rays.len());
        let mut f = Flights {
            rays,
            next: 0,
            live: Vec::with_capacity(n),
            stack: vec![MaybeUninit::uninit(); n * need],
        };
        for slot in 0..n {
            match f.admit(slot * need, &mut skipped) {
                Some(r) => f.live.push(r),
                None => break,
            }
        }
        f
    }

    /// The stream's next ray that needs a traversal, on the stack at `base`.
    fn admit(&mut self, base: usize, skipped: &mut impl FnMut(usize)) -> Option<Flight> {
        while self.next < self.rays.len() {
            let i = self.next;
            self.next += 1;
            match Flight::start(&self.rays[i], i, base, &mut self.stack) {
                Some(f) => return Some(f),
                None => skipped(i),
            }
        }
        None
    }
}

/// `Accel::intersect` of each ray into `hits`, the rays interleaved.
#[inline(always)]
pub fn closest_stream<N: NodeTest>(
    w: &Wide,
    need: usize,
    rays: &[StreamRay],
    hits: &mut [Option<Hit>],
) {
    let mut f = Flights::new(rays, need, |i| hits[i] = None);
    let mut k = 0;
    while !f.live.is_empty() {
        if k >= f.live.len() {
            k = 0;
        }
        if !f.live[k].closest_turn::<N>(w, &mut f.stack) {
            k += 1;
            continue;
        }
        hits[f.live[k].ray] = f.live[k].best;
        let base = f.live[k].base;
        match f.admit(base, &mut |i| hits[i] = None) {
            Some(r) => f.live[k] = r,
            None => {
                f.live.swap_remove(k);
            }
        }
    }
}

/// `Accel::occluded` of each ray into `blocked`, the rays interleaved.
#[inline(always)]
pub fn occluded_stream<N: NodeTest>(
    w: &Wide,
    need: usize,
    rays: &[StreamRay],
    blocked: &mut [bool],
) {
    let mut f = Flights::new(rays, need, |i| blocked[i] = false);
    let mut k = 0;
    while !f.live.is_empty() {
        if k >= f.live.len() {
            k = 0;
        }
        let ray = f.live[k].ray;
        let mut hit = false;
        if !f.live[k].occluded_turn::<N>(w, &mut f.stack, &mut hit) {
            k += 1;
            continue;
        }
        blocked[ray] = hit;
        let base = f.live[k].base;
        match f.admit(base, &mut |i| blocked[i] = false) {
            Some(r) => f.live[k] = r,
            None => {
                f.live.swap_remove(k);
            }
        }
    }
}
