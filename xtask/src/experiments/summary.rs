//! Writes `results/<experiment>/{cells.csv, cells.json, table.md, plots/, strips/, index.html}` from the
//! finished cell files (needs no renderer: `merge-results` runs it too).
use super::charts::{self, Series};
use super::compositing::{self, StripColumn};
use super::config::{BudgetClock, Experiment};
use super::flip_cells;
use super::flip_table;
use super::plan::{self, Budget, slug};
use super::provenance::{CodeState, Permissions, Provenance};
use super::report::{self, CellResult, Entry, Pixels};
use super::{Notice, cell_key};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write;
use std::path::Path;

/// The finished cells of `exp` in `out/cells`, in plan order; stale ones (another plan key) are left out.
pub fn load_cells(exp: &Experiment, out: &Path) -> Vec<CellResult> {
    let mut result = Vec::new();
    for cell in plan::expand(exp) {
        let p = out.join("cells").join(format!("{}.json", cell.id()));
        if let Some(r) = super::read_cell(&p)
            && r.key == cell_key(&cell)
        {
            result.push(r);
        }
    }
    result
}

fn clock_words(clock: BudgetClock) -> &'static str {
    match clock {
        BudgetClock::Cpu => "CPU seconds per thread",
        BudgetClock::Wall => "Wall seconds",
    }
}

/// The experiment's budgets: its spp counts, then its time budgets.
pub fn budgets(exp: &Experiment) -> Vec<Budget> {
    let mut b: Vec<Budget> = exp.spp.iter().map(|&n| Budget::Spp(n)).collect();
    b.extend(exp.time_budgets.iter().map(|&t| Budget::Time(t)));
    b
}

type Grid = BTreeMap<(String, String), Entry>;

fn grid(cells: &[CellResult], budget: &Budget, pixels: Pixels, clock: BudgetClock) -> Grid {
    let mut groups: BTreeMap<(String, String), Vec<&CellResult>> = BTreeMap::new();
    for c in cells.iter().filter(|c| &c.budget == budget) {
        groups
            .entry((c.scene.clone(), c.strategy.clone()))
            .or_default()
            .push(c);
    }
    groups
        .into_iter()
        .map(|(k, v)| (k, report::entry(&v, pixels, clock)))
        .collect()
}

/// What every table and figure of the report shares: its rows (scenes with results, in the
/// experiment's order), its columns (strategy labels with results), the baseline column, the
/// budgets, the clock of the seconds and each scene's reference noise.
struct Layout<'a> {
    exp: &'a Experiment,
    rows: Vec<String>,
    cols: Vec<String>,
    budgets: Vec<Budget>,
    ref_noise: BTreeMap<String, f64>,
    /// The code states and references behind the cells; its mixed rows are marked.
    provenance: Provenance,
    marks: BTreeMap<String, String>,
}

/// The mark of a row that mixes code states or references.
const MIXED_MARK: &str = "‡";

impl<'a> Layout<'a> {
    fn new(exp: &'a Experiment, cells: &[CellResult], provenance: Provenance) -> Self {
        let rows = exp
            .scenes
            .iter()
            .map(|s| s.label())
            .filter(|l| cells.iter().any(|c| &c.scene == l))
            .collect();
        let cols = exp
            .strategies
            .iter()
            .map(|s| s.label.clone())
            .filter(|l| cells.iter().any(|c| &c.strategy == l))
            .collect();
        let ref_noise = cells
            .iter()
            .map(|c| (c.scene.clone(), c.reference_noise_unlit))
            .collect();
        let marks = provenance
            .mixed_rows
            .keys()
            .map(|r| (r.clone(), MIXED_MARK.to_string()))
            .collect();
        Layout {
            exp,
            rows,
            cols,
            budgets: budgets(exp),
            ref_noise,
            provenance,
            marks,
        }
    }

    fn baseline(&self) -> &str {
        self.exp.baseline()
    }

