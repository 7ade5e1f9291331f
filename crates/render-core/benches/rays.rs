//! Closest-hit and shadow-ray throughput, one thread: coherent camera rays and their shadow
//! rays on a scene of over a million triangles (a field of tessellated spheres over a ground
//! plane, seen by a pinhole camera), and incoherent secondary rays of `builtin:emissive-mesh`
//! (from its camera rays' shading points: shadow rays to random points on random lights, and
//! cosine-distributed BSDF rays traced for their closest hit). Each is timed one ray at a time
//! and as streams of [`STREAM`] rays (`Accel::intersect_stream`, `Accel::occluded_stream`);
//! the camera rays (and `builtin:emissive-mesh`'s camera and BSDF rays) also in packets of
//! eight (`Accel::intersect_packets`).
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Mat4, Vec2, Vec3};
use render_core::accel::{Hit, StreamRay};
use render_core::camera::Camera;
use render_core::frame::Frame;
use render_core::material::Material;
use render_core::rng::SampleStream;
use render_core::sampling::cosine_hemisphere;
use render_core::scene::{Scene, SceneBuilder, offset_origin};

/// Rays per stream: a work unit's batch.
const STREAM: usize = 256;

/// Closest hits found tracing `rays` in streams of [`STREAM`].
fn stream_hits(scene: &Scene, rays: &[StreamRay], hits: &mut [Option<Hit>]) -> usize {
    for (r, h) in rays.chunks(STREAM).zip(hits.chunks_mut(STREAM)) {
        scene.accel.intersect_stream(r, h);
    }
    hits.iter().filter(|h| h.is_some()).count()
}

/// Closest hits found tracing `rays` in packets of eight, [`STREAM`] rays a call.
fn packet_hits(scene: &Scene, rays: &[StreamRay], hits: &mut [Option<Hit>]) -> usize {
    for (r, h) in rays.chunks(STREAM).zip(hits.chunks_mut(STREAM)) {
        scene.accel.intersect_packets(r, h);
    }
    hits.iter().filter(|h| h.is_some()).count()
}

/// Blocked rays of `rays`, traced in streams of [`STREAM`].
fn stream_blocked(scene: &Scene, rays: &[StreamRay], blocked: &mut [bool]) -> usize {
    for (r, b) in rays.chunks(STREAM).zip(blocked.chunks_mut(STREAM)) {
        scene.accel.occluded_stream(r, b);
    }
    blocked.iter().filter(|b| **b).count()
}

/// A UV sphere mesh with `n` segments and `n/2` rings (about n² triangles).
fn sphere_mesh(n: u32) -> (Vec<Vec3>, Vec<u32>) {
    let rings = n / 2;
    let mut p = Vec::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=n {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / n as f32;
            p.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ));
        }
    }
    let mut idx = Vec::new();
    for r in 0..rings {
        for s in 0..n {
            let a = r * (n + 1) + s;
            let b = a + n + 1;
            idx.extend_from_slice(&[a, b, a + 1, a + 1, b, b + 1]);
        }
    }
    (p, idx)
}

fn million_triangle_scene() -> Scene {
    let mut b = SceneBuilder::new("bench");
    let m = b
        .add_material(Material::simple("m", Vec3::splat(0.5), 0.0, 0.3))
        .unwrap();
    let (p, idx) = sphere_mesh(128); // 16,384 triangles, minus the degenerate ones at the poles
    for i in 0..8 {
        for j in 0..8 {
            let t =
                Mat4::from_translation(Vec3::new(i as f32 * 2.5 - 9.0, 1.0, j as f32 * 2.5 - 9.0));
            b.add_mesh("s", &p, None, None, &idx, t, m).unwrap();
        }
    }
    let g = [
        Vec3::new(-20.0, 0.0, -20.0),
        Vec3::new(20.0, 0.0, -20.0),
        Vec3::new(20.0, 0.0, 20.0),
        Vec3::new(-20.0, 0.0, 20.0),
    ];
    b.add_mesh(
        "ground",
        &g,
        None,
        None,
        &[0, 2, 1, 0, 3, 2],
        Mat4::IDENTITY,
        m,
    )
    .unwrap();
    b.add_camera(
        Camera::look_at(
            "c",
            Vec3::new(0.0, 8.0, 22.0),
            Vec3::ZERO,
            Vec3::Y,
            0.8,
            512,
            512,
        )
        .unwrap(),
    );
    b.build().unwrap()
}

