use super::*;
use crate::bsdf::Bsdf;
use crate::bsdf::microfacet::reflect;
use crate::rng::SampleStream;
use chi2_test::{DirectionGrid, chi2_directions_on, sidak_significance};
use glam::DVec3;

/// A dielectric BSDF on the plane z = 0 whose geometric normal is +z (glass below), seen from
/// `wo`: from below the viewer is inside the glass, looking out (η < 1).
fn glass(alpha: f32, ior: f32, wo: Vec3) -> Bsdf {
    let m = material("g", Vec3::ONE, ior, alpha);
    Bsdf::new(Vec3::Z, Vec3::Z, wo, m.params_at(Vec2::ZERO))
}

/// θ from +z in the xz plane: θ > π/2 is below the surface, inside the glass.
fn dir(theta: f32) -> Vec3 {
    Vec3::new(theta.sin(), 0.0, theta.cos())
}

/// (α, ior, θo): smooth to rough, grazing, and from inside the glass (θo > π/2: η = 1/ior),
/// including the total internal reflection beyond the critical angle.
const CASES: [(f32, f32, f32); 8] = [
    (0.05, 1.5, 0.3),
    (0.2, 1.5, 1.0),
    (0.6, 1.5, 0.2),
    (0.2, 1.5, 1.5),
    (0.2, 1.33, 2.8),
    (0.4, 1.5, 2.2),
    (0.1, 1.5, 1.7),
    (0.3, 0.8, 0.6),
];

/// Sampling matches its own density over the whole sphere (chi-square), reflected and
/// transmitted directions together. The grid's pole is across the plane of incidence, so that
/// both lobes lie near its equator, where its bins are even, and the edge of the transmitted
/// lobe's support at grazing ωo (microfacets seen edge-on, all refracting to cos θi = −cos θo/η)
/// crosses bins instead of running along one.
#[test]
fn sampling_matches_pdf_chi2() {
    let sig = sidak_significance(0.01, CASES.len());
    let grid = DirectionGrid {
        axis: Vec3::Y,
        ..DirectionGrid::sphere(40, 80, 8)
    };
    for (k, &(alpha, ior, theta)) in CASES.iter().enumerate() {
        let wo = dir(theta);
        let b = glass(alpha, ior, wo);
        let out = chi2_directions_on(
            &grid,
            200_000,
            |i| {
                let mut r = SampleStream::new(200 + k as u64, i as u64, 0);
                b.sample(wo, r.next_f32(), r.next_2d()).map(|s| s.wi)
            },
            |w| b.pdf(wo, w) as f64,
        );
        assert!(
            out.p_value > sig,
            "case {k} (α={alpha}, ior={ior}, θo={theta}): {out:?}"
        );
    }
}

/// A sample's value and density are those `eval_cos`, `pdf` and `eval` give later for the
/// same direction, and both sides of the surface are reached.
#[test]
fn sample_agrees_with_eval_and_pdf() {
    for (k, &(alpha, ior, theta)) in CASES.iter().enumerate() {
        let wo = dir(theta);
        let b = glass(alpha, ior, wo);
        let mut r = SampleStream::new(k as u64, 1, 0);
        let (mut up, mut down) = (0, 0);
        for _ in 0..2000 {
            let Some(s) = b.sample(wo, r.next_f32(), r.next_2d()) else {
                continue;
            };
            assert_eq!(s.pdf.to_bits(), b.pdf(wo, s.wi).to_bits(), "case {k}");
            assert_eq!(s.f_cos, b.eval_cos(wo, s.wi), "case {k}");
            let v = b.eval(wo, s.wi);
            assert_eq!((v.f_cos, v.pdf), (s.f_cos, s.pdf), "case {k}");
            assert!(s.pdf > 0.0 && s.f_cos.is_finite() && s.f_cos.min_element() >= 0.0);
            if s.wi.dot(wo.z.signum() * Vec3::Z) > 0.0 {
                up += 1;
            } else {
                down += 1;
            }
        }
        assert!(up > 0, "case {k}: some reflection");
        // past the critical angle from inside every microfacet reflects
        if !(theta > 1.6 && (theta - std::f32::consts::PI).abs() > 0.75) {
            assert!(down > 0, "case {k}: some transmission");
        }
    }
}

