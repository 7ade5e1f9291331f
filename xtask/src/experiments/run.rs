//! `cargo xtask run-experiments`, one function per step: select the cells, check that their
//! strategies and scenes exist and ask the binary what they resolve to (`prepare`), ensure the
//! references, render and measure each cell whose stored result is stale (`execute`), write
//! the report (`super::finish`).
use super::config::Experiment;
use super::flip;
use super::manylights::{self, Failure, Manylights, repo_root};
use super::plan::{self, Budget, Cell};
use super::provenance::{self, CellInputs, CodeState, Permissions};
use super::reference::{self, Ensure, Identity, Reference, Validity};
use super::report::CellResult;
use super::{Notice, RunArgs, cell_key, finish, list, load_experiment, read_cell};
use super::{references_dir, results_dir, say};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

pub fn run(args: RunArgs) -> Result<ExitCode, String> {
    if args.list {
        return list();
    }
    let exp = load_experiment(&args.experiment)?;
    let out = results_dir(&exp, &args.results);
    let cells = select_cells(&exp, &args);
    if args.dry_run {
        print_plan(&cells);
        return Ok(ExitCode::SUCCESS);
    }
    let start = Instant::now();
    let ml = Manylights::build()?;
    let options = RunOptions {
        threads: args.threads.or(exp.threads),
        refresh_references: args.refresh_references,
        rerender: args.rerender,
        reuse_stale: args.reuse_stale,
        references_only: args.references_only,
    };
    let prepared = prepare(&exp, &ml, cells, options.threads)?;
    let perm = Permissions {
        allow_dirty: args.allow_dirty,
        allow_mixed: args.allow_mixed || args.reuse_stale,
        current: Some(prepared.code.clone()),
    };
    let done = execute(
        &exp,
        &ml,
        prepared,
        &out,
        &references_dir(),
        &options,
        start,
    )?;
    if !done.references_rendered.is_empty() {
        eprintln!(
            "references rendered: {}",
            done.references_rendered.join(", ")
        );
    }
    let report = (!options.references_only).then_some(&perm);
    finish(&exp, &out, done.notices, start, done.failed, report)
}

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
        code: provenance::code_state(&ml.root, &ml.exe)?,
        scene_hashes,
        strategies,
        reference_strategy,
        threads,
    })
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

/// The experiment's cells, narrowed by `--only` and `--shard`.
fn select_cells(exp: &Experiment, args: &RunArgs) -> Vec<Cell> {
    let mut cells = plan::expand(exp);
    if !args.only.is_empty() {
        cells.retain(|c| args.only.iter().any(|p| c.matches(p)));
    }
    if let Some(shard) = args.shard {
        cells = shard.select(cells);
    }
    cells
}

/// `--dry-run`: the cell ids and their count.
fn print_plan(cells: &[Cell]) {
    for c in cells {
        println!("{}", c.id());
    }
    println!("{} cells", cells.len());
}

/// A skipped or failed step as a notice (`Failure::Skip` = something that does not exist here).
fn failure_notice(what: String, failure: Failure) -> Notice {
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
        let cells = &self.prepared.cells;
        let total = multi.add(ProgressBar::new(cells.len() as u64));
        total.set_style(style(
            "cells {pos}/{len} {wide_bar} [{elapsed_precise}, eta {eta}]",
        ));
        let mut skipped_strategies: BTreeSet<String> = BTreeSet::new();
        for cell in cells {
            let reference = &references[&cell.scene_label];
            if self.is_finished(cell, reference) {
                done.reused.push(cell.id());
                total.inc(1);
                continue;
            }
            if skipped_strategies.contains(&cell.strategy.label) {
                total.inc(1);
                continue;
            }
            match self.render_one(cell, reference, multi, &total, &mut done.notices)? {
                Outcome::Rendered => done.rendered.push(cell.id()),
                Outcome::Skipped => {
                    skipped_strategies.insert(cell.strategy.label.clone());
                }
                Outcome::Failed => done.failed = true,
            }
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
    ) -> Result<Outcome, String> {
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
                say(multi, format!("{verdict} {id}: {}", n.message)).ok();
                notices.push(n);
                return Ok(if skipped {
                    Outcome::Skipped
                } else {
                    Outcome::Failed
                });
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
                say(
                    multi,
                    format!(
                        "{id}: relMSE {:.3e} (unlit) {:.3e} (all), {} spp in {:.2} s",
                        r.unlit.rel_mse, r.all.rel_mse, r.spp, r.wall_seconds
                    ),
                )
                .ok();
                Ok(Outcome::Rendered)
            }
            Err(message) => {
                notices.push(Notice {
                    what: format!("cell {id}"),
                    skipped: false,
                    message,
                });
                Ok(Outcome::Failed)
            }
        }
    }
}

