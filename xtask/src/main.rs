//! Project automation (the `cargo xtask` pattern). Subcommands are added by the issues that need them.
mod contact_sheet;
mod experiments;
mod flip_cmd;
mod fuzz;
mod glossy_mask;
mod yardstick;

/// Counts allocations for `fuzz` (a case may not allocate more than its file can describe).
#[global_allocator]
static ALLOCATOR: scene_fuzz::CountingAllocator = scene_fuzz::CountingAllocator;

/// A subcommand's entry: its arguments parsed by clap (which prints help or a usage error and
/// exits), then `run`, whose error is printed as `error: …` with a failing exit code.
pub(crate) fn run_subcommand<A: clap::Parser>(
    args: &[String],
    run: impl FnOnce(&A) -> Result<(), String>,
) -> std::process::ExitCode {
    let a = A::try_parse_from(args).unwrap_or_else(|e| e.exit());
    match run(&a) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn main() -> std::process::ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        None | Some("help") | Some("--help") => {
            println!(
                "cargo xtask <command>\n\ncommands:\n  help    this text\n  fit-sptd | fit-ltc | validate-brdf-integrals    brdf-integrals tables and accuracy report\n  run-experiments [--experiment NAME] [--list] [--only PATTERN] [--shard i/n] [--publish] …    render an experiment (default `quick`) into out/NAME/ (git-ignored; --publish: the committed results/NAME/; see xtask/README.md)\n  merge-results [--experiment NAME] [--publish] [SHARD_DIRS…]    merge shard results and regenerate the report\n  report --experiment NAME [--publish]    rebuild the report (table.md, plots, strips, index.html) from a local run's cell files\n  headline [--check] [--readme PATH]    write README.md's headline table (between its headline-table markers) from results/paper/cells.csv\n  contact-sheet    one labelled PNG of every scene (mis3-adaptive, 16 spp) into results/scenes/\n  flip IMAGE.exr REFERENCE.exr [--mask M.png]… [--map OUT.png] [--json]    HDR-ꟻLIP of a render against a reference (the harness's metric)\n  fuzz [--minutes N] [--seed S] [--case K]    fuzz the scene loaders (crates/scene-fuzz) for N minutes\n  glossy-mask SCENE W H OUT.png [--max-alpha A] [--subpixels N] [--footprint R] [--no-emitter-px]    mask of the pixels whose camera rays see GGX α < A (the authors' objects: --subpixels 16 --footprint 1 --no-emitter-px)\n  yardstick [--strategy S]… [--rounds N] [--spp LO,HI] [--pin CPU] [--mitsuba-python PY] [--no-mitsuba] [--out CSV]    marginal CPU per camera sample, ours against Mitsuba 3 (llvm_ad_rgb), one thread, in one sitting"
            );
        }
        Some(cmd @ ("fit-sptd" | "fit-ltc" | "validate-brdf-integrals")) => {
            // brdf-integrals: fits its tables / writes results/brdf-integrals (see its README)
            let sub = if cmd == "validate-brdf-integrals" {
                "validate"
            } else {
                cmd
            };
            let status = std::process::Command::new(env!("CARGO"))
                .args(["run", "--release", "-p", "brdf-tool", "--", sub])
                .args(&args[1..])
                .status()
                .expect("failed to run cargo");
            std::process::exit(status.code().unwrap_or(1));
        }
        // issue 6: experiment harness
        Some("run-experiments" | "merge-results" | "report" | "headline") => {
            return experiments::main(&args);
        }
        // issue 7: every scene on one sheet
        Some("contact-sheet") => return contact_sheet::main(&args),
        Some("glossy-mask") => return glossy_mask::main(&args),
        Some("flip") => return flip_cmd::main(&args),
        Some("fuzz") => return fuzz::main(&args),
        // issue 55: ours against Mitsuba 3 per camera sample
        Some("yardstick") => return yardstick::main(&args),
        Some(other) => {
            eprintln!("error: unknown xtask command `{other}` (try `cargo xtask help`)");
            std::process::exit(2);
        }
    }
    std::process::ExitCode::SUCCESS
}
