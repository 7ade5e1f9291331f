//! pbrt-v3's film reconstruction by weighted splatting, the other way to apply a pixel filter
//! (the default is filter importance sampling, `crate::filter`).
//!
//! Each pixel's camera sample is uniform over the pixel's own square; it is added, weighted by
//! the filter at the offset from their centres, to every pixel whose centre lies within the
//! filter radius, and a pixel's value is Σ f·L / Σ f. So a pixel averages the samples of its
//! neighbours as well as its own: at equal spp its variance is lower than under filter
//! importance sampling (about 2.25× for the triangle filter of radius 1), at the price of
//! correlated neighbours and a ratio estimator, consistent rather than unbiased. Both converge
//! to the same filtered image. pbrt-v3 also samples the pixels within the filter radius outside
//! the image, so that edge pixels see a full filter; the sample grid here has the same border.
//!
//! Determinism: samples are first stored per sample pixel, then every image pixel gathers the
//! samples around it in a fixed order after each pass, so the image does not depend on which
//! thread rendered which pixel.
use crate::filter::PixelFilter;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// How camera samples become pixel values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reconstruction {
    /// Filter importance sampling: each sample counts for its own pixel (pbrt-v4's approach).
    #[default]
    Sampled,
    /// Weighted splatting into every pixel within the filter radius (pbrt-v3's film).
    Splat,
}

impl Reconstruction {
    /// Both, in the order the command line lists them.
    pub const ALL: [Reconstruction; 2] = [Reconstruction::Sampled, Reconstruction::Splat];

    /// The name the command line uses.
    pub fn name(self) -> &'static str {
        match self {
            Reconstruction::Sampled => "sampled",
            Reconstruction::Splat => "splat",
        }
    }

    /// The reconstruction called `name`, or an error naming the choices.
    pub fn parse(name: &str) -> Result<Reconstruction, String> {
        Reconstruction::ALL
            .into_iter()
            .find(|r| r.name() == name)
            .ok_or_else(|| format!("unknown reconstruction `{name}` (choose sampled or splat)"))
    }
}

impl std::fmt::Display for Reconstruction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The pixels that take camera samples: the image and, when splatting, a border of
/// `border` pixels on every side (pbrt-v3's sample bounds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleGrid {
    /// Sample pixels per row.
    pub width: usize,
    /// Sample pixel rows.
    pub height: usize,
    /// Sample pixels outside the image on each side.
    pub border: usize,
}

impl SampleGrid {
    /// The grid for an image of `width` × `height` under `reconstruction` with `filter`.
    pub fn new(
        width: usize,
        height: usize,
        reconstruction: Reconstruction,
        f: &PixelFilter,
    ) -> Self {
        let border = match reconstruction {
            Reconstruction::Sampled => 0,
            // pbrt-v3: from floor(0.5 − r) to ceil(w − 0.5 + r), i.e. ⌈r − ½⌉ pixels each side.
            Reconstruction::Splat => (f.radius() - 0.5).max(0.0).ceil() as usize,
        };
        SampleGrid {
            width: width + 2 * border,
            height: height + 2 * border,
            border,
        }
    }

    /// Sample pixels in all.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// Whether the grid has no pixel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Image coordinates of sample pixel `index` (negative or beyond the image in the border).
    pub fn image_xy(&self, index: usize) -> (i64, i64) {
        let (x, y) = (index % self.width, index / self.width);
        (x as i64 - self.border as i64, y as i64 - self.border as i64)
    }
}

/// One pass's camera sample at one sample pixel.
#[derive(Clone, Copy, Debug, Default)]
pub struct PassSample {
    /// Its radiance.
    pub radiance: Vec3,
    /// Its position on the film, in image pixels (pixel (x, y) spans [x, x + 1) × [y, y + 1)).
    pub film: Vec2,
    /// Whether its camera ray saw a light.
    pub sees_light: bool,
}

/// What an image pixel has gathered over the passes.
#[derive(Clone, Copy, Debug, Default)]
struct SplatPixel {
    weighted: [f64; 3],
    weight: f64,
    light_weight: f64,
    /// Σ and Σ² of the per-pass values Σ_pass f·L / Σ_pass f, and how many passes gave one.
    pass_sum: [f64; 3],
    pass_sum_sq: [f64; 3],
    passes: u32,
}

/// The image being reconstructed by splatting.
pub struct SplatFilm {
    width: usize,
    filter: PixelFilter,
    pixels: Vec<SplatPixel>,
}

/// Entries of pbrt-v3's filter table per axis: the filter is read at the midpoint of the
/// sixteenth of its radius an offset falls in, as pbrt-v3's `Film::AddSample` does.
const TABLE_WIDTH: f32 = 16.0;

