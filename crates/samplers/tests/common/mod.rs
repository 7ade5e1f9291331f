//! Small scenes with known answers, built directly with the scene builder.
#![allow(dead_code)]
use glam::Mat4;
use render_core::camera::Camera;
use render_core::estimator::ShadingPoint;
use render_core::estimator::{DirectLighting, PIXEL_MEMORY, SampleContext};
use render_core::material::Material;
use render_core::render::{RenderResult, RenderSettings, render, shading_point};
use render_core::rng::SampleStream;
use render_core::scene::{Scene, SceneBuilder};
use render_core::stats::Counters;
use render_core::{Vec2, Vec3};

/// A large white Lambertian floor at z = 0, facing +z.
pub fn floor(b: &mut SceneBuilder, half: f32) {
    let m = b
        .add_material(Material::diffuse("white", Vec3::ONE))
        .unwrap();
    let p = [
        Vec3::new(-half, -half, 0.0),
        Vec3::new(half, -half, 0.0),
        Vec3::new(half, half, 0.0),
        Vec3::new(-half, half, 0.0),
    ];
    b.add_mesh(
        "floor",
        &p,
        None,
        None,
        &[0, 1, 2, 0, 2, 3],
        Mat4::IDENTITY,
        m,
    )
    .unwrap();
}

/// A one-sided emissive square of side `side` at height `h`, centred above the origin, facing down.
pub fn ceiling_square(b: &mut SceneBuilder, side: f32, h: f32, radiance: f32) {
    let m = b
        .add_material(Material {
            emission: Vec3::splat(radiance),
            double_sided: false,
            ..Material::diffuse("lamp", Vec3::ZERO)
        })
        .unwrap();
    let s = side / 2.0;
    let p = [
        Vec3::new(-s, -s, h),
        Vec3::new(s, -s, h),
        Vec3::new(s, s, h),
        Vec3::new(-s, s, h),
    ];
    // clockwise seen from above = counter-clockwise seen from below: the front faces down
    b.add_mesh(
        "lamp",
        &p,
        None,
        None,
        &[0, 2, 1, 0, 3, 2],
        Mat4::IDENTITY,
        m,
    )
    .unwrap();
}

/// Estimates the reflected radiance at the origin (looking straight down) `n` times;
/// returns the mean and its standard error.
pub fn estimate_at_origin(
    scene: &Scene,
    strategy: &dyn DirectLighting,
    n: usize,
    seed: u64,
) -> (f64, f64) {
    let hit = scene
        .intersect(Vec3::new(1e-3, 2e-3, 0.5), -Vec3::Z, 0.0, f32::INFINITY)
        .expect("floor below");
    let sp = shading_point(scene, hit, Vec3::Z).expect("floor has a material");
    let mut counters = Counters::default();
    let mut memory = [0.0; PIXEL_MEMORY];
    let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
    for i in 0..n {
        let mut rng = SampleStream::new(seed, 0, i as u64);
        let mut ctx = SampleContext {
            counters: &mut counters,
            aux: [0.0; 4],
            pixel_memory: &mut memory,
        };
        let v = strategy.estimate(scene, &sp, &mut rng, &mut ctx).x as f64;
        sum += v;
        sum_sq += v * v;
    }
    let mean = sum / n as f64;
    let var = (sum_sq / n as f64 - mean * mean).max(0.0) / (n as f64 - 1.0);
    (mean, var.sqrt())
}

/// A glossy-and-diffuse test scene with sphere lights, one- and two-sided triangle lights of
/// different powers, occluders and a camera: small enough to render in a test.
pub fn mixed_scene(n_spheres: usize) -> Scene {
    mixed_scene_builder(n_spheres).build().unwrap()
}

