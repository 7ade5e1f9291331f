//! What every work unit of a render shares, and where a unit's camera samples fall.
use super::settings::RenderSettings;
use crate::estimator::DirectLighting;
use crate::rng::SampleStream;
use crate::scene::Scene;
use crate::splat::{Reconstruction, SampleGrid};
use glam::Vec2;

/// Most pixels in one work unit: the granularity at which a time budget can stop a render.
pub const UNIT_PIXELS: usize = 256;

/// What every work unit of a render shares.
pub(super) struct PassJob<'a> {
    pub(super) scene: &'a Scene,
    pub(super) strategy: &'a dyn DirectLighting,
    pub(super) settings: &'a RenderSettings,
    pub(super) aspect: f32,
    pub(super) n_aux: usize,
    pub(super) grid: SampleGrid,
}

impl PassJob<'_> {
    /// `rng` told where pixel `index` lies in the sample grid (for samplers ordered across pixels).
    pub(super) fn in_grid(&self, index: usize, rng: SampleStream) -> SampleStream {
        let grid = self.grid;
        rng.in_image(
            ((index % grid.width) as u32, (index / grid.width) as u32),
            (grid.width as u32, grid.height as u32),
        )
    }

    /// A camera sample's position in pixel `index`: on the film in pixels, on the film in
    /// [0, 1]², and the filter weight it carries.
    pub(super) fn film_position(&self, index: usize, rng: &mut SampleStream) -> (Vec2, Vec2, f32) {
        let s = self.settings;
        let (x, y) = self.grid.image_xy(index);
        let (offset, weight) = match s.reconstruction {
            Reconstruction::Sampled => s.filter.sample(rng.next_2d()),
            // pbrt-v3: uniform over the pixel; the filter weighs the sample at the gather.
            Reconstruction::Splat => (rng.next_2d(), 1.0),
        };
        let on_film = Vec2::new(x as f32 + offset.x, y as f32 + offset.y);
        let film = on_film / Vec2::new(s.width as f32, s.height as f32);
        (on_film, film, weight)
    }

    /// The strategy's weight of pass `pass`, refused unless a positive number.
    pub(super) fn pass_weight(&self, pass: u32) -> Result<f64, String> {
        let pass_weight = self.strategy.pass_weight(pass);
        if !(pass_weight.is_finite() && pass_weight > 0.0) {
            return Err(format!(
                "strategy {}: the weight of pass {pass} is {pass_weight}, not a positive number",
                self.strategy.name()
            ));
        }
        Ok(pass_weight)
    }
}
