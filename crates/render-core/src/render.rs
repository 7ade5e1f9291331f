//! The render loop: camera rays, emission seen directly, one direct-lighting estimate per
//! camera hit, in progressive passes (one sample index each) over work units of at most
//! [`UNIT_PIXELS`] consecutive pixels, claimed in order by the worker threads.
//!
//! Every pixel is owned by one unit per pass and its samples are accumulated in sample
//! order, with random numbers that depend only on (seed, pixel, sample, dimension): the image
//! is bit-identical whatever the thread count. A time budget stops the claiming of units, so a
//! render ends at a boundary (full passes, then the first `partial_pixels` pixels of one more)
//! that depends on the clock but fully determines the image; the budget is overrun by at most
//! one unit per thread and one reading of the clock, not by a whole pass. Before the first pass
//! a strategy may ask for a pilot (`crate::pilot`): samples of a sparse set of pixels with
//! numbers of their own, kept out of the image, that the strategy learns from.
use crate::bsdf::Bsdf;
use crate::camera::Camera;
use crate::emission_rays::{EmissionRays, plan_splits};
use crate::estimator::{DirectLighting, MAX_AUX, PIXEL_MEMORY, SampleContext, ShadingPoint};
use crate::filter::PixelFilter;
use crate::pilot::Pilot;
use crate::rng::SampleStream;
use crate::sampler::Sampler;
use crate::scene::{NO_LIGHT, Scene, SurfaceHit};
use crate::splat::{PassSample, Reconstruction, SampleGrid, SplatFilm};
use crate::stats::Counters;
use glam::{Vec2, Vec3};
use host::process_cpu_seconds;
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Most pixels in one work unit: the granularity at which a time budget can stop a render.
pub const UNIT_PIXELS: usize = 256;
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

