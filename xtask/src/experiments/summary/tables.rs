//! table.md's tables: relMSE, HDR-ꟻLIP, multiples of the oracle, seconds and spp reached,
//! one per budget; shadow rays per camera sample, one for all budgets.
use super::layout::{Layout, clock_words};
use crate::experiments::cell::CellResult;
use crate::experiments::config::BudgetClock;
use crate::experiments::flip_table;
use crate::experiments::plan::Budget;
use crate::experiments::report::{self, Entry, Pixels};
use std::collections::BTreeMap;
use std::fmt::Write;

type Grid = BTreeMap<(String, String), Entry>;

pub fn grid(cells: &[CellResult], budget: &Budget, pixels: Pixels, clock: BudgetClock) -> Grid {
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

/// One paper-style relMSE table per budget (see [`report::format_table`]).
pub fn write_error_tables(md: &mut String, layout: &Layout, cells: &[CellResult], pixels: Pixels) {
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
pub fn write_flip_tables(md: &mut String, layout: &Layout, cells: &[CellResult], pixels: Pixels) {
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
pub fn write_oracle_tables(md: &mut String, layout: &Layout, cells: &[CellResult]) {
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
pub fn write_time_tables(md: &mut String, layout: &Layout, cells: &[CellResult]) {
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

/// Shadow rays per camera sample of each scene × strategy, over all its cells (every budget):
/// what a sample costs in visibility, beside the seconds and spp of the time tables.
pub fn write_ray_table(md: &mut String, layout: &Layout, cells: &[CellResult]) {
    let mut sums: BTreeMap<(String, String), (f64, f64)> = BTreeMap::new();
    for c in cells {
        let rays = &c.render["rays"];
        if let (Some(shadow), Some(camera)) = (rays["shadow"].as_f64(), rays["camera"].as_f64()) {
            let e = sums
                .entry((c.scene.clone(), c.strategy.clone()))
                .or_default();
            e.0 += shadow;
            e.1 += camera;
        }
    }
    if sums.is_empty() {
        return;
    }
    md.push_str("## Shadow rays per camera sample (all budgets)\n\n");
    md.push_str(&report::format_ratio_table(
        &layout.rows,
        &layout.cols,
        &sums,
    ));
    md.push('\n');
}