/// Walter et al.'s BSDF written out in f64 with absolute indices (ηo on the viewer's side, ηt
/// beyond), height-correlated G: f·|cos θi|.
fn reference_f_cos(alpha: f64, eta_o: f64, eta_t: f64, wo: Vec3, wi: Vec3) -> f64 {
    let (wo, wi) = (wo.as_dvec3(), wi.as_dvec3());
    let n = DVec3::Z * wo.z.signum();
    let reflect = wi.dot(n) > 0.0;
    let eta_i = if reflect { eta_o } else { eta_t };
    let mut h = if reflect {
        wo + wi
    } else {
        eta_o * wo + eta_i * wi
    }
    .normalize();
    if h.dot(n) < 0.0 {
        h = -h;
    }
    let a2 = alpha * alpha;
    let c = h.dot(n);
    let d = a2 / (std::f64::consts::PI * (c * c * (a2 - 1.0) + 1.0).powi(2));
    let lambda = |w: DVec3| 0.5 * ((1.0 + a2 * (1.0 - w.z * w.z) / (w.z * w.z)).sqrt() - 1.0);
    let g = 1.0 / (1.0 + lambda(wo) + lambda(wi));
    let (oh, ih) = (wo.dot(h), wi.dot(h));
    let f = {
        let st = eta_o / eta_t * (1.0 - oh * oh).sqrt();
        if st >= 1.0 {
            1.0
        } else {
            let ct = (1.0 - st * st).sqrt();
            let rs = (eta_o * oh - eta_t * ct) / (eta_o * oh + eta_t * ct);
            let rp = (eta_t * oh - eta_o * ct) / (eta_t * oh + eta_o * ct);
            0.5 * (rs * rs + rp * rp)
        }
    };
    let (co, ci) = (wo.dot(n).abs(), wi.dot(n).abs());
    if reflect {
        return f * d * g / (4.0 * co);
    }
    let fr = (ih * oh).abs() / (ci * co) * eta_o * eta_o * (1.0 - f) * g * d
        / (eta_i * ih + eta_o * oh).powi(2);
    fr * ci
}

/// The value against the paper's formula, from outside and from inside the glass.
#[test]
fn eval_matches_walter_formula() {
    for (alpha, ior) in [(0.1f32, 1.5f32), (0.4, 1.33), (0.25, 0.8)] {
        for (to, ti, phi) in [
            (0.3f32, 2.9f32, 3.0f32),
            (0.8, 2.5, 3.1),
            (1.2, 2.0, 2.5),
            (0.5, 0.6, 3.1),
            (2.6, 0.4, 3.0),
            (2.8, 2.7, 3.1),
        ] {
            let wo = dir(to);
            let wi = Vec3::new(ti.sin() * phi.cos(), ti.sin() * phi.sin(), ti.cos());
            let b = glass(alpha, ior, wo);
            let (eta_o, eta_t) = if wo.z > 0.0 { (1.0, ior) } else { (ior, 1.0) };
            let want = reference_f_cos(alpha as f64, eta_o as f64, eta_t as f64, wo, wi);
            let got = b.eval_cos(wo, wi).x as f64;
            assert!(
                (got - want).abs() <= 1e-4 * want.abs() + 1e-7,
                "α {alpha} ior {ior} θo {to} θi {ti}: {got} vs {want}"
            );
        }
    }
}

/// Reflection is symmetric, transmission reciprocal in the generalised form
/// f(ωo, ωi)/ηo² = f(ωi, ωo)/ηi² (the BTDF carries radiance's (ηo/ηi)²).
#[test]
fn reciprocity_holds_with_the_radiance_scaling() {
    let mut r = SampleStream::new(17, 0, 0);
    let ior = 1.5f32;
    let mut checked = 0;
    for _ in 0..2000 {
        let wo = crate::sampling::uniform_sphere(r.next_2d());
        let wi = crate::sampling::uniform_sphere(r.next_2d());
        let (a, b) = (glass(0.3, ior, wo), glass(0.3, ior, wi));
        let f_oi = a.eval_cos(wo, wi).x / wi.z.abs();
        let f_io = b.eval_cos(wi, wo).x / wo.z.abs();
        let index = |w: Vec3| if w.z > 0.0 { 1.0 } else { ior };
        let (lhs, rhs) = (f_oi / index(wo).powi(2), f_io / index(wi).powi(2));
        assert!(
            (lhs - rhs).abs() <= 1e-3 * lhs.abs().max(rhs.abs()) + 1e-6,
            "{wo} {wi}: {lhs} vs {rhs}"
        );
        checked += (lhs > 0.0) as usize;
    }
    assert!(checked > 1000, "{checked} pairs with a value");
}

/// Reflected and transmitted energy, R + η²·T (the η² undoes the radiance scaling), estimated
/// through `sample`: at most 1 (single scattering loses energy to masking), near 1 for a
/// smooth surface away from grazing, where the split follows the smooth interface's Fresnel
/// term.
#[test]
fn white_furnace() {
    for (k, &(alpha, ior, theta)) in CASES.iter().enumerate() {
        let wo = dir(theta);
        let b = glass(alpha, ior, wo);
        let mut r = SampleStream::new(300 + k as u64, 0, 0);
        let n = 50_000;
        let (mut refl, mut trans) = (0.0f64, 0.0f64);
        for _ in 0..n {
            if let Some(s) = b.sample(wo, r.next_f32(), r.next_2d()) {
                let w = (s.f_cos.x / s.pdf) as f64;
                if s.wi.z * wo.z > 0.0 {
                    refl += w;
                } else {
                    trans += w * (b.eta as f64).powi(2);
                }
            }
        }
        let (refl, trans) = (refl / n as f64, trans / n as f64);
        let energy = refl + trans;
        assert!(energy <= 1.0 + 2e-3, "case {k}: {refl} + {trans}");
        if alpha <= 0.1 && wo.z.abs() > 0.3 {
            let fr = fresnel::dielectric(wo.z.abs(), 1.0, b.eta) as f64;
            assert!(energy > 0.97, "case {k}: {refl} + {trans}");
            assert!((refl - fr).abs() < 0.02, "case {k}: R {refl} vs F {fr}");
        }
    }
}