#[derive(Clone, Copy, Default)]
struct PixelAccum {
    sum: [f64; 3],
    sum_sq: [f64; 3],
    light_hits: u32,
    /// Extra emission rays traced (beyond one per sample) and how many of them saw a light.
    extra_rays: u32,
    extra_lit: u32,
    /// The next sample takes extra emission rays (`emission_rays::plan_splits`).
    split: bool,
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

/// Whether a time budget is spent, readable from every worker thread.
struct BudgetClockReader {
    budget: TimeBudget,
    start: Instant,
    cpu_start: Option<f64>,
    threads: usize,
}

impl BudgetClockReader {
    /// `last_cpu_read`: this thread's last reading of the CPU clock, so that the /proc read
    /// happens at most every [`CPU_CLOCK_INTERVAL`] per thread.
    fn spent(&self, last_cpu_read: &mut Option<Instant>) -> bool {
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

/// What every work unit of a render shares.
struct PassJob<'a> {
    scene: &'a Scene,
    strategy: &'a dyn DirectLighting,
    settings: &'a RenderSettings,
    aspect: f32,
    n_aux: usize,
    grid: SampleGrid,
}

impl PassJob<'_> {
    /// The `rays − 1` extra emission rays of pixel `index`'s sample `sample_index`: the sum of
    /// their filter-weighted emission and how many saw a light.
    fn extra_emission(
        &self,
        index: usize,
        sample_index: u64,
        rays: u32,
        c: &mut Counters,
    ) -> (Vec3, u32) {
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

    /// `rng` told where pixel `index` lies in the sample grid (for samplers ordered across pixels).
    fn in_grid(&self, index: usize, rng: SampleStream) -> SampleStream {
        let grid = self.grid;
        rng.in_image(
            ((index % grid.width) as u32, (index / grid.width) as u32),
            (grid.width as u32, grid.height as u32),
        )
    }

    /// A camera sample's position in pixel `index`: on the film in pixels, on the film in
    /// [0, 1]², and the filter weight it carries.
    fn film_position(&self, index: usize, rng: &mut SampleStream) -> (Vec2, Vec2, f32) {
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

    /// Runs `pilot` (`crate::pilot`) on the worker threads and hands the strategy its pixels'
    /// memory in pixel order; returns what it counted and its camera samples. Under a time
    /// budget, a chunk of pilot pixels that finds the budget spent is skipped (its pixels keep
    /// an empty memory), so the pilot overruns the budget by at most one chunk per thread.
    fn run_pilot(
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

    /// Sample `sample_index` of the pixels of work unit `u`, accumulated into `unit` and, when
    /// splatting, kept in `splats` for the pass's gather.
    fn render_unit(
        &self,
        u: usize,
        (sample_index, pass_weight): (u64, f64),
        (unit, splats): (&mut [PixelAccum], &mut [PassSample]),
        c: &mut Counters,
    ) {
        for (i, px) in unit.iter_mut().enumerate() {
            let index = u * UNIT_PIXELS + i;
            let mut rng = self.in_grid(
                index,
                SampleStream::with_sampler(
                    self.settings.sampler,
                    self.settings.seed,
                    index as u64,
                    sample_index,
                )
                .with_pixel_samples(self.settings.spp.unwrap_or(0)),
            );
            let (on_film, film, weight) = self.film_position(index, &mut rng);
            // Fixed before the sample is drawn, from the pixel's earlier passes only.
            let rays = self.settings.emission_rays.rays_for(px.split);
            let mut ctx = SampleContext {
                counters: c,
                aux: [0.0; MAX_AUX],
                pixel_memory: &mut px.memory,
            };
            let CameraSample {
                emitted,
                direct,
                distant,
                sees_light,
            } = shade_camera_sample(
                self.scene,
                self.strategy,
                &self.settings.camera,
                self.aspect,
                film,
                &mut rng,
                &mut ctx,
            );
            let aux = ctx.aux;
            // Exact for the weight-1 filters (box, triangle).
            let l = if rays == 1 {
                ((emitted + direct) + distant) * weight
            } else {
                let (sum, lit) = self.extra_emission(index, sample_index, rays, c);
                px.extra_rays += rays - 1;
                px.extra_lit += lit;
                (direct + distant) * weight + (emitted * weight + sum) / rays as f32
            };
            // A non-finite sample is a bug upstream; keep it visible in the image rather than hiding it.
            for k in 0..3 {
                let v = l[k] as f64;
                px.sum[k] += pass_weight * v;
                px.sum_sq[k] += pass_weight * (v * v);
            }
            px.light_hits += sees_light as u32;
            for (acc, v) in px.aux.iter_mut().zip(aux).take(self.n_aux) {
                *acc += v as f64;
            }
            if let Some(s) = splats.get_mut(i) {
                *s = PassSample {
                    radiance: l,
                    film: on_film,
                    sees_light,
                };
            }
        }
    }
}

/// What one camera ray found: the emission it sees, the strategy's direct-lighting estimate and
/// the distant lights at its hit (kept apart so that extra emission rays can replace the first).
#[derive(Default)]
struct CameraSample {
    emitted: Vec3,
    direct: Vec3,
    distant: Vec3,
    sees_light: bool,
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
) -> CameraSample {
    let dir = camera.ray_direction(film, aspect);
    ctx.counters.camera_rays += 1;
    let Some(hit) = scene.intersect(camera.position, dir, 0.0, f32::INFINITY) else {
        return CameraSample::default();
    };
    let wo = -dir;
    let mut out = CameraSample::default();
    if hit.light != NO_LIGHT {
        out.emitted = scene.lights[hit.light as usize].emitted(hit.ng, hit.uv, wo);
        out.sees_light = out.emitted != Vec3::ZERO;
    }
    let Some(sp) = shading_point(scene, hit, wo) else {
        return out;
    };
    ctx.counters.shading_points += 1;
    ctx.counters.glossy_points += !sp.bsdf.is_pure_diffuse() as u64;
    out.direct = strategy.estimate(scene, &sp, rng, ctx);
    out.distant = distant_lighting(scene, &sp, ctx);
    out
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
fn plan_emission_splits(
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

/// Renders `scene` with `strategy`. `progress` is called after each pass with (passes done, full passes so far).
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
    if settings.sampler.needs_spp() && settings.spp.is_none() {
        return Err(format!(
            "the {} sampler cuts its strata by the sample count: give spp (with a time budget, \
             the most samples a pixel may take)",
            settings.sampler
        ));
    }
    if settings.emission_rays != EmissionRays::OFF
        && settings.reconstruction == Reconstruction::Splat
    {
        return Err(
            "extra emission rays need the sampled reconstruction (each ray in its own pixel), \
             not splatting"
                .into(),
        );
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
    let grid = SampleGrid::new(w, h, settings.reconstruction, &settings.filter);
    let splatting = settings.reconstruction == Reconstruction::Splat;
    let mut accum = vec![PixelAccum::default(); grid.len()];
    plan_emission_splits(settings, grid.width, 0, &mut accum);
    let mut splats = vec![PassSample::default(); if splatting { grid.len() } else { 0 }];
    let mut film = splatting.then(|| SplatFilm::new(w, h, settings.filter.clone()));
    let threads = pool.current_num_threads();
    let start = Instant::now();
    let cpu_start = process_cpu_seconds();
    let clock = settings.time_budget.map(|budget| BudgetClockReader {
        budget,
        start,
        cpu_start,
        threads,
    });
    strategy.begin_render();
    let job = PassJob {
        scene,
        strategy,
        settings,
        aspect,
        n_aux,
        grid,
    };
    let mut counters = Counters::default();
    let mut pilot_samples = 0;
    if let Some(pilot) = strategy.pilot(grid.width, grid.height) {
        let (c, n) = job.run_pilot(&pool, pilot, clock.as_ref());
        counters.merge(&c);
        pilot_samples = n;
    }
    let mut spp_done = 0u32;
    let mut passes = 0u32;
    // Each pass's weight, in order (the partial last one too).
    let mut weights: Vec<f64> = Vec::new();
    let mut partial_pixels = 0usize;
    let stop = AtomicBool::new(false);
    loop {
        if let Some(limit) = settings.spp
            && spp_done >= limit
        {
            break;
        }
        if stop.load(Ordering::Relaxed) {
            break;
        }
        let sample_index = spp_done as u64;
        let pass_weight = strategy.pass_weight(spp_done);
        if !(pass_weight.is_finite() && pass_weight > 0.0) {
            return Err(format!(
                "strategy {}: the weight of pass {spp_done} is {pass_weight}, not a positive number",
                strategy.name()
            ));
        }
        weights.push(pass_weight);
        // Units are handed out in order, and every unit claimed is finished: the units done
        // in this pass are always a prefix of the image.
        let mut splat_chunks = splats.chunks_mut(UNIT_PIXELS);
        let units: Vec<Mutex<(&mut [PixelAccum], &mut [PassSample])>> = accum
            .chunks_mut(UNIT_PIXELS)
            .map(|a| Mutex::new((a, splat_chunks.next().unwrap_or_default())))
            .collect();
        let next_unit = AtomicUsize::new(0);
        let pass_counters: Vec<Counters> = pool.broadcast(|_| {
            let mut c = Counters::default();
            let mut last_cpu_read = None;
            loop {
                if let Some(clock) = &clock
                    && (stop.load(Ordering::Relaxed) || clock.spent(&mut last_cpu_read))
                {
                    stop.store(true, Ordering::Relaxed);
                    break;
                }
                let u = next_unit.fetch_add(1, Ordering::Relaxed);
                let Some(unit) = units.get(u) else {
                    break;
                };
                let mut unit = unit.lock().unwrap_or_else(|e| e.into_inner());
                let (a, s) = &mut *unit;
                job.render_unit(u, (sample_index, pass_weight), (a, s), &mut c);
            }
            c
        });
        for c in &pass_counters {
            counters.merge(c);
        }
        let mut done = next_unit.load(Ordering::Relaxed).min(units.len());
        if done == 0 && spp_done == 0 {
            // A budget spent before the first unit: take that one anyway, so every render has a sample.
            let mut unit = units[0].lock().unwrap_or_else(|e| e.into_inner());
            let (a, s) = &mut *unit;
            job.render_unit(0, (sample_index, pass_weight), (a, s), &mut counters);
            done = 1;
        }
        let n_units = units.len();
        drop(units);
        if done == 0 {
            break;
        }
        if let Some(film) = &mut film {
            film.gather_pass(
                grid,
                &splats,
                (done * UNIT_PIXELS).min(grid.len()),
                pass_weight,
            );
        }
        passes += 1;
        if done < n_units {
            partial_pixels = done * UNIT_PIXELS;
            progress(passes, spp_done);
            break;
        }
        spp_done += 1;
        strategy.end_pass(&mut accum.iter().map(|p| &p.memory));
        plan_emission_splits(settings, grid.width, spp_done, &mut accum);
        progress(passes, spp_done);
    }
    let samples = |i: usize| (spp_done + (i < partial_pixels) as u32) as f64;
    let pass_weights = PassWeights::new(&weights);
    let image = match &film {
        None => own_samples_image(&accum, samples, &pass_weights),
        Some(film) => FinishedImage {
            pixels: film.pixels(),
            variance_of_mean: film.variance_of_mean(),
            light_fraction: film.light_fraction(),
            unsampled: film.empty_pixels(),
        },
    };
    // The image's pixels in the sample grid (the same pixels unless a splat border surrounds it).
    let cropped: Vec<usize> = (0..w * h)
        .map(|i| (i / w + grid.border) * grid.width + i % w + grid.border)
        .collect();
    let aux = strategy
        .aux_channels()
        .iter()
        .take(n_aux)
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
        partial_pixels,
        pixels: image.pixels,
        variance_of_mean: image.variance_of_mean,
        light_fraction: image.light_fraction,
        aux,
        counters,
        wall_seconds,
        cpu_seconds,
        passes,
        threads,
        pilot_samples,
        unsampled: image.unsampled,
    })
}

/// The finished image before its diagnostics channels.
struct FinishedImage {
    pixels: Vec<Vec3>,
    variance_of_mean: Vec<Vec3>,
    light_fraction: Vec<f32>,
    unsampled: usize,
}

/// Each pixel the mean of its own samples (filter importance sampling), `samples(i)` of them.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimator::ShadingPoint;

    /// One uniformly chosen light, sampled by its shape: cheap, and it uses the random numbers.
    struct OneLight;

    impl DirectLighting for OneLight {
        fn name(&self) -> String {
            "test-one-light".into()
        }

        fn estimate(
            &self,
            scene: &Scene,
            sp: &ShadingPoint,
            rng: &mut SampleStream,
            ctx: &mut SampleContext,
        ) -> Vec3 {
            let n = scene.lights.len();
            let i = ((rng.next_f32() * n as f32) as usize).min(n - 1);
            match scene.lights[i].sample(sp.point(), rng.next_2d()) {
                Some(s) => sp.shade(scene, &s, ctx.counters) * n as f32 / s.pdf,
                None => Vec3::ZERO,
            }
        }
    }

    /// Returns, at each pixel, how many samples it has taken (its count kept in the pixel's
    /// memory), and weighs pass i by `weight(i)`.
    struct CountingPasses(fn(u32) -> f64);

    impl DirectLighting for CountingPasses {
        fn name(&self) -> String {
            "test-counting-passes".into()
        }

        fn estimate(
            &self,
            _: &Scene,
            _: &ShadingPoint,
            _: &mut SampleStream,
            ctx: &mut SampleContext,
        ) -> Vec3 {
            ctx.pixel_memory[0] += 1.0;
            Vec3::splat(ctx.pixel_memory[0])
        }

        fn pass_weight(&self, pass: u32) -> f64 {
            (self.0)(pass)
        }
    }

    /// A pixel's value is Σ wᵢxᵢ/Σ wᵢ over its passes: with xᵢ = wᵢ = i (from 1) and four
    /// passes, 30/10 = 3, against the plain mean 2.5; a weight that is not positive is an error.
    #[test]
    fn passes_are_averaged_with_the_strategys_weights() {
        let scene = test_scene();
        let s = settings(&scene, Some(4), None, 2, Sampler::Independent);
        let plain = render(&scene, &CountingPasses(|_| 1.0), &s, &|_, _| {}).unwrap();
        let weighted = render(&scene, &CountingPasses(|i| i as f64 + 1.0), &s, &|_, _| {}).unwrap();
        // The pixels whose every sample saw the floor (the others mix in the sky's zeros).
        let floor: Vec<usize> = (0..plain.pixels.len())
            .filter(|&i| plain.pixels[i] == Vec3::splat(2.5))
            .collect();
        assert!(floor.len() > 1000, "{}", floor.len());
        for &i in &floor {
            assert_eq!(weighted.pixels[i], Vec3::splat(3.0));
            assert!(weighted.variance_of_mean[i].is_finite());
        }
        for bad in [|_| 0.0, |_| -1.0, |_| f64::NAN] {
            match render(&scene, &CountingPasses(bad), &s, &|_, _| {}) {
                Err(e) => assert!(e.contains("weight of pass 0"), "{e}"),
                Ok(_) => panic!("a weight that is not positive was taken"),
            }
        }
    }

    /// A glossy floor under 64 small sphere lights on a jittered grid, seen from above at an angle.
    fn test_scene() -> Scene {
        use crate::camera::Camera;
        use crate::material::Material;
        let mut b = crate::scene::SceneBuilder::new("render-test");
        let floor = b
            .add_material(Material::simple("floor", Vec3::splat(0.6), 0.0, 0.3))
            .unwrap();
        let p = [
            Vec3::new(-4.0, 0.0, -4.0),
            Vec3::new(4.0, 0.0, -4.0),
            Vec3::new(4.0, 0.0, 4.0),
            Vec3::new(-4.0, 0.0, 4.0),
        ];
        b.add_mesh(
            "floor",
            &p,
            None,
            None,
            &[0, 2, 1, 0, 3, 2],
            glam::Mat4::IDENTITY,
            floor,
        )
        .unwrap();
        for i in 0..64u32 {
            let (x, z) = ((i % 8) as f32 - 3.5, (i / 8) as f32 - 3.5);
            let jitter = ((i * 37 % 11) as f32 / 11.0 - 0.5) * 0.4;
            let centre = Vec3::new(x + jitter, 0.5 + 0.1 * (i % 5) as f32, z - jitter);
            b.add_sphere_light(centre, 0.02, Vec3::splat(50.0 + i as f32), None)
                .unwrap();
        }
        b.add_camera(Camera::look_at(
            "top",
            Vec3::new(0.0, 5.0, 7.0),
            Vec3::ZERO,
            Vec3::Y,
            0.7,
            64,
            40,
        ));
        b.build().unwrap()
    }

    fn run(scene: &Scene, spp: Option<u32>, budget: Option<f64>, threads: usize) -> RenderResult {
        run_with(scene, spp, budget, threads, Sampler::Independent)
    }

    fn run_with(
        scene: &Scene,
        spp: Option<u32>,
        budget: Option<f64>,
        threads: usize,
        sampler: Sampler,
    ) -> RenderResult {
        render(
            scene,
            &OneLight,
            &settings(scene, spp, budget, threads, sampler),
            &|_, _| {},
        )
        .unwrap()
    }

    fn settings(
        scene: &Scene,
        spp: Option<u32>,
        budget: Option<f64>,
        threads: usize,
        sampler: Sampler,
    ) -> RenderSettings {
        RenderSettings {
            width: 64,
            height: 40,
            spp,
            seed: 3,
            time_budget: budget.map(|seconds| TimeBudget {
                seconds,
                clock: BudgetClock::Wall,
            }),
            threads: Some(threads),
            camera: scene.camera(None).unwrap(),
            sampler,
            filter: Default::default(),
            reconstruction: Default::default(),
            emission_rays: Default::default(),
        }
    }

    /// `OneLight` that asks for a pilot (when `pilot`) and keeps what the pilot's pixels
    /// remembered: per pixel the samples shaded and the sum of their first random numbers.
    struct PilotRecorder {
        pilot: bool,
        seen: Mutex<Vec<[f32; 2]>>,
        /// Every pixel's memory after the image's second pass.
        second_pass: Mutex<Vec<[f32; 2]>>,
    }

    impl DirectLighting for PilotRecorder {
        fn name(&self) -> String {
            "test-pilot-recorder".into()
        }

        fn estimate(
            &self,
            scene: &Scene,
            sp: &ShadingPoint,
            rng: &mut SampleStream,
            ctx: &mut SampleContext,
        ) -> Vec3 {
            ctx.pixel_memory[0] += 1.0;
            let mut probe = rng.clone();
            ctx.pixel_memory[1] += probe.next_f32();
            OneLight.estimate(scene, sp, rng, ctx)
        }

        fn pilot(&self, _: usize, _: usize) -> Option<Pilot> {
            self.pilot.then_some(Pilot {
                stride: 4,
                samples: 2,
            })
        }

        fn end_pilot(&self, memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
            *self.seen.lock().unwrap() = memory.map(|m| [m[0], m[1]]).collect();
        }

        fn end_pass(&self, memory: &mut dyn Iterator<Item = &[f32; PIXEL_MEMORY]>) {
            let all: Vec<[f32; 2]> = memory.map(|m| [m[0], m[1]]).collect();
            if all.iter().any(|m| m[0] == 2.0) && all.iter().all(|m| m[0] <= 2.0) {
                *self.second_pass.lock().unwrap() = all;
            }
        }
    }

    /// The image, what the pilot's pixels remembered, every pixel's memory after pass 2.
    type PilotRun = (RenderResult, Vec<[f32; 2]>, Vec<[f32; 2]>);

    fn run_pilot(scene: &Scene, pilot: bool, threads: usize) -> PilotRun {
        let strategy = PilotRecorder {
            pilot,
            seen: Mutex::new(Vec::new()),
            second_pass: Mutex::new(Vec::new()),
        };
        let s = settings(scene, Some(3), None, threads, Sampler::Independent);
        let image = render(scene, &strategy, &s, &|_, _| {}).unwrap();
        let seen = strategy.seen.into_inner().unwrap();
        (image, seen, strategy.second_pass.into_inner().unwrap())
    }

    #[test]
    fn a_pilot_is_kept_out_of_the_image_and_the_same_for_any_thread_count() {
        let scene = test_scene();
        let (plain, none, image_memory) = run_pilot(&scene, false, 2);
        assert!(none.is_empty());
        assert_eq!(plain.pilot_samples, 0);
        let (one, seen_one, _) = run_pilot(&scene, true, 1);
        let (three, seen_three, _) = run_pilot(&scene, true, 3);
        // The image's samples are the same with and without the pilot.
        assert_eq!(one.pixels, plain.pixels);
        assert_eq!(three.pixels, plain.pixels);
        // The pilot: the centres of the 4 × 4 blocks, two samples each with the memory carried
        // from the first to the second, the same numbers for any thread count.
        let pixels = Pilot {
            stride: 4,
            samples: 2,
        }
        .pixels(64, 40);
        assert_eq!(seen_one.len(), pixels.len());
        assert_eq!(one.pilot_samples, 2 * pixels.len() as u64);
        assert_eq!(seen_one, seen_three);
        assert!(seen_one.iter().all(|m| m[0] == 0.0 || m[0] == 2.0));
        assert!(seen_one.iter().filter(|m| m[0] == 2.0).count() > pixels.len() / 2);
        // Its numbers are not the image's: the image's first two samples of the same pixels
        // drew other numbers.
        let mut compared = 0;
        for (m, &p) in seen_one.iter().zip(&pixels) {
            if m[0] == 2.0 && image_memory[p][0] == 2.0 {
                assert_ne!(m[1], image_memory[p][1], "pixel {p}");
                compared += 1;
            }
        }
        assert!(compared > pixels.len() / 2);
        assert!(one.counters.camera_rays > plain.counters.camera_rays);
    }

    /// A time budget spent before the pilot skips it (the strategy still hears of it, with
    /// empty memories) and the render still takes its one unit.
    #[test]
    fn a_spent_budget_skips_the_pilot() {
        let scene = test_scene();
        let strategy = PilotRecorder {
            pilot: true,
            seen: Mutex::new(Vec::new()),
            second_pass: Mutex::new(Vec::new()),
        };
        let s = settings(&scene, None, Some(0.0), 1, Sampler::Independent);
        let image = render(&scene, &strategy, &s, &|_, _| {}).unwrap();
        assert_eq!(image.pilot_samples, 0);
        let seen = strategy.seen.into_inner().unwrap();
        assert!(!seen.is_empty() && seen.iter().all(|m| m[0] == 0.0));
        assert!(image.partial_pixels > 0 || image.spp > 0);
    }

    /// No direct lighting: an image of the emission seen directly alone.
    struct EmissionOnly;

    impl DirectLighting for EmissionOnly {
        fn name(&self) -> String {
            "test-emission-only".into()
        }

        fn estimate(
            &self,
            _: &Scene,
            _: &ShadingPoint,
            _: &mut SampleStream,
            _: &mut SampleContext,
        ) -> Vec3 {
            Vec3::ZERO
        }
    }

    /// `spp` samples of seed `seed` with `k` emission rays per splitting sample.
    fn run_emission(scene: &Scene, spp: u32, seed: u64, k: u32, threads: usize) -> RenderResult {
        run_emission_with(&OneLight, scene, spp, seed, k, threads, Sampler::Sobol)
    }

    fn run_emission_with(
        strategy: &dyn DirectLighting,
        scene: &Scene,
        spp: u32,
        seed: u64,
        k: u32,
        threads: usize,
        sampler: Sampler,
    ) -> RenderResult {
        let mut s = settings(scene, Some(spp), None, threads, sampler);
        s.seed = seed;
        s.emission_rays = EmissionRays::new(k).unwrap();
        render(scene, strategy, &s, &|_, _| {}).unwrap()
    }

    #[test]
    fn images_are_identical_for_any_thread_count() {
        let scene = test_scene();
        let mut images = Vec::new();
        for sampler in Sampler::ALL {
            let a = run_with(&scene, Some(3), None, 1, sampler);
            let b = run_with(&scene, Some(3), None, 3, sampler);
            assert_eq!((a.spp, a.partial_pixels, b.spp), (3, 0, 3));
            assert_eq!(a.pixels, b.pixels, "{sampler}");
            assert_eq!(a.variance_of_mean, b.variance_of_mean, "{sampler}");
            assert_eq!(a.counters, b.counters, "{sampler}");
            images.push(a.pixels);
        }
        assert_ne!(images[0], images[1], "the samplers draw different numbers");
    }

    /// A budget spent at once stops after one work unit, inside the first pass: the render
    /// ends at a unit boundary, not after a pass over the image, and what it did is exactly
    /// the start of a fixed-spp render, whatever the thread count.
    #[test]
    fn a_budget_ends_at_a_unit_boundary_inside_a_pass() {
        let scene = test_scene();
        let full = run(&scene, Some(1), None, 2);
        let pixels = 64 * 40;
        assert!(pixels > 4 * UNIT_PIXELS, "the image needs several units");
        for threads in [1, 3] {
            let r = run(&scene, None, Some(1e-9), threads);
            assert_eq!(
                (r.spp, r.partial_pixels),
                (0, UNIT_PIXELS),
                "{threads} threads"
            );
            assert_eq!(r.unsampled_pixels(), pixels - UNIT_PIXELS);
            assert_eq!(r.passes, 1);
            assert_eq!(r.counters.camera_rays, UNIT_PIXELS as u64);
            assert_eq!(r.pixels[..UNIT_PIXELS], full.pixels[..UNIT_PIXELS]);
            assert!(r.pixels[UNIT_PIXELS..].iter().all(|p| *p == Vec3::ZERO));
            assert_eq!((r.samples_at(0), r.samples_at(UNIT_PIXELS)), (1, 0));
        }
    }

    /// Relative squared error of `image` against `reference`, over the pixels `keep` selects.
    fn rel_error(image: &RenderResult, reference: &RenderResult, keep: &[bool]) -> f64 {
        let mut sum = 0.0;
        for ((a, r), _) in image
            .pixels
            .iter()
            .zip(&reference.pixels)
            .zip(keep)
            .filter(|(_, k)| **k)
        {
            let (a, r) = (a.x as f64, r.x as f64);
            sum += (a - r) * (a - r) / (r * r + 0.01);
        }
        sum
    }

    /// Extra emission rays leave the image's expectation alone (a block-mean comparison with a
    /// high-spp one-ray render) and cut the error of the pixels whose coverage of the small
    /// sphere lights is mixed.
    #[test]
    fn emission_rays_converge_to_the_one_ray_image_with_less_noise() {
        let scene = test_scene();
        // The emission alone: the noise there is the pixels' coverage of the lights.
        let emission = |spp, seed, k| {
            run_emission_with(&EmissionOnly, &scene, spp, seed, k, 2, Sampler::Sobol)
        };
        let exact = emission(128, 11, 64);
        let lit: Vec<bool> = exact.light_fraction.iter().map(|&f| f > 0.0).collect();
        assert!(
            lit.iter().filter(|&&l| l).count() > 40,
            "the camera sees the lights"
        );
        let one = emission(8, 5, 1);
        let split = emission(8, 5, 16);
        assert!(split.counters.emission_rays > 15 * 64 * 40);
        assert_eq!(one.counters.emission_rays, 0);
        let (e1, e16) = (
            rel_error(&one, &exact, &lit),
            rel_error(&split, &exact, &lit),
        );
        assert!(
            e16 < 0.25 * e1,
            "lit pixels: {e16} with 16 rays, {e1} with one"
        );
        // Unbiased: the emission image with 16 rays against the one-ray one, both under the
        // independent sampler (whose per-pixel variance estimates are unbiased), each difference
        // in units of its standard deviation: over the whole image and over 8 × 8 blocks.
        let independent = |spp, seed, k| {
            run_emission_with(&EmissionOnly, &scene, spp, seed, k, 2, Sampler::Independent)
        };
        let reference = independent(4096, 11, 1);
        let many = independent(256, 7, 16);
        let block = |bx: usize, by: usize, size: usize| {
            let (mut d, mut v) = (0.0f64, 0.0f64);
            for y in by * size..(by * size + size).min(40) {
                for x in bx * size..(bx * size + size).min(64) {
                    let i = y * 64 + x;
                    d += (many.pixels[i].x - reference.pixels[i].x) as f64;
                    v += (many.variance_of_mean[i].x + reference.variance_of_mean[i].x) as f64;
                }
            }
            (d, v)
        };
        let (d, v) = block(0, 0, 64);
        assert!(d * d < 12.25 * v, "whole image: z = {}", d / v.sqrt());
        let (mut z2, mut blocks) = (0.0, 0);
        for (bx, by) in (0..8).flat_map(|bx| (0..5).map(move |by| (bx, by))) {
            let (d, v) = block(bx, by, 8);
            if v > 0.0 {
                z2 += d * d / v;
                blocks += 1;
            } else {
                assert_eq!(d, 0.0, "a difference without variance");
            }
        }
        assert!(blocks > 20, "{blocks} blocks see a light");
        let mean_z2 = z2 / blocks as f64;
        assert!(
            mean_z2 < 2.0,
            "mean squared z over {blocks} blocks: {mean_z2}"
        );
    }

    #[test]
    fn emission_rays_give_the_same_image_for_any_thread_count() {
        let scene = test_scene();
        let a = run_emission(&scene, 4, 2, 8, 1);
        let b = run_emission(&scene, 4, 2, 8, 3);
        assert_eq!(a.pixels, b.pixels);
        assert_eq!(a.light_fraction, b.light_fraction);
        assert_eq!(a.counters, b.counters);
        // The first pass splits every pixel, later ones only the pixels of mixed coverage.
        let pixels = 64 * 40;
        assert!(a.counters.emission_rays > 7 * pixels as u64);
        assert!(a.counters.emission_rays < 4 * 7 * pixels as u64 / 2);
    }

    #[test]
    fn emission_rays_with_splatting_are_refused() {
        let scene = test_scene();
        let mut s = settings(&scene, Some(1), None, 1, Sampler::Sobol);
        s.emission_rays = EmissionRays::new(4).unwrap();
        s.reconstruction = Reconstruction::Splat;
        let e = render(&scene, &OneLight, &s, &|_, _| {})
            .err()
            .expect("refused");
        assert!(e.contains("sampled reconstruction"), "{e}");
    }
}
