//! `cargo xtask run-experiments`, one function per step: select the cells, check that their
//! strategies and scenes exist, ensure the references, render and measure each cell, write the
//! report (`super::finish`).
use super::config::Experiment;
use super::manylights::{self, Failure, Manylights, repo_root};
use super::plan::{self, Budget, Cell};
use super::reference::{self, Ensure, Identity, Reference, Validity};
use super::report::CellResult;
use super::{Notice, RunArgs, cell_key, finish, is_done, list, load_experiment, references_dir};
use super::{results_dir, say};
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
    let threads = args.threads.or(exp.threads);
    let mut cells = select_cells(&exp, &args);
    if args.dry_run {
        print_plan(&cells);
        return Ok(ExitCode::SUCCESS);
    }

    let start = Instant::now();
    let ml = Manylights::build()?;
    let mut notices: Vec<Notice> = Vec::new();
    let unavailable = unavailable_strategies(&exp, &ml, &mut notices)?;
    let scene_hashes = available_scenes(&exp, &ml, &cells, &mut notices);
    print_notices(&notices);
    cells.retain(|c| {
        scene_hashes.contains_key(&c.scene_label) && !unavailable.contains(&c.strategy.label)
    });

    let multi = MultiProgress::new();
    let references = ensure_references(
        &exp,
        &ml,
        &cells,
        &scene_hashes,
        threads,
        args.refresh_references,
        &multi,
        &mut notices,
    )?;
    cells.retain(|c| references.contains_key(&c.scene_label));
    if args.references_only {
        return finish(&exp, &out, notices, start, false);
    }

    let renderer = CellRenderer {
        ml: &ml,
        exp: &exp,
        cells_dir: out.join("cells"),
        renders_dir: out.join("renders"),
        threads,
        rerender: args.rerender,
    };
    let failed = renderer.render_all(&cells, &references, &multi, &mut notices, start)?;
    finish(&exp, &out, notices, start, failed)
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

/// Labels of the experiment's strategies this manylights cannot render (unknown name, or a flag
/// it does not take), each with a notice.
fn unavailable_strategies(
    exp: &Experiment,
    ml: &Manylights,
    notices: &mut Vec<Notice>,
) -> Result<BTreeSet<String>, String> {
    let known = ml.strategies()?;
    let help = ml.render_help();
    let mut unavailable = BTreeSet::new();
    for s in &exp.strategies {
        let reason = if !known.contains(&s.name) {
            Some(format!(
                "strategy `{}` is unknown to this manylights",
                s.name
            ))
        } else {
            let bad = manylights::unsupported_flags(&s.cli_args()?, &help);
            (!bad.is_empty())
                .then(|| format!("this manylights does not take {} yet", bad.join(", ")))
        };
        if let Some(message) = reason {
            notices.push(Notice {
                what: format!("strategy {}", s.label),
                skipped: true,
                message,
            });
            unavailable.insert(s.label.clone());
        }
    }
    Ok(unavailable)
}

/// Content hash of every scene some cell needs and manylights can load, by label; absent
/// scene files and failed `info` calls become notices.
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
        match ml.info(&s.spec) {
            Ok(info) => {
                hashes.insert(label, reference::scene_content_hash(&root, &s.spec, &info));
            }
            Err(f) => notices.push(failure_notice(format!("scene {label}"), f)),
        }
    }
    hashes
}