    fn clock(&self) -> BudgetClock {
        self.exp.budget_clock
    }
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
    write_header(&mut md, &layout, &cells);
    write_error_tables(&mut md, &layout, &cells, Pixels::Unlit);
    write_flip_tables(&mut md, &layout, &cells, Pixels::Unlit);
    write_oracle_tables(&mut md, &layout, &cells);
    write_error_tables(&mut md, &layout, &cells, Pixels::All);
    write_flip_tables(&mut md, &layout, &cells, Pixels::All);
    write_time_tables(&mut md, &layout, &cells);
    write_figures(&mut md, &layout, &cells, out, refs_dir)?;
    write_notices(&mut md, notices);
    write_missing(&mut md, exp, &cells);
    render_core::output::write_atomically(&out.join("table.md"), |tmp| {
        std::fs::write(tmp, &md).map_err(|e| e.to_string())
    })?;
    super::viewer::write(
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

/// cells.csv and cells.json: every finished cell.
fn write_cell_files(out: &Path, cells: &[CellResult]) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    report::write_csv(&out.join("cells.csv"), cells)?;
    render_core::output::write_json(
        &out.join("cells.json"),
        &serde_json::to_value(cells).unwrap(),
    )
}

/// Title, description, provenance (cells, commits, threads, clock) and how to read the tables.
fn write_header(md: &mut String, layout: &Layout, cells: &[CellResult]) {
    let exp = layout.exp;
    let _ = writeln!(md, "# Experiment `{}`\n", exp.name);
    if !exp.description.is_empty() {
        let _ = writeln!(md, "{}\n", exp.description);
    }
    let threads: BTreeSet<String> = cells
        .iter()
        .map(|c| match c.render["threads"].as_u64() {
            Some(t) => t.to_string(),
            None => "all".into(),
        })
        .collect();
    let _ = writeln!(
        md,
        "Generated by `cargo xtask run-experiments --experiment {}`: {} cells ({} scenes × {} strategies × {} budgets × {} seeds planned), \
         rendered by {}, render threads: {} (of {} cores on the machine that wrote this report). \
         Time budgets and the seconds in speed-ups count {}.\n",
        exp.name,
        cells.len(),
        exp.scenes.len(),
        exp.strategies.len(),
        layout.budgets.len(),
        exp.seeds.len(),
        code_words(&layout.provenance),
        threads.into_iter().collect::<Vec<_>>().join(", "),
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1),
        match exp.budget_clock {
            BudgetClock::Cpu =>
                "the render process's CPU seconds per worker thread (other jobs on the machine do not shorten them)",
            BudgetClock::Wall => "wall seconds (they need an otherwise idle machine)",
        },
    );
    let _ = writeln!(
        md,
        "Error: relMSE = mean over pixels and channels of (x − r)² / (r² + 0.01) against the reference, \
         over the pixels where no camera ray of the reference or of the render itself sees a light unless the table says \"all pixels\"; \
         mean ± standard deviation over the seeds {:?}. **Bold**: lowest in the row. \
         (n×): speed-up over the baseline `{}`: at equal time the ratio of relMSE, \
         at equal spp the ratio of relMSE × seconds (how much longer the baseline needs for the same error). \
         *ref. noise*: relMSE between the reference's two independent halves ({} at {} spp in all{}); \
         *ref. own*: the reference's own relMSE estimated from it (a quarter: each half has twice the \
         variance of their average, their difference four times it); every measured relMSE includes it, \
         so differences below it are not real, and an entry marked {} is within {}× of it (its error, \
         and its speed-up over a noisier column, are then understated).\n",
        exp.seeds,
        layout.baseline(),
        exp.reference.strategy,
        exp.reference.spp,
        exp.scenes
            .iter()
            .filter_map(|s| s.reference_spp.map(|n| format!(", {n} for {}", s.label())))
            .collect::<String>(),
        report::REF_FLAG,
        report::REF_FLAG_FACTOR,
    );
    md.push_str(
        "HDR-ꟻLIP (Andersson et al. 2020, 2021; `nv-flip`'s LDR-ꟻLIP over the exposures from the one that \
         brings the reference's maximum to 0.85 after tone mapping to the one that brings its median there, \
         per pixel the largest): the mean per-pixel perceived difference from the reference in [0, 1] \
         (0: none) for a viewer at 67 pixels per degree, over the same pixels as relMSE. It has no speed-ups: \
         it is not proportional to the variance. Its maps are in `flip-maps/` and in index.html.\n\n",
    );
}

