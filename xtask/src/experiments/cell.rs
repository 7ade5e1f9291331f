//! What a finished cell records (`<results>/cells/<id>.json`) and what keys it: its plan key,
//! the inputs the binary reports, the code that rendered it. Written by a run, read by the
//! report, `merge-results` and the next run's reuse check.
use super::code_state::CodeState;
use super::config::BudgetClock;
use super::plan::{Budget, Cell, hex_hash};
use super::reference::Metric;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// `<results>/cells/<id>.json`: one finished cell.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CellResult {
    pub id: String,
    /// Hash of everything that determines the result; a stored cell with another key is stale.
    pub key: String,
    pub experiment: String,
    pub scene: String,
    pub scene_spec: String,
    pub strategy: String,
    pub strategy_name: String,
    pub strategy_args: Vec<String>,
    pub budget: Budget,
    pub seed: u64,
    pub width: u32,
    pub height: u32,
    /// Content id of the reference the cell was measured against.
    pub reference: String,
    /// Its directory under references/.
    pub reference_dir: String,
    pub reference_noise_unlit: f64,
    pub all: Metric,
    pub unlit: Metric,
    /// Mean HDR-ꟻLIP over all pixels and over the unlit ones (see [`super::flip`]); absent in
    /// cells from before it was measured (the report computes it when the render is there).
    #[serde(default)]
    pub flip_all: Option<f64>,
    #[serde(default)]
    pub flip_unlit: Option<f64>,
    pub spp: u64,
    pub wall_seconds: f64,
    pub cpu_seconds: f64,
    /// The render's own JSON (stats, rays, technique samples, parameters, commit).
    pub render: serde_json::Value,
    /// The code that rendered it (absent in cells from before it was recorded).
    #[serde(default)]
    pub code: Option<CodeState>,
    /// The loaded scene, the strategy's resolved parameters and (time budgets) the threads.
    #[serde(default)]
    pub inputs: Option<CellInputs>,
}

impl CellResult {
    /// The code state the cell records (the render's commit for cells from before).
    pub fn code_state(&self) -> CodeState {
        self.code
            .clone()
            .unwrap_or_else(|| CodeState::legacy(&self.render))
    }

    /// The render's duration on `clock`: wall seconds, or CPU seconds per worker thread (wall
    /// seconds where the render did not record its CPU time or thread count).
    pub fn seconds(&self, clock: BudgetClock) -> f64 {
        let threads = self.render["worker_threads"].as_u64().unwrap_or(0);
        match clock {
            BudgetClock::Cpu if threads > 0 && self.cpu_seconds > 0.0 => {
                self.cpu_seconds / threads as f64
            }
            _ => self.wall_seconds,
        }
    }
}

/// What besides the plan and the code determines a cell's image, as the binary reports it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CellInputs {
    /// `manylights info --json`'s `scene_hash`: the loaded scene.
    pub scene_hash: String,
    /// `manylights strategy --json`: the strategy's every parameter and the sampler.
    pub strategy: serde_json::Value,
    /// Render threads, for time budgets only (an spp render is the same on any count).
    pub threads: Option<usize>,
}

impl CellInputs {
    pub fn new(
        scene_hash: &str,
        strategy: &serde_json::Value,
        threads: usize,
        budget: &Budget,
    ) -> Self {
        CellInputs {
            scene_hash: scene_hash.to_string(),
            strategy: strategy.clone(),
            threads: matches!(budget, Budget::Time(_)).then_some(threads),
        }
    }
}

/// A notice about something skipped or failed, kept in `<results>/notices.json`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
pub struct Notice {
    pub what: String,
    pub skipped: bool,
    pub message: String,
}

/// The plan key of a cell: a stored result with another key is of another plan.
pub fn cell_key(cell: &Cell) -> String {
    hex_hash(cell.key_material().as_bytes())
}

/// A stored cell; `None` when the file is absent or not a cell (then the cell is rendered again).
pub fn read_cell(path: &Path) -> Option<CellResult> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// Cells and code states for the tests of the modules that read them.
#[cfg(test)]
pub mod testing {
    use super::*;

    pub fn code(id: &str, dirty: bool) -> CodeState {
        CodeState {
            id: id.into(),
            commit: Some("0123456789ab".into()),
            dirty,
        }
    }

    pub fn cell_result(id: &str, reference: &str, code_id: &str) -> CellResult {
        CellResult {
            id: id.into(),
            key: "k".into(),
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
            code: Some(code(code_id, false)),
            inputs: None,
            flip_all: None,
            flip_unlit: None,
        }
    }
}