impl SplatFilm {
    /// An empty `width` × `height` film reconstructing with `filter`.
    pub fn new(width: usize, height: usize, filter: PixelFilter) -> Self {
        SplatFilm {
            width,
            filter,
            pixels: vec![SplatPixel::default(); width * height],
        }
    }

    /// pbrt-v3's tabulated filter weight at offset `d` from a pixel centre, per axis.
    fn weight_1d(&self, d: f32) -> f32 {
        let r = self.filter.radius();
        let bin = ((d.abs() / r * TABLE_WIDTH).floor()).min(TABLE_WIDTH - 1.0);
        self.filter.eval_1d((bin + 0.5) / TABLE_WIDTH * r)
    }

    /// Adds the samples of one pass: `samples[i]` for sample pixel `i` of `grid`, only the
    /// first `taken` of which were rendered in this pass.
    /// `pass_weight`: the pass's weight in every pixel's average (its filter weights are
    /// scaled by it).
    pub fn gather_pass(
        &mut self,
        grid: SampleGrid,
        samples: &[PassSample],
        taken: usize,
        pass_weight: f64,
    ) {
        let r = self.filter.radius();
        let reach = r.ceil() as i64 + 1;
        let width = self.width;
        let this = &*self;
        let gathered: Vec<Option<([f64; 3], f64, f64)>> = (0..this.pixels.len())
            .into_par_iter()
            .map(|i| {
                let (x, y) = ((i % width) as i64, (i / width) as i64);
                let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let (mut fl, mut f, mut fs) = ([0.0f64; 3], 0.0f64, 0.0f64);
                let mut any = false;
                for sy in (y - reach)..=(y + reach) {
                    for sx in (x - reach)..=(x + reach) {
                        let (gx, gy) = (sx + grid.border as i64, sy + grid.border as i64);
                        if gx < 0 || gy < 0 || gx >= grid.width as i64 || gy >= grid.height as i64 {
                            continue;
                        }
                        let g = gy as usize * grid.width + gx as usize;
                        if g >= taken {
                            continue;
                        }
                        let s = &samples[g];
                        let d = s.film - centre;
                        if d.x.abs() > r || d.y.abs() > r {
                            continue;
                        }
                        any = true;
                        let w = (this.weight_1d(d.x) * this.weight_1d(d.y)) as f64 * pass_weight;
                        for k in 0..3 {
                            fl[k] += w * s.radiance[k] as f64;
                        }
                        f += w;
                        fs += w * s.sees_light as u32 as f64;
                    }
                }
                any.then_some((fl, f, fs))
            })
            .collect();
        for (p, g) in self.pixels.iter_mut().zip(gathered) {
            let Some((fl, f, fs)) = g else { continue };
            for k in 0..3 {
                p.weighted[k] += fl[k];
            }
            p.weight += f;
            p.light_weight += fs;
            if f != 0.0 {
                p.passes += 1;
                for k in 0..3 {
                    let v = fl[k] / f;
                    p.pass_sum[k] += v;
                    p.pass_sum_sq[k] += v * v;
                }
            }
        }
    }

    /// Σ f·L / Σ f per pixel (black where nothing was gathered).
    pub fn pixels(&self) -> Vec<Vec3> {
        self.pixels
            .iter()
            .map(|p| {
                let v = |k: usize| {
                    if p.weight != 0.0 {
                        (p.weighted[k] / p.weight) as f32
                    } else {
                        0.0
                    }
                };
                Vec3::new(v(0), v(1), v(2))
            })
            .collect()
    }

    /// Variance of each pixel's value, estimated from the spread of its per-pass values (an
    /// approximation: the passes' filter weights differ).
    pub fn variance_of_mean(&self) -> Vec<Vec3> {
        self.pixels
            .iter()
            .map(|p| {
                let n = p.passes as f64;
                let v = |k: usize| {
                    if n < 2.0 {
                        return f32::INFINITY;
                    }
                    let mean = p.pass_sum[k] / n;
                    (((p.pass_sum_sq[k] / n - mean * mean) * n / (n - 1.0)).max(0.0) / n) as f32
                };
                Vec3::new(v(0), v(1), v(2))
            })
            .collect()
    }

