//! The AVX2 traversal and the forced SSE2 fallback return the same hits, bit for bit, on
//! every built-in scene: camera rays, and from their hits shadow rays to random points on
//! random lights and cosine-distributed bounce rays (the incoherent rays a render casts).
use glam::Vec2;
use render_core::accel::{Hit, Simd};
use render_core::frame::Frame;
use render_core::rng::SampleStream;
use render_core::sampling::cosine_hemisphere;
use render_core::scene::{Scene, offset_origin, ray_epsilon};

/// A hit's primitive and the bits of its distance and barycentrics.
type HitBits = Option<(u32, u32, u32, u32)>;

/// (closest hits of camera and bounce rays, occlusion of shadow rays) at 48×48 pixels.
fn trace(scene: &Scene) -> (Vec<HitBits>, Vec<bool>) {
    let cam = scene.camera(None).unwrap();
    let bits = |h: Option<Hit>| h.map(|h| (h.prim, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()));
    let (mut hits, mut blocked) = (Vec::new(), Vec::new());
    let n = 48u32;
    for pixel in 0..n * n {
        let mut rng = SampleStream::new(3, pixel as u64, 0);
        let film = Vec2::new(
            ((pixel % n) as f32 + rng.next_f32()) / n as f32,
            ((pixel / n) as f32 + rng.next_f32()) / n as f32,
        );
        let dir = cam.ray_direction(film, 1.0);
        let h = scene.accel.intersect(cam.position, dir, 0.0, f32::INFINITY);
        hits.push(bits(h));
        let Some(h) = h else { continue };
        let s = scene.surface(cam.position, dir, &h);
        if !scene.lights.is_empty() {
            let light = ((rng.next_f32() * scene.lights.len() as f32) as u32)
                .min(scene.lights.len() as u32 - 1);
            if let Some(ls) = scene.sample_light(light, s.point, s.ns, rng.next_2d()) {
                let d = ls.point - s.point;
                let dist = d.length();
                if dist > 0.0 {
                    let d = d / dist;
                    let tmax = dist * (1.0 - 1e-4) - ray_epsilon(ls.point);
                    blocked.push(scene.accel.occluded(
                        offset_origin(s.point, s.ng, d),
                        d,
                        0.0,
                        tmax,
                    ));
                }
            }
        }
        let nrm = if s.ng.dot(-dir) >= 0.0 { s.ng } else { -s.ng };
        let d = Frame::from_normal(nrm).to_world(cosine_hemisphere(rng.next_2d()));
        let o = offset_origin(s.point, s.ng, d);
        hits.push(bits(scene.accel.intersect(o, d, 0.0, f32::INFINITY)));
        blocked.push(scene.accel.occluded(o, d, 0.0, 2.0 + rng.next_f32()));
    }
    (hits, blocked)
}

#[test]
fn forced_sse2_fallback_matches_avx2_on_every_builtin() {
    if Simd::detect() != Simd::Avx2 {
        eprintln!("no AVX2 on this CPU: nothing to compare the fallback with");
        return;
    }
    for b in scene_formats::builtin::list_builtins() {
        let mut scene = scene_formats::load_scene(&format!("builtin:{}", b.name), None).unwrap();
        assert_eq!(scene.accel.simd(), Simd::Avx2);
        let fast = trace(&scene);
        scene.accel.set_simd(Simd::Sse2).unwrap();
        let fallback = trace(&scene);
        let found = fast.0.iter().filter(|h| h.is_some()).count();
        assert!(found > 100, "{}: only {found} hits", b.name);
        assert!(fast.0 == fallback.0, "{}: closest hits differ", b.name);
        assert!(fast.1 == fallback.1, "{}: occlusion differs", b.name);
    }
}
