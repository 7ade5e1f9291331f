use super::*;
use crate::rng::SampleStream;
use crate::spherical_triangle::bilinear_invert;
use chi2_test::{chi2_directions, sidak_significance};

fn triangle(p: [Vec3; 3], two_sided: bool) -> Light {
    let c = (p[1] - p[0]).cross(p[2] - p[0]);
    Light {
        shape: LightShape::Triangle {
            p,
            normal: c.normalize(),
            area: 0.5 * c.length(),
            uv: [Vec2::ZERO; 3],
        },
        emission: Vec3::ONE,
        texture: None,
        mean_emission: Vec3::ONE,
        two_sided,
        spot: None,
    }
}

fn vertices(l: &Light) -> [Vec3; 3] {
    match &l.shape {
        LightShape::Triangle { p, .. } => *p,
        _ => unreachable!(),
    }
}

/// A large triangle close to the receiver (about 1.4 sr from the origin), facing it.
fn close() -> Light {
    triangle(
        [
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(0.0, 1.5, 0.8),
            Vec3::new(2.0, -0.5, 1.5),
        ],
        false,
    )
}

/// A receiver normal tilted away from the light, so that the warp matters.
fn receiver_normal() -> Vec3 {
    Vec3::new(0.6, 0.2, 0.77).normalize()
}

/// Where the ray from `x` along `w` meets the light's plane, if inside the triangle.
fn point_along(l: &Light, x: Vec3, w: Vec3) -> Option<(Vec3, Vec3)> {
    let LightShape::Triangle { p, normal, .. } = &l.shape else {
        return None;
    };
    let t = (p[0] - x).dot(*normal) / w.dot(*normal);
    let y = x + w * t;
    let inside = |a: Vec3, b: Vec3| (b - a).cross(y - a).dot(*normal) >= 0.0;
    (t > 0.0 && inside(p[0], p[1]) && inside(p[1], p[2]) && inside(p[2], p[0]))
        .then_some((y, *normal))
}

#[test]
fn every_sampler_matches_its_own_density() {
    let sig = sidak_significance(0.01, 6);
    let n = receiver_normal();
    let lights = [close(), triangle(vertices(&close()).map(|v| v * 3.0), true)];
    for (k, mode) in LightPoints::ALL.into_iter().enumerate() {
        for (j, l) in lights.iter().enumerate() {
            let out = chi2_directions(
                100_000,
                40,
                80,
                8,
                |i| {
                    let mut r = SampleStream::new(20 + k as u64, i as u64, j as u64);
                    mode.sample(l, Vec3::ZERO, n, r.next_2d()).map(|s| s.wi)
                },
                |w| match point_along(l, Vec3::ZERO, w) {
                    Some((y, ny)) => mode.pdf(l, Vec3::ZERO, n, y, ny) as f64,
                    None => 0.0,
                },
            );
            assert!(out.p_value > sig, "{} light {j}: {out:?}", mode.name());
        }
    }
}

