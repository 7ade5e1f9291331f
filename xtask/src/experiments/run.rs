//! `cargo xtask run-experiments`, one function per step: select the cells, check that their
//! strategies and scenes exist and ask the binary what they resolve to
//! ([`prepare`](super::prepare)), ensure the references, render and measure each cell whose
//! stored result is stale ([`execute`](super::execute)), write the report
//! ([`finish`](super::summary::finish)).
use super::code_state;
use super::config::{self, Experiment};
use super::execute::{RunOptions, execute};
use super::headline;
use super::manylights::{Manylights, repo_root};
use super::paths::{OutputArgs, experiments_dir, load_experiment, published_dir};
use super::plan::{self, Cell, Shard};
use super::prepare::prepare;
use super::provenance::{self, Permissions};
use super::summary::finish;
use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser, Debug)]
#[command(
    name = "cargo xtask run-experiments",
    about = "Render an experiment's cells against cached references and write out/<experiment>/ (results/<experiment>/ with --publish)"
)]
pub struct RunArgs {
    /// Experiment name (experiments/NAME.toml) or a path to a .toml file.
    #[arg(long, default_value = "quick")]
    pub experiment: String,
    /// List the experiments and exit.
    #[arg(long)]
    pub list: bool,
    /// Only cells whose id, scene, strategy label/name or budget tag matches (substring, `*`
    /// wildcards; repeatable: any matches).
    #[arg(long)]
    pub only: Vec<String>,
    /// Shard i of n (1-based): a deterministic round-robin split of the cells.
    #[arg(long)]
    pub shard: Option<Shard>,
    /// Render threads (default: the experiment's, else all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Render the references again even when the cached ones are valid.
    #[arg(long)]
    pub refresh_references: bool,
    /// Render finished cells again.
    #[arg(long)]
    pub rerender: bool,
    /// Keep finished cells rendered by other code when nothing else that keys them changed
    /// (scene, strategy parameters, threads, reference); the table marks their rows.
    #[arg(long)]
    pub reuse_stale: bool,
    /// Write the table even from cells rendered by a dirty build (its header says so).
    #[arg(long)]
    pub allow_dirty: bool,
    /// Write the table even from cells of several code states or references (rows marked).
    #[arg(long)]
    pub allow_mixed: bool,
    /// Render (or check) the references and stop.
    #[arg(long)]
    pub references_only: bool,
    /// Print the cells that would run and exit.
    #[arg(long)]
    pub dry_run: bool,
    #[command(flatten)]
    pub output: OutputArgs,
}

pub fn run(args: RunArgs) -> Result<ExitCode, String> {
    if args.list {
        return list();
    }
    let exp = load_experiment(&args.experiment)?;
    let out = args.output.dir(&exp);
    let refs = args.output.references();
    let cells = select_cells(&exp, &args);
    if args.dry_run {
        print_plan(&cells);
        return Ok(ExitCode::SUCCESS);
    }
    let start = Instant::now();
    let ml = Manylights::build()?;
    let options = RunOptions {
        threads: args.threads.or(exp.threads),
        refresh_references: args.refresh_references,
        rerender: args.rerender,
        reuse_stale: args.reuse_stale,
        references_only: args.references_only,
    };
    let prepared = prepare(&exp, &ml, cells, options.threads)?;
    let perm = Permissions {
        allow_dirty: args.allow_dirty,
        allow_mixed: args.allow_mixed || args.reuse_stale,
        current: Some(prepared.code.clone()),
    };
    let done = execute(&exp, &ml, prepared, &out, &refs, &options, start)?;
    if !done.references_rendered.is_empty() {
        eprintln!(
            "references rendered: {}",
            done.references_rendered.join(", ")
        );
    }
    let report = (!options.references_only).then_some(&perm);
    let code = finish(&exp, &out, &refs, done.notices, start, done.failed, report)?;
    if args.output.publish && report.is_some() {
        headline::after_publish(&exp);
    }
    Ok(code)
}

/// `--list`: every experiment, its cell count and how its results stand against today's code.
fn list() -> Result<ExitCode, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(experiments_dir())
        .map_err(|e| format!("cannot read experiments/: {e}"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    let now = code_state::clean_code_state(&repo_root());
    for f in files {
        match config::load(&f) {
            Ok(e) => {
                let cells = published_dir(&e).join("cells.csv");
                let fresh =
                    provenance::Freshness::of(&provenance::cell_code_states(&cells), now.as_ref());
                println!(
                    "{:<18} {:>5} cells  {}\n{:<26}{}",
                    e.name,
                    plan::expand(&e).len(),
                    e.description,
                    "",
                    fresh.describe(now.is_some())
                )
            }
            Err(err) => println!("{:<18} INVALID: {err}", f.display()),
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// The experiment's cells, narrowed by `--only` and `--shard`.
fn select_cells(exp: &Experiment, args: &RunArgs) -> Vec<Cell> {
    let mut cells = plan::expand(exp);
    if !args.only.is_empty() {
        cells.retain(|c| args.only.iter().any(|p| c.matches(p)));
    }
    if let Some(shard) = args.shard {
        cells = shard.select(cells);
    }
    cells
}

/// `--dry-run`: the cell ids and their count.
fn print_plan(cells: &[Cell]) {
    for c in cells {
        println!("{}", c.id());
    }
    println!("{} cells", cells.len());
}
