//! Build time and per-query cost (sample + pmf, adaptive cut) at 10³…10⁶ lights.
//!
//! Lights: small emitters (half one-sided quads with random normals, half spheres) uniform
//! in a 100³ box, edge/radius 0.05. Queries: receivers uniform in the box, random normals.
//!
//! `cargo bench -p light-tree --bench light_tree -- --quick`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use light_tree::{LightBounds, LightTree, Rescaled, SplitCriterion, SplitParams};

/// The authors' cut: τ = 0.85, their σ, at most 64 nodes (the figures in the README).
const SPLIT: SplitParams = SplitParams {
    tau: 0.85,
    max_size: 64,
    criterion: SplitCriterion::Authors,
};
use rand::{Rng, RngExt, SeedableRng};
use rand_pcg::Pcg32;
use std::f32::consts::{FRAC_PI_2, PI};
use std::hint::black_box;
use std::time::Duration;

const SIZES: [usize; 4] = [1_000, 10_000, 100_000, 1_000_000];
/// Enough distinct queries that the 10⁶-light tree does not sit in cache between iterations.
const QUERIES: usize = 16384;

fn rand_dir(rng: &mut impl Rng) -> Vec3 {
    let z = 1.0 - 2.0 * rng.random::<f32>();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * rng.random::<f32>();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn rand_point(rng: &mut impl Rng) -> Vec3 {
    Vec3::new(rng.random(), rng.random(), rng.random()) * 100.0
}

fn lights(n: usize) -> Vec<LightBounds> {
    let mut rng = Pcg32::seed_from_u64(n as u64);
    (0..n)
        .map(|i| {
            let p = rand_point(&mut rng);
            let h = Vec3::splat(0.05);
            if i % 2 == 0 {
                LightBounds {
                    aabb_min: p - h,
                    aabb_max: p + h,
                    axis: rand_dir(&mut rng),
                    theta_o: 0.0,
                    theta_e: FRAC_PI_2,
                    power: PI * 0.01 * (1.0 + 9.0 * rng.random::<f32>()),
                    two_sided: false,
                }
            } else {
                LightBounds {
                    aabb_min: p - h,
                    aabb_max: p + h,
                    axis: Vec3::Z,
                    theta_o: PI,
                    theta_e: FRAC_PI_2,
                    power: 4.0 * PI * PI * 0.0025 * (1.0 + 9.0 * rng.random::<f32>()),
                    two_sided: false,
                }
            }
        })
        .collect()
}

/// Receivers and the descents' 64 random bits (made of an f32 draw, so that the queries are
/// those of the benchmark's f32 days).
fn queries() -> Vec<(Vec3, Vec3, u64)> {
    let mut rng = Pcg32::seed_from_u64(99);
    (0..QUERIES)
        .map(|_| {
            (
                rand_point(&mut rng),
                rand_dir(&mut rng),
                (rng.random::<f32>() as f64 * 18_446_744_073_709_551_616.0) as u64,
            )
        })
        .collect()
}

fn bench_build(c: &mut Criterion) {
    let mut g = c.benchmark_group("build");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for n in SIZES {
        let ls = lights(n);
        g.throughput(Throughput::Elements(n as u64));
        g.bench_with_input(BenchmarkId::from_parameter(n), &ls, |b, ls| {
            b.iter(|| LightTree::build(black_box(ls)).unwrap())
        });
    }
    g.finish();
}

/// A group of `QUERIES` queries per iteration.
fn query_group<'a>(
    c: &'a mut Criterion,
    name: &str,
) -> criterion::BenchmarkGroup<'a, criterion::measurement::WallTime> {
    let mut g = c.benchmark_group(name);
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    g.throughput(Throughput::Elements(QUERIES as u64));
    g
}

fn bench_queries(c: &mut Criterion) {
    let qs = queries();
    let mut g = query_group(c, "sample+pmf");
    let trees: Vec<(usize, LightTree)> = SIZES
        .iter()
        .map(|&n| (n, LightTree::build(&lights(n)).unwrap()))
        .collect();
    for (n, tree) in &trees {
        g.bench_with_input(BenchmarkId::from_parameter(n), tree, |b, tree| {
            b.iter(|| {
                let mut acc = 0.0f32;
                for &(x, nrm, u) in &qs {
                    if let Some((l, p)) = tree.sample(x, nrm, u) {
                        acc += p + tree.pmf(x, nrm, l);
                    }
                }
                acc
            })
        });
    }
    g.finish();
    // The same descents (without the replays), one at a time and two side by side.
    for paired in [false, true] {
        let name = if paired {
            "sample, paired"
        } else {
            "sample, single"
        };
        let mut g = query_group(c, name);
        for (n, tree) in &trees {
            g.bench_with_input(BenchmarkId::from_parameter(n), tree, |b, tree| {
                b.iter(|| {
                    let mut acc = 0.0f32;
                    let root = tree.root();
                    for q in qs.chunks_exact(2) {
                        let (mut ua, mut ub) = (Rescaled(q[0].2), Rescaled(q[1].2));
                        let found = if paired {
                            tree.sample_pair_from(
                                [root, root],
                                [q[0].0, q[1].0],
                                [q[0].1, q[1].1],
                                [&mut ua, &mut ub],
                            )
                        } else {
                            [
                                tree.sample_from(root, q[0].0, q[0].1, &mut ua),
                                tree.sample_from(root, q[1].0, q[1].1, &mut ub),
                            ]
                        };
                        for (_, p) in found.into_iter().flatten() {
                            acc += p;
                        }
                    }
                    acc
                })
            });
        }
        g.finish();
    }
    let mut g = query_group(c, "adaptive_cut(0.85,64)");
    for (n, tree) in &trees {
        g.bench_with_input(BenchmarkId::from_parameter(n), tree, |b, tree| {
            b.iter(|| {
                let mut acc = 0usize;
                for &(x, nrm, _) in &qs {
                    acc += tree.adaptive_cut(x, nrm, &SPLIT).len();
                }
                acc
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_build, bench_queries);
criterion_main!(benches);
