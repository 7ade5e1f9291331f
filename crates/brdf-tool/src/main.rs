//! Fitting and validation driver for `brdf-integrals` (called by `cargo xtask fit-sptd | fit-ltc |
//! validate-brdf-integrals`), and the CPU cost of one cap integral (`bench-cpu`).

use brdf_integrals::{ltc, sptd};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

mod validate;

#[derive(Parser)]
#[command(
    name = "brdf-tool",
    about = "Fit, validate and time the brdf-integrals tables"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Fit the 64×64 SPTD table (pivot norm and elevation, albedo) to the GGX lobe.
    FitSptd(FitArgs),
    /// Fit the 64×64 LTC table (inverse matrix, albedo) to the GGX lobe.
    FitLtc(FitArgs),
    /// Compare SPTD and LTC with the reference integrator; writes accuracy.{md,csv}.
    Validate {
        /// Reference samples per cap.
        #[arg(long, default_value_t = 1 << 16)]
        samples: usize,
        /// Output directory (default: results/brdf-integrals).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// CPU time per cap integral and per shading-point lobe (one thread, ~3 CPU-s per method).
    BenchCpu,
}

#[derive(clap::Args)]
struct FitArgs {
    /// Quasi-Monte Carlo samples per cell for the fit objective.
    #[arg(long, default_value_t = 4096)]
    samples: usize,
    /// Quasi-Monte Carlo samples per cell for the albedo.
    #[arg(long, default_value_t = 1 << 16)]
    albedo_samples: usize,
    /// Output directory (default: the crate's data/).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// The repository's directory `rel` (this crate lives in `ROOT/crates/brdf-tool`).
fn repo_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

pub(crate) fn write_file(path: &Path, contents: impl AsRef<[u8]>) -> Result<(), String> {
    std::fs::write(path, contents).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::FitSptd(a) => fit_sptd(&a),
        Command::FitLtc(a) => fit_ltc(&a),
        Command::Validate { samples, out } => validate::run(
            samples,
            &out.unwrap_or_else(|| repo_path("results/brdf-integrals")),
        ),
        Command::BenchCpu => {
            bench_cpu();
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn fit_sptd(args: &FitArgs) -> Result<(), String> {
    let (samples, albedo_samples) = (args.samples, args.albedo_samples);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| repo_path("crates/brdf-integrals/data"));
    let t0 = Instant::now();
    let done = AtomicUsize::new(0);
    let table = sptd::fit_table(samples, albedo_samples, |_| {
        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
        eprint!(
            "\rfit-sptd: {d}/64 rows, {:.0} s",
            t0.elapsed().as_secs_f64()
        );
    });
    let secs = t0.elapsed().as_secs_f64();
    eprintln!();
    create_dir(&out)?;
    write_file(&out.join("sptd_ggx_64x64.bin"), table.to_bytes(sptd::MAGIC))?;
    let stats = summary(table.cells.iter().map(|c| c[3] as f64));
    let manifest = format!(
        "SPTD table for the GGX lobe (height-correlated Smith, no Fresnel), fitted by brdf-integrals.\n\
         file: sptd_ggx_64x64.bin = 8-byte magic SPTDGGX1, u32 n_theta=64, n_alpha=64, channels=4, then f32 LE [theta][alpha][channel]\n\
         grid: theta_o = i/63 * pi/2 (fitted at min(theta_o, 89.5 deg)), sqrt(alpha) = j/63 (fitted at max(alpha, 0.001))\n\
         channels: rho (pivot norm), theta_p (pivot elevation, rad; <0 = mirror side), albedo A, relative L1 fit error\n\
         objective: L1 distance between f*cos and A*D_pivot/D_pivot(H) on H, {samples} QMC samples/cell; albedo {albedo_samples} VNDF QMC samples/cell\n\
         relative L1 error over cells: {stats}\n\
         regenerate: cargo xtask fit-sptd   (= cargo run --release -p brdf-tool -- fit-sptd --samples {samples} --albedo-samples {albedo_samples})\n\
         fit time: {secs:.0} s wall on this machine ({} rayon threads)\n",
        rayon::current_num_threads()
    );
    write_file(&out.join("sptd_ggx_64x64.txt"), &manifest)?;
    print!("{manifest}");
    Ok(())
}

fn fit_ltc(args: &FitArgs) -> Result<(), String> {
    let (samples, albedo_samples) = (args.samples, args.albedo_samples);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| repo_path("crates/brdf-integrals/data"));
    let t0 = Instant::now();
    let done = AtomicUsize::new(0);
    let table = ltc::fit_table(samples, albedo_samples, |_| {
        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
        eprint!(
            "\rfit-ltc: {d}/64 rows, {:.0} s",
            t0.elapsed().as_secs_f64()
        );
    });
    let secs = t0.elapsed().as_secs_f64();
    eprintln!();
    create_dir(&out)?;
    write_file(&out.join("ltc_ggx_64x64.bin"), table.to_bytes(ltc::MAGIC))?;
    let stats = summary(table.cells.iter().map(|c| c[5] as f64));
    let manifest = format!(
        "LTC table for the GGX lobe (height-correlated Smith, no Fresnel), fitted by brdf-integrals.\n\
         file: ltc_ggx_64x64.bin = 8-byte magic LTCGGX01, u32 n_theta=64, n_alpha=64, channels=6, then f32 LE [theta][alpha][channel]\n\
         grid: theta_o = i/63 * pi/2 (fitted at min(theta_o, 89.5 deg)), sqrt(alpha) = j/63 (fitted at max(alpha, 0.001))\n\
         channels: M^-1 = [[m0,0,m1],[0,1,0],[m2,0,m3]] (normalised so M^-1_yy = 1), albedo A, relative L1 fit error\n\
         objective: L1 distance between f*cos and A*D_ltc/D_ltc(H) on H, {samples} QMC samples/cell; albedo {albedo_samples} VNDF QMC samples/cell\n\
         relative L1 error over cells: {stats}\n\
         regenerate: cargo xtask fit-ltc   (= cargo run --release -p brdf-tool -- fit-ltc --samples {samples} --albedo-samples {albedo_samples})\n\
         fit time: {secs:.0} s wall on this machine ({} rayon threads)\n",
        rayon::current_num_threads()
    );
    write_file(&out.join("ltc_ggx_64x64.txt"), &manifest)?;
    print!("{manifest}");
    Ok(())
}

fn create_dir(dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))
}

