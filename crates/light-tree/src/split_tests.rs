//! The E&K split metric against an independent evaluation of its formula: direction, units
//! and the unit-free criterion's invariance under scaling.

use crate::{LightBounds, LightTree, NodeId, SplitCriterion, SplitParams};
use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg32;
use std::f32::consts::{FRAC_PI_2, PI};

fn lights(seed: u64, n: usize) -> Vec<LightBounds> {
    let mut rng = Pcg32::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let p = Vec3::new(
                rng.random::<f32>() * 2.0 - 1.0,
                rng.random::<f32>() * 2.0 - 1.0,
                rng.random::<f32>() * 0.5,
            );
            let h = 0.01 + 0.04 * rng.random::<f32>();
            let z = 1.0 - 2.0 * rng.random::<f32>();
            let r = (1.0 - z * z).sqrt();
            let phi = 2.0 * PI * rng.random::<f32>();
            LightBounds {
                aabb_min: p - Vec3::splat(h),
                aabb_max: p + Vec3::splat(h),
                axis: Vec3::new(r * phi.cos(), r * phi.sin(), z),
                theta_o: if rng.random::<bool>() { 0.0 } else { PI },
                theta_e: FRAC_PI_2,
                power: 0.1 + 10.0 * rng.random::<f32>().powi(3),
                two_sided: false,
            }
        })
        .collect()
}

/// The powers of the lights under `node`.
fn powers_under(tree: &LightTree, lights: &[LightBounds], node: NodeId) -> Vec<f64> {
    let (first, last) = tree.subtree_range(node);
    (first..=last)
        .filter_map(|id| tree.node(id).light())
        .map(|l| lights[l].power as f64)
        .collect()
}

