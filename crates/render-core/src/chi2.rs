//! Chi-square goodness-of-fit testing of sampling routines against their own densities,
//! in the manner of Mitsuba's `chi2` tests: histogram the samples, integrate the density
//! over the same bins, pool sparse bins, and compare the statistic with a significance
//! level corrected for the number of tests (Šidák).

/// Result of one test.
#[derive(Clone, Debug)]
pub struct Chi2Outcome {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Expected mass the density put outside the sampled domain or lost to pooling.
    pub message: String,
}

/// Compares observed counts with expected counts (same length). Bins expected below 5
/// are pooled together. Returns the p-value of the chi-square statistic.
pub fn chi2_test(observed: &[f64], expected: &[f64]) -> Chi2Outcome {
    assert_eq!(observed.len(), expected.len());
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pooled_o, mut pooled_e) = (0.0, 0.0);
    let mut stat = 0.0;
    let mut bins = 0usize;
    let mut message = String::new();
    // Bins the quadrature saw as empty can still be grazed by a discontinuous density (the
    // edge of a cap); their samples join the pooled bin, but more than 0.1 % of all samples
    // there means the sampler covers what the density excludes.
    let total_observed: f64 = observed.iter().sum();
    let stray: f64 = observed
        .iter()
        .zip(expected)
        .filter(|(_, e)| **e == 0.0)
        .map(|(o, _)| *o)
        .sum();
    if stray > 1e-3 * total_observed.max(1.0) {
        message = format!("{stray} samples in bins where the density integrates to 0");
        return Chi2Outcome {
            statistic: f64::INFINITY,
            dof: 0,
            p_value: 0.0,
            message,
        };
    }
    for &i in &order {
        let (o, e) = (observed[i], expected[i]);
        if e < 5.0 || pooled_e > 0.0 && pooled_e < 5.0 {
            pooled_o += o;
            pooled_e += e;
            if pooled_e >= 5.0 {
                stat += (pooled_o - pooled_e).powi(2) / pooled_e;
                bins += 1;
                pooled_o = 0.0;
                pooled_e = 0.0;
            }
            continue;
        }
        stat += (o - e).powi(2) / e;
        bins += 1;
    }
    if pooled_e > 0.0 {
        stat += (pooled_o - pooled_e).powi(2) / pooled_e;
        bins += 1;
    }
    let dof = bins.saturating_sub(1).max(1);
    let p = gamma_q(dof as f64 / 2.0, stat / 2.0);
    Chi2Outcome {
        statistic: stat,
        dof,
        p_value: p,
        message,
    }
}

/// The significance for one of `tests` tests so that the family rejects a correct sampler
/// with probability `alpha` (Šidák correction).
pub fn sidak_significance(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}

fn ln_gamma(x: f64) -> f64 {
    // Lanczos approximation (g = 7, n = 9), accurate to ~1e-15 for x > 0.
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
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma function Q(a, x).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    if x < a + 1.0 {
        // series for P, then Q = 1 − P
        let mut sum = 1.0 / a;
        let mut term = sum;
        let mut n = a;
        for _ in 0..10_000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - ln_gamma(a)).exp()
    } else {
        // Lentz continued fraction for Q
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
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
        (-x + a * x.ln() - ln_gamma(a)).exp() * h
    }
}

/// Histograms directions sampled by `sample` over a (cos θ, φ) grid of `res_theta × res_phi`
/// bins of the whole sphere and tests them against `pdf` (a solid-angle density), integrated
/// over each bin with `sub × sub` midpoint quadrature. `sample` returns `None` for a
/// rejected sample (counted as missing mass, which the density must also account for by
/// integrating to less than one).
pub fn chi2_directions(
    n_samples: usize,
    res_theta: usize,
    res_phi: usize,
    sub: usize,
    mut sample: impl FnMut(usize) -> Option<glam::Vec3>,
    pdf: impl Fn(glam::Vec3) -> f64,
) -> Chi2Outcome {
    use std::f64::consts::PI;
    let bins = res_theta * res_phi;
    let mut observed = vec![0.0; bins + 1];
    let bin_of = |w: glam::Vec3| {
        let c = (w.z as f64).clamp(-1.0, 1.0);
        let t = (((1.0 - c) * 0.5) * res_theta as f64).min(res_theta as f64 - 1.0) as usize;
        let mut phi = (w.y as f64).atan2(w.x as f64);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let p = ((phi / (2.0 * PI)) * res_phi as f64).min(res_phi as f64 - 1.0) as usize;
        t * res_phi + p
    };
    for i in 0..n_samples {
        match sample(i) {
            Some(w) => observed[bin_of(w)] += 1.0,
            None => observed[bins] += 1.0,
        }
    }
    let mut expected = vec![0.0; bins + 1];
    let mut total = 0.0;
    for t in 0..res_theta {
        for p in 0..res_phi {
            let integrate = |sub: usize| {
                let (mut acc, mut zeros) = (0.0, 0usize);
                for i in 0..sub {
                    for j in 0..sub {
                        let c = 1.0
                            - 2.0 * (t as f64 + (i as f64 + 0.5) / sub as f64) / res_theta as f64;
                        let phi =
                            2.0 * PI * (p as f64 + (j as f64 + 0.5) / sub as f64) / res_phi as f64;
                        let s = (1.0 - c * c).max(0.0).sqrt();
                        let w = glam::Vec3::new(
                            (s * phi.cos()) as f32,
                            (s * phi.sin()) as f32,
                            c as f32,
                        );
                        let v = pdf(w);
                        zeros += (v == 0.0) as usize;
                        acc += v;
                    }
                }
                (acc / (sub * sub) as f64, zeros)
            };
            let (mut mean, zeros) = integrate(sub);
            if zeros > 0 && zeros < sub * sub {
                // the bin straddles an edge of the support: integrate it much more finely
                mean = integrate(sub * 16).0;
            }
            let area = (2.0 / res_theta as f64) * (2.0 * PI / res_phi as f64);
            let mass = mean * area;
            expected[t * res_phi + p] = mass * n_samples as f64;
            total += mass;
        }
    }
    expected[bins] = ((1.0 - total).max(0.0)) * n_samples as f64;
    chi2_test(&observed, &expected)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_q_matches_known_values() {
        // chi-square survival: dof 2 → exp(−x/2)
        for x in [0.5, 1.0, 3.0, 10.0] {
            assert!((gamma_q(1.0, x / 2.0) - (-x / 2.0f64).exp()).abs() < 1e-12);
        }
        // dof 10, x = 18.307 → p = 0.05
        assert!((gamma_q(5.0, 18.307 / 2.0) - 0.05).abs() < 1e-4);
    }

    #[test]
    fn detects_a_wrong_density() {
        // Uniform samples on the sphere tested against a cosine-weighted hemisphere pdf.
        let mut k = 0u64;
        let mut next = || {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (k >> 40) as f32 / (1u64 << 24) as f32
        };
        let out = chi2_directions(
            20_000,
            10,
            20,
            4,
            |_| {
                Some(crate::sampling::uniform_sphere(glam::Vec2::new(
                    next(),
                    next(),
                )))
            },
            |w| (w.z.max(0.0) as f64) / std::f64::consts::PI,
        );
        assert!(out.p_value < 1e-6, "{out:?}");
    }
}
