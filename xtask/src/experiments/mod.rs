//! `cargo xtask run-experiments`, `merge-results` and `report`: scenes × strategies × spp /
//! time budgets × seeds against cached high-spp references; tables, plots and strips in
//! `out/<experiment>/`, or the published `results/<experiment>/` (`--publish`). See
//! docs/experiments.md.
//!
//! The modules from the bottom up: `config` (the TOML), `plan` (cells, budgets, keys),
//! `code_state`, `reference`, `cell` (what a finished cell records), `provenance` (the checks
//! before a table), `report`/`flip_table` (table formats), `summary` and `viewer` (the report),
//! then the commands: `run` (`prepare`, `execute`, `measure`), `merge`.
pub mod cell;
pub mod charts;
pub mod code_state;
pub mod compositing;
pub mod config;
pub mod execute;
pub mod flip;
pub mod flip_cells;
pub mod flip_table;
pub mod headline;
#[cfg(test)]
mod keys_tests;
pub mod manylights;
pub mod measure;
pub mod merge;
pub mod paths;
pub mod plan;
pub mod prepare;
pub mod progress;
pub mod provenance;
pub mod reference;
pub mod report;
pub mod run;
#[cfg(test)]
mod shards_tests;
pub mod summary;
pub mod viewer;

use clap::Parser;
use std::process::ExitCode;

/// Entry point of `run-experiments`, `merge-results`, `report` and `headline`; `args` are the words after `cargo xtask`.
pub fn main(args: &[String]) -> ExitCode {
    let result = match args.first().map(String::as_str) {
        Some("run-experiments") => match run::RunArgs::try_parse_from(args) {
            Ok(a) => run::run(a),
            Err(e) => e.exit(),
        },
        Some("merge-results") => match merge::MergeArgs::try_parse_from(args) {
            Ok(a) => merge::merge(a),
            Err(e) => e.exit(),
        },
        Some("report") => match merge::ReportArgs::try_parse_from(args) {
            Ok(a) => merge::report(a),
            Err(e) => e.exit(),
        },
        Some("headline") => headline::main(args),
        _ => Err("unknown experiments command".into()),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
