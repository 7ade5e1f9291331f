//! Writes `<results>/{cells.csv, cells.json, table.md, plots/, strips/, index.html}` from the
//! finished cell files (needs no renderer: `merge-results` runs it too).
mod figures;
mod header;
mod layout;
mod tables;

use crate::experiments::cell::{CellResult, Notice, cell_key, read_cell};
use crate::experiments::config::Experiment;
use crate::experiments::flip_cells;
use crate::experiments::plan;
use crate::experiments::provenance::{Permissions, Provenance};
use crate::experiments::report::{self, Pixels};
use crate::experiments::viewer;
use layout::Layout;
use std::fmt::Write;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

/// The finished cells of `exp` in `out/cells`, in plan order; stale ones (another plan key) are left out.
pub fn load_cells(exp: &Experiment, out: &Path) -> Vec<CellResult> {
    let mut result = Vec::new();
    for cell in plan::expand(exp) {
        let p = out.join("cells").join(format!("{}.json", cell.id()));
        if let Some(r) = read_cell(&p)
            && r.key == cell_key(&cell)
        {
            result.push(r);
        }
    }
    result
}

/// Writes cells.csv, cells.json, the plots, the strips and table.md of `out`, or nothing when
/// the cells are of a dirty build or mix code states or references and `perm` does not allow it.
pub fn generate(
    exp: &Experiment,
    out: &Path,
    refs_dir: &Path,
    notices: &[Notice],
    perm: &Permissions,
) -> Result<(), String> {
    let mut cells = load_cells(exp, out);
    let provenance = Provenance::check(&cells, perm)?;
    // ꟻLIP of cells measured before it was, where their renders are on this machine
    let mut flips = flip_cells::Sources::new(out, refs_dir);
    flips.fill_missing(&mut cells);
    write_cell_files(out, &cells)?;
    let layout = Layout::new(exp, &cells, provenance);
    let mut md = String::new();
    header::write_header(&mut md, &layout, &cells);
    tables::write_error_tables(&mut md, &layout, &cells, Pixels::Unlit);
    tables::write_flip_tables(&mut md, &layout, &cells, Pixels::Unlit);
    tables::write_oracle_tables(&mut md, &layout, &cells);
    tables::write_error_tables(&mut md, &layout, &cells, Pixels::All);
    tables::write_flip_tables(&mut md, &layout, &cells, Pixels::All);
    tables::write_time_tables(&mut md, &layout, &cells);
    tables::write_ray_table(&mut md, &layout, &cells);
    figures::write_figures(&mut md, &layout, &cells, out, refs_dir)?;
    write_notices(&mut md, notices);
    write_missing(&mut md, exp, &cells);
    let table = without_strips(&md);
    render_core::output::write_atomically(&out.join("table.md"), |tmp| {
        std::fs::write(tmp, &table).map_err(|e| e.to_string())
    })?;
    viewer::write(
        exp,
        out,
        refs_dir,
        &layout.rows,
        &layout.cols,
        &cells,
        &md,
        &mut flips,
    )
}

/// Merges the notices with those of earlier runs, writes the report (unless `perm` is `None`:
/// a `--references-only` run has no new cells to report).
pub fn finish(
    exp: &Experiment,
    out: &Path,
    refs_dir: &Path,
    mut notices: Vec<Notice>,
    start: Instant,
    failed: bool,
    perm: Option<&Permissions>,
) -> Result<ExitCode, String> {
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    notices.sort();
    notices.dedup();
    render_core::output::write_json(
        &out.join("notices.json"),
        &serde_json::to_value(&notices).unwrap(),
    )?;
    if let Some(perm) = perm {
        generate(exp, out, refs_dir, &notices, perm)?;
    }
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

/// table.md as committed: the page shows the comparison strips, table.md does not link them
/// (they are written on every run and not committed, so the links would not resolve in a
/// clone); the plots stay.
pub fn without_strips(md: &str) -> String {
    let mut out = String::with_capacity(md.len());
    let mut skip_blank = false;
    for line in md.split_inclusive('\n') {
        if line.starts_with("![") && line.contains("](strips/") {
            skip_blank = true;
            continue;
        }
        if skip_blank && line.trim().is_empty() {
            skip_blank = false;
            continue;
        }
        skip_blank = false;
        out.push_str(line);
    }
    out
}

/// cells.csv and cells.json: every finished cell.
fn write_cell_files(out: &Path, cells: &[CellResult]) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    report::write_csv(&out.join("cells.csv"), cells)?;
    render_core::output::write_json(
        &out.join("cells.json"),
        &serde_json::to_value(cells).unwrap(),
    )
}

/// The skipped and failed scenes, strategies, references and cells.
fn write_notices(md: &mut String, notices: &[Notice]) {
    if notices.is_empty() {
        return;
    }
    md.push_str("## Skipped and failed\n\n");
    for n in notices {
        let _ = writeln!(
            md,
            "- {} {}: {}",
            if n.skipped { "skipped" } else { "**failed**" },
            n.what,
            n.message
        );
    }
    md.push('\n');
}

/// How many planned cells have no result.
fn write_missing(md: &mut String, exp: &Experiment, cells: &[CellResult]) {
    let missing = plan::expand(exp)
        .iter()
        .filter(|c| !cells.iter().any(|r| r.id == c.id()))
        .count();
    if missing > 0 {
        let _ = writeln!(
            md,
            "{missing} planned cells have no result (skipped, failed, filtered out by --only/--shard, or not run yet).\n"
        );
    }
}

#[cfg(test)]
mod tests;