/// The table's code state, as its header names it: one commit, or what else is mixed in.
fn code_words(p: &Provenance) -> String {
    let Some(main) = &p.main else {
        return "no cells yet".into();
    };
    let mut s = format!("**{}**", main.describe());
    if p.dirty {
        s.push_str(
            " — **it includes cells of a dirty build (written with --allow-dirty): not a committed state**",
        );
    }
    // Commits that agree on the code paths are one code state: named, not marked.
    let (same_code, others): (Vec<_>, Vec<_>) = p
        .states
        .iter()
        .filter(|(st, _)| *st != main)
        .partition(|(st, _)| st.id == main.id);
    let words = |states: Vec<(&CodeState, &usize)>| -> Vec<String> {
        states
            .into_iter()
            .map(|(st, n)| format!("{} ({n} cells)", st.describe()))
            .collect()
    };
    let (same_code, others) = (words(same_code), words(others));
    if !same_code.is_empty() {
        s.push_str(&format!(
            " and, with the same code ({}), {}",
            main.id,
            same_code.join(", ")
        ));
    }
    if !others.is_empty() {
        s.push_str(&format!(
            "; also {}: rows marked {MIXED_MARK} hold cells of another code state or several references ({})",
            others.join(", "),
            p.mixed_rows
                .iter()
                .map(|(r, why)| format!("{r}: {why}"))
                .collect::<Vec<_>>()
                .join("; ")
        ));
    } else if !p.mixed_rows.is_empty() {
        s.push_str(&format!(
            "; rows marked {MIXED_MARK} were scored against several references ({})",
            p.mixed_rows.keys().cloned().collect::<Vec<_>>().join(", ")
        ));
    }
    s
}

/// One paper-style relMSE table per budget (see [`report::format_table`]).
fn write_error_tables(md: &mut String, layout: &Layout, cells: &[CellResult], pixels: Pixels) {
    let which = match pixels {
        Pixels::Unlit => "",
        Pixels::All => "all pixels, ",
    };
    for budget in &layout.budgets {
        let g = grid(cells, budget, pixels, layout.clock());
        if g.is_empty() {
            continue;
        }
        let _ = writeln!(md, "## relMSE, {which}{}\n", budget.describe());
        md.push_str(&report::format_table(
            &layout.rows,
            &layout.cols,
            &g,
            layout.baseline(),
            budget,
            &layout.ref_noise,
            &layout.marks,
        ));
        let near = report::count_near_reference(&g, &layout.ref_noise);
        if near > 0 {
            let _ = writeln!(
                md,
                "\n{} {near} entries are within {}× of their reference's own error: the reference's \
                 noise is a large part of them (render a larger reference, `reference_spp`).",
                report::REF_FLAG,
                report::REF_FLAG_FACTOR
            );
        }
        md.push('\n');
    }
}

/// One HDR-ꟻLIP table per budget (see [`flip_table::format`]), where its cells have ꟻLIP.
fn write_flip_tables(md: &mut String, layout: &Layout, cells: &[CellResult], pixels: Pixels) {
    let which = match pixels {
        Pixels::Unlit => "",
        Pixels::All => "all pixels, ",
    };
    for budget in &layout.budgets {
        let mut groups: BTreeMap<(String, String), Vec<&CellResult>> = BTreeMap::new();
        for c in cells.iter().filter(|c| &c.budget == budget) {
            groups
                .entry((c.scene.clone(), c.strategy.clone()))
                .or_default()
                .push(c);
        }
        let g: BTreeMap<(String, String), report::Stat> = groups
            .into_iter()
            .filter_map(|(k, v)| Some((k, flip_table::entry(&v, pixels)?)))
            .collect();
        if g.is_empty() {
            continue;
        }
        let _ = writeln!(md, "## HDR-ꟻLIP, {which}{}\n", budget.describe());
        md.push_str(&flip_table::format(
            &layout.rows,
            &layout.cols,
            &g,
            &layout.marks,
        ));
        md.push('\n');
    }
}

/// Where the experiment has an `oracle` strategy: each strategy's relMSE (unlit pixels) as a
/// multiple of the oracle's at the same spp (see [`report::format_oracle_table`]).
fn write_oracle_tables(md: &mut String, layout: &Layout, cells: &[CellResult]) {
    let Some(oracle) = layout
        .exp
        .strategies
        .iter()
        .find(|s| s.name == "oracle" && layout.cols.contains(&s.label))
    else {
        return;
    };
    for budget in layout
        .budgets
        .iter()
        .filter(|b| matches!(b, Budget::Spp(_)))
    {
        let g = grid(cells, budget, Pixels::Unlit, layout.clock());
        if !g.keys().any(|(_, c)| c == &oracle.label) {
            continue;
        }
        let _ = writeln!(
            md,
            "## relMSE as a multiple of `{}`'s, {}\n",
            oracle.label,
            budget.describe()
        );
        md.push_str(&report::format_oracle_table(
            &layout.rows,
            &layout.cols,
            &g,
            &oracle.label,
        ));
        md.push('\n');
    }
}

