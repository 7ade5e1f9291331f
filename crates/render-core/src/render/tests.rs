//! The render loop as a whole: thread counts, budgets, pass weights, pilots, emission rays.
use super::*;
use crate::emission_rays::EmissionRays;
use crate::estimator::{PIXEL_MEMORY, SampleContext, ShadingPoint};
use crate::pilot::Pilot;
use crate::rng::SampleStream;
use crate::sampler::Sampler;
use crate::splat::Reconstruction;
use glam::Vec3;
use std::sync::Mutex;

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
    b.add_camera(
        Camera::look_at(
            "top",
            Vec3::new(0.0, 5.0, 7.0),
            Vec3::ZERO,
            Vec3::Y,
            0.7,
            64,
            40,
        )
        .unwrap(),
    );
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
        engine: Default::default(),
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
    let emission =
        |spp, seed, k| run_emission_with(&EmissionOnly, &scene, spp, seed, k, 2, Sampler::Sobol);
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

/// A cancel flag set before the render, or by the progress callback after its second pass,
/// ends it with `CANCELLED` instead of an image; an unset one changes nothing.
#[test]
fn a_cancelled_render_returns_the_cancelled_error() {
    let scene = test_scene();
    let s = settings(&scene, Some(50), None, 2, Sampler::Independent);
    let set = AtomicBool::new(true);
    let r = render_cancellable(&scene, &OneLight, &s, &|_, _| {}, &set);
    assert_eq!(r.err().as_deref(), Some(CANCELLED));
    let cancel = AtomicBool::new(false);
    let passes_seen = std::sync::atomic::AtomicU32::new(0);
    let r = render_cancellable(
        &scene,
        &OneLight,
        &s,
        &|passes, _| {
            passes_seen.store(passes, Ordering::Relaxed);
            if passes == 2 {
                cancel.store(true, Ordering::Relaxed);
            }
        },
        &cancel,
    );
    assert_eq!(r.err().as_deref(), Some(CANCELLED));
    assert_eq!(
        passes_seen.load(Ordering::Relaxed),
        2,
        "no pass after the flag"
    );
    let unset = AtomicBool::new(false);
    let s3 = settings(&scene, Some(3), None, 2, Sampler::Independent);
    let a = render_cancellable(&scene, &OneLight, &s3, &|_, _| {}, &unset).unwrap();
    assert_eq!(a.pixels, run(&scene, Some(3), None, 1).pixels);
}

/// A finish flag set by the progress callback after the second pass ends the render with
/// those two passes' image, bit for bit, marked interrupted; an unset one changes nothing.
#[test]
fn a_finished_render_keeps_the_passes_done() {
    let scene = test_scene();
    let s = settings(&scene, Some(50), None, 2, Sampler::Independent);
    let finish = AtomicBool::new(false);
    let stop_after_two = |passes: u32, _| {
        if passes == 2 {
            finish.store(true, Ordering::Relaxed);
        }
    };
    let r = render_interruptible(&scene, &OneLight, &s, &stop_after_two, &finish).unwrap();
    assert!(r.interrupted);
    assert_eq!((r.spp, r.partial_pixels, r.passes), (2, 0, 2));
    assert_eq!(r.pixels, run(&scene, Some(2), None, 1).pixels);
    let unset = AtomicBool::new(false);
    let s3 = settings(&scene, Some(3), None, 2, Sampler::Independent);
    let a = render_interruptible(&scene, &OneLight, &s3, &|_, _| {}, &unset).unwrap();
    assert!(!a.interrupted);
    assert_eq!(a.pixels, run(&scene, Some(3), None, 1).pixels);
}