/// That the render used the scene and strategy the cell is keyed by (a file edited during
/// the run, or a binary that resolves differently from `manylights strategy`, is an error).
fn check_render(render: &serde_json::Value, inputs: &CellInputs) -> Result<(), String> {
    if render["scene_hash"].as_str() != Some(inputs.scene_hash.as_str()) {
        return Err(format!(
            "the render loaded scene {}, not the one planned ({}): did a scene file change during the run?",
            render["scene_hash"], inputs.scene_hash
        ));
    }
    if render["resolved_strategy"] != inputs.strategy {
        return Err(format!(
            "the render resolved the strategy to {}, `manylights strategy` to {}",
            render["resolved_strategy"], inputs.strategy
        ));
    }
    Ok(())
}

/// The cell's errors against its reference, over all pixels and over the unlit ones.
fn measure(
    cell: &Cell,
    exr: &Path,
    reference: &Reference,
    render: serde_json::Value,
    experiment: &str,
) -> Result<CellResult, String> {
    let (w, h, px) = render_core::output::read_exr(exr)?;
    if (w, h)
        != (
            reference.manifest.identity.width,
            reference.manifest.identity.height,
        )
    {
        return Err(format!("render is {w}x{h}, its reference is not"));
    }
    let all = render_core::metrics::error_metrics(&px, &reference.pixels, None).into();
    // Unlit = neither the reference's camera rays nor this render's saw a light. The reference
    // alone misses lights that cover a tiny part of a pixel; one camera sample of this render
    // landing on one adds light-seen-directly noise that no light-sampling strategy changes
    // (at equal spp and seed every strategy shoots the same camera rays, so the same pixels).
    let own = render_core::output::read_mask_png(&exr.with_extension("mask.png"), w, h)?;
    let unlit_pixels: Vec<bool> = reference
        .unlit
        .iter()
        .zip(&own)
        .map(|(&r, &c)| r && c)
        .collect();
    let unlit =
        render_core::metrics::error_metrics(&px, &reference.pixels, Some(&unlit_pixels)).into();
    // HDR-ꟻLIP beside relMSE; its map is kept beside the render for the report.
    let flip = flip::score(&px, &reference.pixels, &unlit_pixels, w, h)?;
    flip::save_map(&exr.with_extension("flip.png"), &flip.map, w, h)?;
    Ok(CellResult {
        id: cell.id(),
        key: cell_key(cell),
        experiment: experiment.to_string(),
        scene: cell.scene_label.clone(),
        scene_spec: cell.scene.spec.clone(),
        strategy: cell.strategy.label.clone(),
        strategy_name: cell.strategy.name.clone(),
        strategy_args: cell.strategy.cli_args()?,
        budget: cell.budget,
        seed: cell.seed,
        width: w,
        height: h,
        reference: reference.manifest.content_id(),
        reference_dir: reference
            .dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        reference_noise_unlit: reference.manifest.noise_unlit.rel_mse,
        all,
        unlit,
        flip_all: Some(flip.all),
        flip_unlit: Some(flip.unlit),
        spp: render["spp"].as_u64().unwrap_or(0),
        wall_seconds: render["wall_seconds"].as_f64().unwrap_or(0.0),
        cpu_seconds: render["cpu_seconds"].as_f64().unwrap_or(0.0),
        render,
        code: None,
        inputs: None,
    })
}
