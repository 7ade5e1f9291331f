//! A run's rendering: the references its cells need, then every cell whose stored result is
//! stale, rendered, measured ([`measure`](super::measure)) and written at once.
use super::cell::{CellInputs, CellResult, Notice, cell_key, read_cell};
use super::code_state::CodeState;
use super::config::Experiment;
use super::manylights::{Failure, Manylights};
use super::measure::{check_render, measure};
use super::paths;
use super::plan::{self, Budget, Cell};
use super::prepare::{Prepared, failure_notice};
use super::progress::{Eta, say};
use super::reference::{self, Ensure, Identity, Reference, Validity};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What a run was asked to do beyond the cells.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    pub threads: Option<usize>,
    pub refresh_references: bool,
    pub rerender: bool,
    /// Keep finished cells of another code state when nothing else about them changed.
    pub reuse_stale: bool,
    pub references_only: bool,
}

/// What a run did.
pub struct Done {
    pub notices: Vec<Notice>,
    pub failed: bool,
    /// Ids of the cells rendered, and of those kept from an earlier run.
    pub rendered: Vec<String>,
    pub reused: Vec<String>,
    /// Directory names of the references rendered (not taken from the cache).
    pub references_rendered: Vec<String>,
}

/// Ensures the references and renders every cell whose stored result is stale.
pub fn execute(
    exp: &Experiment,
    ml: &Manylights,
    mut p: Prepared,
    out: &Path,
    refs_dir: &Path,
    options: &RunOptions,
    start: Instant,
) -> Result<Done, String> {
    let multi = MultiProgress::new();
    let mut notices = std::mem::take(&mut p.notices);
    let references = ensure_references(exp, ml, &p, refs_dir, options, &multi, &mut notices)?;
    let references_rendered = references
        .values()
        .filter(|r| r.rendered)
        .filter_map(|r| r.dir.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    p.cells.retain(|c| references.contains_key(&c.scene_label));
    let mut done = Done {
        notices,
        failed: false,
        rendered: vec![],
        reused: vec![],
        references_rendered,
    };
    if options.references_only {
        return Ok(done);
    }
    let renderer = CellRenderer {
        ml,
        exp,
        prepared: &p,
        cells_dir: out.join("cells"),
        renders_dir: out.join("renders"),
        options,
    };
    renderer.render_all(&references, &multi, &mut done, start)?;
    Ok(done)
}

/// The valid cached reference of every scene some cell needs, rendering the missing or stale
/// ones; a scene whose reference fails gets a notice and no entry.
fn ensure_references(
    exp: &Experiment,
    ml: &Manylights,
    p: &Prepared,
    refs_dir: &Path,
    options: &RunOptions,
    multi: &MultiProgress,
    notices: &mut Vec<Notice>,
) -> Result<BTreeMap<String, Reference>, String> {
    let mut references = BTreeMap::new();
    for s in &exp.scenes {
        let label = s.label();
        if !p.cells.iter().any(|c| c.scene_label == label) {
            continue;
        }
        let (width, height) = plan::scene_resolution(exp, s);
        let ensure = Ensure {
            ml,
            refs_dir,
            identity: Identity {
                scene: s.spec.clone(),
                camera: s.camera.clone(),
                strategy: exp.reference.strategy.clone(),
                args: exp.reference.cli_args()?,
                spp: s.reference_spp.unwrap_or(exp.reference.spp),
                seed: exp.reference.seed,
                width,
                height,
            },
            validity: Validity {
                scene_hash: p.scene_hashes[&label].clone(),
                strategy: p.reference_strategy.clone(),
                epoch: reference::REFERENCE_EPOCH,
            },
            threads: Some(p.threads),
            force: options.refresh_references,
        };
        paths::seed_reference(refs_dir, &ensure.identity.dir_name())?;
        match ensure.run(multi) {
            Ok(r) => {
                references.insert(label, r);
            }
            Err(f) => {
                let n = failure_notice(format!("reference {label}"), f);
                say(
                    multi,
                    format!("reference for {label} failed: {}", n.message),
                )
                .ok();
                notices.push(n);
            }
        }
    }
    Ok(references)
}

/// The `manylights render` arguments of a cell (without `--out`).
pub fn render_args(cell: &Cell, threads: Option<usize>) -> Result<Vec<String>, String> {
    let mut cmd: Vec<String> = vec![
        cell.scene.spec.clone(),
        "--strategy".into(),
        cell.strategy.name.clone(),
        "--seed".into(),
        cell.seed.to_string(),
        "--width".into(),
        cell.width.to_string(),
        "--height".into(),
        cell.height.to_string(),
    ];
    match cell.budget {
        Budget::Spp(n) => cmd.extend(["--spp".into(), n.to_string()]),
        Budget::Time(t) => cmd.extend([
            "--time-budget".into(),
            t.to_string(),
            "--budget-clock".into(),
            cell.budget_clock.cli_name().into(),
        ]),
    }
    if let Some(c) = &cell.scene.camera {
        cmd.extend(["--camera".into(), c.clone()]);
    }
    // The render's own light mask (and the strategy's diagnostic maps) for the unlit metric.
    cmd.push("--aux".into());
    if let Some(t) = threads {
        cmd.extend(["--threads".into(), t.to_string()]);
    }
    cmd.extend(cell.strategy.cli_args()?);
    Ok(cmd)
}

fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template).unwrap_or(ProgressStyle::default_bar())
}

