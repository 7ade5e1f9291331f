//! The progressive passes: one sample index each, over work units claimed in order by the
//! worker threads, until the sample count is reached or the time budget spent.
use super::accum::PixelAccum;
use super::emission::plan_emission_splits;
use super::pass_job::{PassJob, UNIT_PIXELS};
use super::settings::BudgetClockReader;
use crate::splat::{PassSample, SplatFilm};
use crate::stats::Counters;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The image's samples so far and where the passes have got to.
pub(super) struct Passes {
    pub(super) accum: Vec<PixelAccum>,
    /// The samples of the pass under way, kept for its gather when splatting.
    pub(super) splats: Vec<PassSample>,
    pub(super) film: Option<SplatFilm>,
    /// Full passes done.
    pub(super) spp_done: u32,
    /// Passes started, the partial one included.
    pub(super) passes: u32,
    /// Each pass's weight, in order (the partial last one too).
    pub(super) weights: Vec<f64>,
    /// Pixels with one sample more than `spp_done` (a budget spent inside a pass).
    pub(super) partial_pixels: usize,
    /// What an image-space strategy hands from one pass to the next.
    pub(super) carry: crate::image_space::PassCarry,
}

/// A pass's work units, each claimed by one worker thread.
type Units<'a> = Vec<Mutex<(&'a mut [PixelAccum], &'a mut [PassSample])>>;

impl Passes {
    /// Empty accumulators for `job`, the first pass's emission splits planned.
    pub(super) fn new(job: &PassJob) -> Passes {
        let (settings, grid) = (job.settings, job.grid);
        let splatting = settings.reconstruction == crate::splat::Reconstruction::Splat;
        let mut accum = vec![PixelAccum::default(); grid.len()];
        plan_emission_splits(settings, grid.width, 0, &mut accum);
        let splats = vec![PassSample::default(); if splatting { grid.len() } else { 0 }];
        let (w, h) = (settings.width as usize, settings.height as usize);
        let film = splatting.then(|| SplatFilm::new(w, h, settings.filter.clone()));
        Passes {
            accum,
            splats,
            film,
            spp_done: 0,
            passes: 0,
            weights: Vec::new(),
            partial_pixels: 0,
            carry: None,
        }
    }

    /// Runs passes until the sample count is reached or the budget stops one inside; calls
    /// `progress` after each with (passes done, full passes so far). A set `cancel` ends it
    /// with [`super::CANCELLED`]; a set `finish` ends it as a spent budget does.
    pub(super) fn run(
        &mut self,
        job: &PassJob,
        pool: &rayon::ThreadPool,
        clock: Option<&BudgetClockReader>,
        counters: &mut Counters,
        (progress, stops): (&(dyn Fn(u32, u32) + Sync), super::Stops),
    ) -> Result<(), String> {
        let stop = AtomicBool::new(false);
        let image_space = job.strategy.image_space();
        let mut pass_started = 0.0;
        loop {
            if let Some(limit) = job.settings.spp
                && self.spp_done >= limit
            {
                break;
            }
            if stop.load(Ordering::Relaxed) || stops.finish.load(Ordering::Relaxed) {
                break;
            }
            // An image-space pass is never cut short: another one starts while at least half
            // of the last one's time is left, so the budget is missed by at most half a pass.
            if let (Some(_), Some(clock)) = (image_space, clock)
                && self.passes > 0
            {
                let elapsed = clock.elapsed();
                let last_pass = elapsed - pass_started;
                if elapsed + 0.5 * last_pass >= clock.budget.seconds {
                    break;
                }
            }
            if image_space.is_some() {
                pass_started = clock.map_or(0.0, |c| c.elapsed());
            }
            let pass_weight = job.pass_weight(self.spp_done)?;
            self.weights.push(pass_weight);
            let (done, n_units) = match image_space {
                Some(strategy) => {
                    let sample = (self.spp_done as u64, pass_weight);
                    self.image_pass(job, pool, strategy, sample, counters)?;
                    let n_units = job.grid.len().div_ceil(UNIT_PIXELS);
                    (n_units, n_units)
                }
                None => self.pass(job, pool, (clock, &stop, stops), pass_weight, counters),
            };
            if stops.cancel.load(Ordering::Relaxed) {
                return Err(super::CANCELLED.into());
            }
            if done == 0 {
                break;
            }
            if let Some(film) = &mut self.film {
                let pixels = (done * UNIT_PIXELS).min(job.grid.len());
                film.gather_pass(job.grid, &self.splats, pixels, pass_weight);
            }
            self.passes += 1;
            if done < n_units {
                self.partial_pixels = done * UNIT_PIXELS;
                progress(self.passes, self.spp_done);
                break;
            }
            self.spp_done += 1;
            job.strategy
                .end_pass(&mut self.accum.iter().map(|p| &p.memory));
            plan_emission_splits(job.settings, job.grid.width, self.spp_done, &mut self.accum);
            progress(self.passes, self.spp_done);
        }
        Ok(())
    }

