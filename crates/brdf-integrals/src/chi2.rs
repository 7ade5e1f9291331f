//! A small chi-square goodness-of-fit test for direction samplers (in the spirit of Mitsuba's
//! `chi2` tests): histogram samples on a (cos θ, φ) grid, integrate the claimed pdf over every
//! cell, pool cells with low expected counts, and compare with a Šidák-corrected significance.

use glam::{DVec3, Vec3};
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug)]
pub struct Chi2Config {
    pub theta_bins: usize,
    pub phi_bins: usize,
    pub samples: usize,
    /// Family-wise significance level, e.g. 0.01.
    pub significance: f64,
    /// Number of tests in the family (Šidák correction).
    pub tests: usize,
    /// Midpoint-rule subdivisions per cell side when integrating the pdf (raise for peaked pdfs).
    pub pdf_subdivisions: usize,
    /// The grid's pole: cos θ is measured from this unit axis.
    pub axis: Vec3,
    /// The grid covers cos θ ∈ [cos_min, 1] (−1: the whole sphere). Samples outside fail the test.
    pub cos_min: f64,
}

impl Chi2Config {
    /// Whole sphere, pole +z, 8 pdf subdivisions, 1 test at 1 % significance.
    pub fn sphere(theta_bins: usize, phi_bins: usize, samples: usize) -> Self {
        Self {
            theta_bins,
            phi_bins,
            samples,
            significance: 0.01,
            tests: 1,
            pdf_subdivisions: 8,
            axis: Vec3::Z,
            cos_min: -1.0,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Chi2Result {
    pub passed: bool,
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    pub threshold: f64,
    pub message: String,
}

/// Runs the test on the (cos θ, φ) grid about `cfg.axis`, cos θ ∈ [cfg.cos_min, 1].
pub fn run_test(
    mut sample: impl FnMut(usize) -> Vec3,
    pdf: impl Fn(Vec3) -> f64,
    cfg: Chi2Config,
) -> Chi2Result {
    let (nt, np) = (cfg.theta_bins, cfg.phi_bins);
    let axis = cfg.axis.as_dvec3().normalize();
    let (tx, ty) = crate::pivot::basis(axis);
    let range = 1.0 - cfg.cos_min;
    let cell = |w: DVec3| -> Option<usize> {
        let z = w.dot(axis).clamp(-1.0, 1.0);
        if z < cfg.cos_min {
            return None;
        }
        let t = (((1.0 - z) / range) * nt as f64)
            .floor()
            .clamp(0.0, nt as f64 - 1.0) as usize;
        let (x, y) = (w.dot(tx), w.dot(ty));
        let mut phi = y.atan2(x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let p = ((phi / (2.0 * PI)) * np as f64)
            .floor()
            .clamp(0.0, np as f64 - 1.0) as usize;
        Some(t * np + p)
    };
    let mut observed = vec![0.0f64; nt * np];
    for i in 0..cfg.samples {
        let w = sample(i).as_dvec3();
        if !w.is_finite() {
            return fail(format!("sample {i} is not finite: {w}"));
        }
        match cell(w) {
            Some(c) => observed[c] += 1.0,
            None => return fail(format!("sample {i} = {w} lies outside the tested region")),
        }
    }
    // expected counts: midpoint rule with sub×sub sub-cells in (cos θ, φ), which is area-uniform
    let sub = cfg.pdf_subdivisions.max(1);
    let mut expected = vec![0.0f64; nt * np];
    for t in 0..nt {
        for p in 0..np {
            let mut s = 0.0;
            for a in 0..sub {
                let z = 1.0 - range * (t as f64 + (a as f64 + 0.5) / sub as f64) / nt as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                for b in 0..sub {
                    let phi = 2.0 * PI * (p as f64 + (b as f64 + 0.5) / sub as f64) / np as f64;
                    let w = axis * z + (tx * phi.cos() + ty * phi.sin()) * r;
                    s += pdf(w.as_vec3());
                }
            }
            let area = 2.0 * PI * range / (nt * np) as f64;
            expected[t * np + p] = s / (sub * sub) as f64 * area * cfg.samples as f64;
        }
    }
    evaluate(&observed, &expected, cfg)
}

fn fail(message: String) -> Chi2Result {
    Chi2Result {
        passed: false,
        statistic: f64::NAN,
        dof: 0,
        p_value: 0.0,
        threshold: 0.0,
        message,
    }
}

/// Pools cells with expected count < 5, computes the statistic and the p-value.
pub fn evaluate(observed: &[f64], expected: &[f64], cfg: Chi2Config) -> Chi2Result {
    let mut idx: Vec<usize> = (0..expected.len()).collect();
    idx.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    let mut stat = 0.0;
    let mut dof = 0usize;
    for &i in &idx {
        let (o, e) = (observed[i], expected[i]);
        if e <= 0.0 && o > 0.0 {
            return fail(format!(
                "cell {i}: {o} samples where the pdf integrates to 0"
            ));
        }
        if e < 5.0 {
            pool_o += o;
            pool_e += e;
            continue;
        }
        stat += (o - e) * (o - e) / e;
        dof += 1;
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    } else if pool_o > 0.0 {
        return fail(format!("{pool_o} samples in cells with zero expectation"));
    }
    if dof < 2 {
        return fail("fewer than 2 cells with enough expectation".into());
    }
    let dof = dof - 1;
    let p_value = gamma_q(dof as f64 * 0.5, stat * 0.5);
    let threshold = 1.0 - (1.0 - cfg.significance).powf(1.0 / cfg.tests.max(1) as f64);
    let passed = p_value > threshold;
    Chi2Result {
        passed,
        statistic: stat,
        dof,
        p_value,
        threshold,
        message: format!(
            "chi2 = {stat:.1}, dof = {dof}, p = {p_value:.3e}, threshold {threshold:.3e}"
        ),
    }
}

/// ln Γ(x) for x > 0 (Lanczos approximation, g = 7, 9 terms).
pub fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma Q(s, x) = Γ(s, x)/Γ(s): series for x < s + 1, continued
/// fraction (modified Lentz) otherwise.
pub fn gamma_q(s: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let lnpre = s * x.ln() - x - ln_gamma(s);
    if x < s + 1.0 {
        let (mut sum, mut term, mut n) = (1.0 / s, 1.0 / s, s);
        for _ in 0..10_000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        (1.0 - sum * lnpre.exp()).clamp(0.0, 1.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - s;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - s);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (lnpre.exp() * h).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_q_known_values() {
        // chi-square survival: dof 2 → exp(−x/2)
        for &x in &[0.5f64, 2.0, 10.0] {
            assert!((gamma_q(1.0, x / 2.0) - (-x / 2.0).exp()).abs() < 1e-12);
        }
        // dof 10, x = 18.307 is the 95th percentile
        assert!((gamma_q(5.0, 18.307 / 2.0) - 0.05).abs() < 1e-4);
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
    }
}
