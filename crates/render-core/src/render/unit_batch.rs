//! One work unit of a pass through a strategy's batched form (`crate::batch`), in phases:
//! every pixel's film position and camera ray, the camera rays traced in packets of eight, the
//! shading points lit together by the strategy, then each sample's distant lights and extra
//! emission rays and its accumulation, exactly as `unit.rs` does one pixel at a time.
use super::accum::PixelAccum;
use super::pass_job::{PassJob, UNIT_PIXELS};
use super::shading::{camera_ray, distant_lighting, seen_by_camera};
use crate::batch::{BatchLighting, ShadingBatch};
use crate::estimator::MAX_AUX;
use crate::splat::PassSample;
use crate::stats::Counters;
use glam::Vec3;

/// Pixels that go through the phases together: the batch's buffers (about 400 bytes a pixel)
/// stay in the first-level cache.
const BATCH: usize = 64;

impl PassJob<'_> {
    /// [`PassJob::render_unit`] through `strategy`, the same samples bit for bit.
    pub(super) fn render_unit_batched(
        &self,
        strategy: &dyn BatchLighting,
        u: usize,
        sample: (u64, f64),
        (unit, splats): (&mut [PixelAccum], &mut [PassSample]),
        c: &mut Counters,
    ) {
        let mut splats = splats.chunks_mut(BATCH);
        for (k, accums) in unit.chunks_mut(BATCH).enumerate() {
            let first = u * UNIT_PIXELS + k * BATCH;
            let batch_splats = splats.next().unwrap_or_default();
            self.render_batch(strategy, first, sample, (accums, batch_splats), c);
        }
    }

    /// The samples of pixels `first`.. (one per accumulator of `unit`), in phases.
    fn render_batch(
        &self,
        strategy: &dyn BatchLighting,
        first: usize,
        (sample_index, pass_weight): (u64, f64),
        (unit, splats): (&mut [PixelAccum], &mut [PassSample]),
        c: &mut Counters,
    ) {
        let n = unit.len();
        let mut rngs = Vec::with_capacity(n);
        let mut films = Vec::with_capacity(n);
        let mut rays = Vec::with_capacity(n);
        let lens = self.settings.camera.film_rays(self.aspect);
        for i in 0..n {
            let index = first + i;
            let mut rng = self.sample_stream(index, sample_index);
            let (on_film, film, weight) = self.film_position(index, &mut rng);
            rays.push(camera_ray(&self.settings.camera, &lens, film));
            films.push((on_film, weight));
            rngs.push(rng);
        }
        let (mut hits, mut surfaces) = (Vec::new(), Vec::new());
        self.scene
            .intersect_packets(&rays, &mut hits, &mut surfaces);
        let mut cameras = Vec::with_capacity(n);
        let mut points = Vec::with_capacity(n);
        for (ray, hit) in rays.iter().zip(surfaces) {
            let (camera, sp) = seen_by_camera(self.scene, ray.dir, hit, c);
            cameras.push(camera);
            points.push(sp);
        }
        let mut direct = vec![Vec3::ZERO; n];
        strategy.estimate_batch(
            self.scene,
            ShadingBatch {
                points: &points,
                rngs: &mut rngs,
                counters: c,
                out: &mut direct,
            },
        );
        let samples = cameras.into_iter().zip(&points).zip(direct).zip(films);
        for (i, (((mut camera, sp), l), (on_film, weight))) in samples.enumerate() {
            let index = first + i;
            let px = &mut unit[i];
            let rays = self.settings.emission_rays.rays_for(px.split);
            if let Some(sp) = sp {
                camera.direct = l;
                camera.distant = distant_lighting(self.scene, sp, c);
            }
            let sample = self.pixel_sample(
                (index, sample_index),
                (on_film, weight),
                rays,
                (camera, [0.0; MAX_AUX]),
                c,
            );
            self.accumulate(px, splats.get_mut(i), sample, pass_weight);
        }
    }
}
