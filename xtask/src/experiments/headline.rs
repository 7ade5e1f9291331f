//! `cargo xtask headline`: the README's headline table, written from `results/paper/cells.csv`
//! so that it cannot drift from the published cells: per scene, E&K (`tree-split+bsdf`)
//! against the paper's method (`mis3-adaptive`), both with their default flags, at the paper
//! experiment's equal-time budget; relMSE over the unlit pixels, mean ± std over the seeds, and
//! the speed-up, computed and formatted as `table.md` does.
use super::config::{BudgetClock, Experiment};
use super::paths::{load_experiment, published_dir};
use super::plan::Budget;
use super::report::{self, Entry, Stat};
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The lines that enclose the generated block in README.md.
pub const BEGIN: &str = "<!-- headline-table:begin -->";
pub const END: &str = "<!-- headline-table:end -->";

/// The experiment the headline comes from and the two strategies it compares.
pub const EXPERIMENT: &str = "paper";
pub const BASELINE: &str = "tree-split+bsdf";
pub const METHOD: &str = "mis3-adaptive";

/// One row of cells.csv, the columns the headline reads.
#[derive(Debug, serde::Deserialize)]
struct Row {
    scene: String,
    strategy: String,
    strategy_name: String,
    strategy_args: String,
    budget: String,
    budget_value: String,
    rel_mse_unlit: f64,
    reference_noise_unlit: f64,
}

/// `cargo xtask headline [--check] [--readme PATH]`: writes the block into README.md (or
/// PATH); `--check` only says whether it is up to date.
pub fn main(args: &[String]) -> Result<ExitCode, String> {
    let mut check = false;
    let mut readme = super::manylights::repo_root().join("README.md");
    let mut it = args.iter().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--check" => check = true,
            "--readme" => {
                readme = PathBuf::from(it.next().ok_or("--readme needs a path")?);
            }
            other => {
                return Err(format!(
                    "unknown argument `{other}` (usage: cargo xtask headline [--check] [--readme PATH])"
                ));
            }
        }
    }
    let exp = load_experiment(EXPERIMENT)?;
    let block = block(&exp, &published_dir(&exp).join("cells.csv"))?;
    let text = std::fs::read_to_string(&readme)
        .map_err(|e| format!("cannot read {}: {e}", readme.display()))?;
    let new = splice(&text, &block)?;
    if check {
        if new == text {
            println!("{}: the headline table is up to date", readme.display());
            return Ok(ExitCode::SUCCESS);
        }
        eprintln!(
            "{}: the headline table differs from results/{EXPERIMENT}/cells.csv; run `cargo xtask headline`",
            readme.display()
        );
        return Ok(ExitCode::FAILURE);
    }
    if new != text {
        std::fs::write(&readme, new)
            .map_err(|e| format!("cannot write {}: {e}", readme.display()))?;
    }
    println!("headline table written into {}", readme.display());
    Ok(ExitCode::SUCCESS)
}

/// After a `--publish` of the headline's experiment: README.md's block written again from the
/// new cells.csv (a warning, not an error, where README.md has no block).
pub fn after_publish(exp: &Experiment) {
    if exp.name != EXPERIMENT {
        return;
    }
    let readme = super::manylights::repo_root().join("README.md");
    let updated = std::fs::read_to_string(&readme)
        .map_err(|e| e.to_string())
        .and_then(|text| {
            let new = splice(&text, &block(exp, &published_dir(exp).join("cells.csv"))?)?;
            std::fs::write(&readme, new).map_err(|e| e.to_string())
        });
    match updated {
        Ok(()) => eprintln!("README.md's headline table written from the new cells.csv"),
        Err(e) => eprintln!("warning: README.md's headline table not written: {e}"),
    }
}

/// `text` with the lines between [`BEGIN`] and [`END`] replaced by `block`.
pub fn splice(text: &str, block: &str) -> Result<String, String> {
    let lines: Vec<&str> = text.lines().collect();
    let find = |marker: &str| lines.iter().position(|l| l.trim_end() == marker);
    let (Some(b), Some(e)) = (find(BEGIN), find(END)) else {
        return Err(format!(
            "README.md has no headline block: put the lines `{BEGIN}` and `{END}` where the table goes, then run `cargo xtask headline`"
        ));
    };
    if e < b {
        return Err(format!("`{END}` comes before `{BEGIN}`"));
    }
    let mut out: Vec<&str> = lines[..=b].to_vec();
    out.extend(block.lines());
    out.extend(&lines[e..]);
    let mut s = out.join("\n");
    if text.ends_with('\n') {
        s.push('\n');
    }
    Ok(s)
}

/// The equal-time budget of the headline: the experiment's largest time budget.
fn headline_budget(exp: &Experiment) -> Result<f64, String> {
    exp.time_budgets
        .iter()
        .copied()
        .max_by(f64::total_cmp)
        .ok_or_else(|| format!("experiment `{}` has no time budget", exp.name))
}

