//! Streams against single rays: in a stream of any length, on every SIMD path this CPU has,
//! each ray's closest hit (primitive, distance and barycentrics, bit for bit) and occlusion
//! are those of `Accel::intersect` and `Accel::occluded`; and the 16-lane node test, run as
//! plain arrays, finds what the 4- and 8-lane ones find.
use super::simd_paths_tests::{Rng, bits, random_rays, soup};
use super::*;

/// The paths this CPU runs, with a line for each one it lacks.
fn paths() -> Vec<Simd> {
    Simd::ALL
        .into_iter()
        .filter(|s| {
            let ok = s.available();
            if !ok {
                eprintln!("this CPU has no {}: its path is not checked", s.name());
            }
            ok
        })
        .collect()
}

/// Rays a stream must answer as the single-ray calls do without a normal traversal.
pub(super) fn odd_rays() -> Vec<StreamRay> {
    let ray = |origin, dir, tmin, tmax| StreamRay {
        origin,
        dir,
        tmin,
        tmax,
    };
    let d = Vec3::new(0.3, -0.2, 0.9).normalize();
    vec![
        ray(Vec3::ZERO, Vec3::NAN, 0.0, f32::INFINITY),
        ray(
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            -Vec3::X,
            0.0,
            f32::INFINITY,
        ),
        ray(Vec3::new(0.0, 0.0, 1e30), -Vec3::Z, 0.0, f32::INFINITY),
        // An empty segment, a NaN end, and one wholly behind the origin.
        ray(Vec3::new(1.0, 2.0, -3.0), d, 5.0, 1.0),
        ray(Vec3::new(1.0, 2.0, -3.0), d, 0.0, f32::NAN),
        ray(Vec3::new(1.0, 2.0, 3.0), d, -30.0, -1.0),
        ray(Vec3::new(-1.0, 0.5, 2.0), -d, -30.0, -0.5),
    ]
}

/// The soup's random rays with the odd ones spread among them, and rays from the soup's
/// vertices along directions with zero components: their origins lie on box planes, where
/// a slab distance is 0 · ∞ = NaN and the order of `min`/`max` operands decides.
fn rays(rng: &mut Rng, prims: &[Primitive]) -> Vec<StreamRay> {
    let mut rays: Vec<StreamRay> = random_rays(rng, 20_000)
        .into_iter()
        .map(|(_, r)| r)
        .collect();
    for (i, r) in odd_rays().into_iter().enumerate() {
        rays.insert(1 + 2_311 * i, r);
    }
    for k in 0..2_000 {
        let Primitive::Triangle { v0, v1, v2 } = prims[k * 7 % prims.len()] else {
            continue;
        };
        let mut d = rng.v(-1.0, 1.0);
        d[k % 3] = if k % 2 == 0 { 0.0 } else { -0.0 };
        if k % 5 == 0 {
            d[(k + 1) % 3] = 0.0;
        }
        rays.push(StreamRay {
            origin: [v0, v1, v2][k % 3],
            dir: d.normalize_or(Vec3::Z),
            tmin: if k % 4 == 0 { 0.0 } else { -1e-3 },
            tmax: f32::INFINITY,
        });
    }
    rays
}

#[test]
fn streams_match_single_rays_bit_for_bit_on_every_path() {
    let mut rng = Rng(0x5EED_0F57_AE4D_0001);
    let prims = soup(&mut rng);
    let rays = rays(&mut rng, &prims);
    let mut accel = Accel::build(&prims);
    accel.set_simd(Simd::Sse2).unwrap();
    let single: Vec<_> = rays
        .iter()
        .map(|r| accel.intersect(r.origin, r.dir, r.tmin, r.tmax))
        .collect();
    let blocked: Vec<_> = rays
        .iter()
        .map(|r| accel.occluded(r.origin, r.dir, r.tmin, r.tmax))
        .collect();
    let found = single.iter().filter(|h| h.is_some()).count();
    assert!(found > 2_000 && found < 18_000, "{found} hits");
    assert!(blocked.iter().filter(|b| **b).count() > 2_000);
    assert!(blocked.iter().any(|b| !b));
    // Each slot starts wrong, so a slot the stream leaves alone fails.
    let wrong = Some(Hit {
        prim: u32::MAX,
        t: -1.0,
        b1: 0.0,
        b2: 0.0,
    });
    for simd in paths() {
        accel.set_simd(simd).unwrap();
        for (k, r) in rays.iter().enumerate() {
            let h = accel.intersect(r.origin, r.dir, r.tmin, r.tmax);
            assert_eq!(bits(h), bits(single[k]), "{simd:?} single ray {k}");
        }
        for len in [1, 3, 17, 256] {
            let mut hits = vec![wrong; rays.len()];
            let mut occ: Vec<bool> = blocked.iter().map(|b| !b).collect();
            for ((c, h), o) in rays
                .chunks(len)
                .zip(hits.chunks_mut(len))
                .zip(occ.chunks_mut(len))
            {
                accel.intersect_stream(c, h);
                accel.occluded_stream(c, o);
            }
            for k in 0..rays.len() {
                assert_eq!(bits(hits[k]), bits(single[k]), "{simd:?}, {len}, ray {k}");
                assert_eq!(occ[k], blocked[k], "{simd:?}, {len}, occlusion of ray {k}");
            }
        }
    }
}

