//! Every SIMD path this CPU has and the forced SSE2 fallback return the same hits, bit for
//! bit, on every built-in scene: camera rays, and from their hits shadow rays to random
//! points on random lights and cosine-distributed bounce rays (the incoherent rays a render
//! casts); and the same rays traced as streams give the same answers.
use glam::Vec2;
use render_core::accel::{Hit, Simd, StreamRay};
use render_core::frame::Frame;
use render_core::rng::SampleStream;
use render_core::sampling::cosine_hemisphere;
use render_core::scene::{Scene, offset_origin, ray_epsilon};

/// A hit's primitive and the bits of its distance and barycentrics.
type HitBits = Option<(u32, u32, u32, u32)>;

/// The rays of [`trace`], in its order: (rays traced for their closest hit, shadow rays).
type Rays = (Vec<StreamRay>, Vec<StreamRay>);

/// (closest hits of camera and bounce rays, occlusion of shadow rays) at 48×48 pixels, and
/// the rays themselves.
fn trace(scene: &Scene) -> (Vec<HitBits>, Vec<bool>, Rays) {
    let cam = scene.camera(None).unwrap();
    let (mut hits, mut blocked) = (Vec::new(), Vec::new());
    let (mut closest, mut shadow) = (Vec::new(), Vec::new());
    let ray = |origin, dir, tmax| StreamRay {
        origin,
        dir,
        tmin: 0.0,
        tmax,
    };
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
        closest.push(ray(cam.position, dir, f32::INFINITY));
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
                    let o = offset_origin(s.point, s.ng, d);
                    blocked.push(scene.accel.occluded(o, d, 0.0, tmax));
                    shadow.push(ray(o, d, tmax));
                }
            }
        }
        let nrm = if s.ng.dot(-dir) >= 0.0 { s.ng } else { -s.ng };
        let d = Frame::from_normal(nrm).to_world(cosine_hemisphere(rng.next_2d()));
        let o = offset_origin(s.point, s.ng, d);
        hits.push(bits(scene.accel.intersect(o, d, 0.0, f32::INFINITY)));
        closest.push(ray(o, d, f32::INFINITY));
        let tmax = 2.0 + rng.next_f32();
        blocked.push(scene.accel.occluded(o, d, 0.0, tmax));
        shadow.push(ray(o, d, tmax));
    }
    (hits, blocked, (closest, shadow))
}

fn bits(h: Option<Hit>) -> HitBits {
    h.map(|h| (h.prim, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
}

/// The answers to `rays` traced as streams of 256.
fn streamed(scene: &Scene, rays: &Rays) -> (Vec<HitBits>, Vec<bool>) {
    let mut hits = vec![None; rays.0.len()];
    for (r, h) in rays.0.chunks(256).zip(hits.chunks_mut(256)) {
        scene.accel.intersect_stream(r, h);
    }
    let mut blocked = vec![false; rays.1.len()];
    for (r, b) in rays.1.chunks(256).zip(blocked.chunks_mut(256)) {
        scene.accel.occluded_stream(r, b);
    }
    (hits.into_iter().map(bits).collect(), blocked)
}

#[test]
fn every_path_single_and_streamed_matches_the_fallback_on_every_builtin() {
    for b in scene_formats::builtin::list_builtins() {
        let mut scene = scene_formats::load_scene(&format!("builtin:{}", b.name), None).unwrap();
        assert_eq!(scene.accel.simd(), Simd::detect());
        scene.accel.set_simd(Simd::Sse2).unwrap();
        let (hits, blocked, rays) = trace(&scene);
        let found = hits.iter().filter(|h| h.is_some()).count();
        assert!(found > 100, "{}: only {found} hits", b.name);
        for simd in Simd::ALL {
            if !simd.available() {
                eprintln!("this CPU has no {}: its path is not checked", simd.name());
                continue;
            }
            scene.accel.set_simd(simd).unwrap();
            let (h, o, _) = trace(&scene);
            assert!(h == hits, "{}, {simd:?}: closest hits differ", b.name);
            assert!(o == blocked, "{}, {simd:?}: occlusion differs", b.name);
            let (h, o) = streamed(&scene, &rays);
            assert!(
                h == hits,
                "{}, {simd:?}: streamed closest hits differ",
                b.name
            );
            assert!(
                o == blocked,
                "{}, {simd:?}: streamed occlusion differs",
                b.name
            );
        }
    }
}
