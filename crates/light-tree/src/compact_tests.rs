//! Tests of the compact node pairs and quads: bounds rounded outward, the compact importance
//! positive wherever the exact one is and close to it, both lane implementations
//! bit-identical, and the compact descents equal to the generic ones bit for bit.

use crate::codes::{LEAF_BIT, slots_importance};
use crate::compact::{pair_importance, quad_importance};
use crate::lanes::{Fast, Fast8, Portable, Scalar4};
use crate::tests::{Layout, eight_wide_importance, rand_lights, rand_receiver, tree_configs};
use crate::{DescentSimd, LightTree, NodeId, Rescaled};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg32;

/// Least ratio compact / exact importance allowed at receivers farther than 1e-3 of the root
/// box's longest extent from every light box (measured: 0.99955 over 518,408 positive pairs).
const MIN_RATIO: f32 = 0.99;

fn trees(rng: &mut Pcg32) -> Vec<(LightTree, Vec<crate::LightBounds>)> {
    let mut out = Vec::new();
    for (n, layout, zero) in tree_configs() {
        let lights = rand_lights(rng, n, layout, zero);
        out.push((LightTree::build(&lights).unwrap(), lights));
    }
    let lights = rand_lights(rng, 2000, Layout::Uniform, true);
    out.push((LightTree::build(&lights).unwrap(), lights));
    out
}

#[test]
fn compact_bounds_contain_the_exact_ones() {
    let mut rng = Pcg32::seed_from_u64(41);
    for (tree, _) in trees(&mut rng) {
        for id in 0..tree.nodes().len() as NodeId {
            let (lo, hi, cos_o, cos_e) = tree.compact.decoded(id);
            let (elo, ehi) = tree.node(id).aabb();
            assert!(lo.cmple(elo).all() && hi.cmpge(ehi).all(), "node {id}");
            let e = tree.node_extra(id);
            assert!(cos_o as f64 <= (e.theta_o as f64).cos(), "node {id}");
            assert!(cos_e as f64 <= (e.theta_e as f64).cos(), "node {id}");
        }
    }
}

/// Wherever the exact E&K importance of a node is positive, the compact one is too, and at
/// receivers away from the lights it is at least `MIN_RATIO` of it.
#[test]
fn compact_importance_is_conservative() {
    let mut rng = Pcg32::seed_from_u64(42);
    let mut worst = f32::INFINITY;
    let mut positive = 0usize;
    for (tree, lights) in trees(&mut rng) {
        let (rlo, rhi) = tree.node(0).aabb();
        let scale = (rhi - rlo).max_element().max(1e-3);
        for _ in 0..200 {
            let (x, n) = rand_receiver(&mut rng);
            // Within a few quanta of a light box the compact box's extra margin dominates
            // Φ / max(d², r²/4); the ratio is only bounded away from the lights.
            let far = lights.iter().all(|l| {
                let d = (x - x.clamp(l.aabb_min, l.aabb_max)).length();
                d > 1e-3 * scale
            });
            for id in 0..tree.nodes().len() as NodeId {
                let exact = tree.node(id).importance(x, n);
                let compact = tree.importance(id, x, n);
                assert!(
                    compact >= 0.0 && compact.is_finite(),
                    "node {id}: {compact}"
                );
                if exact > 0.0 {
                    positive += 1;
                    assert!(
                        compact > 0.0,
                        "node {id} at {x} {n}: exact {exact}, compact 0"
                    );
                    if far {
                        worst = worst.min(compact / exact);
                    }
                }
            }
        }
    }
    println!(
        "{positive} positive exact importances; least compact/exact ratio away from the lights {worst}"
    );
    assert!(positive > 10_000);
    assert!(worst >= MIN_RATIO, "ratio {worst}");
}

/// The SSE2 lanes and the portable ones give the same bits (the fallback is forced here).
#[test]
fn lane_implementations_agree() {
    let mut rng = Pcg32::seed_from_u64(43);
    for (tree, _) in trees(&mut rng) {
        let c = &tree.compact;
        for _ in 0..50 {
            let (x, n) = rand_receiver(&mut rng);
            // Also receivers on a node's centre and far away.
            let x = match rng.random_range(0..8u32) {
                0 => tree.node(0).center(),
                1 => x * 1e4,
                _ => x,
            };
            for (i, p) in c.pairs.iter().enumerate() {
                let a = pair_importance::<Fast>(p, &c.quant, x, n);
                let b = pair_importance::<Scalar4>(p, &c.quant, x, n);
                assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "{a:?} vs {b:?}");
                // Four lanes from two pairs: each pair's lanes as on their own.
                let other = &c.pairs[(i * 7 + 3) % c.pairs.len()];
                let o = pair_importance::<Scalar4>(other, &c.quant, x, n);
                let want = [a[0], a[1], o[0], o[1]].map(f32::to_bits);
                for q in [
                    quad_importance::<Fast>(p, other, &c.quant, x, n),
                    quad_importance::<Scalar4>(p, other, &c.quant, x, n),
                ] {
                    assert_eq!(q.map(f32::to_bits), want);
                }
            }
        }
    }
}