fn bench_rays(c: &mut Criterion) {
    let scene = million_triangle_scene();
    assert!(
        scene.triangles.len() >= 1_000_000,
        "{} triangles",
        scene.triangles.len()
    );
    let cam = scene.camera(None).unwrap();
    let n = 64 * 64;
    let rays: Vec<Vec3> = (0..n)
        .map(|i| {
            cam.ray_direction(
                Vec2::new((i % 64) as f32 / 64.0, (i / 64) as f32 / 64.0),
                1.0,
            )
        })
        .collect();
    let hits: Vec<Vec3> = rays
        .iter()
        .filter_map(|d| {
            scene
                .intersect(cam.position, *d, 0.0, f32::INFINITY)
                .map(|h| h.point + h.ng * 1e-4)
        })
        .collect();
    let light = Vec3::new(3.0, 30.0, 5.0);
    let camera_rays: Vec<StreamRay> = rays
        .iter()
        .map(|d| segment(cam.position, *d, f32::INFINITY))
        .collect();
    let shadow_rays: Vec<StreamRay> = hits
        .iter()
        .map(|p| {
            let d = light - *p;
            let dist = d.length();
            segment(*p, d / dist, dist)
        })
        .collect();
    let mut g = c.benchmark_group("rays_1M_triangles");
    g.sample_size(10);
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("closest_hit", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|d| {
                    scene
                        .accel
                        .intersect(cam.position, **d, 0.0, f32::INFINITY)
                        .is_some()
                })
                .count()
        })
    });
    g.throughput(Throughput::Elements(hits.len() as u64));
    g.bench_function("shadow", |b| {
        b.iter(|| {
            hits.iter()
                .filter(|p| {
                    let d = light - **p;
                    let dist = d.length();
                    scene.accel.occluded(**p, d / dist, 0.0, dist)
                })
                .count()
        })
    });
    let mut out = vec![None; camera_rays.len()];
    g.throughput(Throughput::Elements(camera_rays.len() as u64));
    g.bench_function("closest_hit_stream", |b| {
        b.iter(|| stream_hits(&scene, &camera_rays, &mut out))
    });
    g.bench_function("closest_hit_packets", |b| {
        b.iter(|| packet_hits(&scene, &camera_rays, &mut out))
    });
    let mut blocked = vec![false; shadow_rays.len()];
    g.throughput(Throughput::Elements(shadow_rays.len() as u64));
    g.bench_function("shadow_stream", |b| {
        b.iter(|| stream_blocked(&scene, &shadow_rays, &mut blocked))
    });
    g.finish();
}

/// A ray as the benchmark stores it: origin, unit direction and the segment's far end.
struct Segment {
    o: Vec3,
    d: Vec3,
    tmax: f32,
}

/// The segment [0, tmax) of o + t·d as a ray of a stream.
fn segment(origin: Vec3, dir: Vec3, tmax: f32) -> StreamRay {
    StreamRay {
        origin,
        dir,
        tmin: 0.0,
        tmax,
    }
}

/// Shadow and BSDF rays from the shading points of `builtin:emissive-mesh`'s camera rays
/// (one light sample and one BSDF direction per 256×256 pixel), in pixel order: each ray's
/// neighbours start nearby but head anywhere.
fn emissive_mesh_rays() -> (Scene, Vec<Segment>, Vec<Segment>) {
    let scene = scene_formats::load_scene("builtin:emissive-mesh", None).unwrap();
    let cam = scene.camera(None).unwrap();
    let (w, h) = (256u32, 256u32);
    let aspect = w as f32 / h as f32;
    let (mut shadow, mut bsdf) = (Vec::new(), Vec::new());
    for pixel in 0..w * h {
        let mut rng = SampleStream::new(7, pixel as u64, 0);
        let film = Vec2::new(
            ((pixel % w) as f32 + 0.5) / w as f32,
            ((pixel / w) as f32 + 0.5) / h as f32,
        );
        let dir = cam.ray_direction(film, aspect);
        let Some(hit) = scene.intersect(cam.position, dir, 0.0, f32::INFINITY) else {
            continue;
        };
        if hit.material.is_none() || scene.lights.is_empty() {
            continue;
        }
        let light = (rng.next_f32() * scene.lights.len() as f32) as u32;
        let light = light.min(scene.lights.len() as u32 - 1);
        if let Some(s) = scene.sample_light(light, hit.point, hit.ns, rng.next_2d()) {
            let d = s.point - hit.point;
            let dist = d.length();
            if dist > 0.0 {
                let d = d / dist;
                let o = offset_origin(hit.point, hit.ng, d);
                // As Scene::occluded shortens it, so the light's own surface never occludes.
                let tmax = dist * (1.0 - 1e-4) - render_core::scene::ray_epsilon(s.point);
                shadow.push(Segment { o, d, tmax });
            }
        }
        let n = if hit.ng.dot(-dir) >= 0.0 {
            hit.ng
        } else {
            -hit.ng
        };
        let d = Frame::from_normal(n).to_world(cosine_hemisphere(rng.next_2d()));
        bsdf.push(Segment {
            o: offset_origin(hit.point, hit.ng, d),
            d,
            tmax: f32::INFINITY,
        });
    }
    (scene, shadow, bsdf)
}