/// Streams through node test `N` with hand-overs at every node below `hot`, against the
/// single-ray answers of `accel`.
fn check_streams<N: node::NodeTest>(accel: &Accel, rays: &[StreamRay], hot: u32, what: &str) {
    let w = accel.wide.as_ref().unwrap();
    let need = accel.stack_need;
    for len in [3, 256] {
        let mut hits = vec![None; rays.len()];
        let mut occ = vec![false; rays.len()];
        for ((c, h), o) in rays
            .chunks(len)
            .zip(hits.chunks_mut(len))
            .zip(occ.chunks_mut(len))
        {
            stream::closest_stream::<N>(w, need, hot, c, h);
            stream::occluded_stream::<N>(w, need, hot, c, o);
        }
        for (k, r) in rays.iter().enumerate() {
            let h = accel.intersect(r.origin, r.dir, r.tmin, r.tmax);
            assert_eq!(bits(hits[k]), bits(h), "{what}, hot {hot}, {len}, ray {k}");
            let b = accel.occluded(r.origin, r.dir, r.tmin, r.tmax);
            assert_eq!(occ[k], b, "{what}, hot {hot}, {len}, occlusion of ray {k}");
        }
    }
}

#[test]
fn every_hand_over_point_gives_the_same_answers() {
    // The soup's tree is small: with the usual threshold every node is a top one, so the
    // hand-overs at nodes are checked with lower ones.
    let mut rng = Rng(0x0DD_BA11);
    let prims = soup(&mut rng);
    let rays = rays(&mut rng, &prims);
    let mut accel = Accel::build(&prims);
    accel.set_simd(Simd::Sse2).unwrap();
    assert!(accel.wide.as_ref().unwrap().nodes.len() > 64);
    for hot in [0, 1, 9, 64] {
        check_streams::<node::Lanes4>(&accel, &rays, hot, "SSE2");
    }
}

#[test]
fn sixteen_lane_node_test_matches_on_this_cpu_as_arrays() {
    let mut rng = Rng(0xA11_1A7E5);
    let prims = soup(&mut rng);
    let rays = rays(&mut rng, &prims);
    let mut accel = Accel::build(&prims);
    accel.set_simd(Simd::Sse2).unwrap();
    for hot in [0, stream::HOT_NODES] {
        check_streams::<node16::Array16>(&accel, &rays, hot, "16 lanes as arrays");
    }
    let w = accel.wide.as_ref().unwrap();
    for (k, r) in rays.iter().enumerate() {
        if !(r.origin.is_finite() && r.dir.is_finite()) {
            continue;
        }
        let d = positive_zeros(r.dir);
        let single = traverse::with_stack(accel.stack_need, |s| {
            traverse::closest::<node16::Array16>(w, r.origin, d, r.tmin, r.tmax, s)
        });
        let h = accel.intersect(r.origin, r.dir, r.tmin, r.tmax);
        assert_eq!(bits(single), bits(h), "single ray {k}");
    }
}

#[test]
fn empty_scenes_and_streams_answer_nothing() {
    let a = Accel::build(&[]);
    let rays = odd_rays();
    let mut hits = vec![
        Some(Hit {
            prim: 0,
            t: 1.0,
            b1: 0.0,
            b2: 0.0,
        });
        rays.len()
    ];
    let mut occ = vec![true; rays.len()];
    a.intersect_stream(&rays, &mut hits);
    a.occluded_stream(&rays, &mut occ);
    assert!(hits.iter().all(|h| h.is_none()));
    assert!(occ.iter().all(|b| !b));
    let a = Accel::build(&[Primitive::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    }]);
    a.intersect_stream(&[], &mut []);
    a.occluded_stream(&[], &mut []);
}