/// One table of seconds and spp reached per budget.
fn write_time_tables(md: &mut String, layout: &Layout, cells: &[CellResult]) {
    for budget in &layout.budgets {
        let g = grid(cells, budget, Pixels::Unlit, layout.clock());
        if g.is_empty() {
            continue;
        }
        let _ = writeln!(
            md,
            "## {} / spp reached, {}\n",
            clock_words(layout.clock()),
            budget.describe()
        );
        md.push_str(&report::format_time_table(&layout.rows, &layout.cols, &g));
        md.push('\n');
    }
}

/// The curves of one scene's convergence plot: per strategy, relMSE against spp (spp
/// budgets only) and against seconds (every budget).
fn convergence_series(
    layout: &Layout,
    cells: &[CellResult],
    scene: &str,
) -> (Vec<Series>, Vec<Series>) {
    let mut vs_spp = Vec::new();
    let mut vs_sec = Vec::new();
    for col in &layout.cols {
        let mut a = Vec::new();
        let mut b = Vec::new();
        for budget in &layout.budgets {
            let sel: Vec<&CellResult> = cells
                .iter()
                .filter(|c| c.scene == scene && &c.strategy == col && &c.budget == budget)
                .collect();
            if sel.is_empty() {
                continue;
            }
            let e = report::entry(&sel, Pixels::Unlit, layout.clock());
            if let Budget::Spp(n) = budget {
                a.push((*n as f64, e.error.mean, e.error.std));
            }
            b.push((e.seconds, e.error.mean, e.error.std));
        }
        b.sort_by(|x, y| x.0.total_cmp(&y.0));
        if !a.is_empty() {
            vs_spp.push(Series {
                label: col.clone(),
                points: a,
            });
        }
        if !b.is_empty() {
            vs_sec.push(Series {
                label: col.clone(),
                points: b,
            });
        }
    }
    (vs_spp, vs_sec)
}

