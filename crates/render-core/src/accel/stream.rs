//! A stream of rays traversed several at a time on one thread. A few rays are in flight, each
//! with its own stack; they take turns. A turn tests a ray's entries until the next one is a
//! leaf or a node below the tree's top levels, prefetches that one and hands over: by the
//! time the ray's turn comes again the others' tests have covered that load, where one ray
//! alone would wait for it. (The top levels, which every ray visits and the caches keep, cost
//! no hand-over.)
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
use glam::Vec3;
use std::mem::MaybeUninit;

/// Rays in flight per thread: enough turns between a ray's request and its use for an L3
/// (or memory) load to arrive, few enough that the rays' states and stack tops stay in L1.
/// On our machine 1 to 24 measured alike (docs/notes/rays.md, "Streams").
pub const IN_FLIGHT: usize = 8;

/// Nodes at the top of the tree a ray tests in one turn: the collapse stores nodes breadth
/// first, so these are the top levels, which every ray visits and the caches keep.
pub const HOT_NODES: u32 = 512;

/// A ray in flight and where its stack lives.
struct Flight {
    br: BoxRay,
    /// The direction (−0.0 made +0.0), for the leaves' lanes.
    d: Vec3,
    tmax: f32,
    /// Closest hit's answer so far.
    best: Option<Hit>,
    /// Occlusion's answer: set when a primitive lies on the segment.
    blocked: bool,
    /// The ray's index in the stream.
    ray: usize,
    /// Its stack: `need` entries from `base` in the shared buffer, the top at `base + sp`.
    base: usize,
    sp: usize,
}

impl Flight {
    /// Takes ray `ray` in place of the one done, with the root on `stack` (its own); false for a ray
    /// that finds nothing without a traversal (a non-finite origin or direction, as in
    /// `Accel::intersect`).
    #[inline(always)]
    fn start(&mut self, r: &StreamRay, ray: usize, stack: &mut [MaybeUninit<Entry>]) -> bool {
        if !(r.origin.is_finite() && r.dir.is_finite()) {
            return false;
        }
        self.d = positive_zeros(r.dir);
        self.br = BoxRay::new(r.origin, self.d, r.tmin);
        self.tmax = r.tmax;
        self.best = None;
        self.blocked = false;
        self.ray = ray;
        stack[0] = MaybeUninit::new(Entry { code: 0, t: r.tmin });
        self.sp = 1;
        true
    }

    /// The ray as the leaves' lanes read it.
    #[inline(always)]
    fn lanes(&self) -> LaneRay {
        LaneRay::new(self.br.origin(), self.d, self.br.tmin)
    }

    /// One turn of closest hit: entries within `tmax` tested until the next one is a leaf
    /// or a node below the top levels, which is prefetched. True when the ray is done.
    #[inline(always)]
    fn closest_turn<N: NodeTest>(
        &mut self,
        w: &Wide,
        stack: &mut [MaybeUninit<Entry>],
        hot: u32,
    ) -> bool {
        let s = stack;
        // The stack top in a register for the turn, not in `self`, which the pushes alias.
        let mut sp = self.sp;
        loop {
            let Some(e) = pop::<true>(s, &mut sp, self.tmax) else {
                return true;
            };
            if e.code & LEAF == 0 {
                let node = &w.nodes[e.code as usize];
                let (mask, tnear) = N::test(node, &self.br, self.tmax);
                push_nearest_on_top(node, mask, &tnear, s, &mut sp);
            } else {
                leaf_closest(w, e.code, &self.lanes(), &mut self.tmax, &mut self.best);
            }
            match next::<true>(w, s, &mut sp, self.tmax, hot) {
                Next::Done => return true,
                Next::Hot => {}
                Next::Asked => {
                    self.sp = sp;
                    return false;
                }
            }
        }
    }

    /// One turn of occlusion, as [`Flight::closest_turn`]. True when the ray is done, with
    /// `blocked` set when something lies on its segment.
    #[inline(always)]
    fn occluded_turn<N: NodeTest>(
        &mut self,
        w: &Wide,
        stack: &mut [MaybeUninit<Entry>],
        hot: u32,
    ) -> bool {
        let s = stack;
        let mut sp = self.sp;
        loop {
            let Some(e) = pop::<false>(s, &mut sp, self.tmax) else {
                return true;
            };
            if e.code & LEAF == 0 {
                let node = &w.nodes[e.code as usize];
                let (mask, _) = N::test(node, &self.br, self.tmax);
                push_as_found(node, mask, s, &mut sp);
            } else if leaf_blocks(w, e.code, &self.lanes(), self.tmax) {
                self.blocked = true;
                return true;
            }
            match next::<false>(w, s, &mut sp, self.tmax, hot) {
                Next::Done => return true,
                Next::Hot => {}
                Next::Asked => {
                    self.sp = sp;
                    return false;
                }
            }
        }
    }
}

/// The entry the single-ray traversal would test next, or `None` when the stack holds no
/// more. Closest hit (`CULL`) skips entries beyond `tmax` as that traversal does; occlusion
/// skips none.
#[inline(always)]
fn pop<const CULL: bool>(s: &[MaybeUninit<Entry>], sp: &mut usize, tmax: f32) -> Option<Entry> {
    while *sp > 0 {
        *sp -= 1;
        // SAFETY: entries below `sp` were written.
        let e = unsafe { s[*sp].assume_init() };
        if !(CULL && e.t > tmax) {
            return Some(e);
        }
    }
    None
}

