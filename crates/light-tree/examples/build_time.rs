//! Times `LightTree::build` on N random small lights (default 10⁶) and prints wall and CPU
//! time: `cargo run --release -p light-tree --example build_time -- 1000000 5`.
use glam::Vec3;
use light_tree::{LightBounds, LightTree};
use rand::{RngExt, SeedableRng};
use std::f32::consts::{FRAC_PI_2, PI};
use std::time::Instant;

fn cpu_seconds() -> f64 {
    // utime + stime of this process from /proc/self/stat (clock ticks, 100 Hz on Linux).
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = s.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let t = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (t(11) + t(12)) / 100.0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1_000_000);
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(3);
    let mut rng = rand_pcg::Pcg32::seed_from_u64(n as u64);
    let lights: Vec<LightBounds> = (0..n)
        .map(|i| {
            let p = Vec3::new(rng.random(), rng.random(), rng.random()) * 100.0;
            let z = 1.0 - 2.0 * rng.random::<f32>();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * PI * rng.random::<f32>();
            let one_sided = i % 2 == 0;
            LightBounds {
                aabb_min: p - 0.05,
                aabb_max: p + 0.05,
                axis: Vec3::new(r * phi.cos(), r * phi.sin(), z),
                theta_o: if one_sided { 0.0 } else { PI },
                theta_e: FRAC_PI_2,
                power: 1.0 + 9.0 * rng.random::<f32>(),
                two_sided: false,
            }
        })
        .collect();
    for _ in 0..reps {
        let (t0, c0) = (Instant::now(), cpu_seconds());
        let tree = LightTree::build(&lights).unwrap();
        let (wall, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
        println!(
            "n {n}: build wall {wall:.3} s, cpu {cpu:.2} s, max depth {}",
            tree.max_depth()
        );
    }
}
