//! The render loop: camera rays, emission seen directly, one direct-lighting estimate per
//! camera hit, in progressive passes over bands of rows in parallel.
//!
//! Every pixel is owned by one task per pass and its samples are accumulated in sample
//! order, with random numbers that depend only on (seed, pixel, sample, dimension):
//! the image is bit-identical whatever the thread count.
use crate::bsdf::Bsdf;
use crate::camera::Camera;
use crate::estimator::{DirectLighting, MAX_AUX, PIXEL_MEMORY, SampleContext, ShadingPoint};
use crate::rng::SampleStream;
use crate::scene::{NO_LIGHT, Scene, SurfaceHit};
use crate::stats::Counters;
use glam::{Vec2, Vec3};
use host::process_cpu_seconds;
use rayon::prelude::*;
use std::time::Instant;

/// Rows per parallel task.
const BAND_ROWS: usize = 4;

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel; with a time budget, the most that will be taken (`None` = no limit).
    pub spp: Option<u32>,
    pub seed: u64,
    /// No new pass starts once this budget is spent.
    pub time_budget: Option<TimeBudget>,
    /// Worker threads (`None` = all cores).
    pub threads: Option<usize>,
    pub camera: Camera,
}

/// A render-time limit, checked between passes.
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

#[derive(Clone, Copy, Default)]
struct PixelAccum {
    sum: [f64; 3],
    sum_sq: [f64; 3],
    light_hits: u32,
    aux: [f64; MAX_AUX],
    memory: [f32; PIXEL_MEMORY],
}

/// Bytes a render of `width` × `height` pixels holds at its peak: the per-pixel accumulators,
/// then the finished image, its variance, light mask and `aux_channels` maps, and an output
/// image being encoded (EXR or PNG).
pub fn memory_estimate(width: u32, height: u32, aux_channels: usize) -> u64 {
    let finished = 3 * size_of::<Vec3>() + size_of::<f32>() * (1 + aux_channels);
    let per_pixel = size_of::<PixelAccum>() + finished;
    width as u64 * height as u64 * per_pixel as u64
}

/// Refuses, before anything is allocated, a render that needs more memory than the machine
/// has (where the platform says how much it has).
pub fn check_memory(width: u32, height: u32, aux_channels: usize) -> Result<(), String> {
    let need = memory_estimate(width, height, aux_channels);
    match host::physical_memory_bytes() {
        Some(have) if need > have => Err(format!(
            "a {width}×{height} render needs about {:.1} GiB ({} bytes per pixel), more than \
             this machine's {:.1} GiB of memory",
            need as f64 / GIB,
            need / (width as u64 * height as u64),
            have as f64 / GIB
        )),
        _ => Ok(()),
    }
}

const GIB: f64 = (1u64 << 30) as f64;

/// The finished image with its diagnostics.
pub struct RenderResult {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
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
    pub passes: u32,
    /// Worker threads the passes ran on.
    pub threads: usize,
}

impl RenderResult {
    /// Pixels whose camera rays never see a light directly.
    pub fn unlit_mask(&self) -> Vec<bool> {
        self.light_fraction.iter().map(|&f| f == 0.0).collect()
    }
}

/// Whether `budget` is used up since `start` (wall) / `cpu_start` (process CPU seconds).
fn budget_spent(
    budget: &TimeBudget,
    start: Instant,
    cpu_start: Option<f64>,
    threads: usize,
) -> bool {
    // Reads the CPU clock only when the budget counts it; without one (not a Unix) wall time
    // stands in rather than never stopping.
    let cpu_spent = || Some((process_cpu_seconds()? - cpu_start?) / threads.max(1) as f64);
    let spent = match budget.clock {
        BudgetClock::Cpu => cpu_spent().unwrap_or_else(|| start.elapsed().as_secs_f64()),
        BudgetClock::Wall => start.elapsed().as_secs_f64(),
    };
    spent >= budget.seconds
}

/// Camera-ray shading: emission seen directly plus direct lighting at the hit.
fn shade_camera_sample(
    scene: &Scene,
    strategy: &dyn DirectLighting,
    camera: &Camera,
    aspect: f32,
    film: Vec2,
    rng: &mut SampleStream,
    ctx: &mut SampleContext,
) -> (Vec3, bool) {
    let dir = camera.ray_direction(film, aspect);
    ctx.counters.camera_rays += 1;
    let Some(hit) = scene.intersect(camera.position, dir, 0.0, f32::INFINITY) else {
        return (Vec3::ZERO, false);
    };
    let wo = -dir;
    let mut l = Vec3::ZERO;
    let mut sees_light = false;
    if hit.light != NO_LIGHT {
        let e = scene.lights[hit.light as usize].emitted(hit.ng, hit.uv, wo);
        sees_light = e != Vec3::ZERO;
        l += e;
    }
    let Some(material) = hit.material else {
        return (l, sees_light);
    };
    let params = scene.materials[material as usize].params_at(hit.uv);
    let sp = ShadingPoint {
        hit,
        wo,
        bsdf: Bsdf::new(hit.ns, hit.ng, wo, params),
    };
    ctx.counters.shading_points += 1;
    l += strategy.estimate(scene, &sp, rng, ctx);
    l += distant_lighting(scene, &sp, ctx);
    (l, sees_light)
}