/// Every even-depth interior node has a quad whose lanes are its grandchildren (a leaf child
/// in the first lane of its half, beside an empty lane of importance 0), each lane the same
/// bits as `importance` of its node on both lane implementations, with the right codes.
#[test]
fn quads_hold_the_grandchildren() {
    let mut rng = Pcg32::seed_from_u64(46);
    for (tree, _) in trees(&mut rng) {
        let c = &tree.compact;
        let code = |id: NodeId| match tree.node(id).light() {
            Some(l) => LEAF_BIT | l as u32,
            None => c.quad_of[id as usize],
        };
        for _ in 0..10 {
            let (x, n) = rand_receiver(&mut rng);
            for id in 0..tree.nodes().len() as NodeId {
                let node = tree.node(id);
                let q = c.quad_of[id as usize];
                let Some((l, r)) = node.children(id) else {
                    assert_eq!(q, u32::MAX);
                    continue;
                };
                if node.depth() % 2 == 1 {
                    assert_eq!(q, u32::MAX);
                    continue;
                }
                let quad = &c.quads[q as usize];
                let fast = slots_importance::<4, Fast, _>(&quad.0, &c.quant, x, n);
                let portable = slots_importance::<4, Scalar4, _>(&quad.0, &c.quant, x, n);
                assert_eq!(fast.map(f32::to_bits), portable.map(f32::to_bits));
                for (half, child) in [(0, l), (1, r)] {
                    let lanes: [Option<NodeId>; 2] = match tree.node(child).children(child) {
                        Some((a, b)) => [Some(a), Some(b)],
                        None => [Some(child), None],
                    };
                    for (k, lane) in lanes.into_iter().enumerate() {
                        let i = 2 * half + k;
                        match lane {
                            Some(g) => {
                                assert_eq!(fast[i].to_bits(), tree.importance(g, x, n).to_bits());
                                assert_eq!(quad.child[i], code(g));
                            }
                            None => {
                                assert_eq!(fast[i], 0.0);
                                assert_eq!(quad.child[i], LEAF_BIT);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Every interior node at a depth divisible by 3 has an oct whose lanes are its
/// great-grandchildren in branch-bit order (a leaf above that depth in the first lane of its
/// range, beside empty lanes of importance 0), each lane the same bits as `importance` of its
/// node on every lane implementation, with the right codes.
#[test]
fn octs_hold_the_great_grandchildren() {
    let mut rng = Pcg32::seed_from_u64(47);
    for (tree, _) in trees(&mut rng) {
        let c = &tree.compact;
        let code = |id: NodeId| match tree.node(id).light() {
            Some(l) => LEAF_BIT | l as u32,
            None => c.oct_of[id as usize],
        };
        // The lanes under `id` by branch bits: (lane, node), leaves in their range's first.
        fn lanes_of(
            tree: &LightTree,
            id: NodeId,
            first: usize,
            span: usize,
            out: &mut Vec<(usize, NodeId)>,
        ) {
            match tree.node(id).children(id) {
                Some((l, r)) if span > 1 => {
                    lanes_of(tree, l, first, span / 2, out);
                    lanes_of(tree, r, first + span / 2, span / 2, out);
                }
                _ => out.push((first, id)),
            }
        }
        for _ in 0..10 {
            let (x, n) = rand_receiver(&mut rng);
            for id in 0..tree.nodes().len() as NodeId {
                let node = tree.node(id);
                let o = c.oct_of[id as usize];
                if node.is_leaf() || node.depth() % 3 != 0 {
                    assert_eq!(o, u32::MAX);
                    assert_eq!(tree.oct_of(id), None);
                    continue;
                }
                let fast = tree.oct_lanes::<Fast8>(o, x, n);
                let portable = tree.oct_lanes::<Portable<8>>(o, x, n);
                assert_eq!(fast.map(f32::to_bits), portable.map(f32::to_bits));
                // What a caller's own descent reads: the same oct and lanes.
                assert_eq!(tree.oct_of(id), Some(o));
                let public = tree.oct_importances(o, x, n);
                assert_eq!(public.map(f32::to_bits), portable.map(f32::to_bits));
                #[cfg(target_arch = "x86_64")]
                if DescentSimd::detect() == DescentSimd::Avx2 {
                    // SAFETY: the CPU has AVX2.
                    let avx = unsafe { avx_lanes(&tree, o, x, n) };
                    assert_eq!(avx.map(f32::to_bits), portable.map(f32::to_bits));
                }
                let (l, r) = node.children(id).unwrap();
                let mut lanes = Vec::new();
                lanes_of(&tree, l, 0, 4, &mut lanes);
                lanes_of(&tree, r, 4, 4, &mut lanes);
                let oct = &c.octs[o as usize];
                let mut filled = [false; 8];
                for (lane, g) in lanes {
                    filled[lane] = true;
                    assert_eq!(fast[lane].to_bits(), tree.importance(g, x, n).to_bits());
                    assert_eq!(oct.child[lane], code(g));
                    assert_eq!(c.oct_nodes[o as usize][lane], g);
                }
                for lane in (0..8).filter(|&k| !filled[k]) {
                    assert_eq!(fast[lane], 0.0);
                    assert_eq!(oct.child[lane], LEAF_BIT);
                    assert_eq!(c.oct_nodes[o as usize][lane], crate::NO_NODE);
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn avx_lanes(tree: &LightTree, oct: u32, x: glam::Vec3, n: glam::Vec3) -> [f32; 8] {
    tree.oct_lanes::<crate::lanes::Avx8>(oct, x, n)
}

/// `sample_from` / `pmf_from` sample the binary descent under `LightTree::importance` with
/// interior nodes at depths not divisible by 3 weighed as the sum of their children's (the
/// eight-wide descent, `oct.rs`): the replayed pmf is `pmf_subtree`'s under that weight to
/// f32 rounding, from random start nodes; a sample's pmf is its replay's, bit for bit; and
/// AVX and the forced fallback give the same lights and pmfs. `child_importances` equals the
/// two `importance` calls.
#[test]
fn compact_descent_samples_the_eight_wide_weights() {
    let mut rng = Pcg32::seed_from_u64(44);
    for (mut tree, _) in trees(&mut rng) {
        let mut fallback = tree.clone();
        fallback.set_descent_simd(DescentSimd::Fallback).unwrap();
        for _ in 0..100 {
            let (x, n) = rand_receiver(&mut rng);
            let start = rng.random_range(0..tree.nodes().len() as NodeId);
            let imp = |c| tree.importance(c, x, n);
            if let Some((l, r)) = tree.node(start).children(start) {
                let ci = tree.child_importances(start, x, n).unwrap();
                assert_eq!(ci.map(f32::to_bits), [imp(l).to_bits(), imp(r).to_bits()]);
            } else {
                assert!(tree.child_importances(start, x, n).is_none());
            }
            let (own, sib) = tree.importance_and_sibling(start, x, n);
            assert_eq!(own.to_bits(), imp(start).to_bits());
            match sib {
                None => assert_eq!(start, tree.root()),
                Some((s, v)) => {
                    assert_eq!(v.to_bits(), imp(s).to_bits());
                    // The sibling shares the parent: both sit in one pair, other side.
                    let (a, b) = (
                        tree.compact.slot_of[start as usize],
                        tree.compact.slot_of[s as usize],
                    );
                    assert_eq!((a >> 1, a & 1), (b >> 1, 1 - (b & 1)));
                }
            }
            for _ in 0..4 {
                let u = rng.random::<u64>();
                let a = tree.sample_from(start, x, n, &mut Rescaled(u));
                let b = fallback.sample_from(start, x, n, &mut Rescaled(u));
                assert_eq!(
                    a.map(|(l, p)| (l, p.to_bits())),
                    b.map(|(l, p)| (l, p.to_bits()))
                );
                if let Some((l, p)) = a {
                    assert_eq!(tree.pmf_from(start, x, n, l).to_bits(), p.to_bits());
                }
            }
            let eight_wide = |c| eight_wide_importance(&tree, start, c, x, n);
            for light in 0..tree.num_lights().min(64) {
                let p = tree.pmf_from(start, x, n, light);
                assert_eq!(p.to_bits(), fallback.pmf_from(start, x, n, light).to_bits());
                let want = tree.pmf_subtree(start, eight_wide, light);
                assert!(
                    (p - want).abs() <= 1e-5 * want + 1e-12,
                    "start {start} light {light}: {p} vs {want}"
                );
            }
        }
        // Forcing AVX2 works exactly where the CPU has it.
        assert_eq!(
            tree.set_descent_simd(DescentSimd::Avx2).is_ok(),
            DescentSimd::detect() == DescentSimd::Avx2
        );
    }
}

/// Two descents side by side are the two single descents bit for bit (lights, pmfs, and the
/// rescaled numbers they leave), on AVX and on the forced fallback, from random start nodes
/// at any depth (binary steps first), with receivers with and without a normal (mixed pairs
/// go one after the other).
#[test]
fn paired_descents_equal_the_single_ones() {
    let mut rng = Pcg32::seed_from_u64(45);
    for (tree, _) in trees(&mut rng) {
        let mut fallback = tree.clone();
        fallback.set_descent_simd(DescentSimd::Fallback).unwrap();
        for t in [&tree, &fallback] {
            for _ in 0..200 {
                let q = [rand_receiver(&mut rng), rand_receiver(&mut rng)];
                let nodes = t.nodes().len() as NodeId;
                let start = if rng.random::<f32>() < 0.5 {
                    [t.root(), t.root()]
                } else {
                    [rng.random_range(0..nodes), rng.random_range(0..nodes)]
                };
                let u = [rng.random::<u64>(), rng.random::<u64>()];
                let (mut a, mut b) = (Rescaled(u[0]), Rescaled(u[1]));
                let single = [
                    t.sample_from(start[0], q[0].0, q[0].1, &mut a),
                    t.sample_from(start[1], q[1].0, q[1].1, &mut b),
                ];
                let (mut pa, mut pb) = (Rescaled(u[0]), Rescaled(u[1]));
                let paired = t.sample_pair_from(
                    start,
                    [q[0].0, q[1].0],
                    [q[0].1, q[1].1],
                    [&mut pa, &mut pb],
                );
                let bits =
                    |r: [Option<(usize, f32)>; 2]| r.map(|o| o.map(|(l, p)| (l, p.to_bits())));
                assert_eq!(bits(paired), bits(single));
                assert_eq!((pa.0, pb.0), (a.0, b.0));
            }
        }
    }
}

/// `pmf_from_cached` is `pmf_from` bit for bit, whether its cache starts empty, holds every
/// oct it reads, or forgets some between replays (a direct-mapped cache evicts).
#[test]
fn cached_pmf_replay_matches_the_uncached_one() {
    struct Lossy {
        map: std::collections::HashMap<u32, [f32; 8]>,
        hits: usize,
        drop_odd: bool,
    }
    impl crate::LaneCache for Lossy {
        fn get(&mut self, oct: u32) -> Option<[f32; 8]> {
            let v = self.map.get(&oct).copied();
            self.hits += v.is_some() as usize;
            v
        }
        fn put(&mut self, oct: u32, lanes: [f32; 8]) {
            if !(self.drop_odd && oct % 2 == 1) {
                self.map.insert(oct, lanes);
            }
        }
    }
    let mut rng = Pcg32::seed_from_u64(46);
    for (tree, _) in trees(&mut rng) {
        for drop_odd in [false, true] {
            for _ in 0..20 {
                let (x, n) = rand_receiver(&mut rng);
                let start = rng.random_range(0..tree.nodes().len() as NodeId);
                let mut cache = Lossy {
                    map: Default::default(),
                    hits: 0,
                    drop_odd,
                };
                for _ in 0..2 {
                    for light in 0..tree.num_lights().min(64) {
                        assert_eq!(
                            tree.pmf_from_cached(start, x, n, light, &mut cache)
                                .to_bits(),
                            tree.pmf_from(start, x, n, light).to_bits()
                        );
                    }
                }
                // The second round read every quad the first one kept.
                assert!(cache.map.is_empty() || cache.hits > 0);
            }
        }
    }
}

/// `importances` gives each node's `importance`, bit for bit, for node lists in any order:
/// cuts (siblings side by side), random lists with repeats, the empty list.
#[test]
fn batched_importances_match_one_call_per_node() {
    let mut rng = Pcg32::seed_from_u64(45);
    for (tree, _) in trees(&mut rng) {
        let count = tree.nodes().len() as NodeId;
        for _ in 0..40 {
            let (x, n) = rand_receiver(&mut rng);
            let mut lists = vec![Vec::new(), vec![tree.root()]];
            lists.push(
                tree.cut(1 + rng.random_range(0..64usize), |_| true)
                    .nodes
                    .clone(),
            );
            lists.push(
                (0..rng.random_range(1..50))
                    .map(|_| rng.random_range(0..count))
                    .collect(),
            );
            for nodes in lists {
                let mut out = vec![f32::NAN; nodes.len()];
                tree.importances(&nodes, x, n, &mut out);
                for (&node, v) in nodes.iter().zip(&out) {
                    assert_eq!(
                        v.to_bits(),
                        tree.importance(node, x, n).to_bits(),
                        "node {node}"
                    );
                }
            }
        }
    }
}

/// `sample_quads` / `pmf_quads` under a caller's weight equal `sample_subtree` /
/// `pmf_subtree` under the same weight with each odd-depth interior node weighed as the sum of
/// its children's (sanitised), bit for bit, from random start nodes; the weight sees each
/// quad's own nodes, and its empty lanes count as 0 whatever it returns there.
#[test]
fn caller_weighted_quad_descent_matches_the_generic_one() {
    let mut rng = Pcg32::seed_from_u64(46);
    // An arbitrary deterministic weight with zeros, NaN and infinities among its values.
    let weight = |id: NodeId| match (id as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 59 {
        0 => 0.0,
        1 => f32::NAN,
        2 => f32::INFINITY,
        k => (k as f32).powi(3) * 1e-3, // k < 32
    };
    for (tree, _) in trees(&mut rng) {
        let binary = |id: NodeId| {
            let node = tree.node(id);
            match node.children(id) {
                Some((l, r)) if node.depth() % 2 == 1 => {
                    crate::descent_step::sanitize(weight(l))
                        + crate::descent_step::sanitize(weight(r))
                }
                _ => weight(id),
            }
        };
        let mut lanes = |quad: Option<u32>, nodes: &[NodeId; 4]| {
            if let Some(q) = quad {
                assert_eq!(tree.quad_nodes(q), nodes);
            }
            nodes.map(|id| {
                if id == crate::NO_NODE {
                    7.0
                } else {
                    weight(id)
                }
            })
        };
        for _ in 0..200 {
            let start = rng.random_range(0..tree.nodes().len() as NodeId);
            let u = rng.random::<u64>();
            let a = tree.sample_quads(start, &mut lanes, &mut Rescaled(u));
            let b = tree.sample_subtree(start, binary, &mut Rescaled(u));
            assert_eq!(
                a.map(|(l, p)| (l, p.to_bits())),
                b.map(|(l, p)| (l, p.to_bits()))
            );
            for light in 0..tree.num_lights().min(64) {
                assert_eq!(
                    tree.pmf_quads(start, &mut lanes, light).to_bits(),
                    tree.pmf_subtree(start, binary, light).to_bits()
                );
            }
        }
    }
}

/// The pair handle gives `child_importances`, bit for bit, for every interior node, and no pair
/// for a leaf.
#[test]
fn pair_child_importances_match_child_importances() {
    let mut rng = Pcg32::seed_from_u64(46);
    for (tree, _) in trees(&mut rng) {
        for _ in 0..10 {
            let (x, n) = rand_receiver(&mut rng);
            for id in 0..tree.nodes().len() as NodeId {
                let Some(pair) = tree.children_pair_of(id) else {
                    assert!(tree.node(id).is_leaf(), "node {id}");
                    continue;
                };
                let want = tree.child_importances(id, x, n).unwrap();
                let got = tree.pair_child_importances(pair, x, n);
                assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits), "node {id}");
            }
        }
    }
}

/// The eight-lane look-ahead gives each pair's `pair_child_importances`, bit for bit, on both
/// kinds of lanes, and `None` below a leaf.
#[test]
fn pair_child_importances_ahead_match_one_call_per_pair() {
    let mut rng = Pcg32::seed_from_u64(47);
    for (mut tree, _) in trees(&mut rng) {
        for simd in [DescentSimd::Fallback, DescentSimd::detect()] {
            tree.set_descent_simd(simd).unwrap();
            for _ in 0..10 {
                let (x, n) = rand_receiver(&mut rng);
                for id in 0..tree.nodes().len() as NodeId {
                    let Some(pair) = tree.children_pair_of(id) else {
                        continue;
                    };
                    let (own, below) = tree.pair_child_importances_ahead(pair, x, n);
                    let bits = |v: [f32; 2]| v.map(f32::to_bits);
                    assert_eq!(bits(own), bits(tree.pair_child_importances(pair, x, n)));
                    let (l, r) = tree.node(id).children(id).unwrap();
                    for (child, got) in [l, r].into_iter().zip(below) {
                        let want = tree.child_importances(child, x, n);
                        assert_eq!(got.map(bits), want.map(bits), "node {id}, child {child}");
                    }
                }
            }
        }
    }
}