#[test]
fn ior_near_one_or_invalid_is_refused() {
    assert!(check_ior(1.5).is_ok() && check_ior(0.7).is_ok());
    for bad in [1.0, 1.0005, 0.0, -1.5, 1e-30, 1e30, f32::NAN, f32::INFINITY] {
        assert!(check_ior(bad).is_err(), "{bad}");
    }
}

/// Opaque materials are not transmitting; the dielectric is, whichever side is viewed.
#[test]
fn only_the_dielectric_transmits() {
    let wo = dir(0.4);
    assert!(glass(0.2, 1.5, wo).transmits());
    let m = crate::material::Material::simple("m", Vec3::ONE, 0.0, 0.5);
    let b = Bsdf::new(Vec3::Z, Vec3::Z, wo, m.params_at(Vec2::ZERO));
    assert!(!b.transmits() && b.eta == 1.0);
    assert_eq!(glass(0.2, 1.5, wo).eta, 1.5);
    assert_eq!(glass(0.2, 1.5, -wo).eta, 1.0 / 1.5);
}

/// A scene refuses an index-matched or invalid dielectric with its name, and the content hash
/// tells two indices apart.
#[test]
fn scene_checks_and_hashes_the_index() {
    let build = |ior: f32| {
        let mut b = crate::scene::SceneBuilder::new("t");
        let mi = b
            .add_material(material("pane", Vec3::ONE, ior, 0.2))
            .unwrap();
        b.add_mesh(
            "tri",
            &[Vec3::ZERO, Vec3::X, Vec3::Y],
            None,
            None,
            &[0, 1, 2],
            glam::Mat4::IDENTITY,
            mi,
        )
        .unwrap();
        b.add_sphere_light(Vec3::new(0.0, 0.0, -2.0), 0.1, Vec3::ONE, None)
            .unwrap();
        b.build().map(|s| s.content_hash())
    };
    let err = build(1.0).unwrap_err().to_string();
    assert!(err.contains("pane") && err.contains("ior"), "{err}");
    assert!(build(f32::NAN).is_err());
    assert_ne!(build(1.5).unwrap(), build(1.33).unwrap());
}

/// The mirrored transmitted lobe peaks where the transmitted samples gather, and its weight
/// is their albedo, for a smooth pane from either side; beyond the critical angle there is none.
#[test]
fn mirrored_transmission_follows_the_transmitted_lobe() {
    for (theta, ior) in [(0.5f32, 1.5f32), (1.0, 1.5), (2.7, 1.5), (0.4, 1.33)] {
        let wo = dir(theta);
        let b = glass(0.05, ior, wo);
        let lo = b.frame.to_local(wo);
        let m = b.mirrored_transmission(lo).unwrap();
        assert!(m.view.z > 0.0 && m.alpha < b.ggx.alpha);
        let peak = reflect(m.view, Vec3::Z) * Vec3::new(1.0, 1.0, -1.0);
        let mut r = SampleStream::new(40, 0, 0);
        let (mut mean, mut albedo, n) = (Vec3::ZERO, 0.0f64, 20_000);
        for _ in 0..n {
            if let Some(s) = b.sample(wo, r.next_f32(), r.next_2d()) {
                let li = b.frame.to_local(s.wi);
                if li.z < 0.0 {
                    mean += li;
                    albedo += (s.f_cos.x / s.pdf) as f64;
                }
            }
        }
        let mean = mean.normalize();
        assert!(mean.dot(peak) > 0.995, "θo {theta}: {mean} vs {peak}");
        let albedo = albedo / n as f64;
        let want = m.weight.x as f64;
        assert!(
            (albedo - want).abs() < 0.03 * want,
            "θo {theta}: {albedo} vs {want}"
        );
    }
    let inside_grazing = dir(2.0);
    let b = glass(0.05, 1.5, inside_grazing);
    assert!(
        b.mirrored_transmission(b.frame.to_local(inside_grazing))
            .is_none()
    );
}

/// The glossy weight (the BO importance's reflection weight) is the Fresnel reflectance seen
/// from the viewer's side: 0.04 head-on from either side, total reflection past the critical
/// angle from inside.
#[test]
fn glossy_weight_is_the_reflectance_from_the_viewers_side() {
    let weight = |theta: f32| {
        let b = glass(0.1, 1.5, dir(theta));
        b.glossy_weight(b.frame.to_local(dir(theta))).x
    };
    assert!((weight(0.0) - 0.04).abs() < 1e-5);
    assert!((weight(std::f32::consts::PI) - 0.04).abs() < 1e-5);
    assert_eq!(weight(std::f32::consts::PI - 1.0), 1.0);
    assert!(weight(1.0) < 0.1);
}
