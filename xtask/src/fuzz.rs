//! `cargo xtask fuzz --minutes N [--seed S] [--first K] [--case K]`: the scene-input fuzzer of
//! `crates/scene-fuzz` for longer than its test runs (release build, cases K, K+1, … of run
//! seed S until the time is up). `--case K` reruns one case. Failing inputs are kept in
//! `target/scene-fuzz/`.
use clap::Parser;
use scene_fuzz::Fuzzer;
use std::process::ExitCode;
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(
    name = "cargo xtask fuzz",
    about = "Fuzz the scene loaders (glTF, GLB, composition TOML)"
)]
struct Args {
    /// How long to run.
    #[arg(long, default_value_t = 1.0)]
    minutes: f64,
    /// Run seed (the test uses 1, from case 0).
    #[arg(long, default_value_t = 2)]
    seed: u64,
    /// First case index.
    #[arg(long, default_value_t = 0)]
    first: u64,
    /// Run only this case (of --seed) and print what it did.
    #[arg(long)]
    case: Option<u64>,
}

pub fn main(args: &[String]) -> ExitCode {
    let a = match Args::try_parse_from(args) {
        Ok(a) => a,
        Err(e) => e.exit(),
    };
    if !(a.minutes > 0.0 && a.minutes.is_finite()) {
        eprintln!("error: --minutes must be a positive number");
        return ExitCode::FAILURE;
    }
    let root = crate::experiments::manylights::repo_root();
    let dir = root.join("target/scene-fuzz");
    let shared = root.join("../shared/scenes");
    let fuzzer = match Fuzzer::new(&dir, a.seed, shared.is_dir().then_some(shared.as_path())) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: cannot prepare {}: {e}", dir.display());
            return ExitCode::FAILURE;
        }
    };
    let (first, count, deadline) = match a.case {
        Some(k) => (k, 1, None),
        None => (
            a.first,
            u64::MAX,
            Some(Instant::now() + Duration::from_secs_f64(a.minutes * 60.0)),
        ),
    };
    let report = fuzzer.run(first, count, deadline);
    for n in &report.notices {
        eprintln!("{n}");
    }
    for f in &report.failures {
        eprintln!("FAILED {f}");
    }
    println!(
        "seed {}: {} cases (from {first}) in {:.1} s, {:?}, {} failures; largest single allocation {} bytes",
        a.seed,
        report.cases,
        report.seconds,
        report.outcomes,
        report.failures.len(),
        report.largest_allocation
    );
    if report.failures.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
