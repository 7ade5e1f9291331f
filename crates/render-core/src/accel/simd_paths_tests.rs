//! The AVX2 and SSE2 traversals against each other and against a brute-force loop over
//! every primitive with the scalar tests the obvhs-based traversal used.
use super::*;
use glam::Vec3A;

/// Möller–Trumbore as the obvhs closure computed it: (t, b1, b2), t = ∞ on a miss.
fn scalar_triangle(
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
    o: Vec3,
    d: Vec3,
    tmin: f32,
    tmax: f32,
) -> (f32, f32, f32) {
    let (v0, e1, e2): (Vec3A, Vec3A, Vec3A) = (v0.into(), (v1 - v0).into(), (v2 - v0).into());
    let (o, d): (Vec3A, Vec3A) = (o.into(), d.into());
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let inv = 1.0 / det;
    let s = o - v0;
    let b1 = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&b1) {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let q = s.cross(e1);
    let b2 = d.dot(q) * inv;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let t = e2.dot(q) * inv;
    if t >= tmin && t <= tmax {
        (t, b1, b2)
    } else {
        (f32::INFINITY, 0.0, 0.0)
    }
}

/// The ray–sphere test the obvhs closure used.
fn scalar_sphere(c: Vec3, radius: f32, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> f32 {
    let (c, o, d): (Vec3A, Vec3A, Vec3A) = (c.into(), o.into(), d.into());
    let f = o - c;
    let tca = -f.dot(d);
    let perp = f + d * tca;
    let h2 = radius * radius - perp.length_squared();
    if h2 < 0.0 {
        return f32::INFINITY;
    }
    let h = h2.sqrt();
    let t0 = tca - h;
    if t0 >= tmin && t0 <= tmax {
        return t0;
    }
    let t1 = tca + h;
    if t1 >= tmin && t1 <= tmax {
        t1
    } else {
        f32::INFINITY
    }
}

/// Closest hit by testing every primitive in index order, keeping strictly nearer ones: the
/// nearest, ties to the lowest index, which is the traversal's rule.
fn brute_force(prims: &[Primitive], o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
    let d = d + Vec3::ZERO;
    let mut best = None;
    let mut far = tmax;
    for (i, p) in prims.iter().enumerate() {
        let (t, b1, b2) = match *p {
            Primitive::Triangle { v0, v1, v2 } => scalar_triangle(v0, v1, v2, o, d, tmin, far),
            Primitive::Sphere { center, radius } => {
                (scalar_sphere(center, radius, o, d, tmin, far), 0.0, 0.0)
            }
        };
        if t < far {
            far = t;
            best = Some(Hit {
                prim: i as u32,
                t,
                b1,
                b2,
            });
        }
    }
    best
}

/// xorshift64*: the test's own reproducible numbers in [0, 1).
pub(super) struct Rng(pub(super) u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
    }
    pub(super) fn v(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.f(), self.f(), self.f()) * (hi - lo) + Vec3::splat(lo)
    }
}

/// A random soup: small triangles, some long thin ones, a few sharing edges, and spheres.
pub(super) fn soup(rng: &mut Rng) -> Vec<Primitive> {
    let mut prims = Vec::new();
    for k in 0..3000 {
        let v0 = rng.v(-10.0, 10.0);
        let size = if k % 10 == 0 { 8.0 } else { 0.8 };
        let v1 = v0 + rng.v(-size, size);
        let v2 = v0 + rng.v(-size, size);
        prims.push(Primitive::Triangle { v0, v1, v2 });
        if k % 7 == 0 {
            // A neighbour across the edge v1–v2.
            prims.push(Primitive::Triangle {
                v0: v2,
                v1,
                v2: v1 + v2 - v0,
            });
        }
        if k % 13 == 0 {
            prims.push(Primitive::Sphere {
                center: rng.v(-10.0, 10.0),
                radius: 0.01 + rng.f(),
            });
        }
    }
    prims
}

pub(super) fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.prim, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
}

/// `n` random rays through the soup's box, numbered, without the zero directions: some
/// axis-aligned and some with zero components of both signs, a third of them finite segments.
pub(super) fn random_rays(rng: &mut Rng, n: usize) -> Vec<(usize, StreamRay)> {
    let mut rays = Vec::new();
    for k in 0..n {
        let o = rng.v(-12.0, 12.0);
        let mut d = rng.v(-1.0, 1.0);
        match k % 11 {
            0 => d.x = 0.0,
            1 => d = Vec3::new(-0.0, 0.0, d.z),
            2 => d = Vec3::new(0.0, d.y, -0.0),
            _ => {}
        }
        if d == Vec3::ZERO {
            continue;
        }
        let (tmin, tmax) = if k % 3 == 0 {
            (0.5, 4.0 + 20.0 * rng.f())
        } else {
            (0.0, f32::INFINITY)
        };
        let dir = d.normalize();
        rays.push((
            k,
            StreamRay {
                origin: o,
                dir,
                tmin,
                tmax,
            },
        ));
    }
    rays
}

