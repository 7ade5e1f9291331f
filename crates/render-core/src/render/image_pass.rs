//! A pass of a strategy that works on the whole image (`crate::image_space`): every pixel's
//! camera sample traced to its shading point, the strategy's phases over the image, then each
//! pixel's sample added to its sums exactly as a per-sample pass adds it.
use super::pass_job::PassJob;
use super::passes::Passes;
use super::shading::{camera_hit, distant_lighting};
use super::unit::PixelSample;
use crate::estimator::{MAX_AUX, ShadingPoint};
use crate::image_space::{ImagePass, ImageSpaceLighting, par_pixels};
use crate::rng::SampleStream;
use crate::stats::Counters;
use glam::Vec3;
use std::sync::Mutex;

/// Bytes per pixel an image-space pass adds (`crate::image_space`): the shading points, sample
/// streams and camera samples of the pass, its result, and `strategy_bytes` of the strategy's own.
pub(super) fn image_pass_bytes(strategy_bytes: usize) -> usize {
    size_of::<Option<ShadingPoint>>()
        + size_of::<SampleStream>()
        + size_of::<PixelSample>()
        + size_of::<(Vec3, [f32; MAX_AUX])>()
        + strategy_bytes
}

impl Passes {
    /// Pass `sample_index` of every pixel through `strategy`'s image-space form.
    pub(super) fn image_pass(
        &mut self,
        job: &PassJob,
        pool: &rayon::ThreadPool,
        strategy: &dyn ImageSpaceLighting,
        (sample_index, pass_weight): (u64, f64),
        counters: &mut Counters,
    ) -> Result<(), String> {
        let n = job.grid.len();
        let accum = &self.accum;
        let (traced, c) = par_pixels(pool, n, |i, c| {
            let mut rng = job.sample_stream(i, sample_index);
            let (on_film, film, weight) = job.film_position(i, &mut rng);
            let rays = job.settings.emission_rays.rays_for(accum[i].split);
            let (mut camera, sp) = camera_hit(job.scene, &job.settings.camera, job.aspect, film, c);
            if let Some(sp) = &sp {
                camera.distant = distant_lighting(job.scene, sp, c);
            }
            let sample = job.pixel_sample(
                (i, sample_index),
                (on_film, weight),
                rays,
                (camera, [0.0; MAX_AUX]),
                c,
            );
            (sample, sp, rng)
        });
        counters.merge(&c);
        let mut samples = Vec::with_capacity(n);
        let mut points = Vec::with_capacity(n);
        let mut streams = Vec::with_capacity(n);
        for (s, p, r) in traced {
            samples.push(s);
            points.push(p);
            streams.push(r);
        }
        let pass = ImagePass {
            scene: job.scene,
            width: job.grid.width,
            height: job.grid.height,
            camera_position: job.settings.camera.position,
            points: &points,
            streams: &streams,
            seed: job.settings.seed,
            sample_index,
            pool,
            counters: Mutex::new(Counters::default()),
        };
        let direct = strategy.estimate_image(&pass, &mut self.carry);
        if direct.len() != n {
            return Err(format!(
                "strategy {}: its image-space pass returned {} pixels, not {n}",
                job.strategy.name(),
                direct.len()
            ));
        }
        counters.merge(
            &pass
                .counters
                .into_inner()
                .unwrap_or_else(|e| e.into_inner()),
        );
        let mut splats = self.splats.iter_mut();
        for (((px, mut s), sp), (l, aux)) in
            self.accum.iter_mut().zip(samples).zip(&points).zip(direct)
        {
            if sp.is_some() {
                s.camera.direct = l;
                s.aux = aux;
            }
            job.accumulate(px, splats.next(), s, pass_weight);
        }
        Ok(())
    }
}
