//! One work unit of a pass: one sample of each of its pixels, accumulated in sample order.
use super::accum::PixelAccum;
use super::pass_job::{PassJob, UNIT_PIXELS};
use super::shading::{CameraSample, shade_camera_sample};
use crate::estimator::{MAX_AUX, SampleContext};
use crate::rng::SampleStream;
use crate::splat::PassSample;
use crate::stats::Counters;
use glam::{Vec2, Vec3};

/// One camera sample of a pixel, shaded, before it is added to the pixel's sums.
pub(super) struct PixelSample {
    /// Where it fell on the film, in pixels, and the filter weight it carries.
    pub(super) on_film: Vec2,
    pub(super) weight: f32,
    /// Camera rays for its emission (1, or more for a split sample).
    pub(super) rays: u32,
    pub(super) camera: CameraSample,
    /// The extra emission rays' filter-weighted sum and how many saw a light.
    pub(super) extra: (Vec3, u32),
    pub(super) aux: [f32; MAX_AUX],
}

impl PassJob<'_> {
    /// The random numbers of sample `sample_index` of pixel `index`.
    pub(super) fn sample_stream(&self, index: usize, sample_index: u64) -> SampleStream {
        self.in_grid(
            index,
            SampleStream::with_sampler(
                self.settings.sampler,
                self.settings.seed,
                index as u64,
                sample_index,
            )
            .with_pixel_samples(self.settings.spp.unwrap_or(0)),
        )
    }

    /// Sample `sample_index` of the pixels of work unit `u`, accumulated into `unit` and, when
    /// splatting, kept in `splats` for the pass's gather.
    pub(super) fn render_unit(
        &self,
        u: usize,
        (sample_index, pass_weight): (u64, f64),
        (unit, splats): (&mut [PixelAccum], &mut [PassSample]),
        c: &mut Counters,
    ) {
        if self.settings.engine == super::Engine::Batched
            && let Some(batched) = self.strategy.batched()
        {
            return self.render_unit_batched(
                batched,
                u,
                (sample_index, pass_weight),
                (unit, splats),
                c,
            );
        }
        for (i, px) in unit.iter_mut().enumerate() {
            let index = u * UNIT_PIXELS + i;
            let mut rng = self.sample_stream(index, sample_index);
            let (on_film, film, weight) = self.film_position(index, &mut rng);
            // Fixed before the sample is drawn, from the pixel's earlier passes only.
            let rays = self.settings.emission_rays.rays_for(px.split);
            let mut ctx = SampleContext {
                counters: c,
                aux: [0.0; MAX_AUX],
                pixel_memory: &mut px.memory,
            };
            let camera = shade_camera_sample(
                self.scene,
                self.strategy,
                &self.settings.camera,
                self.aspect,
                film,
                &mut rng,
                &mut ctx,
            );
            let aux = ctx.aux;
            let sample = self.pixel_sample(
                (index, sample_index),
                (on_film, weight),
                rays,
                (camera, aux),
                c,
            );
            self.accumulate(px, splats.get_mut(i), sample, pass_weight);
        }
    }

    /// Sample `sample_index` of pixel `index`, shaded, with its extra emission rays traced
    /// (`rays` camera rays in all).
    pub(super) fn pixel_sample(
        &self,
        (index, sample_index): (usize, u64),
        (on_film, weight): (Vec2, f32),
        rays: u32,
        (camera, aux): (CameraSample, [f32; MAX_AUX]),
        c: &mut Counters,
    ) -> PixelSample {
        let extra = self.extra_emission(index, sample_index, rays, c);
        PixelSample {
            on_film,
            weight,
            rays,
            camera,
            extra,
            aux,
        }
    }

    /// Adds a shaded camera sample to its pixel's sums (and, when splatting, to the pass's samples).
    pub(super) fn accumulate(
        &self,
        px: &mut PixelAccum,
        splat: Option<&mut PassSample>,
        s: PixelSample,
        pass_weight: f64,
    ) {
        let CameraSample {
            emitted,
            direct,
            distant,
            sees_light,
        } = s.camera;
        let weight = s.weight;
        // Exact for the weight-1 filters (box, triangle).
        let l = if s.rays == 1 {
            ((emitted + direct) + distant) * weight
        } else {
            let (sum, lit) = s.extra;
            px.extra_rays += s.rays - 1;
            px.extra_lit += lit;
            (direct + distant) * weight + (emitted * weight + sum) / s.rays as f32
        };
        // A non-finite sample is a bug upstream; keep it visible in the image rather than hiding it.
        for k in 0..3 {
            let v = l[k] as f64;
            px.sum[k] += pass_weight * v;
            px.sum_sq[k] += pass_weight * (v * v);
        }
        px.light_hits += sees_light as u32;
        for (acc, v) in px.aux.iter_mut().zip(s.aux).take(self.n_aux) {
            *acc += v as f64;
        }
        if let Some(splat) = splat {
            *splat = PassSample {
                radiance: l,
                film: s.on_film,
                sees_light,
            };
        }
    }
}