/// Renders cells into `renders_dir` and writes their measured results into `cells_dir`.
struct CellRenderer<'a> {
    ml: &'a Manylights,
    exp: &'a Experiment,
    prepared: &'a Prepared,
    cells_dir: PathBuf,
    renders_dir: PathBuf,
    options: &'a RunOptions,
}

/// What became of one rendered cell.
enum Outcome {
    Rendered,
    /// A strategy found missing at render time: its remaining cells are passed over.
    Skipped,
    Failed,
}

/// Whether a stored cell can be kept for `cell`: the same plan, reference, loaded scene,
/// resolved strategy and (time budgets) threads, and the same code unless `reuse_stale`. The
/// code is compared by its id (the tree of the code paths, or the binary's hash), not by the
/// commit it was rendered at: a later commit that changes only docs or results renders the
/// same images.
pub fn is_current(
    stored: &CellResult,
    cell: &Cell,
    reference_id: &str,
    inputs: &CellInputs,
    code: &CodeState,
    reuse_stale: bool,
) -> bool {
    stored.key == cell_key(cell)
        && stored.reference == reference_id
        && stored.inputs.as_ref() == Some(inputs)
        && (reuse_stale || stored.code.as_ref().is_some_and(|c| c.id == code.id))
}

impl CellRenderer<'_> {
    /// Every cell in order, with progress bars, into `done`.
    fn render_all(
        &self,
        references: &BTreeMap<String, Reference>,
        multi: &MultiProgress,
        done: &mut Done,
        start: Instant,
    ) -> Result<(), String> {
        for d in [&self.cells_dir, &self.renders_dir] {
            std::fs::create_dir_all(d)
                .map_err(|e| format!("cannot create {}: {e}", d.display()))?;
        }
        // The cells kept from an earlier run first, so that the estimate counts only renders.
        let (kept, to_render): (Vec<&Cell>, Vec<&Cell>) = self
            .prepared
            .cells
            .iter()
            .partition(|c| self.is_finished(c, &references[&c.scene_label]));
        done.reused.extend(kept.iter().map(|c| c.id()));
        say(
            multi,
            format!(
                "{} cells to render, {} kept from an earlier run",
                to_render.len(),
                kept.len()
            ),
        )
        .ok();
        let total = multi.add(ProgressBar::new(to_render.len() as u64));
        total.set_style(style(
            "cells {pos}/{len} {wide_bar} [{elapsed_precise}, eta {eta}]",
        ));
        let mut eta = Eta::new(to_render.len());
        let mut skipped_strategies: BTreeSet<String> = BTreeSet::new();
        for cell in to_render {
            let reference = &references[&cell.scene_label];
            if skipped_strategies.contains(&cell.strategy.label) {
                eta.pass();
                total.inc(1);
                continue;
            }
            let (outcome, line) =
                self.render_one(cell, reference, multi, &total, &mut done.notices)?;
            match outcome {
                Outcome::Rendered => done.rendered.push(cell.id()),
                Outcome::Skipped => {
                    skipped_strategies.insert(cell.strategy.label.clone());
                }
                Outcome::Failed => done.failed = true,
            }
            say(multi, eta.line(&line)).ok();
            total.inc(1);
        }
        total.finish_and_clear();
        eprintln!(
            "{} cells rendered, {} reused from an earlier run, in {:.1} s",
            done.rendered.len(),
            done.reused.len(),
            start.elapsed().as_secs_f64()
        );
        Ok(())
    }

    /// Whether the cell's result of an earlier run can be kept (see [`is_current`]).
    fn is_finished(&self, cell: &Cell, reference: &Reference) -> bool {
        let path = self.cells_dir.join(format!("{}.json", cell.id()));
        !self.options.rerender
            && read_cell(&path).is_some_and(|stored| {
                is_current(
                    &stored,
                    cell,
                    &reference.manifest.content_id(),
                    &self.prepared.inputs(cell),
                    &self.prepared.code,
                    self.options.reuse_stale,
                )
            })
    }

    /// Renders and measures the cell, and writes its result.
    fn render_one(
        &self,
        cell: &Cell,
        reference: &Reference,
        multi: &MultiProgress,
        total: &ProgressBar,
        notices: &mut Vec<Notice>,
    ) -> Result<(Outcome, String), String> {
        let id = cell.id();
        let path = self.cells_dir.join(format!("{id}.json"));
        let cmd = render_args(cell, Some(self.prepared.threads))?;
        let expected = match cell.budget {
            Budget::Spp(_) => None,
            Budget::Time(t) => Some(t),
        };
        let bar = multi.insert_before(total, ProgressBar::new(1000));
        bar.set_style(if expected.is_some() {
            style("  {spinner} {msg} {bar:30} [{elapsed_precise}]")
        } else {
            style("  {spinner} {msg} [{elapsed_precise}]")
        });
        bar.set_message(id.clone());
        let exr = self.renders_dir.join(format!("{id}.exr"));
        let result = self.ml.render(&cmd, &exr, &bar, expected);
        bar.finish_and_clear();
        let json = match result {
            Ok(j) => j,
            Err(f) => {
                let skipped = matches!(f, Failure::Skip(_));
                let what = if skipped {
                    format!("strategy {}", cell.strategy.label)
                } else {
                    format!("cell {id}")
                };
                let n = failure_notice(what, f);
                let verdict = if skipped { "skipped" } else { "FAILED" };
                let line = format!("{verdict} {id}: {}", n.message);
                notices.push(n);
                let outcome = if skipped {
                    Outcome::Skipped
                } else {
                    Outcome::Failed
                };
                return Ok((outcome, line));
            }
        };
        let inputs = self.prepared.inputs(cell);
        let measured = check_render(&json, &inputs).and_then(|()| {
            measure(cell, &exr, reference, json, &self.exp.name).map(|mut r| {
                r.code = Some(self.prepared.code.clone());
                r.inputs = Some(inputs);
                r
            })
        });
        match measured {
            Ok(r) => {
                render_core::output::write_json(&path, &serde_json::to_value(&r).unwrap())?;
                let line = format!(
                    "{id}: relMSE {:.3e} (unlit) {:.3e} (all), {} spp in {:.2} s",
                    r.unlit.rel_mse, r.all.rel_mse, r.spp, r.wall_seconds
                );
                Ok((Outcome::Rendered, line))
            }
            Err(message) => {
                let line = format!("FAILED {id}: {message}");
                notices.push(Notice {
                    what: format!("cell {id}"),
                    skipped: false,
                    message,
                });
                Ok((Outcome::Failed, line))
            }
        }
    }
}
