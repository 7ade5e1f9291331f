//! Build time (wall and CPU) and single-thread query cost at 10³…10⁶ random small lights,
//! reported as medians of repeated runs with CPU time beside wall time, because the shared
//! machine's wall times swing with other people's jobs:
//! `cargo run --release -p light-tree --example perf_report [-- REPS]`.
use glam::Vec3;
use light_tree::{LightBounds, LightTree, SplitCriterion, SplitParams};

/// The authors' cut: τ = 0.85, their σ, at most 64 nodes (the figures in the README).
const SPLIT: SplitParams = SplitParams {
    tau: 0.85,
    max_size: 64,
    criterion: SplitCriterion::Authors,
};
use rand::{Rng, RngExt, SeedableRng};
use std::f32::consts::{FRAC_PI_2, PI};
use std::hint::black_box;
use std::time::Instant;

/// CPU time (user + system) of this process; 0 where the platform has no CPU clock.
fn cpu_seconds() -> f64 {
    host::process_cpu_seconds().unwrap_or(0.0)
}

fn rand_dir(rng: &mut impl Rng) -> Vec3 {
    let z = 1.0 - 2.0 * rng.random::<f32>();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * rng.random::<f32>();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Same scene as the criterion bench: half one-sided quads with random normals, half
/// spheres, uniform in a 100³ box, half-size 0.05.
fn lights(n: usize) -> Vec<LightBounds> {
    let mut rng = rand_pcg::Pcg32::seed_from_u64(n as u64);
    (0..n)
        .map(|i| {
            let p = Vec3::new(rng.random(), rng.random(), rng.random()) * 100.0;
            let one_sided = i % 2 == 0;
            LightBounds {
                aabb_min: p - 0.05,
                aabb_max: p + 0.05,
                axis: rand_dir(&mut rng),
                theta_o: if one_sided { 0.0 } else { PI },
                theta_e: FRAC_PI_2,
                power: 1.0 + 9.0 * rng.random::<f32>(),
                two_sided: false,
            }
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let reps: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    println!(
        "| lights | build wall | build CPU | max depth | sample+pmf wall / CPU ns | adaptive cut (τ 0.85, ≤ 64) wall / CPU ns | mean cut size | sample() = None |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        let ls = lights(n);
        let (mut walls, mut cpus) = (Vec::new(), Vec::new());
        let mut tree = None;
        for _ in 0..reps {
            let (t0, c0) = (Instant::now(), cpu_seconds());
            let t = LightTree::build(&ls).unwrap();
            walls.push(t0.elapsed().as_secs_f64());
            cpus.push(cpu_seconds() - c0);
            tree = Some(t);
        }
        let tree = tree.unwrap();
        let mut rng = rand_pcg::Pcg32::seed_from_u64(7);
        let qs: Vec<(Vec3, Vec3, u64)> = (0..200_000)
            .map(|_| {
                let x = Vec3::new(rng.random(), rng.random(), rng.random()) * 100.0;
                (x, rand_dir(&mut rng), rng.random::<u64>())
            })
            .collect();
        let (mut sp, mut spc) = (Vec::new(), Vec::new());
        let (mut cutt, mut cutc) = (Vec::new(), Vec::new());
        let mut cut_sizes = 0usize;
        let mut misses = 0usize;
        for _ in 0..reps {
            let (t0, c0) = (Instant::now(), cpu_seconds());
            let mut acc = 0.0f32;
            for &(x, nrm, u) in &qs {
                if let Some((l, p)) = tree.sample(x, nrm, u) {
                    acc += p + tree.pmf(x, nrm, l);
                } else {
                    misses += 1;
                }
            }
            black_box(acc);
            sp.push(t0.elapsed().as_secs_f64() * 1e9 / qs.len() as f64);
            spc.push((cpu_seconds() - c0) * 1e9 / qs.len() as f64);
            let (t0, c0) = (Instant::now(), cpu_seconds());
            cut_sizes = 0;
            for &(x, nrm, _) in &qs[..50_000] {
                cut_sizes += black_box(tree.adaptive_cut(x, nrm, &SPLIT)).len();
            }
            cutt.push(t0.elapsed().as_secs_f64() * 1e9 / 50_000.0);
            cutc.push((cpu_seconds() - c0) * 1e9 / 50_000.0);
        }
        println!(
            "| {n} | {:.1} ms | {:.2} s | {} | {:.0} / {:.0} | {:.0} / {:.0} | {:.1} | {:.1} % |",
            median(walls) * 1e3,
            median(cpus),
            tree.max_depth(),
            median(sp),
            median(spc),
            median(cutt),
            median(cutc),
            cut_sizes as f64 / 50_000.0,
            100.0 * misses as f64 / (reps * qs.len()) as f64
        );
    }
}