/// Per scene a convergence plot (plots/) and a comparison strip (strips/, where the renders
/// and the reference are on this machine), and the section that shows them.
fn write_figures(
    md: &mut String,
    layout: &Layout,
    cells: &[CellResult],
    out: &Path,
    refs_dir: &Path,
) -> Result<(), String> {
    let plots_dir = out.join("plots");
    let strips_dir = out.join("strips");
    for d in [&plots_dir, &strips_dir] {
        std::fs::create_dir_all(d).map_err(|e| e.to_string())?;
    }
    let mut figures = String::new();
    for scene in &layout.rows {
        let (vs_spp, vs_sec) = convergence_series(layout, cells, scene);
        let file = format!("{}.png", slug(scene));
        let floor = layout
            .ref_noise
            .get(scene)
            .map(|n| report::reference_own(*n));
        charts::convergence_plot(
            &plots_dir.join(&file),
            &format!("{scene}: relMSE (unlit pixels), mean ± std over seeds"),
            &vs_spp,
            &vs_sec,
            &clock_words(layout.clock()).to_lowercase(),
            floor,
        )?;
        let _ = writeln!(figures, "![{scene}: convergence](plots/{file})\n");
        match strip(layout.exp, out, refs_dir, scene, &layout.cols, cells) {
            Ok(Some(f)) => {
                let _ = writeln!(figures, "![{scene}: comparison](strips/{f})\n");
            }
            Ok(None) => {
                if strips_dir.join(&file).is_file() {
                    let _ = writeln!(figures, "![{scene}: comparison](strips/{file})\n");
                }
            }
            Err(e) => eprintln!("warning: no comparison strip for {scene}: {e}"),
        }
    }
    if !figures.is_empty() {
        md.push_str("## Plots and comparison strips\n\n");
        md.push_str(
            "Plots: relMSE (unlit pixels) vs spp and vs seconds (as above), log-log; the dashed line is the \
             reference's own estimated error. Strips: the reference with the insets marked; per strategy \
             the insets at the highest spp (seed of the first listed), the per-pixel relMSE map \
             (log scale 1e-4 dark → 10 yellow, grey = the camera sees a light) and the relMSE.\n\n",
        );
        md.push_str(&figures);
    }
    Ok(())
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

/// The comparison strip of `scene` (None when its renders or reference are not on this machine).
fn strip(
    exp: &Experiment,
    out: &Path,
    refs_dir: &Path,
    scene: &str,
    cols: &[String],
    cells: &[CellResult],
) -> Result<Option<String>, String> {
    let mine: Vec<&CellResult> = cells
        .iter()
        .filter(|c| c.scene == scene && c.seed == exp.seeds[0])
        .collect();
    let budget = exp.spp.iter().max().map(|&n| Budget::Spp(n)).or_else(|| {
        exp.time_budgets
            .iter()
            .copied()
            .max_by(f64::total_cmp)
            .map(Budget::Time)
    });
    let Some(budget) = budget else {
        return Ok(None);
    };
    let Some(first) = mine.first() else {
        return Ok(None);
    };
    let ref_dir = refs_dir.join(&first.reference_dir);
    if !ref_dir.join("ref.exr").is_file() {
        return Ok(None);
    }
    let (w, h, reference) = render_core::output::read_exr(&ref_dir.join("ref.exr"))?;
    let unlit = render_core::output::read_mask_png(&ref_dir.join("mask.png"), w, h)?;
    let mut columns = Vec::new();
    let mut baseline_err = None;
    for col in cols {
        let Some(c) = mine
            .iter()
            .find(|c| &c.strategy == col && c.budget == budget)
        else {
            continue;
        };
        let exr = out.join("renders").join(format!("{}.exr", c.id));
        if !exr.is_file() {
            return Ok(None);
        }
        let (iw, ih, px) = render_core::output::read_exr(&exr)?;
        if (iw, ih) != (w, h) {
            return Err(format!("{} is not {w}x{h}", exr.display()));
        }
        let err = render_core::metrics::rel_mse_map(&px, &reference);
        let maps = out.join("error-maps");
        std::fs::create_dir_all(&maps).map_err(|e| e.to_string())?;
        let rgb: Vec<u8> = err
            .iter()
            .zip(&unlit)
            .flat_map(|(v, u)| compositing::error_colour(*v, *u))
            .collect();
        compositing::save_png(
            &maps.join(format!("{}__{}.png", slug(scene), slug(col))),
            w,
            h,
            &rgb,
        )?;
        // and its HDR-ꟻLIP map (magma), beside it
        let flip_maps = out.join("flip-maps");
        std::fs::create_dir_all(&flip_maps).map_err(|e| e.to_string())?;
        super::flip::save_map(
            &flip_maps.join(format!("{}__{}.png", slug(scene), slug(col))),
            &super::flip::hdr_flip_map(&px, &reference, w, h)?,
            w,
            h,
        )?;
        if col == exp.baseline() || baseline_err.is_none() {
            baseline_err = Some(err.clone());
        }
        columns.push(StripColumn {
            label: col.clone(),
            caption: format!(
                "relMSE {}\n{:.2} s, {} spp",
                report::sci(c.unlit.rel_mse),
                c.seconds(exp.budget_clock),
                c.spp
            ),
            image: px,
            error: Some(err),
        });
    }
    if columns.is_empty() {
        return Ok(None);
    }
    columns.push(StripColumn {
        label: "reference".into(),
        caption: format!("ref. noise\n{}", report::sci(first.reference_noise_unlit)),
        image: reference.clone(),
        error: None,
    });
    let entry = exp.scenes.iter().find(|s| s.label() == scene);
    let insets = match entry.filter(|s| !s.insets.is_empty()) {
        Some(s) => s.insets.clone(),
        None => {
            let score: Vec<f32> = baseline_err
                .unwrap_or_default()
                .iter()
                .zip(&unlit)
                .map(|(e, u)| if *u { e.min(100.0) } else { 0.0 })
                .collect();
            compositing::pick_insets(&score, w, h, 2)
        }
    };
    let file = format!("{}.png", slug(scene));
    let desc = match budget {
        Budget::Spp(n) => format!("{n} spp"),
        Budget::Time(t) => format!("{t} s"),
    };
    compositing::comparison_strip(
        &out.join("strips").join(&file),
        &format!("{scene} — {desc}, seed {}", exp.seeds[0]),
        w,
        h,
        &reference,
        &unlit,
        &insets,
        &columns,
    )?;
    Ok(Some(file))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::config::parse;
    use crate::experiments::reference::Metric;

    /// The whole report from cell files alone (no renders, no references): what
    /// `merge-results` does on a machine that rendered nothing.
    #[test]
    fn report_from_cell_files() {
        let exp = parse(
            "t",
            r#"
            width = 8
            height = 4
            seeds = [0, 1]
            spp = [4, 16]
            time_budgets = [1.0]
            baseline = "B"
            [reference]
            strategy = "power+bsdf"
            spp = 8
            [[scenes]]
            label = "s"
            spec = "builtin:s"
            [[strategies]]
            label = "A"
            name = "tree"
            [[strategies]]
            label = "B"
            name = "power"
            "#,
        )
        .unwrap();
        let out = std::env::temp_dir().join(format!("xtask-summary-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir_all(out.join("cells")).unwrap();
        let cells = plan::expand(&exp);
        // one stale cell (another key) must be left out
        for (k, cell) in cells.iter().enumerate() {
            let spp = match cell.budget {
                Budget::Spp(n) => n as u64,
                Budget::Time(_) => 10,
            };
            let err = if cell.strategy.label == "A" { 0.1 } else { 0.4 } / spp as f64;
            let r = CellResult {
                id: cell.id(),
                key: if k == 0 {
                    "stale".into()
                } else {
                    cell_key(cell)
                },
                experiment: "t".into(),
                scene: cell.scene_label.clone(),
                scene_spec: cell.scene.spec.clone(),
                strategy: cell.strategy.label.clone(),
                strategy_name: cell.strategy.name.clone(),
                strategy_args: vec![],
                budget: cell.budget,
                seed: cell.seed,
                width: 8,
                height: 4,
                reference: "r".into(),
                reference_dir: "absent".into(),
                reference_noise_unlit: 1e-4,
                all: Metric {
                    rel_mse: err * 2.0,
                    mse: err,
                    pixels: 32,
                },
                unlit: Metric {
                    rel_mse: err * (1.0 + cell.seed as f64 * 0.1),
                    mse: err,
                    pixels: 30,
                },
                spp,
                wall_seconds: spp as f64 * 0.1,
                cpu_seconds: spp as f64 * 0.2,
                render: serde_json::json!({ "git_commit": "abc" }),
                code: None,
                inputs: None,
                flip_all: None,
                flip_unlit: None,
            };
            render_core::output::write_json(
                &out.join("cells").join(format!("{}.json", r.id)),
                &serde_json::to_value(&r).unwrap(),
            )
            .unwrap();
        }
        let notices = vec![Notice {
            what: "strategy C".into(),
            skipped: true,
            message: "not implemented yet".into(),
        }];
        generate(
            &exp,
            &out,
            &out.join("no-refs"),
            &notices,
            &Permissions::default(),
        )
        .unwrap();
        assert_eq!(load_cells(&exp, &out).len(), cells.len() - 1);
        let md = std::fs::read_to_string(out.join("table.md")).unwrap();
        assert!(md.contains("## relMSE, equal spp = 16"), "{md}");
        assert!(
            md.contains("| scene | A | B (baseline) | ref. noise | ref. own |"),
            "{md}"
        );
        // A: 0.1/16 and 0.11/16 → mean 6.56e-3, 4× better than B at the same seconds
        assert!(md.contains("**6.56e-3 ± 4.42e-4** (4.00×)"), "{md}");
        assert!(
            md.contains("skipped strategy C: not implemented yet"),
            "{md}"
        );
        assert!(md.contains("1 planned cells have no result"), "{md}");
        assert!(out.join("plots/s.png").is_file());
        let csv = std::fs::read_to_string(out.join("cells.csv")).unwrap();
        assert_eq!(csv.lines().count(), cells.len());
        // cells from before code states were recorded: their render's commit stands in
        assert!(
            csv.lines()
                .next()
                .unwrap()
                .ends_with("code_state,code_commit,code_dirty")
        );
        assert!(
            csv.lines()
                .nth(1)
                .unwrap()
                .ends_with("legacy:abc,abc,false"),
            "{csv}"
        );
        assert!(md.contains("rendered by **commit abc**"), "{md}");
        let _ = std::fs::remove_dir_all(&out);
    }
}
