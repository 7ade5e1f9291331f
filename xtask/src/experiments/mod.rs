//! `cargo xtask run-experiments` and `cargo xtask merge-results`: scenes × strategies × spp /
//! time budgets × seeds against cached high-spp references; tables, plots and strips in
//! `results/<experiment>/`. See xtask/README.md.
pub mod charts;
pub mod compositing;
pub mod config;
pub mod manylights;
pub mod plan;
pub mod reference;
pub mod report;
pub mod run;
pub mod summary;
pub mod viewer;

use clap::Parser;
use config::Experiment;
use indicatif::MultiProgress;
use manylights::repo_root;
use plan::{Cell, Shard, hex_hash};
use report::CellResult;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser, Debug)]
#[command(
    name = "cargo xtask run-experiments",
    about = "Render an experiment's cells against cached references and write results/<experiment>/"
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
    /// Render (or check) the references and stop.
    #[arg(long)]
    pub references_only: bool,
    /// Print the cells that would run and exit.
    #[arg(long)]
    pub dry_run: bool,
    /// Results directory (default results/<experiment>).
    #[arg(long)]
    pub results: Option<PathBuf>,
}

#[derive(Parser, Debug)]
#[command(
    name = "cargo xtask merge-results",
    about = "Copy finished cells from shard result directories into results/<experiment>/ and regenerate its report"
)]
pub struct MergeArgs {
    #[arg(long, default_value = "quick")]
    pub experiment: String,
    /// Result directories of shards (each a copy of some machine's results/<experiment>/).
    pub sources: Vec<PathBuf>,
    #[arg(long)]
    pub results: Option<PathBuf>,
}

pub fn experiments_dir() -> PathBuf {
    repo_root().join("experiments")
}

pub fn resolve_experiment(name: &str) -> PathBuf {
    if name.ends_with(".toml") || name.contains('/') {
        PathBuf::from(name)
    } else {
        experiments_dir().join(format!("{name}.toml"))
    }
}

fn load_experiment(name: &str) -> Result<Experiment, String> {
    let path = resolve_experiment(name);
    if !path.exists() {
        let mut names: Vec<String> = std::fs::read_dir(experiments_dir())
            .map(|d| {
                d.filter_map(|e| {
                    let p = e.ok()?.path();
                    (p.extension()? == "toml")
                        .then(|| p.file_stem().map(|s| s.to_string_lossy().into_owned()))?
                })
                .collect()
            })
            .unwrap_or_default();
        names.sort();
        return Err(format!(
            "no experiment `{name}` ({} does not exist); experiments: {}",
            path.display(),
            names.join(", ")
        ));
    }
    config::load(&path)
}

fn results_dir(exp: &Experiment, given: &Option<PathBuf>) -> PathBuf {
    given
        .clone()
        .unwrap_or_else(|| repo_root().join("results").join(&exp.name))
}

pub fn references_dir() -> PathBuf {
    repo_root().join("references")
}

