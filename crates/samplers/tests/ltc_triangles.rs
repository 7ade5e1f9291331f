//! BRDF-aware points on triangle lights (`--ltc-triangles`): the sampler against its own
//! density, its density at sampling against its replay, and the samples leaning into the lobe.
use brdf_integrals::{CapIntegral, Sptd};
use chi2_test::{chi2_directions, sidak_significance};
use render_core::frame::Frame;
use render_core::light::{Light, LightShape};
use render_core::light_points::LightPoints;
use render_core::rng::SampleStream;
use render_core::{Vec2, Vec3};
use samplers::brdf_oriented::importance::BoRecord;
use samplers::brdf_oriented::ltc_triangle::LtcTriangle;

fn triangle(p: [Vec3; 3]) -> Light {
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
        two_sided: true,
        spot: None,
    }
}

/// A glossy point at the origin (normal +z) seen from 40° off the normal, roughness `alpha`.
fn setup(alpha: f32) -> (BoRecord<<Sptd as CapIntegral>::Lobe>, LtcTriangle) {
    let wo = Vec3::new(40f32.to_radians().sin(), 0.0, 40f32.to_radians().cos());
    let lobe = Sptd::default().lobe(wo, alpha);
    let rec = BoRecord::from_parts(
        Vec3::ZERO,
        Frame::from_normal(Vec3::Z),
        lobe,
        1.0,
        0.0,
        true,
        false,
    );
    (rec, LtcTriangle::new(wo, alpha).expect("an invertible LTC"))
}

/// A large triangle over the point, straddling the mirror direction (−x, +z).
fn big_light() -> Light {
    triangle([
        Vec3::new(-3.0, -2.0, 1.0),
        Vec3::new(1.0, -2.0, 1.2),
        Vec3::new(-1.0, 2.5, 0.9),
    ])
}

/// The point where the ray from the origin along `w` meets the light, if it does.
fn along(l: &Light, w: Vec3) -> Option<(Vec3, Vec3)> {
    let LightShape::Triangle { p, normal, .. } = &l.shape else {
        return None;
    };
    let t = p[0].dot(*normal) / w.dot(*normal);
    let y = w * t;
    let s = |a: Vec3, b: Vec3| (b - a).cross(y - a).dot(*normal);
    let (s0, s1, s2) = (s(p[0], p[1]), s(p[1], p[2]), s(p[2], p[0]));
    let inside = (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0);
    (t > 0.0 && inside).then_some((y, *normal))
}

#[test]
fn ltc_points_match_their_density() {
    let sig = sidak_significance(0.01, 4);
    let l = big_light();
    for (k, (alpha, points)) in [
        (0.2, LightPoints::SolidAngle),
        (0.2, LightPoints::Area),
        (0.5, LightPoints::SolidAngleWarp),
        (0.08, LightPoints::SolidAngle),
    ]
    .into_iter()
    .enumerate()
    {
        let (rec, t) = setup(alpha);
        let out = chi2_directions(
            100_000,
            40,
            80,
            8,
            |i| {
                let mut r = SampleStream::new(60 + k as u64, i as u64, 0);
                t.sample(&rec, &l, points, &mut r).map(|s| s.wi)
            },
            |w| match along(&l, w) {
                Some((y, n)) => t.pdf(&rec, &l, points, y, n) as f64,
                None => 0.0,
            },
        );
        assert!(out.p_value > sig, "α {alpha}, {}: {out:?}", points.name());
    }
}

#[test]
fn ltc_density_at_sampling_is_its_replay_and_follows_the_lobe() {
    let l = big_light();
    let (rec, t) = setup(0.15);
    let mut r = SampleStream::new(70, 0, 0);
    let mirror = Vec3::new(-40f32.to_radians().sin(), 0.0, 40f32.to_radians().cos());
    let (mut near_ltc, mut near_plain, n) = (0, 0, 4000);
    for _ in 0..n {
        let s = t
            .sample(&rec, &l, LightPoints::SolidAngle, &mut r)
            .expect("the light faces the point");
        let replay = t.pdf(&rec, &l, LightPoints::SolidAngle, s.point, s.normal);
        assert!(
            (s.pdf - replay).abs() <= 1e-5 * s.pdf,
            "{} vs {replay}",
            s.pdf
        );
        near_ltc += (s.wi.dot(mirror) > 0.95) as u32;
        let u = r.next_2d();
        let plain = LightPoints::SolidAngle
            .sample(&l, Vec3::ZERO, Vec3::Z, u)
            .unwrap();
        near_plain += (plain.wi.dot(mirror) > 0.95) as u32;
    }
    // Half the samples follow the lobe: many more land near the mirror direction.
    assert!(near_ltc > 2 * near_plain, "{near_ltc} vs {near_plain}");
}
