//! Statistical and structural tests of the tree (unit tests beside the code).

use chi2_test::{chi2_test, sidak_significance as sidak};

fn counts(observed: &[u64]) -> Vec<f64> {
    observed.iter().map(|&o| o as f64).collect()
}
use crate::{
    BuildError, Fresh, LightBounds, LightTree, MAX_DEPTH, NodeId, Rescaled, SplitCriterion,
    SplitParams,
};
use glam::Vec3;
use rand::{Rng, RngExt, SeedableRng};
use rand_pcg::Pcg32;
use std::f32::consts::{FRAC_PI_2, PI};

pub(crate) fn rand_dir(rng: &mut impl Rng) -> Vec3 {
    let z = 1.0 - 2.0 * rng.random::<f32>();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * rng.random::<f32>();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub(crate) fn rand_in_box(rng: &mut impl Rng, h: f32) -> Vec3 {
    Vec3::new(
        rng.random::<f32>() * 2.0 - 1.0,
        rng.random::<f32>() * 2.0 - 1.0,
        rng.random::<f32>() * 2.0 - 1.0,
    ) * h
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum Layout {
    /// Uniform in [-1, 1]³.
    Uniform,
    /// All lights at the same point.
    Coincident,
    /// Two tight clusters far apart.
    Clustered,
}

/// Random light of a random kind: one-sided quad, two-sided quad, sphere, point, spot.
fn rand_light(rng: &mut impl Rng, p: Vec3, zero_power_ok: bool) -> LightBounds {
    let kind = rng.random_range(0..5u32);
    let size = if kind == 3 {
        0.0
    } else {
        0.01 + 0.05 * rng.random::<f32>()
    };
    let axis = rand_dir(rng);
    let (theta_o, theta_e, two_sided) = match kind {
        0 => (0.0, FRAC_PI_2, false),
        1 => (0.0, FRAC_PI_2, true),
        2 | 3 => (PI, FRAC_PI_2, false),
        _ => (0.3 * rng.random::<f32>(), 0.5 * rng.random::<f32>(), false),
    };
    let mut power = 0.1 + 10.0 * rng.random::<f32>();
    if zero_power_ok && rng.random::<f32>() < 0.1 {
        power = 0.0;
    }
    LightBounds {
        aabb_min: p - Vec3::splat(size),
        aabb_max: p + Vec3::splat(size),
        axis,
        theta_o,
        theta_e,
        power,
        two_sided,
    }
}

pub(crate) fn rand_lights(
    rng: &mut impl Rng,
    n: usize,
    layout: Layout,
    zero_power_ok: bool,
) -> Vec<LightBounds> {
    let c = rand_in_box(rng, 1.0);
    (0..n)
        .map(|_| {
            let p = match layout {
                Layout::Uniform => rand_in_box(rng, 1.0),
                Layout::Coincident => c,
                Layout::Clustered => {
                    let off = if rng.random::<bool>() {
                        Vec3::X
                    } else {
                        -Vec3::X
                    };
                    off * 5.0 + rand_in_box(rng, 0.05)
                }
            };
            rand_light(rng, p, zero_power_ok)
        })
        .collect()
}

/// Random receiver: a point in [-1.5, 1.5]³ and a normal that is zero one time in four.
pub(crate) fn rand_receiver(rng: &mut impl Rng) -> (Vec3, Vec3) {
    let x = rand_in_box(rng, 1.5);
    let n = if rng.random::<f32>() < 0.25 {
        Vec3::ZERO
    } else {
        rand_dir(rng)
    };
    (x, n)
}

/// Reference distribution of a descent from `start` by top-down propagation:
/// (probability per light, mass lost in dead ends).
/// The node weights of the eight-wide descent from `start` (`LightTree::sample_from`):
/// `importance`, except that an interior node at a depth not divisible by 3, below the first
/// such depth under `start` (above it the descent takes binary steps), weighs as the sum of
/// its children's weights (sanitised).
pub(crate) fn eight_wide_importance(
    tree: &LightTree,
    start: NodeId,
    id: NodeId,
    x: Vec3,
    n: Vec3,
) -> f32 {
    let first_oct = tree.node(start).depth().div_ceil(3) * 3;
    let node = tree.node(id);
    match node.children(id) {
        Some((l, r)) if node.depth() % 3 != 0 && node.depth() > first_oct => {
            let w = |c| crate::descent_step::sanitize(eight_wide_importance(tree, start, c, x, n));
            w(l) + w(r)
        }
        _ => tree.importance(id, x, n),
    }
}

fn reference_pmf(tree: &LightTree, start: NodeId, imp: &dyn Fn(NodeId) -> f32) -> (Vec<f64>, f64) {
    let mut probs = vec![0.0f64; tree.num_lights()];
    let mut dead = 0.0f64;
    let mut stack = vec![(start, 1.0f64)];
    while let Some((id, p)) = stack.pop() {
        let node = tree.node(id);
        if let Some(light) = node.light() {
            probs[light] += p;
            continue;
        }
        let (l, r) = node.children(id).unwrap();
        let (il, ir) = (imp(l).max(0.0) as f64, imp(r).max(0.0) as f64);
        if il + ir <= 0.0 {
            dead += p;
            continue;
        }
        stack.push((l, p * il / (il + ir)));
        stack.push((r, p * ir / (il + ir)));
    }
    (probs, dead)
}

/// All the sizes and layouts the statistical tests run over.
pub(crate) fn tree_configs() -> Vec<(usize, Layout, bool)> {
    let mut v = Vec::new();
    for n in [1usize, 2, 3, 5, 17, 64] {
        v.push((n, Layout::Uniform, false));
    }
    v.push((40, Layout::Coincident, false));
    v.push((40, Layout::Clustered, true));
    v.push((300, Layout::Uniform, true));
    v
}

#[test]
fn node_is_one_cache_line() {
    assert_eq!(std::mem::size_of::<crate::Node>(), 64);
    assert_eq!(std::mem::align_of::<crate::Node>(), 64);
}

#[test]
fn structure_invariants() {
    let mut rng = Pcg32::seed_from_u64(1);
    for (n, layout, z) in tree_configs() {
        let lights = rand_lights(&mut rng, n, layout, z);
        let tree = LightTree::build(&lights).unwrap();
        let nodes = tree.nodes();
        assert_eq!(nodes.len(), 2 * n - 1);
        assert_eq!(tree.num_lights(), n);
        let mut seen = vec![false; n];
        for (id, node) in nodes.iter().enumerate() {
            let id = id as NodeId;
            let (first, last) = tree.subtree_range(id);
            assert_eq!(first, id);
            assert!((last as usize) < nodes.len());
            let (bmin, bmax) = node.aabb();
            assert!((node.center() - (bmin + bmax) * 0.5).length() < 1e-5);
            match node.children(id) {
                None => {
                    let l = node.light().unwrap();
                    assert!(!seen[l]);
                    seen[l] = true;
                    assert_eq!(tree.leaf_of(l), id);
                    assert_eq!(node.num_lights(), 1);
                    assert_eq!(bmin, lights[l].aabb_min);
                    assert_eq!(node.power(), lights[l].power);
                    // The trail replays the path from the root to this leaf.
                    let mut cur = tree.root();
                    let mut bits = tree.bit_trail(l);
                    for _ in 0..node.depth() {
                        let (lc, rc) = tree.node(cur).children(cur).unwrap();
                        cur = if bits & 1 == 0 { lc } else { rc };
                        bits >>= 1;
                    }
                    assert_eq!(cur, id);
                    assert_eq!(bits, 0);
                }
                Some((l, r)) => {
                    let (ln, rn) = (tree.node(l), tree.node(r));
                    assert_eq!(ln.num_lights() + rn.num_lights(), node.num_lights());
                    assert_eq!(r, tree.subtree_range(l).1 + 1);
                    assert_eq!(tree.subtree_range(r).1, last);
                    assert_eq!(ln.depth(), node.depth() + 1);
                    let sum = ln.power() + rn.power();
                    assert!((sum - node.power()).abs() <= 1e-4 * node.power().max(1.0));
                    for c in [l, r] {
                        let (cmin, cmax) = tree.node(c).aabb();
                        assert!(cmin.cmpge(bmin).all() && cmax.cmple(bmax).all());
                        assert!(tree.node_extra(c).theta_e <= tree.node_extra(id).theta_e);
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
        assert!(tree.max_depth() <= MAX_DEPTH);
    }
}

#[test]
fn importance_matches_point_light_formulas() {
    let mut rng = Pcg32::seed_from_u64(2);
    for _ in 0..200 {
        let p = rand_in_box(&mut rng, 1.0);
        let axis = rand_dir(&mut rng);
        let sphere = LightBounds::point(p, 2.0);
        let planar = LightBounds {
            axis,
            theta_o: 0.0,
            theta_e: FRAC_PI_2,
            ..sphere
        };
        let two = LightBounds {
            two_sided: true,
            ..planar
        };
        let (x, n) = rand_receiver(&mut rng);
        let w = p - x;
        let d2 = w.length_squared();
        let w = w / d2.sqrt();
        let recv = if n == Vec3::ZERO {
            1.0
        } else {
            n.dot(w).max(0.0)
        };
        let emit = (-axis.dot(w)).max(0.0);
        let emit2 = axis.dot(w).abs();
        for (l, expected) in [
            (sphere, sphere.power * recv / d2),
            (planar, planar.power * emit * recv / d2),
            (two, two.power * emit2 * recv / d2),
        ] {
            let t = LightTree::build(&[l]).unwrap();
            // The exact importance; the compact one is tested in compact_tests.rs.
            let got = t.node(0).importance(x, n);
            assert!(
                (got - expected).abs() <= 1e-4 * expected.max(1e-3),
                "got {got} expected {expected}"
            );
        }
    }
}

/// With zero-size lights (leaf sphere = a point inside every ancestor's sphere), a light of
/// positive leaf importance must have positive importance at every ancestor.
#[test]
fn importance_support_is_conservative() {
    let mut rng = Pcg32::seed_from_u64(3);
    for _ in 0..20 {
        let lights: Vec<LightBounds> = (0..64)
            .map(|_| {
                let p = rand_in_box(&mut rng, 1.0);
                let mut l = rand_light(&mut rng, p, false);
                l.aabb_max = l.aabb_min;
                l
            })
            .collect();
        let tree = LightTree::build(&lights).unwrap();
        for _ in 0..50 {
            let (x, n) = rand_receiver(&mut rng);
            for light in 0..lights.len() {
                if tree.importance(tree.leaf_of(light), x, n) <= 0.0 {
                    continue;
                }
                // Never lost in a dead end.
                assert!(tree.pmf(x, n, light) > 0.0);
                let mut cur = tree.root();
                let mut bits = tree.bit_trail(light);
                while cur != tree.leaf_of(light) {
                    assert!(
                        tree.importance(cur, x, n) > 0.0,
                        "ancestor {cur} of {light} is 0"
                    );
                    let (l, r) = tree.node(cur).children(cur).unwrap();
                    cur = if bits & 1 == 0 { l } else { r };
                    bits >>= 1;
                }
            }
        }
    }
}

/// Σ pmf = 1 (minus dead-end mass), pmf matches the reference, sample's pmf == pmf exactly.
#[test]
fn pmf_sums_to_one_and_matches_sample() {
    let mut rng = Pcg32::seed_from_u64(4);
    let mut cases = 0;
    let mut dead_cases = 0;
    let mut all_zero_cases = 0;
    let mut partial_mass = 0.0;
    for (n, layout, z) in tree_configs() {
        for _ in 0..8 {
            let lights = rand_lights(&mut rng, n, layout, z);
            let tree = LightTree::build(&lights).unwrap();
            for _ in 0..10 {
                let (x, nrm) = rand_receiver(&mut rng);
                let imp = |id| eight_wide_importance(&tree, tree.root(), id, x, nrm);
                let (reference, dead) = reference_pmf(&tree, tree.root(), &imp);
                let pmfs: Vec<f32> = (0..n).map(|l| tree.pmf(x, nrm, l)).collect();
                let sum: f64 = pmfs.iter().map(|&p| p as f64).sum();
                for l in 0..n {
                    assert!((pmfs[l] as f64 - reference[l]).abs() <= 1e-6 + 1e-5 * reference[l]);
                }
                cases += 1;
                if dead == 0.0 {
                    assert!((sum - 1.0).abs() < 1e-5, "sum {sum}");
                } else {
                    dead_cases += 1;
                    if dead < 1.0 {
                        partial_mass += dead;
                    }
                    if dead == 1.0 {
                        all_zero_cases += 1;
                        assert_eq!(sum, 0.0);
                    }
                    assert!((sum - (1.0 - dead)).abs() < 1e-5);
                }
                for _ in 0..20 {
                    let u = rng.random::<u64>();
                    match tree.sample(x, nrm, u) {
                        Some((l, p)) => {
                            assert!(p > 0.0);
                            assert_eq!(p.to_bits(), pmfs[l].to_bits(), "light {l}");
                        }
                        None => assert!(dead > 0.0),
                    }
                }
            }
        }
    }
    // Dead ends (all lights under the horizon or facing away) must be the exception.
    eprintln!(
        "{cases} cases, {dead_cases} with dead ends, {all_zero_cases} all zero, mean partial dead mass {}",
        partial_mass / (dead_cases - all_zero_cases) as f64
    );
    // Both branches of the check above are exercised.
    assert!(
        dead_cases > 0 && (cases - dead_cases) * 4 > cases,
        "{dead_cases} of {cases}"
    );
}

/// Sampled frequencies agree with pmf (chi-square, Šidák-corrected at 1 %).
#[test]
fn sample_frequencies_pass_chi2() {
    let mut rng = Pcg32::seed_from_u64(5);
    let configs = tree_configs();
    let per_config = 3;
    let num_tests = configs.len() * per_config;
    let alpha = sidak(0.01, num_tests);
    let samples = 20_000usize;
    for (n, layout, z) in configs {
        let lights = rand_lights(&mut rng, n, layout, z);
        let tree = LightTree::build(&lights).unwrap();
        for _ in 0..per_config {
            let (x, nrm) = rand_receiver(&mut rng);
            let mut observed = vec![0u64; n + 1];
            for _ in 0..samples {
                match tree.sample(x, nrm, rng.random::<u64>()) {
                    Some((l, _)) => observed[l] += 1,
                    None => observed[n] += 1,
                }
            }
            let mut expected: Vec<f64> = (0..n)
                .map(|l| tree.pmf(x, nrm, l) as f64 * samples as f64)
                .collect();
            let total: f64 = expected.iter().sum();
            expected.push((samples as f64 - total).max(0.0));
            let r = chi2_test(&counts(&observed), &expected);
            assert!(
                r.p_value > alpha,
                "n={n} {layout:?}: chi2 {} dof {} p {}",
                r.statistic,
                r.dof,
                r.p_value
            );
        }
    }
}

/// A custom node importance with zeros, a hash of the node id.
fn custom_importance(id: NodeId) -> f32 {
    let h = (id as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let h = (h ^ (h >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9) >> 40;
    if h.is_multiple_of(7) {
        0.0
    } else {
        (h % 1000) as f32 / 100.0 + 0.01
    }
}

#[test]
fn subtree_descent_with_both_random_sources() {
    let mut rng = Pcg32::seed_from_u64(6);
    let lights = rand_lights(&mut rng, 200, Layout::Uniform, false);
    let tree = LightTree::build(&lights).unwrap();
    let (x, nrm) = rand_receiver(&mut rng);
    let importances: [(&str, &dyn Fn(NodeId) -> f32); 2] = [
        ("custom", &custom_importance),
        ("E&K", &|id| tree.importance(id, x, nrm)),
    ];
    let starts: Vec<NodeId> = (0..6)
        .map(|_| rng.random_range(0..tree.nodes().len() as u32))
        .chain([tree.root()])
        .filter(|&s| !tree.node(s).is_leaf() || s == tree.root())
        .collect();
    let num_tests = starts.len() * importances.len() * 2;
    let alpha = sidak(0.01, num_tests);
    let samples = 20_000usize;
    for &start in &starts {
        let (first, last) = tree.subtree_range(start);
        for (name, imp) in importances {
            let (reference, dead) = reference_pmf(&tree, start, imp);
            let pmfs: Vec<f32> = (0..tree.num_lights())
                .map(|l| tree.pmf_subtree(start, imp, l))
                .collect();
            for (l, &p) in pmfs.iter().enumerate() {
                let leaf = tree.leaf_of(l);
                if leaf < first || leaf > last {
                    assert_eq!(p, 0.0);
                }
                assert!((p as f64 - reference[l]).abs() <= 1e-6 + 1e-5 * reference[l]);
            }
            let sum: f64 = pmfs.iter().map(|&p| p as f64).sum();
            assert!(
                (sum - (1.0 - dead)).abs() < 1e-5,
                "{name}: sum {sum} dead {dead}"
            );
            for fresh in [false, true] {
                let mut observed = vec![0u64; tree.num_lights() + 1];
                let mut r2 = Pcg32::seed_from_u64(rng.random());
                let mut fresh_src = Fresh(|| r2.random::<u64>());
                for _ in 0..samples {
                    let s = if fresh {
                        tree.sample_subtree(start, imp, &mut fresh_src)
                    } else {
                        tree.sample_subtree(start, imp, &mut Rescaled(rng.random::<u64>()))
                    };
                    match s {
                        Some((l, p)) => {
                            assert_eq!(p.to_bits(), pmfs[l].to_bits());
                            observed[l] += 1;
                        }
                        None => *observed.last_mut().unwrap() += 1,
                    }
                }
                let mut expected: Vec<f64> =
                    pmfs.iter().map(|&p| p as f64 * samples as f64).collect();
                expected.push(dead * samples as f64);
                let r = chi2_test(&counts(&observed), &expected);
                assert!(
                    r.p_value > alpha,
                    "{name} start {start} fresh {fresh}: chi2 {} dof {} p {}",
                    r.statistic,
                    r.dof,
                    r.p_value
                );
            }
        }
    }
}

/// Brute-force cluster lookup: the cut nodes whose DFS range holds the light's leaf.
fn covering(tree: &LightTree, nodes: &[NodeId], light: usize) -> Vec<usize> {
    let leaf = tree.leaf_of(light);
    (0..nodes.len())
        .filter(|&i| {
            let (f, l) = tree.subtree_range(nodes[i]);
            f <= leaf && leaf <= l
        })
        .collect()
}

fn check_partition(tree: &LightTree, cut: &crate::Cut, max_size: usize) {
    assert!(!cut.is_empty());
    assert!(cut.len() <= max_size.max(1));
    assert!(cut.nodes.windows(2).all(|w| w[0] < w[1]), "not sorted");
    let covered: usize = cut.nodes.iter().map(|&c| tree.node(c).num_lights()).sum();
    assert_eq!(covered, tree.num_lights());
    for light in 0..tree.num_lights() {
        let cov = covering(tree, &cut.nodes, light);
        assert_eq!(cov.len(), 1, "light {light} in {} clusters", cov.len());
        assert_eq!(cut.cluster_of(tree, light), Some(cov[0]));
    }
}

#[test]
fn adaptive_cut_partitions_lights() {
    let mut rng = Pcg32::seed_from_u64(7);
    let mut sizes = Vec::new();
    for (n, layout, z) in tree_configs() {
        let lights = rand_lights(&mut rng, n, layout, z);
        let tree = LightTree::build(&lights).unwrap();
        for _ in 0..5 {
            let (x, nrm) = rand_receiver(&mut rng);
            for (tau, criterion) in [
                (0.5, SplitCriterion::Authors),
                (0.85, SplitCriterion::Authors),
                (0.99, SplitCriterion::Authors),
                (0.85, SplitCriterion::UnitFree),
                (0.99, SplitCriterion::UnitFree),
            ] {
                for max_size in [0usize, 1, 4, 32, usize::MAX] {
                    let cut = tree.adaptive_cut(
                        x,
                        nrm,
                        &SplitParams {
                            tau,
                            max_size,
                            criterion,
                        },
                    );
                    check_partition(&tree, &cut, max_size);
                    if max_size == usize::MAX {
                        sizes.push(cut.len());
                    }
                }
            }
        }
    }
    // The heuristic does split: some unbounded cuts hold more than the root.
    assert!(sizes.iter().any(|&s| s > 4));
}

#[test]
fn generic_cut_respects_predicate_and_budget() {
    let mut rng = Pcg32::seed_from_u64(8);
    let lights = rand_lights(&mut rng, 100, Layout::Uniform, false);
    let tree = LightTree::build(&lights).unwrap();
    // Always split, no budget: every leaf.
    let all = tree.cut(usize::MAX, |_| true);
    assert_eq!(all.len(), 100);
    assert!(all.nodes.iter().all(|&c| tree.node(c).is_leaf()));
    check_partition(&tree, &all, usize::MAX);
    // Never split: the root.
    assert_eq!(tree.cut(100, |_| false).nodes, vec![tree.root()]);
    // Budget: exactly max_size nodes when always splitting, breadth first.
    for m in [1, 2, 7, 50, 99] {
        let c = tree.cut(m, |_| true);
        assert_eq!(c.len(), m);
        check_partition(&tree, &c, m);
        let depths: Vec<u32> = c.nodes.iter().map(|&i| tree.node(i).depth()).collect();
        let (lo, hi) = (depths.iter().min().unwrap(), depths.iter().max().unwrap());
        // Breadth-first: depths differ by at most 1 unless shallower nodes are leaves.
        for &i in &c.nodes {
            if tree.node(i).depth() + 1 < *hi {
                assert!(tree.node(i).is_leaf(), "lo {lo} hi {hi}");
            }
        }
    }
    // Random predicate.
    for _ in 0..20 {
        let p = rng.random::<f32>();
        let mut r2 = Pcg32::seed_from_u64(rng.random());
        let c = tree.cut(30, |_| r2.random::<f32>() < p);
        check_partition(&tree, &c, 30);
    }
    // With all lights visible (spheres, no receiver normal) and τ > 1 the adaptive cut is
    // every leaf.
    let spheres: Vec<LightBounds> = (0..50)
        .map(|_| LightBounds::point(rand_in_box(&mut rng, 1.0), 1.0))
        .collect();
    let st = LightTree::build(&spheres).unwrap();
    let c = st.adaptive_cut(
        Vec3::splat(3.0),
        Vec3::ZERO,
        &SplitParams {
            tau: 1.0,
            max_size: usize::MAX,
            criterion: SplitCriterion::Authors,
        },
    );
    assert_eq!(c.len(), 50);
}

/// Positions 2^i on a line with powers ∝ 2^i: each SAOH split peels off the farthest light
/// (the top bucket holds only it, and it outweighs all others), which would give depth ~n. The median-split fallback must keep every leaf
/// at depth ≤ 64; with a smaller limit the same code path is forced much earlier.
#[test]
fn depth_is_bounded_on_adversarial_input() {
    let n = 127; // 2^126 is the largest power of two below f32::MAX
    let lights: Vec<LightBounds> = (0..n)
        .map(|i| {
            let mut l = LightBounds::point(Vec3::new(2f32.powi(i), 0.0, 0.0), 1.0);
            l.power = 2f32.powi(i - 126);
            l
        })
        .collect();
    let natural = LightTree::build_with_max_depth(&lights, 64).unwrap();
    // Without the fallback this input degenerates far beyond 64 levels.
    let unlimited_depth_estimate = natural.max_depth();
    assert!(unlimited_depth_estimate <= MAX_DEPTH);
    for limit in [7u32, 10, 20, 64] {
        let tree = LightTree::build_with_max_depth(&lights, limit).unwrap();
        let depth = tree.max_depth();
        assert!(depth <= limit, "limit {limit} depth {depth}");
        // pmf replays correctly down to the deepest leaves.
        let imp = |id: NodeId| tree.node(id).power();
        let sum: f64 = (0..n as usize)
            .map(|l| tree.pmf_subtree(tree.root(), imp, l) as f64)
            .sum();
        assert!((sum - 1.0).abs() < 1e-5, "sum {sum}");
        for i in 0..200 {
            let u = ((i as f64 + 0.5) / 200.0 * 18_446_744_073_709_551_616.0) as u64;
            let (l, p) = tree
                .sample_subtree(tree.root(), imp, &mut Rescaled(u))
                .unwrap();
            assert_eq!(p.to_bits(), tree.pmf_subtree(tree.root(), imp, l).to_bits());
        }
    }
    // The 64-level limit is actually reached, i.e. the fallback was needed.
    assert_eq!(
        unlimited_depth_estimate, MAX_DEPTH,
        "depth {unlimited_depth_estimate}"
    );
}

#[test]
fn build_errors() {
    let good = LightBounds::point(Vec3::ZERO, 1.0);
    assert_eq!(LightTree::build(&[]).unwrap_err(), BuildError::NoLights);
    // Finite lights whose common box overflows f32: the compact codes cannot span it.
    let far = [
        LightBounds::point(Vec3::splat(-3e38), 1.0),
        LightBounds::point(Vec3::splat(3e38), 1.0),
    ];
    assert_eq!(
        LightTree::build(&far).unwrap_err(),
        BuildError::BoundsTooLarge
    );
    let cases: Vec<(LightBounds, BuildError)> = vec![
        (
            LightBounds {
                power: -1.0,
                ..good
            },
            BuildError::NegativePower {
                light: 1,
                power: -1.0,
            },
        ),
        (
            LightBounds {
                power: f32::NAN,
                ..good
            },
            BuildError::NonFinite { light: 1 },
        ),
        (
            LightBounds {
                aabb_max: Vec3::new(f32::INFINITY, 0.0, 0.0),
                ..good
            },
            BuildError::NonFinite { light: 1 },
        ),
        (
            LightBounds {
                aabb_min: Vec3::ONE,
                ..good
            },
            BuildError::InvertedBounds { light: 1 },
        ),
        (
            LightBounds {
                theta_e: 4.0,
                ..good
            },
            BuildError::AngleOutOfRange { light: 1 },
        ),
        (
            LightBounds {
                axis: Vec3::ZERO,
                theta_o: 0.0,
                ..good
            },
            BuildError::ZeroAxis { light: 1 },
        ),
    ];
    for (bad, err) in cases {
        let e = LightTree::build(&[good, bad, good]).unwrap_err();
        assert_eq!(e, err);
        assert!(!e.to_string().is_empty());
    }
    // A zero axis is fine for a full-sphere emitter, and zero power is allowed.
    let ok = LightBounds {
        axis: Vec3::ZERO,
        power: 0.0,
        ..good
    };
    assert!(LightTree::build(&[ok, good]).is_ok());
}

/// All importances zero: `sample` gives None and every pmf is 0.
#[test]
fn all_dark_receiver() {
    let mut rng = Pcg32::seed_from_u64(9);
    // Planar lights below z = -1 facing down, receiver above facing up.
    let lights: Vec<LightBounds> = (0..30)
        .map(|_| {
            let p = rand_in_box(&mut rng, 1.0) - Vec3::Z * 3.0;
            LightBounds {
                aabb_min: p - Vec3::splat(0.01),
                aabb_max: p + Vec3::splat(0.01),
                axis: -Vec3::Z,
                theta_o: 0.0,
                theta_e: FRAC_PI_2,
                power: 1.0,
                two_sided: false,
            }
        })
        .collect();
    let tree = LightTree::build(&lights).unwrap();
    let x = Vec3::new(0.0, 0.0, 1.0);
    for n in [Vec3::Z, Vec3::ZERO] {
        assert!(tree.sample(x, n, 1 << 62).is_none());
        assert!((0..30).all(|l| tree.pmf(x, n, l) == 0.0));
    }
    // Facing the receiver instead, everything is lit.
    let sum: f32 = (0..30).map(|l| tree.pmf(-x * 5.0, Vec3::ZERO, l)).sum();
    assert!((sum - 1.0).abs() < 1e-5);
}

/// Two builds of the same input give identical trees, also through the parallel binning
/// (≥ 65,536 lights) and parallel subtree paths.
#[test]
fn build_is_deterministic() {
    let mut rng = Pcg32::seed_from_u64(10);
    let lights = rand_lights(&mut rng, 70_000, Layout::Uniform, true);
    let a = LightTree::build(&lights).unwrap();
    let b = LightTree::build(&lights).unwrap();
    assert_eq!(a.nodes(), b.nodes());
    assert!((0..lights.len()).all(|l| a.bit_trail(l) == b.bit_trail(l)));
}

/// Unshadowed irradiance from zero-size emitters spread over a large box, estimated with one
/// light sample. The exact variance Σ f²/p − F² of the tree's estimator must be far below that
/// of power-proportional sampling, and every light with f > 0 must have p > 0 (unbiased).
#[test]
fn tree_beats_power_sampling_on_spread_lights() {
    let mut rng = Pcg32::seed_from_u64(11);
    let lights: Vec<LightBounds> = (0..1000)
        .map(|i| {
            let p = rand_in_box(&mut rng, 50.0);
            let mut l = LightBounds::point(p, 0.1 + rng.random::<f32>());
            if i % 2 == 0 {
                l.axis = rand_dir(&mut rng);
                l.theta_o = 0.0;
            }
            l
        })
        .collect();
    let tree = LightTree::build(&lights).unwrap();
    let total_power: f64 = lights.iter().map(|l| l.power as f64).sum();
    let (mut var_tree, mut var_power) = (0.0f64, 0.0f64);
    for _ in 0..50 {
        let x = rand_in_box(&mut rng, 50.0);
        let n = rand_dir(&mut rng);
        let f: Vec<f64> = lights
            .iter()
            .map(|l| {
                let d = l.aabb_min - x;
                let d2 = d.length_squared() as f64;
                let w = d.normalize();
                let emit = if l.theta_o == 0.0 {
                    (-l.axis.dot(w)).max(0.0)
                } else {
                    1.0
                };
                l.power as f64 * emit as f64 * n.dot(w).max(0.0) as f64 / d2
            })
            .collect();
        let big_f: f64 = f.iter().sum();
        if big_f == 0.0 {
            continue;
        }
        let (mut m2_tree, mut m2_power) = (0.0, 0.0);
        for (l, &fl) in f.iter().enumerate() {
            if fl == 0.0 {
                continue;
            }
            let p = tree.pmf(x, n, l) as f64;
            assert!(p > 0.0, "light {l} contributes but has pmf 0");
            m2_tree += fl * fl / p;
            m2_power += fl * fl / (lights[l].power as f64 / total_power);
        }
        // Relative variances, so every receiver weighs the same.
        var_tree += (m2_tree - big_f * big_f) / (big_f * big_f);
        var_power += (m2_power - big_f * big_f) / (big_f * big_f);
    }
    eprintln!("relative variance: tree {var_tree:.3}, power {var_power:.3}");
    assert!(
        var_tree * 5.0 < var_power,
        "tree {var_tree} power {var_power}"
    );
}

/// splitmix64: 64 independent-looking bits per call, for the many-sample tests below.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// At 2²⁰ lights a descent decides 20 times. With one number rescaled down the levels, each
/// decision uses up the bits the ones above it consumed; with only 24 of them, every leaf's
/// realised probability was a multiple of 2⁻²⁴ (about 16 quanta per leaf here), off the pmf by
/// a few per cent (this test gave p = 5·10⁻²²). 2²⁴ descents, a chi-square test over the
/// leaves against the exact (f64) distribution of the descent: it must not reject at 0.1 %.
#[test]
fn deep_descent_frequencies_match_the_pmf_at_2_pow_20_lights() {
    let n = 1usize << 20;
    let lights: Vec<LightBounds> = (0..n)
        .map(|i| LightBounds::point(Vec3::new((i % 1024) as f32, (i / 1024) as f32, 0.0), 1.0))
        .collect();
    let tree = LightTree::build(&lights).unwrap();
    assert!(tree.max_depth() >= 20, "depth {}", tree.max_depth());
    // Importances in [1, 2): every p_left in [1/3, 2/3], almost never a dyadic fraction (on
    // which a float rescale is exact).
    let imp = |id: NodeId| {
        let h = (id as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let h = (h ^ (h >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9) >> 40;
        1.0 + (h % 4096) as f32 / 4096.0
    };
    let (reference, dead) = reference_pmf(&tree, tree.root(), &imp);
    assert_eq!(dead, 0.0);
    // Sixteen fixed chunks of 2²⁰ descents, each from its own seed, on threads of their own (the
    // counts do not depend on the scheduling).
    let chunks = 16u64;
    let samples = chunks << 20;
    let parts: Vec<Vec<u32>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..chunks)
            .map(|c| {
                let (tree, imp) = (&tree, &imp);
                s.spawn(move || {
                    let mut observed = vec![0u32; n];
                    let mut state = 20 + c;
                    for _ in 0..1 << 20 {
                        let mut u = Rescaled(splitmix(&mut state));
                        let (l, _) = tree.sample_subtree(tree.root(), imp, &mut u).unwrap();
                        observed[l] += 1;
                    }
                    observed
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let observed: Vec<f64> = (0..n)
        .map(|l| parts.iter().map(|p| p[l] as f64).sum())
        .collect();
    let expected: Vec<f64> = reference.iter().map(|p| p * samples as f64).collect();
    let r = chi2_test(&observed, &expected);
    eprintln!(
        "2^20 lights, depth {}: chi2 {} dof {} p {}",
        tree.max_depth(),
        r.statistic,
        r.dof,
        r.p_value
    );
    assert!(
        r.p_value > 1e-3,
        "chi2 {} dof {} p {}",
        r.statistic,
        r.dof,
        r.p_value
    );
}
