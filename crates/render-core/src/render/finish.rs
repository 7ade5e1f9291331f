//! The finished render: each pixel's mean and variance from its samples (or from the splatted
//! film), the strategy's diagnostic channels, and what the render measured.
use super::accum::PixelAccum;
use super::pass_job::PassJob;
use super::passes::Passes;
use crate::stats::Counters;
use glam::Vec3;
use host::process_cpu_seconds;
use std::time::Instant;

/// The finished image with its diagnostics.
pub struct RenderResult {
    pub width: u32,
    pub height: u32,
    /// Full passes: every pixel has at least this many samples.
    pub spp: u32,
    /// Sample pixels (the first ones in row-major order) with one sample more than `spp`, when a
    /// time budget stopped the render inside a pass; 0 otherwise. Under splatting these are
    /// pixels of the sample grid, which has a border around the image.
    pub partial_pixels: usize,
    /// Mean radiance per pixel, row-major from the top.
    pub pixels: Vec<Vec3>,
    /// Per-pixel variance of the mean (sample variance / spp), per channel.
    pub variance_of_mean: Vec<Vec3>,
    /// Fraction of a pixel's camera rays that saw a light directly.
    pub light_fraction: Vec<f32>,
    /// Per-pixel means of the strategy's diagnostic channels.
    pub aux: Vec<(String, Vec<f32>)>,
    pub counters: Counters,
    pub wall_seconds: f64,
    pub cpu_seconds: Option<f64>,
    /// Passes started, the partial one included.
    pub passes: u32,
    /// Worker threads the passes ran on.
    pub threads: usize,
    /// Camera samples of the strategy's pilot (`crate::pilot`; not in the image, their work in
    /// `counters` and the seconds).
    pub pilot_samples: u64,
    /// Ended early by its caller ([`super::render_interruptible`]): the image holds the samples
    /// done, as a spent time budget's does.
    pub interrupted: bool,
    /// Pixels without any sample (a budget spent inside the first pass).
    unsampled: usize,
}

impl RenderResult {
    /// Pixels whose camera rays never see a light directly.
    pub fn unlit_mask(&self) -> Vec<bool> {
        self.light_fraction.iter().map(|&f| f == 0.0).collect()
    }

    /// Samples taken at pixel `index` (row-major).
    pub fn samples_at(&self, index: usize) -> u32 {
        self.spp + (index < self.partial_pixels) as u32
    }

    /// Pixels that got no sample at all (a time budget spent inside the first pass): black.
    pub fn unsampled_pixels(&self) -> usize {
        self.unsampled
    }
}

/// What the render measured beside its passes.
pub(super) struct RunInfo {
    pub(super) start: Instant,
    pub(super) cpu_start: Option<f64>,
    pub(super) threads: usize,
    pub(super) pilot_samples: u64,
    pub(super) interrupted: bool,
}

/// The image and its diagnostics from the passes' accumulators.
pub(super) fn finish(
    job: &PassJob,
    passes: &Passes,
    counters: Counters,
    run: RunInfo,
) -> RenderResult {
    let settings = job.settings;
    let (spp_done, partial_pixels) = (passes.spp_done, passes.partial_pixels);
    let samples = |i: usize| (spp_done + (i < partial_pixels) as u32) as f64;
    let pass_weights = PassWeights::new(&passes.weights);
    let image = match &passes.film {
        None => own_samples_image(&passes.accum, samples, &pass_weights),
        Some(film) => FinishedImage {
            pixels: film.pixels(),
            variance_of_mean: film.variance_of_mean(),
            light_fraction: film.light_fraction(),
            unsampled: film.empty_pixels(),
        },
    };
    let aux = aux_means(job, &passes.accum, samples);
    let wall_seconds = run.start.elapsed().as_secs_f64();
    let cpu_seconds = match (run.cpu_start, process_cpu_seconds()) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    RenderResult {
        width: settings.width,
        height: settings.height,
        spp: spp_done,
        partial_pixels,
        pixels: image.pixels,
        variance_of_mean: image.variance_of_mean,
        light_fraction: image.light_fraction,
        aux,
        counters,
        wall_seconds,
        cpu_seconds,
        passes: passes.passes,
        threads: run.threads,
        pilot_samples: run.pilot_samples,
        interrupted: run.interrupted,
        unsampled: image.unsampled,
    }
}

