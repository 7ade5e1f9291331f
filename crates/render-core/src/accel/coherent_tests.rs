//! Packets against single rays: each ray's closest hit, traced in a packet of any fill on
//! every SIMD path this CPU has, is `Accel::intersect`'s (primitive, distance and
//! barycentrics, bit for bit) but at a tie whose box entry rounds beyond the hit (there: the
//! same distance, and the packet's primitive is hit at it), for incoherent rays (the soup's,
//! with the streams' odd ones among them) and for coherent ones (a pinhole's rays).
use super::simd_paths_tests::{Rng, bits, random_rays, soup};
use super::*;

/// Rays from one point through a grid, as a tile's camera rays, row by row.
fn camera_rays(eye: Vec3, n: usize) -> Vec<StreamRay> {
    let mut rays = Vec::new();
    for y in 0..n {
        for x in 0..n {
            let film = Vec3::new(x as f32 / n as f32 - 0.5, y as f32 / n as f32 - 0.5, 1.0);
            rays.push(StreamRay {
                origin: eye,
                dir: film.normalize(),
                tmin: 0.0,
                tmax: f32::INFINITY,
            });
        }
    }
    rays
}

#[test]
fn packets_give_the_single_ray_hits_on_every_path() {
    let mut rng = Rng(0x5EED_0F57_AE4D_0002);
    let prims = soup(&mut rng);
    let mut rays: Vec<StreamRay> = random_rays(&mut rng, 20_000)
        .into_iter()
        .map(|(_, r)| r)
        .collect();
    // The streams' odd rays (non-finite, far away, empty and NaN segments, segments behind
    // the origin) spread over packets of every position.
    for (k, odd) in super::stream_tests::odd_rays().into_iter().enumerate() {
        for j in 0..3 {
            rays.insert(k * 1_999 + j * 7 + k, odd);
        }
    }
    for eye in [Vec3::new(0.1, 0.2, -3.0), Vec3::new(-0.4, 0.3, -1.5)] {
        rays.extend(camera_rays(eye, 96));
    }
    let mut accel = Accel::build(&prims);
    let wrong = Some(Hit {
        prim: u32::MAX,
        t: -1.0,
        b1: 0.0,
        b2: 0.0,
    });
    let (mut found, mut ties) = (0, 0);
    for simd in Simd::ALL {
        if !simd.available() {
            eprintln!("this CPU has no {}: its path is not checked", simd.name());
            continue;
        }
        accel.set_simd(simd).unwrap();
        let single: Vec<_> = rays
            .iter()
            .map(|r| accel.intersect(r.origin, r.dir, r.tmin, r.tmax))
            .collect();
        found = single.iter().filter(|h| h.is_some()).count();
        for len in [1, 5, 8, 64, 1000] {
            let mut hits = vec![wrong; rays.len()];
            for (c, h) in rays.chunks(len).zip(hits.chunks_mut(len)) {
                accel.intersect_packets(c, h);
            }
            for k in 0..rays.len() {
                let (p, s) = (hits[k], single[k]);
                if bits(p) == bits(s) {
                    continue;
                }
                // Only at an exact tie whose other primitive's box entry rounds beyond the
                // shared distance (docs/notes/rays.md, "Ties"): the same distance, and the
                // packet's primitive really is hit there.
                let (p, s) = (p.unwrap(), s.unwrap());
                assert_eq!(p.t.to_bits(), s.t.to_bits(), "{simd:?}, {len}, ray {k}");
                let r = rays[k];
                let alone = Accel::build(&prims[p.prim as usize..=p.prim as usize]);
                let h = alone.intersect(r.origin, r.dir, r.tmin, r.tmax).unwrap();
                assert_eq!(h.t.to_bits(), p.t.to_bits(), "{simd:?}, {len}, ray {k}");
                ties += 1;
            }
        }
    }
    assert!(found > 5_000 && found < rays.len() - 2_000, "{found} hits");
    eprintln!("{ties} answers differed at a tie (rays × paths × lengths)");
}

/// The packet loop over plain 4-lane node tests (the fallback off x86-64) agrees too.
#[test]
fn packets_through_the_four_lane_test_match() {
    let mut rng = Rng(0x5EED_0F57_AE4D_0003);
    let prims = soup(&mut rng);
    let rays = camera_rays(Vec3::new(0.0, 0.0, -2.5), 64);
    let accel = Accel::build(&prims);
    let w = accel.wide.as_ref().unwrap();
    let mut hits = vec![None; rays.len()];
    coherent::closest_packets::<node::Lanes4>(w, accel.stack_need, &rays, &mut hits);
    for (k, r) in rays.iter().enumerate() {
        let h = accel.intersect(r.origin, r.dir, r.tmin, r.tmax);
        assert_eq!(bits(hits[k]), bits(h), "ray {k}");
    }
}