/// What a ray visits next.
enum Next {
    /// Nothing: the ray is done.
    Done,
    /// A node of the top levels (index below `hot`), likely cached: the turn goes on.
    Hot,
    /// A deeper node or a leaf, now prefetched: the turn ends.
    Asked,
}

/// Looks at the entry the ray visits next (dropping, for closest hit, the entries on top
/// that it would skip).
#[inline(always)]
fn next<const CULL: bool>(
    w: &Wide,
    s: &[MaybeUninit<Entry>],
    sp: &mut usize,
    tmax: f32,
    hot: u32,
) -> Next {
    while *sp > 0 {
        // SAFETY: entries below `sp` were written.
        let e = unsafe { s[*sp - 1].assume_init() };
        if !(CULL && e.t > tmax) {
            // A leaf's code has the top bit set, so it is never below `hot`.
            if e.code < hot {
                return Next::Hot;
            }
            fetch_all(w, e.code);
            return Next::Asked;
        }
        *sp -= 1;
    }
    Next::Done
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
    /// Entries of each ray's stack: its slice of `stack`, so that an overflow panics as in
    /// the single-ray traversal instead of reaching the next ray's.
    need: usize,
    /// Nodes below this index (the top levels, stored first) are tested without a turn.
    hot: u32,
}

/// Takes a ray's answer: its index and its state when done, `None` for a ray that needs no
/// traversal.
trait Answer: FnMut(usize, Option<&Flight>) {}
impl<F: FnMut(usize, Option<&Flight>)> Answer for F {}

impl<'a> Flights<'a> {
    /// Up to [`IN_FLIGHT`] rays started.
    #[inline(always)]
    fn new(rays: &'a [StreamRay], need: usize, hot: u32, answer: &mut impl Answer) -> Flights<'a> {
        let n = IN_FLIGHT.min(rays.len());
        let mut f = Flights {
            rays,
            next: 0,
            live: Vec::with_capacity(n),
            stack: vec![MaybeUninit::uninit(); n * need],
            need,
            hot,
        };
        for slot in 0..n {
            f.live.push(Flight {
                br: BoxRay::new(Vec3::ZERO, Vec3::ONE, 0.0),
                d: Vec3::ONE,
                tmax: 0.0,
                best: None,
                blocked: false,
                ray: 0,
                base: slot * need,
                sp: 0,
            });
            if !f.admit(slot, answer) {
                f.live.pop();
                break;
            }
        }
        f
    }

    /// Starts the stream's next ray that needs a traversal in slot `k`; false when none is left.
    #[inline(always)]
    fn admit(&mut self, k: usize, answer: &mut impl Answer) -> bool {
        while self.next < self.rays.len() {
            let i = self.next;
            self.next += 1;
            let r = &mut self.live[k];
            if r.start(
                &self.rays[i],
                i,
                &mut self.stack[r.base..r.base + self.need],
            ) {
                return true;
            }
            answer(i, None);
        }
        false
    }

    /// Turns round the rays in flight until the stream is done: `turn` runs one turn of a ray
    /// and says whether it is done.
    #[inline(always)]
    fn run(
        &mut self,
        mut turn: impl FnMut(&mut Flight, &mut [MaybeUninit<Entry>], u32) -> bool,
        answer: &mut impl Answer,
    ) {
        while !self.live.is_empty() {
            let mut k = 0;
            while k < self.live.len() {
                let r = &mut self.live[k];
                if turn(r, &mut self.stack[r.base..r.base + self.need], self.hot) {
                    answer(self.live[k].ray, Some(&self.live[k]));
                    if !self.admit(k, answer) {
                        self.live.swap_remove(k);
                        continue;
                    }
                }
                k += 1;
            }
        }
    }
}

/// `Accel::intersect` of each ray into `hits`, the rays interleaved; nodes below `hot` cost
/// no hand-over ([`HOT_NODES`] outside the tests).
#[inline(always)]
pub fn closest_stream<N: NodeTest>(
    w: &Wide,
    need: usize,
    hot: u32,
    rays: &[StreamRay],
    hits: &mut [Option<Hit>],
) {
    let mut answer = |i: usize, r: Option<&Flight>| hits[i] = r.and_then(|r| r.best);
    let mut f = Flights::new(rays, need, hot, &mut answer);
    f.run(
        |r, stack, hot| r.closest_turn::<N>(w, stack, hot),
        &mut answer,
    );
}

/// `Accel::occluded` of each ray into `blocked`, as [`closest_stream`].
#[inline(always)]
pub fn occluded_stream<N: NodeTest>(
    w: &Wide,
    need: usize,
    hot: u32,
    rays: &[StreamRay],
    blocked: &mut [bool],
) {
    let mut answer = |i: usize, r: Option<&Flight>| blocked[i] = r.is_some_and(|r| r.blocked);
    let mut f = Flights::new(rays, need, hot, &mut answer);
    f.run(
        |r, stack, hot| r.occluded_turn::<N>(w, stack, hot),
        &mut answer,
    );
}