    /// One pass of sample index `spp_done`: returns the work units done (a prefix of the
    /// image) and the units there are.
    fn pass(
        &mut self,
        job: &PassJob,
        pool: &rayon::ThreadPool,
        (clock, stop, stops): (Option<&BudgetClockReader>, &AtomicBool, super::Stops),
        pass_weight: f64,
        counters: &mut Counters,
    ) -> (usize, usize) {
        let sample = (self.spp_done as u64, pass_weight);
        // Units are handed out in order, and every unit claimed is finished: the units done
        // in this pass are always a prefix of the image.
        let mut splat_chunks = self.splats.chunks_mut(UNIT_PIXELS);
        let units: Units = self
            .accum
            .chunks_mut(UNIT_PIXELS)
            .map(|a| Mutex::new((a, splat_chunks.next().unwrap_or_default())))
            .collect();
        let next_unit = AtomicUsize::new(0);
        let pass_counters: Vec<Counters> =
            pool.broadcast(|_| claim_units(job, &units, &next_unit, (clock, stop, stops), sample));
        for c in &pass_counters {
            counters.merge(c);
        }
        let mut done = next_unit.load(Ordering::Relaxed).min(units.len());
        if done == 0 && self.spp_done == 0 {
            // A budget spent before the first unit: take that one anyway, so every render has a sample.
            let mut unit = units[0].lock().unwrap_or_else(|e| e.into_inner());
            let (a, s) = &mut *unit;
            job.render_unit(0, sample, (a, s), counters);
            done = 1;
        }
        (done, units.len())
    }
}

/// One worker thread's share of a pass: units claimed in order until none is left or the
/// budget is spent or the render cancelled or finished; returns what it counted.
fn claim_units(
    job: &PassJob,
    units: &Units,
    next_unit: &AtomicUsize,
    (clock, stop, stops): (Option<&BudgetClockReader>, &AtomicBool, super::Stops),
    sample: (u64, f64),
) -> Counters {
    let mut c = Counters::default();
    let mut last_cpu_read = None;
    loop {
        if stops.cancel.load(Ordering::Relaxed) {
            break;
        }
        if stops.finish.load(Ordering::Relaxed) {
            stop.store(true, Ordering::Relaxed);
            break;
        }
        if let Some(clock) = clock
            && (stop.load(Ordering::Relaxed) || clock.spent(&mut last_cpu_read))
        {
            stop.store(true, Ordering::Relaxed);
            break;
        }
        let u = next_unit.fetch_add(1, Ordering::Relaxed);
        let Some(unit) = units.get(u) else {
            break;
        };
        let mut unit = unit.lock().unwrap_or_else(|e| e.into_inner());
        let (a, s) = &mut *unit;
        job.render_unit(u, sample, (a, s), &mut c);
    }
    c
}
