//! What a render is asked for, checked before anything is allocated, and the time budget as
//! the worker threads read it.
use crate::camera::Camera;
use crate::emission_rays::EmissionRays;
use crate::filter::PixelFilter;
use crate::sampler::Sampler;
use crate::splat::Reconstruction;
use host::process_cpu_seconds;
use std::time::{Duration, Instant};

/// The process CPU clock (a system call) is read at most this often per thread.
const CPU_CLOCK_INTERVAL: Duration = Duration::from_millis(5);

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel; with a time budget, the most that will be taken (`None` = no limit).
    pub spp: Option<u32>,
    pub seed: u64,
    /// No new work unit starts once this budget is spent.
    pub time_budget: Option<TimeBudget>,
    /// Worker threads (`None` = all cores).
    pub threads: Option<usize>,
    pub camera: Camera,
    /// Where the samples' numbers come from.
    pub sampler: Sampler,
    /// How camera samples are spread over and weighted within their pixel.
    pub filter: PixelFilter,
    /// How the filter turns samples into pixels: filter importance sampling (each sample in its
    /// own pixel) or pbrt-v3's weighted splatting (`crate::splat`).
    pub reconstruction: Reconstruction,
    /// Camera rays per sample that gather the emission seen directly (`emission_rays.rs`;
    /// more than one only under `Reconstruction::Sampled`).
    pub emission_rays: EmissionRays,
    /// How camera samples go through shading: in batches where the strategy can, or one at a
    /// time. Both give the same image.
    pub engine: Engine,
}

/// How a render's camera samples go through shading (`crate::batch`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Engine {
    /// A work unit's samples in phases together, rays traced as streams, for every strategy
    /// with a batched form ([`crate::estimator::DirectLighting::batched`]); the others one at
    /// a time.
    #[default]
    Batched,
    /// Every strategy one camera sample at a time, each ray traced alone.
    PerSample,
}

impl Engine {
    /// What shades `strategy`'s camera samples when a render asks for this engine:
    /// `image-space` (its whole-image passes), `batched` or `per-sample`.
    pub fn used_for(self, strategy: &dyn crate::estimator::DirectLighting) -> &'static str {
        if strategy.image_space().is_some() {
            "image-space"
        } else if self == Engine::Batched && strategy.batched().is_some() {
            "batched"
        } else {
            "per-sample"
        }
    }

    /// The name the command line and the render's JSON use.
    pub fn name(self) -> &'static str {
        match self {
            Engine::Batched => "batched",
            Engine::PerSample => "per-sample",
        }
    }
}

/// A render-time limit, checked before each work unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeBudget {
    pub seconds: f64,
    pub clock: BudgetClock,
}

/// What a time budget counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BudgetClock {
    /// Elapsed wall time.
    Wall,
    /// The process's CPU time divided by the worker threads: the wall time the render would
    /// take on otherwise idle cores. Equal-time comparisons stay fair on a shared machine,
    /// where other jobs would otherwise steal time from some cells and not others.
    Cpu,
}

/// Most worker threads a render may ask for (a typo should not start a hundred thousand).
pub const MAX_THREADS: usize = 4096;

/// The worker threads a render runs on: those asked for (all cores by default), but no more
/// than it has work units to share (more would only wait; the image is the same either way).
pub(super) fn worker_threads(asked: Option<usize>, units: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    asked.unwrap_or(cores).min(units.max(1))
}

impl RenderSettings {
    /// Refuses settings no render can follow, with the reason.
    pub(super) fn check(&self) -> Result<(), String> {
        if self.width == 0 || self.height == 0 {
            return Err("image width and height must be positive".into());
        }
        if self.spp == Some(0) {
            return Err("spp must be at least 1".into());
        }
        if let Some(t) = self.threads
            && !(1..=MAX_THREADS).contains(&t)
        {
            return Err(format!(
                "threads must be between 1 and {MAX_THREADS}, not {t}"
            ));
        }
        if self.spp.is_none() && self.time_budget.is_none() {
            return Err("give spp, a time budget, or both".into());
        }
        if self.sampler.needs_spp() && self.spp.is_none() {
            return Err(format!(
                "the {} sampler cuts its strata by the sample count: give spp (with a time budget, \
                 the most samples a pixel may take)",
                self.sampler
            ));
        }
        if self.emission_rays != EmissionRays::OFF && self.reconstruction == Reconstruction::Splat {
            return Err(
                "extra emission rays need the sampled reconstruction (each ray in its own pixel), \
                 not splatting"
                    .into(),
            );
        }
        Ok(())
    }
}

/// Whether a time budget is spent, readable from every worker thread.
pub(super) struct BudgetClockReader {
    pub(super) budget: TimeBudget,
    pub(super) start: Instant,
    pub(super) cpu_start: Option<f64>,
    pub(super) threads: usize,
}

impl BudgetClockReader {
    /// Seconds spent so far by the budget's clock (CPU: per worker thread; wall time where the
    /// platform has no CPU clock).
    pub(super) fn elapsed(&self) -> f64 {
        let wall = self.start.elapsed().as_secs_f64();
        match (self.budget.clock, process_cpu_seconds(), self.cpu_start) {
            (BudgetClock::Cpu, Some(now), Some(start)) => {
                (now - start) / self.threads.max(1) as f64
            }
            _ => wall,
        }
    }

    /// `last_cpu_read`: this thread's last reading of the CPU clock, so that the /proc read
    /// happens at most every [`CPU_CLOCK_INTERVAL`] per thread.
    pub(super) fn spent(&self, last_cpu_read: &mut Option<Instant>) -> bool {
        let wall = self.start.elapsed().as_secs_f64();
        match self.budget.clock {
            BudgetClock::Wall => wall >= self.budget.seconds,
            BudgetClock::Cpu => {
                // CPU time per thread never exceeds the wall time: no read needed before then.
                if wall < self.budget.seconds {
                    return false;
                }
                let now = Instant::now();
                if last_cpu_read.is_some_and(|t| now - t < CPU_CLOCK_INTERVAL) {
                    return false;
                }
                *last_cpu_read = Some(now);
                // Without a CPU clock (not a Unix) wall time stands in rather than never stopping.
                match (process_cpu_seconds(), self.cpu_start) {
                    (Some(now), Some(start)) => {
                        (now - start) / self.threads.max(1) as f64 >= self.budget.seconds
                    }
                    _ => true,
                }
            }
        }
    }
}

#[cfg(test)]
mod thread_tests {
    use super::*;

    /// The threads asked for, but no more than the work units; a bad count is refused.
    #[test]
    fn a_render_runs_on_no_more_threads_than_work_units() {
        assert_eq!(worker_threads(Some(4000), 4), 4);
        assert_eq!(worker_threads(Some(2), 100), 2);
        assert_eq!(worker_threads(Some(3), 0), 1);
        assert!(worker_threads(None, 1_000_000) >= 1);
    }
}