    /// The filter-weighted fraction of the gathered samples whose camera ray saw a light: zero
    /// exactly where no light seen directly reached the pixel.
    pub fn light_fraction(&self) -> Vec<f32> {
        self.pixels
            .iter()
            .map(|p| {
                if p.weight != 0.0 {
                    (p.light_weight / p.weight) as f32
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Pixels that gathered nothing.
    pub fn empty_pixels(&self) -> usize {
        self.pixels.iter().filter(|p| p.passes == 0).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant_pass(grid: SampleGrid, u: Vec2, l: f32) -> Vec<PassSample> {
        (0..grid.len())
            .map(|i| {
                let (x, y) = grid.image_xy(i);
                PassSample {
                    radiance: Vec3::splat(l),
                    film: Vec2::new(x as f32, y as f32) + u,
                    sees_light: false,
                }
            })
            .collect()
    }

    #[test]
    fn the_border_is_pbrt_v3s_sample_bounds() {
        let tri = |r| PixelFilter::Triangle { radius: r };
        let b = |r| SampleGrid::new(8, 4, Reconstruction::Splat, &tri(r)).border;
        assert_eq!((b(0.5), b(1.0), b(1.5), b(2.0)), (0, 1, 1, 2));
        let g = SampleGrid::new(8, 4, Reconstruction::Sampled, &tri(2.0));
        assert_eq!((g.width, g.height, g.border), (8, 4, 0));
    }

    /// A constant image stays constant, edges included (the border supplies their
    /// neighbours), whatever the sample positions.
    #[test]
    fn a_constant_image_is_reconstructed_exactly() {
        let filter = PixelFilter::Triangle { radius: 1.0 };
        let grid = SampleGrid::new(6, 5, Reconstruction::Splat, &filter);
        let mut film = SplatFilm::new(6, 5, filter);
        for u in [Vec2::new(0.1, 0.7), Vec2::new(0.93, 0.02)] {
            film.gather_pass(grid, &constant_pass(grid, u, 2.0), grid.len(), 1.0);
        }
        for p in film.pixels() {
            assert!((p - Vec3::splat(2.0)).abs().max_element() < 1e-6, "{p}");
        }
        assert_eq!(film.empty_pixels(), 0);
    }

    /// With the one-pixel box each pixel gathers exactly its own sample.
    #[test]
    fn the_box_of_radius_half_keeps_each_sample_in_its_pixel() {
        let filter = PixelFilter::Box { radius: 0.5 };
        let grid = SampleGrid::new(4, 3, Reconstruction::Splat, &filter);
        assert_eq!(grid.border, 0);
        let mut samples = constant_pass(grid, Vec2::new(0.25, 0.75), 0.0);
        for (i, s) in samples.iter_mut().enumerate() {
            s.radiance = Vec3::splat(i as f32);
        }
        let mut film = SplatFilm::new(4, 3, filter);
        film.gather_pass(grid, &samples, grid.len(), 1.0);
        let expect: Vec<Vec3> = (0..12).map(|i| Vec3::splat(i as f32)).collect();
        assert_eq!(film.pixels(), expect);
    }

    /// Only the samples a pass took count, and a pixel none reached stays empty.
    #[test]
    fn a_partial_pass_gathers_its_prefix_only() {
        let filter = PixelFilter::Triangle { radius: 1.0 };
        let grid = SampleGrid::new(8, 8, Reconstruction::Splat, &filter);
        let mut film = SplatFilm::new(8, 8, filter);
        film.gather_pass(
            grid,
            &constant_pass(grid, Vec2::splat(0.5), 1.0),
            grid.width * 2,
            1.0,
        );
        let px = film.pixels();
        assert_eq!(px[0], Vec3::ONE);
        assert_eq!(px[8 * 7], Vec3::ZERO);
        assert!(film.empty_pixels() > 0);
    }

    #[test]
    fn light_seen_by_a_neighbour_marks_the_pixel() {
        let filter = PixelFilter::Triangle { radius: 1.0 };
        let grid = SampleGrid::new(5, 5, Reconstruction::Splat, &filter);
        let mut samples = constant_pass(grid, Vec2::splat(0.5), 1.0);
        let centre = (2 + grid.border) * grid.width + 2 + grid.border;
        samples[centre].film += Vec2::new(0.3, 0.2);
        samples[centre].sees_light = true;
        let mut film = SplatFilm::new(5, 5, filter);
        film.gather_pass(grid, &samples, grid.len(), 1.0);
        let lit: Vec<usize> = (0..25)
            .filter(|&i| film.light_fraction()[i] > 0.0)
            .collect();
        // Shifted by (0.3, 0.2) from its centre the sample reaches the pixels right of and below
        // its own, not those left of or above it.
        assert_eq!(lit, vec![12, 13, 17, 18]);
    }

    #[test]
    fn names_round_trip() {
        for r in Reconstruction::ALL {
            assert_eq!(Reconstruction::parse(r.name()), Ok(r));
        }
        assert!(Reconstruction::parse("blur").is_err());
    }
}