/// E[dist^-k] for dist uniform in [a, b], by composite Simpson quadrature (not the closed form).
fn mean_inverse_power(a: f64, b: f64, k: i32) -> f64 {
    let m = 2000;
    let h = (b - a) / m as f64;
    let f = |t: f64| t.powi(-k);
    let mut s = f(a) + f(b);
    for i in 1..m {
        s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0 / (b - a)
}

/// σ from its definition: the variance of the product of a light's power and the geometric
/// term, both independent, times N² (authors, with their integer 1/(N − 1)), or over the
/// squared mean of the product (unit-free).
fn sigma_reference(powers: &[f64], d: f64, r: f64, criterion: SplitCriterion) -> f64 {
    let n = powers.len() as f64;
    let (a, b) = (d - r, d + r);
    let e_g = mean_inverse_power(a, b, 2);
    let v_g = mean_inverse_power(a, b, 4) - e_g * e_g;
    let e_e = powers.iter().sum::<f64>() / n;
    let ss: f64 = powers.iter().map(|p| (p - e_e) * (p - e_e)).sum();
    let var_product = |v_e: f64| v_e * v_g + v_e * e_g * e_g + e_e * e_e * v_g;
    match criterion {
        SplitCriterion::Authors => {
            let v_e = if powers.len() == 2 { ss } else { 0.0 };
            var_product(v_e).sqrt() * n
        }
        SplitCriterion::UnitFree => var_product(ss / (n - 1.0)).sqrt() / (e_e * e_g),
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-30
}

#[test]
fn split_sigma_matches_its_formula() {
    let ls = lights(11, 60);
    let tree = LightTree::build(&ls).unwrap();
    let mut rng = Pcg32::seed_from_u64(12);
    let mut checked = [0usize; 2];
    for id in 0..tree.nodes().len() as NodeId {
        let node = tree.node(id);
        if node.is_leaf() {
            continue;
        }
        let powers = powers_under(&tree, &ls, id);
        for _ in 0..4 {
            let dir = Vec3::new(
                rng.random::<f32>() - 0.5,
                rng.random::<f32>() - 0.5,
                rng.random::<f32>() - 0.5,
            )
            .normalize();
            let d = node.radius() * (1.05 + 4.0 * rng.random::<f32>());
            let x = node.center() + dir * d;
            let d = (node.center() - x).length() as f64;
            for (k, c) in [SplitCriterion::Authors, SplitCriterion::UnitFree]
                .into_iter()
                .enumerate()
            {
                let ours = tree.split_sigma(id, x, c);
                let reference = sigma_reference(&powers, d, node.radius() as f64, c);
                assert!(
                    close(ours, reference, 2e-3),
                    "{c:?} node {id} ({} lights) d/r {}: {ours} vs {reference}",
                    powers.len(),
                    d / node.radius() as f64
                );
                // ρ < τ exactly when the cut splits by variance.
                let rho = tree.split_metric(id, x, c);
                assert!(rho > 0.0 && rho <= 1.0);
                checked[k] += 1;
            }
        }
    }
    assert!(checked[0] > 100 && checked[1] > 100);
    // Inside the bounding sphere the unit-free σ is infinite (always split).
    let root = tree.node(tree.root());
    assert_eq!(
        tree.split_sigma(tree.root(), root.center(), SplitCriterion::UnitFree),
        f64::INFINITY
    );
}

#[test]
fn split_sigma_direction_and_units() {
    let ls = lights(21, 40);
    let tree = LightTree::build(&ls).unwrap();
    let root = tree.root();
    let node = *tree.node(root);
    let dir = Vec3::new(0.3, -0.2, 0.9).normalize();
    for c in [SplitCriterion::Authors, SplitCriterion::UnitFree] {
        // Farther away: less variance, larger ρ, fewer splits.
        let mut last = f64::INFINITY;
        for k in [1.2f32, 2.0, 4.0, 8.0, 16.0] {
            let s = tree.split_sigma(root, node.center() + dir * node.radius() * k, c);
            assert!(s < last, "{c:?}: σ must fall with distance");
            last = s;
        }
    }
    let x = node.center() + dir * node.radius() * 3.0;
    // More spread in the powers: more variance (two lights: the authors' V[e] is kept).
    let pair = |p1: f32, p2: f32| {
        let mut two = vec![ls[0], ls[1]];
        two[0].power = p1;
        two[1].power = p2;
        LightTree::build(&two).unwrap()
    };
    for c in [SplitCriterion::Authors, SplitCriterion::UnitFree] {
        let (even, uneven) = (pair(5.0, 5.0), pair(1.0, 9.0));
        assert!(
            uneven.split_sigma(0, x, c) > even.split_sigma(0, x, c),
            "{c:?}"
        );
    }
    // Units: the authors' σ scales with power / length²; the unit-free one does not change.
    let scaled = |power: f32, length: f32| -> Vec<LightBounds> {
        ls.iter()
            .map(|l| LightBounds {
                aabb_min: l.aabb_min * length,
                aabb_max: l.aabb_max * length,
                power: l.power * power,
                ..*l
            })
            .collect()
    };
    let brighter = LightTree::build(&scaled(1000.0, 1.0)).unwrap();
    let smaller = LightTree::build(&scaled(1.0, 0.01)).unwrap();
    let base_a = tree.split_sigma(root, x, SplitCriterion::Authors);
    let base_u = tree.split_sigma(root, x, SplitCriterion::UnitFree);
    assert!(close(
        brighter.split_sigma(root, x, SplitCriterion::Authors),
        1000.0 * base_a,
        1e-4
    ));
    assert!(close(
        smaller.split_sigma(root, x * 0.01, SplitCriterion::Authors),
        1e4 * base_a,
        1e-3
    ));
    assert!(close(
        brighter.split_sigma(root, x, SplitCriterion::UnitFree),
        base_u,
        1e-5
    ));
    assert!(close(
        smaller.split_sigma(root, x * 0.01, SplitCriterion::UnitFree),
        base_u,
        1e-4
    ));
}

/// Scaling all emission by 1000 or all lengths by 0.01 changes no unit-free cut.
#[test]
fn unit_free_cuts_ignore_scene_units() {
    let ls = lights(31, 300);
    let build = |power: f32, length: f32| {
        let v: Vec<LightBounds> = ls
            .iter()
            .map(|l| LightBounds {
                aabb_min: l.aabb_min * length,
                aabb_max: l.aabb_max * length,
                power: l.power * power,
                ..*l
            })
            .collect();
        LightTree::build(&v).unwrap()
    };
    let base = build(1.0, 1.0);
    let mut rng = Pcg32::seed_from_u64(32);
    let mut sizes = Vec::new();
    let mut authors_differ = false;
    for (power, length) in [(1000.0f32, 1.0f32), (1.0, 0.01)] {
        let t = build(power, length);
        assert_eq!(t.nodes().len(), base.nodes().len());
        for light in 0..ls.len() {
            assert_eq!(t.leaf_of(light), base.leaf_of(light), "same tree");
        }
        for _ in 0..200 {
            let x = Vec3::new(
                rng.random::<f32>() * 3.0 - 1.5,
                rng.random::<f32>() * 3.0 - 1.5,
                rng.random::<f32>() * 2.0 - 0.5,
            );
            let n = Vec3::new(0.0, 0.0, if rng.random::<bool>() { 1.0 } else { -1.0 });
            for tau in [0.85f32, 0.95, 0.99] {
                let p = SplitParams {
                    tau,
                    max_size: usize::MAX,
                    criterion: SplitCriterion::UnitFree,
                };
                let a = base.adaptive_cut(x, n, &p);
                let b = t.adaptive_cut(x * length, n, &p);
                assert_eq!(a, b, "τ {tau}, scale ({power}, {length}), x {x}");
                sizes.push(a.len());
                let pa = SplitParams {
                    criterion: SplitCriterion::Authors,
                    ..p
                };
                authors_differ |=
                    base.adaptive_cut(x, n, &pa) != t.adaptive_cut(x * length, n, &pa);
            }
        }
    }
    assert!(sizes.iter().any(|&s| s > 8), "the cuts do split: {sizes:?}");
    assert!(
        authors_differ,
        "the authors' criterion depends on the units"
    );
}
