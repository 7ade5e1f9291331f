//! What every table and figure of the report shares.
use crate::experiments::cell::CellResult;
use crate::experiments::config::{BudgetClock, Experiment};
use crate::experiments::plan::{Budget, budgets};
use crate::experiments::provenance::Provenance;
use std::collections::BTreeMap;

pub fn clock_words(clock: BudgetClock) -> &'static str {
    match clock {
        BudgetClock::Cpu => "CPU seconds per thread",
        BudgetClock::Wall => "Wall seconds",
    }
}

/// What every table and figure of the report shares: its rows (scenes with results, in the
/// experiment's order), its columns (strategy labels with results), the baseline column, the
/// budgets, the clock of the seconds and each scene's reference noise.
pub struct Layout<'a> {
    pub exp: &'a Experiment,
    pub rows: Vec<String>,
    pub cols: Vec<String>,
    pub budgets: Vec<Budget>,
    pub ref_noise: BTreeMap<String, f64>,
    /// The code states and references behind the cells; its mixed rows are marked.
    pub provenance: Provenance,
    pub marks: BTreeMap<String, String>,
}

/// The mark of a row that mixes code states or references.
pub const MIXED_MARK: &str = "‡";

impl<'a> Layout<'a> {
    pub fn new(exp: &'a Experiment, cells: &[CellResult], provenance: Provenance) -> Self {
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

    pub fn baseline(&self) -> &str {
        self.exp.baseline()
    }

    pub fn clock(&self) -> BudgetClock {
        self.exp.budget_clock
    }
}