/// The block between the markers: a sentence saying what it is, then the table.
pub fn block(exp: &Experiment, cells_csv: &Path) -> Result<String, String> {
    let seconds = headline_budget(exp)?;
    let rows = read_rows(cells_csv, seconds)?;
    let pick = |name: &str| -> Result<String, String> {
        exp.strategies
            .iter()
            .find(|s| s.name == name && s.cli_args().is_ok_and(|a| a.is_empty()))
            .map(|s| s.label.clone())
            .ok_or_else(|| {
                format!(
                    "experiment `{}` has no `{name}` with its default flags",
                    exp.name
                )
            })
    };
    let (base, method) = (pick(BASELINE)?, pick(METHOD)?);
    let clock = match exp.budget_clock {
        BudgetClock::Cpu => "CPU seconds per render thread",
        BudgetClock::Wall => "wall seconds",
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Equal time, {seconds} {clock}, {}×{}: relMSE over the pixels that see no light (mean ± std \
         over seeds {}) of E&K (`{BASELINE}`) and the paper's method (`{METHOD}`), and the \
         method's speed-up (E&K's relMSE over the method's). Written by `cargo xtask headline` \
         from [`results/{EXPERIMENT}/cells.csv`](results/{EXPERIMENT}/cells.csv); every column \
         is in [`results/{EXPERIMENT}/table.md`](results/{EXPERIMENT}/table.md).\n",
        exp.width,
        exp.height,
        exp.seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", "),
    );
    s.push_str(&table(exp, &rows, &base, &method, seconds)?);
    Ok(s)
}

/// The time-budget rows of cells.csv at `seconds`, in the file's order (the plan's, as the
/// report averages them).
fn read_rows(path: &Path, seconds: f64) -> Result<Vec<Row>, String> {
    let mut reader =
        csv::Reader::from_path(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut rows = Vec::new();
    for r in reader.deserialize::<Row>() {
        let r = r.map_err(|e| format!("{}: {e}", path.display()))?;
        if r.budget == "time" && r.budget_value.parse::<f64>().ok() == Some(seconds) {
            rows.push(r);
        }
    }
    Ok(rows)
}

/// The table: per scene (in the experiment's order) with cells of both strategies, their
/// relMSE and the speed-up; then the geometric mean of the speed-ups.
fn table(
    exp: &Experiment,
    rows: &[Row],
    base: &str,
    method: &str,
    seconds: f64,
) -> Result<String, String> {
    let entry = |scene: &str, label: &str, name: &str| -> Option<(Entry, f64)> {
        let mine: Vec<&Row> = rows
            .iter()
            .filter(|r| {
                r.scene == scene
                    && r.strategy == label
                    && r.strategy_name == name
                    && r.strategy_args.is_empty()
            })
            .collect();
        let first = mine.first()?;
        let errors: Vec<f64> = mine.iter().map(|r| r.rel_mse_unlit).collect();
        let e = Entry {
            error: Stat::of(&errors),
            ..Entry::default()
        };
        Some((e, first.reference_noise_unlit))
    };
    let mut s = format!("| scene | {base} | {method} | speed-up |\n|---|---:|---:|---:|\n");
    let mut speedups = Vec::new();
    let budget = Budget::Time(seconds);
    let mut noise = BTreeMap::new();
    for scene in exp.scenes.iter().map(|s| s.label()) {
        let (Some((b, nb)), Some((m, _))) =
            (entry(&scene, base, BASELINE), entry(&scene, method, METHOD))
        else {
            continue;
        };
        noise.insert(scene.clone(), nb);
        let x = report::speedup(&m, &b, &budget);
        let ratio = x.map_or("–".to_string(), |x| format!("{x:.2}×"));
        speedups.extend(x);
        let _ = writeln!(
            s,
            "| {scene} | {} | {} | {ratio} |",
            value(&b, nb, &m),
            value(&m, nb, &b)
        );
    }
    if noise.is_empty() {
        return Err(format!(
            "no equal-time cells of both `{BASELINE}` and `{METHOD}` in results/{}/cells.csv",
            exp.name
        ));
    }
    if !speedups.is_empty() {
        let g = (speedups.iter().map(|x| x.ln()).sum::<f64>() / speedups.len() as f64).exp();
        let of = if speedups.len() == noise.len() {
            String::new()
        } else {
            format!(" of {} scenes", speedups.len())
        };
        let _ = writeln!(s, "| *geometric mean* | | | *{g:.2}×*{of} |");
    }
    Ok(s)
}

/// An entry as `table.md` writes it (mean ± std, bold when it is the lower of the two, ° when
/// within reach of the reference's own error), without the speed-up.
fn value(e: &Entry, noise: f64, other: &Entry) -> String {
    let mut v = report::sci(e.error.mean);
    if e.error.n > 1 {
        v = format!("{v} ± {}", report::sci(e.error.std));
    }
    if e.error.mean <= other.error.mean {
        v = format!("**{v}**");
    }
    if report::near_reference(e, Some(noise)) {
        v = format!("{v} {}", report::REF_FLAG);
    }
    v
}

#[cfg(test)]
mod tests;
