//! The emission seen directly by extra camera rays (`crate::emission_rays`): which pixels take
//! them, and what they see.
use super::accum::PixelAccum;
use super::pass_job::PassJob;
use super::settings::RenderSettings;
use crate::camera::Camera;
use crate::emission_rays::{EmissionRays, plan_splits};
use crate::scene::{NO_LIGHT, Scene};
use crate::stats::Counters;
use glam::{Vec2, Vec3};

impl PassJob<'_> {
    /// The `rays − 1` extra emission rays of pixel `index`'s sample `sample_index`: the sum of
    /// their filter-weighted emission and how many saw a light (none for a sample of one ray).
    pub(super) fn extra_emission(
        &self,
        index: usize,
        sample_index: u64,
        rays: u32,
        c: &mut Counters,
    ) -> (Vec3, u32) {
        if rays <= 1 {
            return (Vec3::ZERO, 0);
        }
        let s = self.settings;
        let grid = self.grid;
        let (x, y) = grid.image_xy(index);
        let size = Vec2::new(s.width as f32, s.height as f32);
        let mut sum = Vec3::ZERO;
        let mut lit = 0;
        for ray in 0..rays - 1 {
            let mut rng = s
                .emission_rays
                .stream(s.sampler, s.seed, index as u64, s.spp, sample_index, ray)
                .in_image(
                    ((index % grid.width) as u32, (index / grid.width) as u32),
                    (grid.width as u32, grid.height as u32),
                );
            let (offset, weight) = s.filter.sample(rng.next_2d());
            let film = (Vec2::new(x as f32 + offset.x, y as f32 + offset.y)) / size;
            let (e, sees_light) = emission_seen(self.scene, &s.camera, self.aspect, film);
            sum += e * weight;
            lit += sees_light as u32;
        }
        c.camera_rays += (rays - 1) as u64;
        c.emission_rays += (rays - 1) as u64;
        (sum, lit)
    }
}

/// The emission a camera ray through `film` sees directly, and whether it sees a light.
fn emission_seen(scene: &Scene, camera: &Camera, aspect: f32, film: Vec2) -> (Vec3, bool) {
    let dir = camera.ray_direction(film, aspect);
    match scene.intersect(camera.position, dir, 0.0, f32::INFINITY) {
        Some(hit) if hit.light != NO_LIGHT => {
            let e = scene.lights[hit.light as usize].emitted(hit.ng, hit.uv, -dir);
            (e, e != Vec3::ZERO)
        }
        _ => (Vec3::ZERO, false),
    }
}

/// Marks the pixels whose next sample (after `samples` full passes) takes extra emission rays.
pub(super) fn plan_emission_splits(
    settings: &RenderSettings,
    width: usize,
    samples: u32,
    accum: &mut [PixelAccum],
) {
    if settings.emission_rays == EmissionRays::OFF {
        return;
    }
    let seen = |p: &PixelAccum| (samples + p.extra_rays, p.light_hits + p.extra_lit);
    let seen: Vec<(u32, u32)> = accum.iter().map(seen).collect();
    let mut split = vec![false; accum.len()];
    plan_splits(width, |i| seen[i], &mut split);
    for (p, s) in accum.iter_mut().zip(split) {
        p.split = s;
    }
}