#[test]
fn avx2_and_sse2_agree_bit_for_bit_and_match_brute_force() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let prims = soup(&mut rng);
    let mut sse = Accel::build(&prims);
    sse.set_simd(Simd::Sse2).unwrap();
    let fast = Accel::build(&prims);
    if fast.simd() == Simd::Sse2 {
        eprintln!("no AVX2 on this CPU: only the SSE2 path is checked against brute force");
    }
    let (mut hits, mut blocked) = (0, 0);
    for (k, r) in random_rays(&mut rng, 20_000) {
        let (o, d, tmin, tmax) = (r.origin, r.dir, r.tmin, r.tmax);
        let a = fast.intersect(o, d, tmin, tmax);
        let b = sse.intersect(o, d, tmin, tmax);
        assert_eq!(bits(a), bits(b), "closest hit, ray {k}");
        let r = brute_force(&prims, o, d, tmin, tmax);
        assert_eq!(
            a.map(|h| h.t.to_bits()),
            r.map(|h| h.t.to_bits()),
            "distance, ray {k}"
        );
        // Ties (shared edges) included: the same primitive and barycentrics.
        assert_eq!(bits(a), bits(r), "closest hit against brute force, ray {k}");
        let oa = fast.occluded(o, d, tmin, tmax);
        assert_eq!(oa, sse.occluded(o, d, tmin, tmax), "occlusion, ray {k}");
        assert_eq!(oa, r.is_some(), "occlusion against brute force, ray {k}");
        hits += a.is_some() as u32;
        blocked += oa as u32;
    }
    // The rays must exercise both outcomes.
    assert!(hits > 2000 && hits < 18_000, "{hits} hits");
    assert!(blocked > 2000, "{blocked} occluded");
}

#[test]
fn forcing_a_path_the_cpu_lacks_is_an_error() {
    let mut a = Accel::build(&[]);
    for simd in Simd::ALL {
        let r = a.set_simd(simd);
        assert_eq!(r.is_ok(), simd.available(), "{simd:?}");
        if let Err(e) = r {
            assert!(e.contains(simd.name()), "{e}");
        }
    }
    assert!(Simd::detect().available());
    assert!(a.set_simd(Simd::Sse2).is_ok());
    assert!(
        a.intersect(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY)
            .is_none()
    );
    assert!(!a.occluded(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY));
}

#[test]
fn non_finite_and_far_away_rays_end_without_a_loop() {
    // A NaN direction passes every box test (NaN distances are kept conservative): the
    // empty child slots must not lead anywhere, and such rays find nothing.
    let mut rng = Rng(7);
    let prims = soup(&mut rng);
    let mut sse = Accel::build(&prims);
    sse.set_simd(Simd::Sse2).unwrap();
    let fast = Accel::build(&prims);
    for (o, d) in [
        (Vec3::ZERO, Vec3::NAN),
        (Vec3::new(f32::INFINITY, 0.0, 0.0), -Vec3::X),
        (Vec3::new(0.0, 0.0, 1e30), -Vec3::Z),
        (Vec3::new(3.0, 2.0, 1e30), Vec3::new(0.0, 0.0, -1.0)),
    ] {
        for a in [&fast, &sse] {
            let h = a.intersect(o, d, 0.0, f32::INFINITY);
            assert_eq!(bits(h), bits(fast.intersect(o, d, 0.0, f32::INFINITY)));
            assert_eq!(
                a.occluded(o, d, 0.0, f32::INFINITY),
                fast.occluded(o, d, 0.0, f32::INFINITY)
            );
            if !(o.is_finite() && d.is_finite()) {
                assert!(h.is_none());
            }
        }
    }
}

/// Two triangles across a shared edge, hit exactly on it at the same distance: the lower
/// index wins whichever is numbered first, on every path, single and streamed, so the hit
/// does not depend on the order a traversal meets them. (A filler grid around them gives
/// the tree several levels.)
#[test]
fn an_exact_tie_goes_to_the_lowest_index() {
    let a = Primitive::Triangle {
        v0: Vec3::new(0.0, 0.0, 0.0),
        v1: Vec3::new(1.0, 0.0, 0.0),
        v2: Vec3::new(0.0, 1.0, 0.0),
    };
    let b = Primitive::Triangle {
        v0: Vec3::new(1.0, 0.0, 0.0),
        v1: Vec3::new(1.0, 1.0, 0.0),
        v2: Vec3::new(0.0, 1.0, 0.0),
    };
    let filler = (0..64).map(|k| {
        let c = Vec3::new((k % 8) as f32 * 3.0 + 4.0, (k / 8) as f32 * 3.0, 0.0);
        Primitive::Triangle {
            v0: c,
            v1: c + Vec3::X,
            v2: c + Vec3::Y,
        }
    });
    let (o, d) = (Vec3::new(0.5, 0.5, 1.0), Vec3::new(0.0, 0.0, -1.0));
    let alone = |p: Primitive| Accel::build(&[p]).intersect(o, d, 0.0, f32::INFINITY);
    let (ta, tb) = (alone(a).unwrap().t, alone(b).unwrap().t);
    assert_eq!(ta.to_bits(), tb.to_bits(), "not a tie: the test needs one");
    for (first, second) in [(a, b), (b, a)] {
        let prims: Vec<Primitive> = [first, second].into_iter().chain(filler.clone()).collect();
        let mut accel = Accel::build(&prims);
        for simd in Simd::ALL.into_iter().filter(|s| s.available()) {
            accel.set_simd(simd).unwrap();
            let hit = accel.intersect(o, d, 0.0, f32::INFINITY).unwrap();
            assert_eq!((hit.prim, hit.t), (0, ta), "{simd:?}");
            let mut hits = vec![None; 3];
            let ray = StreamRay {
                origin: o,
                dir: d,
                tmin: 0.0,
                tmax: f32::INFINITY,
            };
            accel.intersect_stream(&[ray; 3], &mut hits);
            assert!(
                hits.iter().all(|h| h.is_some_and(|h| h.prim == 0)),
                "{simd:?}"
            );
        }
        assert_eq!(
            brute_force(&prims, o, d, 0.0, f32::INFINITY).unwrap().prim,
            0
        );
    }
}