fn summary(xs: impl Iterator<Item = f64>) -> String {
    let mut v: Vec<f64> = xs.collect();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    format!(
        "median {:.4}, p95 {:.4}, max {:.4}, mean {:.4}",
        v[n / 2],
        v[(n * 95 / 100).min(n - 1)],
        v[n - 1],
        v.iter().sum::<f64>() / n as f64
    )
}

/// CPU seconds (user + system) of the calling thread, so the cost per evaluation can be
/// measured on a machine shared with other jobs.
fn thread_cpu_seconds() -> Option<f64> {
    host::thread_cpu_seconds()
}

/// `bench-cpu`: CPU time per cap integral (single thread, ~3 CPU-seconds per method).
fn bench_cpu() {
    use brdf_integrals::{CapIntegral, Intersection, LobeIntegral, Ltc, Sptd, ggx};
    use glam::Vec3;
    let mut caps = Vec::new();
    let mut rng = brdf_integrals::qmc::SplitMix64::new(5);
    for _ in 0..1024 {
        let z = rng.next_f64() * 1.3 - 0.3;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = rng.next_f64() * std::f64::consts::TAU;
        let ang = (0.005f64.ln() + rng.next_f64() * (1.0f64.ln() - 0.005f64.ln())).exp();
        caps.push((
            Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32),
            ang.cos() as f32,
        ));
    }
    let wo = ggx::wo_from_theta(0.8);
    let run = |name: &str, f: &dyn Fn(Vec3, f32) -> f32| {
        let mut n = 0usize;
        let mut acc = 0.0f32;
        let t0 = thread_cpu_seconds().unwrap_or(0.0);
        let w0 = Instant::now();
        while thread_cpu_seconds().unwrap_or(0.0) - t0 < 3.0 && w0.elapsed().as_secs_f64() < 30.0 {
            for _ in 0..200 {
                for &(a, c) in &caps {
                    acc += f(std::hint::black_box(a), std::hint::black_box(c));
                }
            }
            n += 200 * caps.len();
        }
        let cpu = thread_cpu_seconds().unwrap_or(0.0) - t0;
        println!(
            "{name:<28} {:7.1} ns CPU / evaluation ({n} evaluations, {cpu:.2} CPU-s, {:.2} s wall, checksum {acc:.3})",
            cpu * 1e9 / n as f64,
            w0.elapsed().as_secs_f64()
        );
    };
    let sptd = Sptd::default();
    let lobe = sptd.lobe(wo, 0.1);
    run("sptd integral (exact)", &|a, c| lobe.integral(a, c));
    let so = Sptd::default().intersection(Intersection::OatSander);
    let lobe = so.lobe(wo, 0.1);
    run("sptd integral (oat-sander)", &|a, c| lobe.integral(a, c));
    let ltc = Ltc::default();
    let lobe = ltc.lobe(wo, 0.1);
    run("ltc integral", &|a, c| lobe.integral(a, c));
    run("sptd lobe()", &|a, c| {
        sptd.lobe(wo, 0.1 + 1e-9 * c).hemisphere() + a.x
    });
    run("ltc lobe()", &|a, c| {
        ltc.lobe(wo, 0.1 + 1e-9 * c).hemisphere() + a.x
    });
}
