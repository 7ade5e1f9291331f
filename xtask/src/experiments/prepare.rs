//! Before a run renders: which of the experiment's strategies and scenes this `manylights`
//! can render, and what the binary says keys them (resolved parameters, `scene_hash`, the code
//! state).
use super::cell::{CellInputs, Notice};
use super::code_state::{self, CodeState};
use super::config::Experiment;
use super::manylights::{self, Failure, Manylights, repo_root};
use super::plan::Cell;
use std::collections::{BTreeMap, BTreeSet};

/// The cells to run and everything that keys them, as the binary reports it.
pub struct Prepared {
    pub cells: Vec<Cell>,
    pub notices: Vec<Notice>,
    pub code: CodeState,
    /// `scene_hash` by scene label (the scenes manylights can load).
    pub scene_hashes: BTreeMap<String, String>,
    /// Resolved parameters by strategy label (the strategies manylights can render).
    pub strategies: BTreeMap<String, serde_json::Value>,
    /// The reference strategy's resolved parameters.
    pub reference_strategy: serde_json::Value,
    /// Render threads, passed to every render.
    pub threads: usize,
}

impl Prepared {
    pub fn inputs(&self, cell: &Cell) -> CellInputs {
        CellInputs::new(
            &self.scene_hashes[&cell.scene_label],
            &self.strategies[&cell.strategy.label],
            self.threads,
            &cell.budget,
        )
    }
}

/// Checks the cells' strategies and scenes against the binary and asks it for their keys;
/// the cells it cannot render are dropped with a notice.
pub fn prepare(
    exp: &Experiment,
    ml: &Manylights,
    mut cells: Vec<Cell>,
    threads: Option<usize>,
) -> Result<Prepared, String> {
    let mut notices: Vec<Notice> = Vec::new();
    let strategies = available_strategies(exp, ml, &mut notices)?;
    let scene_hashes = available_scenes(exp, ml, &cells, &mut notices);
    print_notices(&notices);
    cells.retain(|c| {
        scene_hashes.contains_key(&c.scene_label) && strategies.contains_key(&c.strategy.label)
    });
    let reference_strategy = ml
        .resolved_strategy(&exp.reference.strategy, &exp.reference.cli_args()?)
        .map_err(|f| format!("reference strategy {}: {f}", exp.reference.strategy))?;
    let threads = threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    Ok(Prepared {
        cells,
        notices,
        code: code_state::code_state(&ml.root, &ml.exe)?,
        scene_hashes,
        strategies,
        reference_strategy,
        threads,
    })
}

/// A skipped or failed step as a notice (`Failure::Skip` = something that does not exist here).
pub fn failure_notice(what: String, failure: Failure) -> Notice {
    let skipped = matches!(failure, Failure::Skip(_));
    let message = match failure {
        Failure::Skip(m) | Failure::Error(m) => m,
    };
    Notice {
        what,
        skipped,
        message,
    }
}

fn print_notices(notices: &[Notice]) {
    for n in notices {
        eprintln!(
            "{}: {} — {}",
            if n.skipped { "skipped" } else { "ERROR" },
            n.what,
            n.message
        );
    }
}

/// The resolved parameters of each of the experiment's strategies this manylights can render,
/// by label; the others (unknown name, a flag it does not take) get a notice.
fn available_strategies(
    exp: &Experiment,
    ml: &Manylights,
    notices: &mut Vec<Notice>,
) -> Result<BTreeMap<String, serde_json::Value>, String> {
    let known = ml.strategies()?;
    let help = ml.render_help();
    let mut available = BTreeMap::new();
    for s in &exp.strategies {
        let args = s.cli_args()?;
        let reason = if !known.contains(&s.name) {
            Some(Failure::Skip(format!(
                "strategy `{}` is unknown to this manylights",
                s.name
            )))
        } else {
            let bad = manylights::unsupported_flags(&args, &help);
            (!bad.is_empty()).then(|| {
                Failure::Skip(format!(
                    "this manylights does not take {} yet",
                    bad.join(", ")
                ))
            })
        };
        let resolved = match reason {
            Some(f) => Err(f),
            None => ml.resolved_strategy(&s.name, &args),
        };
        match resolved {
            Ok(v) => {
                available.insert(s.label.clone(), v);
            }
            Err(f) => notices.push(failure_notice(format!("strategy {}", s.label), f)),
        }
    }
    Ok(available)
}

/// The loaded scene's hash (`manylights info --json`'s `scene_hash`) of every scene some cell
/// needs and manylights can load, by label; absent scene files and failed `info` calls
/// become notices.
fn available_scenes(
    exp: &Experiment,
    ml: &Manylights,
    cells: &[Cell],
    notices: &mut Vec<Notice>,
) -> BTreeMap<String, String> {
    let root = repo_root();
    let wanted: BTreeSet<&str> = cells.iter().map(|c| c.scene_label.as_str()).collect();
    let mut hashes = BTreeMap::new();
    for s in &exp.scenes {
        let label = s.label();
        if !wanted.contains(label.as_str()) {
            continue;
        }
        if !s.is_builtin() && !root.join(&s.spec).exists() {
            notices.push(Notice {
                what: format!("scene {label}"),
                skipped: true,
                message: format!("{} is absent", s.spec),
            });
            continue;
        }
        let hash = ml.info(&s.spec).and_then(|info| {
            info["scene_hash"]
                .as_str()
                .map(str::to_string)
                .ok_or_else(|| {
                    Failure::Error("this manylights's `info --json` has no scene_hash".into())
                })
        });
        match hash {
            Ok(h) => {
                hashes.insert(label, h);
            }
            Err(f) => notices.push(failure_notice(format!("scene {label}"), f)),
        }
    }
    hashes
}