#[test]
fn sampled_density_is_the_evaluated_density_and_inverts() {
    let n = receiver_normal();
    let lights = [
        close(),
        triangle(vertices(&close()), true),
        // a sliver seen nearly edge-on
        triangle(
            [
                Vec3::new(-1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(0.2, 2e-2, 1.001),
            ],
            true,
        ),
    ];
    for mode in [LightPoints::SolidAngle, LightPoints::SolidAngleWarp] {
        let mut r = SampleStream::new(30, 0, 0);
        for l in &lights {
            let p = vertices(l);
            let st = SphericalTriangle::new(Vec3::ZERO, &p).unwrap();
            let ws = st.cosine_weights(n);
            for _ in 0..500 {
                let u = r.next_2d();
                let Some(s) = mode.sample(l, Vec3::ZERO, n, u) else {
                    continue;
                };
                let replay = mode.pdf(l, Vec3::ZERO, n, s.point, s.normal);
                assert_eq!(s.pdf.to_bits(), replay.to_bits(), "{}", mode.name());
                assert!((s.point.length() - s.dist).abs() < 1e-5 * s.dist);
                let mut back = st.invert(s.point.as_dvec3().normalize());
                if mode == LightPoints::SolidAngleWarp {
                    back = bilinear_invert(back, ws);
                }
                let err = (back[0] - u.x as f64)
                    .abs()
                    .max((back[1] - u.y as f64).abs());
                assert!(err < 1e-4, "{}: {u:?} -> {back:?}", mode.name());
            }
        }
    }
}

#[test]
fn area_sampling_stands_in_outside_the_thresholds() {
    let n = receiver_normal();
    let e = 2e-3_f32; // 1e-6 sr from the origin
    let tiny = triangle(
        [
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(0.0, e, 2.0),
            Vec3::new(e, 0.0, 2.0),
        ],
        false,
    );
    let hemisphere = triangle(
        [
            Vec3::new(-300.0, -200.0, 0.3),
            Vec3::new(0.0, 400.0, 0.3),
            Vec3::new(300.0, -200.0, 0.3),
        ],
        false,
    );
    let near = triangle(
        [
            Vec3::new(-30.0, -20.0, 0.3),
            Vec3::new(0.0, 40.0, 0.3),
            Vec3::new(30.0, -20.0, 0.3),
        ],
        false,
    );
    let solid = |l: &Light| {
        SphericalTriangle::new(Vec3::ZERO, &vertices(l))
            .unwrap()
            .solid_angle()
    };
    assert!(solid(&tiny) < MIN_SOLID_ANGLE && solid(&hemisphere) > MAX_SOLID_ANGLE);
    assert!(solid(&near) > 6.0 && solid(&near) < MAX_SOLID_ANGLE);
    let mut r = SampleStream::new(40, 0, 0);
    for mode in LightPoints::ALL {
        for l in [&tiny, &hemisphere] {
            for _ in 0..200 {
                let u = r.next_2d();
                let (a, b) = (l.sample(Vec3::ZERO, u), mode.sample(l, Vec3::ZERO, n, u));
                let (a, b) = (a.unwrap(), b.unwrap());
                assert_eq!((a.point, a.pdf), (b.point, b.pdf));
                let pdf = mode.pdf(l, Vec3::ZERO, n, b.point, b.normal);
                assert_eq!(pdf, l.pdf(Vec3::ZERO, b.point, b.normal));
            }
        }
        // Near a hemisphere, still in solid angle: every sample lands on the light with the
        // density 1/Ω (or the warp's, which averages to it).
        let (mut sum, count) = (0.0, 2000);
        for _ in 0..count {
            let s = mode.sample(&near, Vec3::ZERO, n, r.next_2d()).unwrap();
            assert!(s.pdf.is_finite() && s.pdf > 0.0 && (s.point.z - 0.3).abs() < 1e-6);
            sum += 1.0 / s.pdf as f64;
        }
        if mode != LightPoints::Area {
            let mean = sum / count as f64;
            assert!(
                (mean / solid(&near) - 1.0).abs() < 0.05,
                "{}: {mean}",
                mode.name()
            );
        }
    }
}

#[test]
fn one_sided_lights_stay_dark_from_behind() {
    let back = triangle(
        [
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(2.0, -0.5, 1.5),
            Vec3::new(0.0, 1.5, 0.8),
        ],
        false,
    );
    let mut r = SampleStream::new(50, 0, 0);
    for mode in LightPoints::ALL {
        assert!((0..50).all(|_| {
            mode.sample(&back, Vec3::ZERO, Vec3::Z, r.next_2d())
                .is_none()
        }));
        let (p, nl) = (Vec3::new(0.2, 0.0, 1.1), Vec3::Z);
        assert_eq!(mode.pdf(&back, Vec3::ZERO, Vec3::Z, p, nl), 0.0);
    }
}

#[test]
fn names_parse_back() {
    for m in LightPoints::ALL {
        assert_eq!(LightPoints::parse(m.name()), Ok(m));
    }
    let err = LightPoints::parse("cone").unwrap_err();
    assert!(err.contains("solid-angle-warp"), "{err}");
}