/// Entry point of both subcommands; `args` are the words after `cargo xtask`.
pub fn main(args: &[String]) -> ExitCode {
    let result = match args.first().map(String::as_str) {
        Some("run-experiments") => match RunArgs::try_parse_from(args) {
            Ok(a) => run::run(a),
            Err(e) => e.exit(),
        },
        Some("merge-results") => match MergeArgs::try_parse_from(args) {
            Ok(a) => merge(a),
            Err(e) => e.exit(),
        },
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

fn list() -> Result<ExitCode, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(experiments_dir())
        .map_err(|e| format!("cannot read experiments/: {e}"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    for f in files {
        match config::load(&f) {
            Ok(e) => println!(
                "{:<18} {:>5} cells  {}",
                e.name,
                plan::expand(&e).len(),
                e.description
            ),
            Err(err) => println!("{:<18} INVALID: {err}", f.display()),
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// A notice about something skipped or failed, kept in results/<exp>/notices.json.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, PartialEq, Eq, PartialOrd, Ord)]
pub struct Notice {
    pub what: String,
    pub skipped: bool,
    pub message: String,
}

fn cell_key(cell: &Cell) -> String {
    hex_hash(cell.key_material().as_bytes())
}

fn read_cell(path: &Path) -> Option<CellResult> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// Whether the finished cell at `path` can be kept: same plan key and same reference.
pub fn is_done(path: &Path, key: &str, reference_id: &str) -> bool {
    read_cell(path).is_some_and(|c| c.key == key && c.reference == reference_id)
}

/// A line above the progress bars, or on stderr when they are hidden (no terminal).
pub fn say(multi: &MultiProgress, msg: String) -> std::io::Result<()> {
    if multi.is_hidden() {
        eprintln!("{msg}");
        Ok(())
    } else {
        multi.println(msg)
    }
}

/// Merges the notices with those of earlier runs, writes the report.
fn finish(
    exp: &Experiment,
    out: &Path,
    mut notices: Vec<Notice>,
    start: Instant,
    failed: bool,
) -> Result<ExitCode, String> {
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    notices.sort();
    notices.dedup();
    render_core::output::write_json(
        &out.join("notices.json"),
        &serde_json::to_value(&notices).unwrap(),
    )?;
    summary::generate(exp, out, &references_dir(), &notices)?;
    eprintln!(
        "results in {} ({:.1} s in all)",
        out.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn merge(args: MergeArgs) -> Result<ExitCode, String> {
    let exp = load_experiment(&args.experiment)?;
    let out = results_dir(&exp, &args.results);
    let mut notices: Vec<Notice> = std::fs::read_to_string(out.join("notices.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default();
    let copied = merge_into(&args.sources, &out, &mut notices)?;
    eprintln!("merged {copied} cell files into {}", out.display());
    finish(&exp, &out, notices, Instant::now(), false)
}

/// Copies cells (and renders, when present) from `sources` into `out`; a cell present in
/// several is taken from the newest file. Returns how many cell files were copied.
pub fn merge_into(
    sources: &[PathBuf],
    out: &Path,
    notices: &mut Vec<Notice>,
) -> Result<usize, String> {
    let mut copied = 0;
    for sub in ["cells", "renders"] {
        std::fs::create_dir_all(out.join(sub)).map_err(|e| e.to_string())?;
    }
    for src in sources {
        if !src.is_dir() {
            return Err(format!("{} is not a directory", src.display()));
        }
        for sub in ["cells", "renders"] {
            let Ok(entries) = std::fs::read_dir(src.join(sub)) else {
                continue;
            };
            for e in entries.flatten() {
                let from = e.path();
                let to = out.join(sub).join(e.file_name());
                let newer = match (from.metadata(), to.metadata()) {
                    (Ok(a), Ok(b)) => a.modified().ok() > b.modified().ok(),
                    (Ok(_), Err(_)) => true,
                    _ => false,
                };
                if newer && from.canonicalize().ok() != to.canonicalize().ok() {
                    render_core::output::write_atomically(&to, |tmp| {
                        std::fs::copy(&from, tmp)
                            .map(|_| ())
                            .map_err(|e| e.to_string())
                    })?;
                    if sub == "cells" {
                        copied += 1;
                    }
                }
            }
        }
        if let Some(n) = std::fs::read_to_string(src.join("notices.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<Vec<Notice>>(&t).ok())
        {
            notices.extend(n);
        }
    }
    Ok(copied)
}

#[cfg(test)]
mod tests {
    use super::*;
    use plan::Budget;

    fn cell_file(dir: &Path, id: &str, key: &str, reference: &str) -> PathBuf {
        let c = CellResult {
            id: id.into(),
            key: key.into(),
            experiment: "t".into(),
            scene: "s".into(),
            scene_spec: "builtin:s".into(),
            strategy: "a".into(),
            strategy_name: "tree".into(),
            strategy_args: vec![],
            budget: Budget::Spp(4),
            seed: 0,
            width: 2,
            height: 2,
            reference: reference.into(),
            reference_dir: "r".into(),
            reference_noise_unlit: 0.0,
            all: Default::default(),
            unlit: Default::default(),
            spp: 4,
            wall_seconds: 1.0,
            cpu_seconds: 2.0,
            render: serde_json::json!({}),
        };
        std::fs::create_dir_all(dir).unwrap();
        let p = dir.join(format!("{id}.json"));
        render_core::output::write_json(&p, &serde_json::to_value(&c).unwrap()).unwrap();
        p
    }

    #[test]
    fn a_finished_cell_is_skipped_unless_stale() {
        let dir = std::env::temp_dir().join(format!("xtask-resume-{}", std::process::id()));
        let p = cell_file(&dir, "c1", "k1", "r1");
        assert!(is_done(&p, "k1", "r1"));
        assert!(!is_done(&p, "k2", "r1"), "another plan key: stale");
        assert!(!is_done(&p, "k1", "r2"), "another reference: stale");
        assert!(!is_done(&dir.join("absent.json"), "k1", "r1"));
        std::fs::write(dir.join("broken.json"), "{\"id\":").unwrap();
        assert!(
            !is_done(&dir.join("broken.json"), "k1", "r1"),
            "a partial file is not done"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn merge_copies_cells_from_shards() {
        let base = std::env::temp_dir().join(format!("xtask-merge-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        cell_file(&base.join("s1/cells"), "c1", "k", "r");
        cell_file(&base.join("s2/cells"), "c2", "k", "r");
        let mut notices = vec![];
        let out = base.join("out");
        let n = merge_into(&[base.join("s1"), base.join("s2")], &out, &mut notices).unwrap();
        assert_eq!(n, 2);
        assert!(out.join("cells/c1.json").is_file() && out.join("cells/c2.json").is_file());
        // again: nothing newer to copy
        assert_eq!(
            merge_into(&[base.join("s1")], &out, &mut notices).unwrap(),
            0
        );
        let _ = std::fs::remove_dir_all(&base);
    }
}