fn bench_incoherent(c: &mut Criterion) {
    let (scene, shadow, bsdf) = emissive_mesh_rays();
    let mut g = c.benchmark_group("rays_emissive_mesh_incoherent");
    g.sample_size(10);
    g.throughput(Throughput::Elements(bsdf.len() as u64));
    g.bench_function("closest_hit", |b| {
        b.iter(|| {
            bsdf.iter()
                .filter(|r| scene.accel.intersect(r.o, r.d, 0.0, r.tmax).is_some())
                .count()
        })
    });
    g.throughput(Throughput::Elements(shadow.len() as u64));
    g.bench_function("shadow", |b| {
        b.iter(|| {
            shadow
                .iter()
                .filter(|r| scene.accel.occluded(r.o, r.d, 0.0, r.tmax))
                .count()
        })
    });
    let streamed = |rays: &[Segment]| -> Vec<StreamRay> {
        rays.iter().map(|r| segment(r.o, r.d, r.tmax)).collect()
    };
    let (bsdf, shadow) = (streamed(&bsdf), streamed(&shadow));
    let mut out = vec![None; bsdf.len()];
    g.throughput(Throughput::Elements(bsdf.len() as u64));
    g.bench_function("closest_hit_stream", |b| {
        b.iter(|| stream_hits(&scene, &bsdf, &mut out))
    });
    g.bench_function("closest_hit_packets", |b| {
        b.iter(|| packet_hits(&scene, &bsdf, &mut out))
    });
    let mut blocked = vec![false; shadow.len()];
    g.throughput(Throughput::Elements(shadow.len() as u64));
    g.bench_function("shadow_stream", |b| {
        b.iter(|| stream_blocked(&scene, &shadow, &mut blocked))
    });
    g.finish();
    bench_camera(c, &scene);
}

/// `builtin:emissive-mesh`'s camera rays through the centres of 256×256 pixels, row by row:
/// one at a time, in streams and in packets.
fn bench_camera(c: &mut Criterion, scene: &Scene) {
    let cam = scene.camera(None).unwrap();
    let lens = cam.film_rays(1.0);
    let rays: Vec<StreamRay> = (0..256 * 256)
        .map(|i| {
            let film = Vec2::new(
                ((i % 256) as f32 + 0.5) / 256.0,
                ((i / 256) as f32 + 0.5) / 256.0,
            );
            segment(cam.position, lens.direction(film), f32::INFINITY)
        })
        .collect();
    let mut g = c.benchmark_group("rays_emissive_mesh_camera");
    g.sample_size(10);
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("closest_hit", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| {
                    scene
                        .accel
                        .intersect(r.origin, r.dir, 0.0, r.tmax)
                        .is_some()
                })
                .count()
        })
    });
    let mut out = vec![None; rays.len()];
    g.bench_function("closest_hit_stream", |b| {
        b.iter(|| stream_hits(scene, &rays, &mut out))
    });
    g.bench_function("closest_hit_packets", |b| {
        b.iter(|| packet_hits(scene, &rays, &mut out))
    });
    g.finish();
}

criterion_group!(benches, bench_rays, bench_incoherent);
criterion_main!(benches);
