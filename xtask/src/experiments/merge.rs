//! `cargo xtask merge-results`: the cells of shard result directories copied into one
//! results directory, checked (one code state, one reference per scene, no conflicts), and its
//! report regenerated.
use super::cell::{CellResult, Notice, read_cell};
use super::headline;
use super::paths::{OutputArgs, load_experiment};
use super::provenance;
use super::summary::finish;
use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser, Debug)]
#[command(
    name = "cargo xtask merge-results",
    about = "Copy finished cells from shard result directories into out/<experiment>/ (results/<experiment>/ with --publish) and regenerate its report"
)]
pub struct MergeArgs {
    #[arg(long, default_value = "quick")]
    pub experiment: String,
    /// Result directories of shards (each a copy of some machine's `out/<experiment>/`).
    pub sources: Vec<PathBuf>,
    #[command(flatten)]
    pub output: OutputArgs,
    /// Write the table even from cells rendered by a dirty build (its header says so).
    #[arg(long)]
    pub allow_dirty: bool,
    /// Merge cells of several code states or references (rows marked) and, where two sources
    /// hold different results for one cell, take the one named last.
    #[arg(long)]
    pub allow_mixed: bool,
}

pub fn merge(args: MergeArgs) -> Result<ExitCode, String> {
    let exp = load_experiment(&args.experiment)?;
    let out = args.output.dir(&exp);
    let mut notices: Vec<Notice> = std::fs::read_to_string(out.join("notices.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default();
    let perm = provenance::Permissions {
        allow_dirty: args.allow_dirty,
        allow_mixed: args.allow_mixed,
        current: None,
    };
    let copied = merge_into(&args.sources, &out, &mut notices, &perm)?;
    eprintln!("merged {copied} cell files into {}", out.display());
    let code = finish(
        &exp,
        &out,
        &args.output.references(),
        notices,
        Instant::now(),
        false,
        Some(&perm),
    )?;
    if args.output.publish {
        headline::after_publish(&exp);
    }
    Ok(code)
}

#[derive(Parser, Debug)]
#[command(
    name = "cargo xtask report",
    about = "Rebuild an experiment's report (table.md, cells.csv, plots, strips, index.html and its viewer) from the cell files of a local run in out/<experiment>/ (results/<experiment>/ with --publish)"
)]
pub struct ReportArgs {
    #[arg(long, default_value = "quick")]
    pub experiment: String,
    #[command(flatten)]
    pub output: OutputArgs,
    /// Write the table even from cells rendered by a dirty build (its header says so).
    #[arg(long)]
    pub allow_dirty: bool,
    /// Write the table even from cells of several code states or references (rows marked).
    #[arg(long)]
    pub allow_mixed: bool,
}

/// `cargo xtask report`: `merge-results` without sources, refused where there are no cell
/// files (the published results keep only tables and plots: their report needs a run).
pub fn report(args: ReportArgs) -> Result<ExitCode, String> {
    let exp = load_experiment(&args.experiment)?;
    let dir = args.output.dir(&exp);
    let has_cells = std::fs::read_dir(dir.join("cells"))
        .map(|d| {
            d.flatten()
                .any(|e| e.path().extension().is_some_and(|x| x == "json"))
        })
        .unwrap_or(false);
    if !has_cells {
        return Err(format!(
            "no cell files in {}: run `cargo xtask run-experiments --experiment {}` first \
             (the committed results/{}/ holds the tables and plots, not the cells)",
            dir.join("cells").display(),
            exp.name,
            exp.name
        ));
    }
    merge(MergeArgs {
        experiment: args.experiment,
        sources: vec![],
        output: args.output,
        allow_dirty: args.allow_dirty,
        allow_mixed: args.allow_mixed,
    })
}