/// [`mixed_scene`] before its build, for a test that adds geometry after its lights (which
/// keeps their order).
pub fn mixed_scene_builder(n_spheres: usize) -> SceneBuilder {
    let mut b = SceneBuilder::new("mixed");
    let glossy = b
        .add_material(Material::simple(
            "glossy",
            Vec3::new(0.6, 0.5, 0.4),
            0.0,
            0.3,
        ))
        .unwrap();
    let metal = b
        .add_material(Material::simple(
            "metal",
            Vec3::new(0.9, 0.7, 0.5),
            1.0,
            0.15,
        ))
        .unwrap();
    let diffuse = b
        .add_material(Material::diffuse("diffuse", Vec3::new(0.3, 0.6, 0.4)))
        .unwrap();
    let quad = |b: &mut SceneBuilder, c: Vec3, ex: Vec3, ey: Vec3, m: u32| {
        let p = [c - ex - ey, c + ex - ey, c + ex + ey, c - ex + ey];
        b.add_mesh(
            "quad",
            &p,
            None,
            None,
            &[0, 1, 2, 0, 2, 3],
            Mat4::IDENTITY,
            m,
        )
        .unwrap();
    };
    quad(&mut b, Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * -2.0, glossy); // floor y = 0, normal +y
    quad(
        &mut b,
        Vec3::new(-0.5, 0.4, 0.0),
        Vec3::X * 0.3,
        Vec3::Y * 0.4,
        metal,
    ); // upright panel, normal +z
    quad(
        &mut b,
        Vec3::new(0.6, 0.3, -0.3),
        Vec3::Z * 0.3,
        Vec3::Y * 0.3,
        diffuse,
    ); // panel, normal -x
    let lamp1 = b
        .add_material(Material {
            emission: Vec3::new(4.0, 3.0, 2.0),
            double_sided: false,
            ..Material::diffuse("lamp1", Vec3::ZERO)
        })
        .unwrap();
    let lamp2 = b
        .add_material(Material {
            emission: Vec3::new(1.0, 2.0, 3.0),
            double_sided: true,
            ..Material::diffuse("lamp2", Vec3::ZERO)
        })
        .unwrap();
    quad(
        &mut b,
        Vec3::new(0.8, 1.2, 0.5),
        Vec3::X * 0.2,
        Vec3::Z * 0.2,
        lamp1,
    ); // facing down
    quad(
        &mut b,
        Vec3::new(-0.9, 0.6, -0.6),
        Vec3::Y * 0.15,
        Vec3::Z * 0.1,
        lamp2,
    ); // two-sided, vertical
    for i in 0..n_spheres {
        let t = i as f32 / n_spheres.max(1) as f32;
        let c = Vec3::new(
            -1.5 + 3.0 * t,
            0.5 + 0.6 * (7.0 * t).sin().abs(),
            -1.5 + 2.5 * ((13.0 * t).cos() * 0.5 + 0.5),
        );
        let l = Vec3::new(1.0 + t, 2.0 - t, 1.5) * (20.0 + 200.0 * (i % 3) as f32);
        b.add_sphere_light(c, 0.01 + 0.02 * (i % 4) as f32, l, None)
            .unwrap();
    }
    b.add_camera(
        Camera::look_at(
            "cam",
            Vec3::new(0.0, 1.4, 2.6),
            Vec3::new(0.0, 0.2, 0.0),
            Vec3::Y,
            50f32.to_radians(),
            48,
            36,
        )
        .unwrap(),
    );
    b
}

pub fn uv(x: f32, y: f32) -> Vec2 {
    Vec2::new(x, y)
}

/// Renders `scene` through its camera (resized to `size`) with strategy `name` and `opts`.
pub fn render_opts(
    scene: &Scene,
    name: &str,
    opts: &samplers::StrategyOptions,
    spp: u32,
    threads: usize,
    seed: u64,
    size: Option<(u32, u32)>,
) -> RenderResult {
    render_sampled(
        scene,
        name,
        opts,
        spp,
        (threads, seed),
        size,
        Default::default(),
    )
}

/// [`render_opts`] with the numbers from `sampler`.
pub fn render_sampled(
    scene: &Scene,
    name: &str,
    opts: &samplers::StrategyOptions,
    spp: u32,
    (threads, seed): (usize, u64),
    size: Option<(u32, u32)>,
    sampler: render_core::sampler::Sampler,
) -> RenderResult {
    render_film(
        scene,
        name,
        opts,
        spp,
        (threads, seed),
        size,
        (sampler, Default::default(), Default::default()),
    )
}

/// [`render_sampled`] with a pixel filter and a reconstruction too.
pub fn render_film(
    scene: &Scene,
    name: &str,
    opts: &samplers::StrategyOptions,
    spp: u32,
    (threads, seed): (usize, u64),
    size: Option<(u32, u32)>,
    (sampler, filter, reconstruction): (
        render_core::sampler::Sampler,
        render_core::filter::PixelFilter,
        render_core::splat::Reconstruction,
    ),
) -> RenderResult {
    let strategy = samplers::create(name, scene, opts).unwrap();
    let mut camera = scene.camera(None).unwrap();
    if let Some((w, h)) = size {
        camera.width = w;
        camera.height = h;
    }
    let settings = RenderSettings {
        width: camera.width,
        height: camera.height,
        spp: Some(spp),
        seed,
        time_budget: None,
        threads: Some(threads),
        camera,
        sampler,
        filter,
        reconstruction,
        emission_rays: Default::default(),
        engine: Default::default(),
    };
    render(scene, strategy.as_ref(), &settings, &|_, _| {}).unwrap()
}

/// Camera of [`mixed_scene`]'s shading-point tests, and targets on its glossy floor, metal panel
/// and diffuse panel.
pub const MIXED_CAMERA: Vec3 = Vec3::new(0.0, 1.4, 2.6);
pub const MIXED_TARGETS: [Vec3; 4] = [
    Vec3::new(0.1, 0.0, -0.4),
    Vec3::new(-0.6, 0.45, 0.0),
    Vec3::new(-1.2, 0.0, 0.5),
    Vec3::new(0.9, 0.0, -1.2),
];

/// The shading points where rays from `cam` towards each of `targets` first hit the scene.
pub fn shading_points_towards(scene: &Scene, cam: Vec3, targets: &[Vec3]) -> Vec<ShadingPoint> {
    targets
        .iter()
        .filter_map(|&target| {
            let d = (target - cam).normalize();
            let hit = scene.intersect(cam, d, 0.0, f32::INFINITY)?;
            shading_point(scene, hit, -d)
        })
        .collect()
}