/// The per-pixel means of the strategy's diagnostic channels over the image's pixels.
fn aux_means(
    job: &PassJob,
    accum: &[PixelAccum],
    samples: impl Fn(usize) -> f64,
) -> Vec<(String, Vec<f32>)> {
    let (w, h) = (job.settings.width as usize, job.settings.height as usize);
    let grid = job.grid;
    // The image's pixels in the sample grid (the same pixels unless a splat border surrounds it).
    let cropped: Vec<usize> = (0..w * h)
        .map(|i| (i / w + grid.border) * grid.width + i % w + grid.border)
        .collect();
    job.strategy
        .aux_channels()
        .iter()
        .take(job.n_aux)
        .enumerate()
        .map(|(k, name)| {
            let aux_mean = |&g: &usize| {
                let n = samples(g);
                if n > 0.0 { accum[g].aux[k] / n } else { 0.0 }
            };
            (
                name.to_string(),
                cropped.iter().map(|g| aux_mean(g) as f32).collect(),
            )
        })
        .collect()
}

/// The finished image before its diagnostics channels.
struct FinishedImage {
    pixels: Vec<Vec3>,
    variance_of_mean: Vec<Vec3>,
    light_fraction: Vec<f32>,
    unsampled: usize,
}

/// The passes' weights as a pixel's average needs them: for n samples (the first n passes),
/// W(n) = Σ wᵢ and Σ wᵢ².
struct PassWeights {
    /// Whether every weight is 1 (the plain average, computed as it always was).
    uniform: bool,
    sums: Vec<(f64, f64)>,
}

impl PassWeights {
    fn new(weights: &[f64]) -> PassWeights {
        let mut sums = vec![(0.0, 0.0)];
        for &w in weights {
            let (s, s2) = sums[sums.len() - 1];
            sums.push((s + w, s2 + w * w));
        }
        PassWeights {
            uniform: weights.iter().all(|&w| w == 1.0),
            sums,
        }
    }

    /// (W, Σ w²) of a pixel with `n` samples.
    fn of(&self, n: f64) -> (f64, f64) {
        self.sums.get(n as usize).copied().unwrap_or((n, n))
    }
}

/// Each pixel the mean of its own samples (filter importance sampling), `samples(i)` of them.
fn own_samples_image(
    accum: &[PixelAccum],
    samples: impl Fn(usize) -> f64,
    weights: &PassWeights,
) -> FinishedImage {
    let mean = |sum: f64, n: f64| if n > 0.0 { sum / n } else { 0.0 };
    let pixels = accum
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let n = samples(i);
            let w = if weights.uniform { n } else { weights.of(n).0 };
            Vec3::new(
                mean(p.sum[0], w) as f32,
                mean(p.sum[1], w) as f32,
                mean(p.sum[2], w) as f32,
            )
        })
        .collect();
    let variance_of_mean = accum
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let n = samples(i);
            let v = |k: usize| {
                if n < 2.0 {
                    return f32::INFINITY;
                }
                if !weights.uniform {
                    return weighted_variance_of_mean(p.sum[k], p.sum_sq[k], weights.of(n));
                }
                let mean = p.sum[k] / n;
                (((p.sum_sq[k] / n - mean * mean) * n / (n - 1.0)).max(0.0) / n) as f32
            };
            Vec3::new(v(0), v(1), v(2))
        })
        .collect();
    let light_fraction = accum
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let rays = samples(i) + p.extra_rays as f64;
            mean((p.light_hits + p.extra_lit) as f64, rays) as f32
        })
        .collect();
    FinishedImage {
        pixels,
        variance_of_mean,
        light_fraction,
        unsampled: (0..accum.len()).filter(|&i| samples(i) == 0.0).count(),
    }
}

/// The variance of a weighted mean Σwx/W from Σwx, Σwx² and (W, Σw²), taking the samples as
/// of one variance σ², estimated with reliability weights: σ̂² = (Σwx² − W·m²)/(W − Σw²/W),
/// and Var = σ̂²·Σw²/W². (A learning strategy's later passes vary less: the estimate is then
/// on the safe side for the later samples' weight.)
fn weighted_variance_of_mean(sum: f64, sum_sq: f64, (w, w2): (f64, f64)) -> f32 {
    let m = sum / w;
    let dof = w - w2 / w;
    if !(dof > 0.0) {
        return f32::INFINITY;
    }
    ((sum_sq - w * m * m).max(0.0) / dof * w2 / (w * w)) as f32
}