/// Copies cells (and their renders, when present) from `sources` into `out`. The cells of
/// `out` and of every source together must be one code state with one reference per scene
/// (unless `perm.allow_mixed`), and a cell held by two of them with different results is a
/// conflict (unless `perm.allow_mixed`: then the source named last wins). File times play no
/// part. Returns how many cell files were copied.
pub fn merge_into(
    sources: &[PathBuf],
    out: &Path,
    notices: &mut Vec<Notice>,
    perm: &provenance::Permissions,
) -> Result<usize, String> {
    for src in sources {
        if !src.is_dir() {
            return Err(format!("{} is not a directory", src.display()));
        }
    }
    // Every cell id → (the directory its chosen result is in, the result); `out` first.
    let mut chosen: std::collections::BTreeMap<String, (PathBuf, CellResult)> = Default::default();
    let mut conflicts = Vec::new();
    for dir in std::iter::once(&out.to_path_buf()).chain(sources) {
        let Ok(entries) = std::fs::read_dir(dir.join("cells")) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
        files.sort();
        for f in files
            .iter()
            .filter(|f| f.extension().is_some_and(|x| x == "json"))
        {
            let c = read_cell(f).ok_or_else(|| format!("{} is not a cell file", f.display()))?;
            if let Some((d, old)) = chosen.get(&c.id)
                && old != &c
                && d != out
            {
                conflicts.push(format!(
                    "{} differs between {} and {}",
                    c.id,
                    d.display(),
                    dir.display()
                ));
            }
            chosen.insert(c.id.clone(), (dir.clone(), c));
        }
    }
    if !conflicts.is_empty() && !perm.allow_mixed {
        return Err(format!(
            "refusing to merge: {} (pass --allow-mixed to take the source named last)",
            conflicts.join("; ")
        ));
    }
    let cells: Vec<CellResult> = chosen.values().map(|(_, c)| c.clone()).collect();
    provenance::Provenance::check(&cells, perm)?;
    for sub in ["cells", "renders"] {
        std::fs::create_dir_all(out.join(sub)).map_err(|e| e.to_string())?;
    }
    let mut copied = 0;
    for (id, (dir, _)) in &chosen {
        if dir.canonicalize().ok() == out.canonicalize().ok() {
            continue;
        }
        let file = format!("{id}.json");
        copy_atomically(
            &dir.join("cells").join(&file),
            &out.join("cells").join(&file),
        )?;
        copied += 1;
        // The render and its siblings (<id>.exr, <id>.json, <id>.mask.png, …).
        let Ok(entries) = std::fs::read_dir(dir.join("renders")) else {
            continue;
        };
        let prefix = format!("{id}.");
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with(&prefix) {
                copy_atomically(&e.path(), &out.join("renders").join(e.file_name()))?;
            }
        }
    }
    for src in sources {
        if let Some(n) = std::fs::read_to_string(src.join("notices.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<Vec<Notice>>(&t).ok())
        {
            notices.extend(n);
        }
    }
    Ok(copied)
}

fn copy_atomically(from: &Path, to: &Path) -> Result<(), String> {
    render_core::output::write_atomically(to, |tmp| {
        std::fs::copy(from, tmp)
            .map(|_| ())
            .map_err(|e| format!("cannot copy {}: {e}", from.display()))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::cell::testing::{cell_result, code};
    use provenance::Permissions;

    fn cell_file(dir: &Path, c: &CellResult) -> PathBuf {
        std::fs::create_dir_all(dir).unwrap();
        let p = dir.join(format!("{}.json", c.id));
        render_core::output::write_json(&p, &serde_json::to_value(c).unwrap()).unwrap();
        p
    }

    #[test]
    fn merge_copies_cells_and_renders_from_shards() {
        let base = std::env::temp_dir().join(format!("xtask-merge-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        cell_file(&base.join("s1/cells"), &cell_result("c1", "r", "tree:a"));
        cell_file(&base.join("s2/cells"), &cell_result("c2", "r", "tree:a"));
        std::fs::create_dir_all(base.join("s2/renders")).unwrap();
        std::fs::write(base.join("s2/renders/c2.exr"), "x").unwrap();
        std::fs::write(base.join("s2/renders/c22.exr"), "not c2's").unwrap();
        let mut notices = vec![];
        let out = base.join("out");
        let perm = Permissions::default();
        let n = merge_into(
            &[base.join("s1"), base.join("s2")],
            &out,
            &mut notices,
            &perm,
        );
        assert_eq!(n, Ok(2));
        assert!(out.join("cells/c1.json").is_file() && out.join("cells/c2.json").is_file());
        assert!(out.join("renders/c2.exr").is_file());
        assert!(
            !out.join("renders/c22.exr").is_file(),
            "another cell's render"
        );
        let _ = std::fs::remove_dir_all(&base);
    }

    #[test]
    fn merge_refuses_mixed_code_states_references_and_conflicts() {
        let base = std::env::temp_dir().join(format!("xtask-merge-mix-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        let out = base.join("out");
        let perm = Permissions::default();
        let mixed = Permissions {
            allow_mixed: true,
            ..Permissions::default()
        };
        let mut notices = vec![];
        // two shards of two code states
        cell_file(&base.join("a/cells"), &cell_result("c1", "r", "tree:a"));
        cell_file(&base.join("b/cells"), &cell_result("c2", "r", "tree:b"));
        let both = [base.join("a"), base.join("b")];
        let e = merge_into(&both, &out, &mut notices, &perm).unwrap_err();
        assert!(e.contains("several code states"), "{e}");
        assert!(!out.join("cells/c1.json").exists(), "nothing merged");
        // two references of one scene
        cell_file(&base.join("b/cells"), &cell_result("c2", "r2", "tree:a"));
        let e = merge_into(&both, &out, &mut notices, &perm).unwrap_err();
        assert!(e.contains("2 references"), "{e}");
        // one cell with different results in two shards, whatever their file times
        cell_file(&base.join("b/cells"), &cell_result("c1", "r", "tree:a"));
        let mut other = cell_result("c1", "r", "tree:a");
        other.spp = 5;
        cell_file(&base.join("b/cells"), &other);
        std::fs::remove_file(base.join("b/cells/c2.json")).unwrap();
        let e = merge_into(&both, &out, &mut notices, &perm).unwrap_err();
        assert!(e.contains("c1 differs"), "{e}");
        // told: the one named last wins
        assert_eq!(merge_into(&both, &out, &mut notices, &mixed), Ok(1));
        assert_eq!(read_cell(&out.join("cells/c1.json")).unwrap().spp, 5);
        // a dirty cell is refused unless allowed
        let mut dirty = cell_result("c3", "r", "binary:1");
        dirty.code = Some(code("binary:1", true));
        cell_file(&base.join("d/cells"), &dirty);
        let e = merge_into(&[base.join("d")], &base.join("out2"), &mut notices, &perm).unwrap_err();
        assert!(e.contains("--allow-dirty"), "{e}");
        let _ = std::fs::remove_dir_all(&base);
    }
}