/// The valid cached reference of every scene some cell needs, rendering the missing or stale
/// ones; a scene whose reference fails gets a notice and no entry.
#[allow(clippy::too_many_arguments)]
fn ensure_references(
    exp: &Experiment,
    ml: &Manylights,
    cells: &[Cell],
    scene_hashes: &BTreeMap<String, String>,
    threads: Option<usize>,
    refresh: bool,
    multi: &MultiProgress,
    notices: &mut Vec<Notice>,
) -> Result<BTreeMap<String, Reference>, String> {
    let refs_dir = references_dir();
    let version = ml.version();
    let mut references = BTreeMap::new();
    for s in &exp.scenes {
        let label = s.label();
        if !cells.iter().any(|c| c.scene_label == label) {
            continue;
        }
        let (width, height) = plan::scene_resolution(exp, s);
        let ensure = Ensure {
            ml,
            refs_dir: &refs_dir,
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
                scene_content_hash: scene_hashes[&label].clone(),
                manylights_version: version.clone(),
                epoch: reference::REFERENCE_EPOCH,
            },
            threads,
            force: refresh,
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
    cells_dir: PathBuf,
    renders_dir: PathBuf,
    threads: Option<usize>,
    rerender: bool,
}

/// What became of one rendered cell.
enum Outcome {
    Rendered,
    /// A strategy found missing at render time: its remaining cells are passed over.
    Skipped,
    Failed,
}

impl CellRenderer<'_> {
    /// Every cell in order, with progress bars; true when some cell failed.
    fn render_all(
        &self,
        cells: &[Cell],
        references: &BTreeMap<String, Reference>,
        multi: &MultiProgress,
        notices: &mut Vec<Notice>,
        start: Instant,
    ) -> Result<bool, String> {
        for d in [&self.cells_dir, &self.renders_dir] {
            std::fs::create_dir_all(d)
                .map_err(|e| format!("cannot create {}: {e}", d.display()))?;
        }
        let total = multi.add(ProgressBar::new(cells.len() as u64));
        total.set_style(style(
            "cells {pos}/{len} {wide_bar} [{elapsed_precise}, eta {eta}]",
        ));
        let (mut rendered, mut reused, mut failed) = (0usize, 0usize, false);
        let mut skipped_strategies: BTreeSet<String> = BTreeSet::new();
        for cell in cells {
            let reference = &references[&cell.scene_label];
            if self.is_finished(cell, reference) {
                reused += 1;
                total.inc(1);
                continue;
            }
            if skipped_strategies.contains(&cell.strategy.label) {
                total.inc(1);
                continue;
            }
            match self.render_one(cell, reference, multi, &total, notices)? {
                Outcome::Rendered => rendered += 1,
                Outcome::Skipped => {
                    skipped_strategies.insert(cell.strategy.label.clone());
                }
                Outcome::Failed => failed = true,
            }
            total.inc(1);
        }
        total.finish_and_clear();
        eprintln!(
            "{rendered} cells rendered, {reused} reused from an earlier run, in {:.1} s",
            start.elapsed().as_secs_f64()
        );
        Ok(failed)
    }

    /// Whether the cell's result of an earlier run can be kept (same plan key and reference).
    fn is_finished(&self, cell: &Cell, reference: &Reference) -> bool {
        let path = self.cells_dir.join(format!("{}.json", cell.id()));
        !self.rerender && is_done(&path, &cell_key(cell), &reference.manifest.content_id())
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
        let key = cell_key(cell);
        let ref_id = reference.manifest.content_id();
        let path = self.cells_dir.join(format!("{id}.json"));
        let cmd = render_args(cell, self.threads)?;
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
        match measure(cell, &exr, reference, json, &self.exp.name, key, ref_id) {
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

/// The cell's errors against its reference, over all pixels and over the unlit ones.
fn measure(
    cell: &Cell,
    exr: &Path,
    reference: &Reference,
    render: serde_json::Value,
    experiment: &str,
    key: String,
    ref_id: String,
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
    Ok(CellResult {
        id: cell.id(),
        key,
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
        reference: ref_id,
        reference_dir: reference
            .dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        reference_noise_unlit: reference.manifest.noise_unlit.rel_mse,
        all,
        unlit,
        spp: render["spp"].as_u64().unwrap_or(0),
        wall_seconds: render["wall_seconds"].as_f64().unwrap_or(0.0),
        cpu_seconds: render["cpu_seconds"].as_f64().unwrap_or(0.0),
        render,
    })
}
