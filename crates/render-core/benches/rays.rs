//! Closest-hit and shadow-ray throughput on a scene of over a million triangles
//! (a field of tessellated spheres over a ground plane, seen by a pinhole camera).
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Mat4, Vec2, Vec3};
use render_core::camera::Camera;
use render_core::material::Material;
use render_core::scene::{Scene, SceneBuilder};

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
    b.add_camera(Camera::look_at(
        "c",
        Vec3::new(0.0, 8.0, 22.0),
        Vec3::ZERO,
        Vec3::Y,
        0.8,
        512,
        512,
    ));
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
    g.finish();
}

criterion_group!(benches, bench_rays);
criterion_main!(benches);