/// Directional lights, each a delta: one shadow ray apiece.
fn distant_lighting(scene: &Scene, sp: &ShadingPoint, ctx: &mut SampleContext) -> Vec3 {
    let mut l = Vec3::ZERO;
    for d in &scene.distant_lights {
        let f = sp.bsdf.eval_cos(sp.wo, d.direction) * d.irradiance;
        if f == Vec3::ZERO {
            continue;
        }
        ctx.counters.shadow_rays += 1;
        if !scene.accel.occluded(
            sp.origin_towards(d.direction),
            d.direction,
            0.0,
            f32::INFINITY,
        ) {
            l += f;
        }
    }
    l
}

/// A surface hit for tests and tools that shade points directly.
pub fn shading_point(scene: &Scene, hit: SurfaceHit, wo: Vec3) -> Option<ShadingPoint> {
    let m = hit.material?;
    let params = scene.materials[m as usize].params_at(hit.uv);
    Some(ShadingPoint {
        hit,
        wo,
        bsdf: Bsdf::new(hit.ns, hit.ng, wo, params),
    })
}

/// Renders `scene` with `strategy`. `progress` is called after each pass with (passes done, spp so far).
pub fn render(
    scene: &Scene,
    strategy: &dyn DirectLighting,
    settings: &RenderSettings,
    progress: &(dyn Fn(u32, u32) + Sync),
) -> Result<RenderResult, String> {
    if settings.width == 0 || settings.height == 0 {
        return Err("image width and height must be positive".into());
    }
    if settings.spp == Some(0) {
        return Err("spp must be at least 1".into());
    }
    if settings.spp.is_none() && settings.time_budget.is_none() {
        return Err("give spp, a time budget, or both".into());
    }
    check_memory(
        settings.width,
        settings.height,
        strategy.aux_channels().len(),
    )?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads.unwrap_or(0))
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))?;
    let (w, h) = (settings.width as usize, settings.height as usize);
    let aspect = w as f32 / h as f32;
    let n_aux = strategy.aux_channels().len().min(MAX_AUX);
    let mut accum = vec![PixelAccum::default(); w * h];
    let start = Instant::now();
    let cpu_start = process_cpu_seconds();
    let mut counters = Counters::default();
    let mut spp_done = 0u32;
    let mut passes = 0u32;
    loop {
        if let Some(limit) = settings.spp
            && spp_done >= limit
        {
            break;
        }
        if let Some(budget) = settings.time_budget
            && passes > 0
            && budget_spent(&budget, start, cpu_start, pool.current_num_threads())
        {
            break;
        }
        let sample_index = spp_done as u64;
        let pass_counters: Vec<Counters> = pool.install(|| {
            accum
                .par_chunks_mut(w * BAND_ROWS)
                .enumerate()
                .map(|(band, rows)| {
                    let mut c = Counters::default();
                    for (i, px) in rows.iter_mut().enumerate() {
                        let index = band * BAND_ROWS * w + i;
                        let (x, y) = (index % w, index / w);
                        let mut rng = SampleStream::new(settings.seed, index as u64, sample_index);
                        let jitter = rng.next_2d();
                        let film = Vec2::new(
                            (x as f32 + jitter.x) / w as f32,
                            (y as f32 + jitter.y) / h as f32,
                        );
                        let mut ctx = SampleContext {
                            counters: &mut c,
                            aux: [0.0; MAX_AUX],
                            pixel_memory: &mut px.memory,
                        };
                        let (l, sees_light) = shade_camera_sample(
                            scene,
                            strategy,
                            &settings.camera,
                            aspect,
                            film,
                            &mut rng,
                            &mut ctx,
                        );
                        let aux = ctx.aux;
                        // A non-finite sample is a bug upstream; keep it visible in the image rather than hiding it.
                        for k in 0..3 {
                            let v = l[k] as f64;
                            px.sum[k] += v;
                            px.sum_sq[k] += v * v;
                        }
                        px.light_hits += sees_light as u32;
                        for (acc, v) in px.aux.iter_mut().zip(aux).take(n_aux) {
                            *acc += v as f64;
                        }
                    }
                    c
                })
                .collect()
        });
        for c in &pass_counters {
            counters.merge(c);
        }
        spp_done += 1;
        passes += 1;
        progress(passes, spp_done);
    }
    let n = spp_done as f64;
    let pixels = accum
        .iter()
        .map(|p| {
            Vec3::new(
                (p.sum[0] / n) as f32,
                (p.sum[1] / n) as f32,
                (p.sum[2] / n) as f32,
            )
        })
        .collect();
    let variance_of_mean = accum
        .iter()
        .map(|p| {
            let v = |k: usize| {
                if n < 2.0 {
                    return f32::INFINITY;
                }
                let mean = p.sum[k] / n;
                (((p.sum_sq[k] / n - mean * mean) * n / (n - 1.0)).max(0.0) / n) as f32
            };
            Vec3::new(v(0), v(1), v(2))
        })
        .collect();
    let light_fraction = accum
        .iter()
        .map(|p| (p.light_hits as f64 / n) as f32)
        .collect();
    let aux = strategy
        .aux_channels()
        .iter()
        .take(n_aux)
        .enumerate()
        .map(|(k, name)| {
            (
                name.to_string(),
                accum.iter().map(|p| (p.aux[k] / n) as f32).collect(),
            )
        })
        .collect();
    let wall_seconds = start.elapsed().as_secs_f64();
    let cpu_seconds = match (cpu_start, process_cpu_seconds()) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    Ok(RenderResult {
        width: settings.width,
        height: settings.height,
        spp: spp_done,
        pixels,
        variance_of_mean,
        light_fraction,
        aux,
        counters,
        wall_seconds,
        cpu_seconds,
        passes,
        threads: pool.current_num_threads(),
    })
}
