//! A strategy's pilot (`crate::pilot`) on the worker threads: samples of a sparse set of
//! pixels, with numbers of their own, that only the strategy's pixel memory keeps.
use super::pass_job::{PassJob, UNIT_PIXELS};
use super::settings::BudgetClockReader;
use super::shading::shade_camera_sample;
use crate::estimator::{MAX_AUX, PIXEL_MEMORY, SampleContext};
use crate::pilot::Pilot;
use crate::stats::Counters;
use rayon::prelude::*;

impl PassJob<'_> {
    /// Runs `pilot` (`crate::pilot`) on the worker threads and hands the strategy its pixels'
    /// memory in pixel order; returns what it counted and its camera samples. Under a time
    /// budget, a chunk of pilot pixels that finds the budget spent is skipped (its pixels keep
    /// an empty memory), so the pilot overruns the budget by at most one chunk per thread.
    pub(super) fn run_pilot(
        &self,
        pool: &rayon::ThreadPool,
        pilot: Pilot,
        clock: Option<&BudgetClockReader>,
    ) -> (Counters, u64) {
        let pixels = pilot.pixels(self.grid.width, self.grid.height);
        let mut memory = vec![[0.0f32; PIXEL_MEMORY]; pixels.len()];
        let per_chunk: Vec<(Counters, u64)> = pool.install(|| {
            memory
                .par_chunks_mut(UNIT_PIXELS)
                .zip(pixels.par_chunks(UNIT_PIXELS))
                .map(|(memory, pixels)| {
                    let mut c = Counters::default();
                    if clock.is_some_and(|clock| clock.spent(&mut None)) {
                        return (c, 0);
                    }
                    for (m, &index) in memory.iter_mut().zip(pixels) {
                        for sample in 0..pilot.samples {
                            self.pilot_sample(pilot, index, sample, m, &mut c);
                        }
                    }
                    (c, pixels.len() as u64 * pilot.samples as u64)
                })
                .collect()
        });
        let mut counters = Counters::default();
        let mut samples = 0;
        for (c, n) in &per_chunk {
            counters.merge(c);
            samples += n;
        }
        self.strategy.end_pilot(&mut memory.iter());
        (counters, samples)
    }

    /// One pilot sample of pixel `index`: only the strategy's pixel memory keeps anything.
    fn pilot_sample(
        &self,
        pilot: Pilot,
        index: usize,
        sample: u32,
        memory: &mut [f32; PIXEL_MEMORY],
        c: &mut Counters,
    ) {
        let s = self.settings;
        let mut rng = self.in_grid(
            index,
            pilot.stream(s.sampler, s.seed, index as u64, sample as u64),
        );
        let (_, film, _) = self.film_position(index, &mut rng);
        let mut ctx = SampleContext {
            counters: c,
            aux: [0.0; MAX_AUX],
            pixel_memory: memory,
        };
        shade_camera_sample(
            self.scene,
            self.strategy,
            &s.camera,
            self.aspect,
            film,
            &mut rng,
            &mut ctx,
        );
    }
}
