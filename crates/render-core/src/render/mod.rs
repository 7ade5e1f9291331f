//! The render loop: camera rays, emission seen directly, one direct-lighting estimate per
//! camera hit, in progressive passes (one sample index each) over work units of at most
//! [`UNIT_PIXELS`] consecutive pixels, claimed in order by the worker threads.
//!
//! Every pixel is owned by one unit per pass and its samples are accumulated in sample
//! order, with random numbers that depend only on (seed, pixel, sample, dimension): the image
//! is bit-identical whatever the thread count. A time budget stops the claiming of units, so a
//! render ends at a boundary (full passes, then the first `partial_pixels` pixels of one more)
//! that depends on the clock but fully determines the image; the budget is overrun by at most
//! one unit per thread and one reading of the clock, not by a whole pass. Before the first pass
//! a strategy may ask for a pilot (`crate::pilot`): samples of a sparse set of pixels with
//! numbers of their own, kept out of the image, that the strategy learns from.
//!
//! Its files: `settings.rs` (what a render is asked for, the budget's clock), `accum.rs` (a
//! pixel's running sums, the memory check), `passes.rs` (the passes and their work units),
//! `pass_job.rs` (what the units share), `unit.rs` (one unit's samples), `shading.rs` (a camera
//! ray's shading), `emission.rs` (extra emission rays), `pilot_run.rs` (a strategy's pilot) and
//! `unit_batch.rs` (a unit's samples in phases, through a strategy's batched form, `crate::batch`),
//! `image_pass.rs` (a pass of a strategy that works on the whole image, `crate::image_space`)
//! and `finish.rs` (the image and its diagnostics).
mod accum;
mod emission;
mod finish;
mod image_pass;
mod pass_job;
mod passes;
mod pilot_run;
mod settings;
mod shading;
#[cfg(test)]
mod tests;
mod unit;
mod unit_batch;

pub use accum::{check_memory, memory_estimate};
pub use finish::RenderResult;
pub use pass_job::UNIT_PIXELS;
pub use settings::{BudgetClock, Engine, MAX_THREADS, RenderSettings, TimeBudget};
pub use shading::shading_point;

use crate::estimator::{DirectLighting, MAX_AUX};
use crate::scene::Scene;
use crate::splat::SampleGrid;
use crate::stats::Counters;
use finish::{RunInfo, finish};
use host::process_cpu_seconds;
use pass_job::PassJob;
use passes::Passes;
use settings::BudgetClockReader;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Renders `scene` with `strategy`. `progress` is called after each pass with (passes done, full passes so far).
pub fn render(
    scene: &Scene,
    strategy: &dyn DirectLighting,
    settings: &RenderSettings,
    progress: &(dyn Fn(u32, u32) + Sync),
) -> Result<RenderResult, String> {
    render_cancellable(scene, strategy, settings, progress, &AtomicBool::new(false))
}

/// The error of a render stopped by its `cancel` flag.
pub const CANCELLED: &str = "the render was cancelled";

/// How another thread may end a render early: `cancel` drops it, `finish` keeps its work.
#[derive(Clone, Copy)]
struct Stops<'a> {
    cancel: &'a AtomicBool,
    finish: &'a AtomicBool,
}

/// [`render`] that another thread can stop by setting `cancel` (a Python host's Ctrl-C): the
/// worker threads stop claiming work units and the render returns [`CANCELLED`] within one
/// unit per thread. Until it is set, the image is [`render`]'s, bit for bit.
pub fn render_cancellable(
    scene: &Scene,
    strategy: &dyn DirectLighting,
    settings: &RenderSettings,
    progress: &(dyn Fn(u32, u32) + Sync),
    cancel: &AtomicBool,
) -> Result<RenderResult, String> {
    let finish = &AtomicBool::new(false);
    render_stopping(
        scene,
        strategy,
        settings,
        progress,
        Stops { cancel, finish },
    )
}

/// [`render`] that another thread can end early by setting `finish` (the command line's
/// Ctrl-C), keeping what it has done: the worker threads stop claiming work units, as when a
/// time budget is spent, and the image holds the passes done and the units of the pass under
/// way (`partial_pixels`), marked [`RenderResult::interrupted`]. Until it is set, the image is
/// [`render`]'s, bit for bit.
pub fn render_interruptible(
    scene: &Scene,
    strategy: &dyn DirectLighting,
    settings: &RenderSettings,
    progress: &(dyn Fn(u32, u32) + Sync),
    finish: &AtomicBool,
) -> Result<RenderResult, String> {
    let cancel = &AtomicBool::new(false);
    render_stopping(
        scene,
        strategy,
        settings,
        progress,
        Stops { cancel, finish },
    )
}

fn render_stopping(
    scene: &Scene,
    strategy: &dyn DirectLighting,
    settings: &RenderSettings,
    progress: &(dyn Fn(u32, u32) + Sync),
    stops: Stops,
) -> Result<RenderResult, String> {
    settings.check()?;
    let image_space = strategy.image_space();
    accum::check_memory_with(
        settings.width,
        settings.height,
        strategy.aux_channels().len(),
        image_space.map_or(0, |s| image_pass::image_pass_bytes(s.bytes_per_pixel())),
    )?;
    let (w, h) = (settings.width as usize, settings.height as usize);
    let job = PassJob {
        scene,
        strategy,
        settings,
        aspect: w as f32 / h as f32,
        n_aux: strategy.aux_channels().len().min(MAX_AUX),
        grid: SampleGrid::new(w, h, settings.reconstruction, &settings.filter),
    };
    let units = job.grid.len().div_ceil(UNIT_PIXELS);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings::worker_threads(settings.threads, units))
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))?;
    if let Some(spp) = settings.spp {
        let grid = (job.grid.width as u32, job.grid.height as u32);
        settings.sampler.check_image(grid, spp)?;
    }
    let mut passes = Passes::new(&job);
    let threads = pool.current_num_threads();
    let start = Instant::now();
    let cpu_start = process_cpu_seconds();
    let clock = settings.time_budget.map(|budget| BudgetClockReader {
        budget,
        start,
        cpu_start,
        threads,
    });
    strategy.begin_render();
    let mut counters = Counters::default();
    let mut pilot_samples = 0;
    if let Some(pilot) = strategy.pilot(job.grid.width, job.grid.height) {
        let (c, n) = job.run_pilot(&pool, pilot, clock.as_ref());
        counters.merge(&c);
        pilot_samples = n;
    }
    if stops.cancel.load(Ordering::Relaxed) {
        return Err(CANCELLED.into());
    }
    passes.run(
        &job,
        &pool,
        clock.as_ref(),
        &mut counters,
        (progress, stops),
    )?;
    let run = RunInfo {
        start,
        cpu_start,
        threads,
        pilot_samples,
        interrupted: stops.finish.load(Ordering::Relaxed),
    };
    Ok(finish(&job, &passes, counters, run))
}
