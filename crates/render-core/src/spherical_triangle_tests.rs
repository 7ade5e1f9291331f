use super::*;
use crate::rng::SampleStream;
use chi2_test::{DirectionGrid, chi2_directions_on, sidak_significance};

/// Where the ray from `x` along `w` meets the triangle `p`, if it does.
fn hits(x: Vec3, p: &[Vec3; 3], w: DVec3) -> bool {
    let (x, w) = (x.as_dvec3(), w);
    let q = p.map(|v| v.as_dvec3() - x);
    let s = |i: usize, j: usize| q[i].cross(q[j]).dot(w);
    let (s0, s1, s2) = (s(0, 1), s(1, 2), s(2, 0));
    (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0)
}

/// Triangles from big and close to slivers and far away: (vertices, viewpoint).
fn cases() -> Vec<([Vec3; 3], Vec3)> {
    vec![
        (
            [Vec3::X, Vec3::Y, Vec3::Z], // an octant: π/2 sr
            Vec3::ZERO,
        ),
        (
            [
                Vec3::new(-1.0, -1.0, 1.0),
                Vec3::new(2.0, -0.5, 1.5),
                Vec3::new(0.0, 1.5, 0.8),
            ],
            Vec3::ZERO,
        ),
        // a sliver: 2 long, 1e-3 wide
        (
            [
                Vec3::new(-1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(0.2, 1e-3, 1.0),
            ],
            Vec3::ZERO,
        ),
        // nearly a hemisphere: a large triangle just above the viewpoint
        (
            [
                Vec3::new(-30.0, -20.0, 0.3),
                Vec3::new(30.0, -20.0, 0.3),
                Vec3::new(0.0, 40.0, 0.3),
            ],
            Vec3::ZERO,
        ),
        // grazing: the viewpoint close to the triangle's plane, beside it
        (
            [
                Vec3::new(1.0, 0.0, 0.02),
                Vec3::new(3.0, -1.0, 0.02),
                Vec3::new(3.0, 1.0, 0.03),
            ],
            Vec3::ZERO,
        ),
    ]
}

#[test]
fn solid_angles_of_known_triangles() {
    let oct = SphericalTriangle::new(Vec3::ZERO, &[Vec3::X, Vec3::Y, Vec3::Z]).unwrap();
    assert!((oct.solid_angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    // A tiny triangle far away: area × cos / d² to first order, here 1e-6 sr.
    let e = 2e-3_f32;
    let small = [
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(e, 0.0, 2.0),
        Vec3::new(0.0, e, 2.0),
    ];
    let st = SphericalTriangle::new(Vec3::ZERO, &small).unwrap();
    let expected = 0.5 * (e as f64).powi(2) / 4.0;
    assert!(
        (st.solid_angle() / expected - 1.0).abs() < 1e-3,
        "{}",
        st.solid_angle()
    );
    let hemi = SphericalTriangle::new(Vec3::ZERO, &cases()[3].0).unwrap();
    assert!(hemi.solid_angle() > 6.0 && hemi.solid_angle() < 2.0 * std::f64::consts::PI);
    // In the plane, or on a vertex: nothing to sample.
    assert!(
        SphericalTriangle::new(Vec3::new(0.5, 0.5, 1.0), &small.map(|p| p - Vec3::Z)).is_none()
    );
    assert!(SphericalTriangle::new(small[0], &small).is_none());
}

#[test]
fn samples_fall_in_the_triangle_and_invert_to_their_numbers() {
    let mut rng = SampleStream::new(11, 0, 0);
    for (p, x) in cases() {
        let st = SphericalTriangle::new(x, &p).unwrap();
        for _ in 0..2000 {
            let u = rng.next_2d();
            let u = [u.x as f64, u.y as f64];
            let w = st.sample(u).unwrap();
            assert!((w.length() - 1.0).abs() < 1e-12);
            assert!(hits(x, &p, w), "{p:?} {u:?}");
            let back = st.invert(w);
            assert!(
                (back[0] - u[0]).abs() < 1e-4 && (back[1] - u[1]).abs() < 1e-4,
                "{p:?}: {u:?} -> {back:?}"
            );
        }
    }
}

#[test]
fn bilinear_warp_inverts_and_its_density_integrates_to_one() {
    let ws = [
        [1.0, 1.0, 1.0, 1.0],
        [0.01, 0.5, 1.0, 0.2],
        [0.9, 0.01, 0.01, 0.3],
    ];
    let mut rng = SampleStream::new(12, 0, 0);
    for w in ws {
        for _ in 0..1000 {
            let xi = rng.next_2d();
            let xi = [xi.x as f64, xi.y as f64];
            let u = bilinear_sample(xi, w);
            let back = bilinear_invert(u, w);
            assert!((back[0] - xi[0]).abs() < 1e-9 && (back[1] - xi[1]).abs() < 1e-9);
        }
        let n = 200;
        let mean: f64 = (0..n * n)
            .map(|k| {
                let u = [
                    ((k % n) as f64 + 0.5) / n as f64,
                    ((k / n) as f64 + 0.5) / n as f64,
                ];
                bilinear_pdf(u, w)
            })
            .sum::<f64>()
            / (n * n) as f64;
        assert!((mean - 1.0).abs() < 1e-6, "{mean}");
    }
}

/// Directions drawn uniformly (`warp` None) or by the warp of normal `n`, against the density
/// 1/Ω × the warp's density at the inverted numbers.
fn chi2(p: [Vec3; 3], x: Vec3, warp: Option<Vec3>, seed: u64) -> f64 {
    let st = SphericalTriangle::new(x, &p).unwrap();
    let weights = warp.map(|n| st.cosine_weights(n));
    // A grid around the triangle's mean direction, so that even small triangles span bins.
    let axis = (p[0] + p[1] + p[2] - 3.0 * x).normalize();
    let spread = st
        .vertices()
        .iter()
        .map(|v| v.dot(axis.as_dvec3()))
        .fold(1.0, f64::min);
    let grid = DirectionGrid {
        theta_bins: 10,
        phi_bins: 20,
        axis,
        cos_min: 1.0 - (1.0 - spread) * 1.05 - 1e-6,
        pdf_subdivisions: 16,
    };
    chi2_directions_on(
        &grid,
        100_000,
        |i| {
            let mut r = SampleStream::new(seed, i as u64, 0);
            let xi = r.next_2d();
            let xi = [xi.x as f64, xi.y as f64];
            let u = weights.map_or(xi, |w| bilinear_sample(xi, w));
            st.sample(u).map(|w| w.as_vec3())
        },
        |w| {
            let w = w.as_dvec3().normalize();
            if !hits(x, &p, w) {
                return 0.0;
            }
            let warp = weights.map_or(1.0, |ws| bilinear_pdf(st.invert(w), ws));
            warp / st.solid_angle()
        },
    )
    .p_value
}

/// Histograms cannot resolve the sliver, the grazing view or the rim of the near-hemisphere
/// (thinner than a bin); the Jacobian test covers those.
#[test]
fn sampled_directions_match_their_density() {
    let sig = sidak_significance(0.01, 4);
    let c = cases();
    let n = Vec3::new(0.3, -0.2, 0.93).normalize();
    for (k, (p, x)) in [&c[0], &c[1]].into_iter().enumerate() {
        let pv = chi2(*p, *x, None, k as u64);
        assert!(pv > sig, "case {k}: {pv}");
        assert!(
            chi2(*p, *x, Some(n), 10 + k as u64) > sig,
            "case {k}, warped"
        );
    }
}

/// Uniform in solid angle: the map from the square has the Jacobian Ω everywhere (by central
/// differences), which also covers the sliver that no histogram resolves.
#[test]
fn the_map_has_a_constant_jacobian() {
    let mut rng = SampleStream::new(13, 0, 0);
    for (p, x) in cases() {
        let st = SphericalTriangle::new(x, &p).unwrap();
        for _ in 0..200 {
            let u = rng.next_2d();
            let u = [0.01 + 0.98 * u.x as f64, 0.01 + 0.98 * u.y as f64];
            let e = 1e-5;
            let at = |a: f64, b: f64| st.sample([u[0] + a, u[1] + b]).unwrap();
            let du = (at(e, 0.0) - at(-e, 0.0)) / (2.0 * e);
            let dv = (at(0.0, e) - at(0.0, -e)) / (2.0 * e);
            let jac = du.cross(dv).length();
            assert!(
                (jac / st.solid_angle() - 1.0).abs() < 1e-3,
                "{p:?} {u:?}: {jac} vs {}",
                st.solid_angle()
            );
        }
    }
}
