//! A small Pearson chi-square goodness-of-fit helper for discrete distributions, in the
//! style of Mitsuba's `ChiSquareTest`: bins with an expected count below 5 are pooled, the
//! p-value comes from the regularised upper incomplete gamma function, and callers reject
//! at a Šidák-corrected significance level.

/// Result of [`chi2_test`].
#[derive(Clone, Copy, Debug)]
pub struct Chi2Result {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
}

/// Compares `observed` counts with `expected` counts (same length; the expected counts are
/// `pmf · num_samples`). Bins with an expected count below 5 are pooled (sorted by expected
/// count, merged until the pool reaches 5, any remainder merged into the last bin). Any
/// observation in a bin with expected count 0 gives p = 0.
pub fn chi2_test(observed: &[u64], expected: &[f64]) -> Chi2Result {
    assert_eq!(observed.len(), expected.len());
    let mut idx: Vec<usize> = (0..observed.len()).collect();
    idx.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut bins: Vec<(f64, f64)> = Vec::new();
    let (mut po, mut pe) = (0.0f64, 0.0f64);
    for &i in &idx {
        let (o, e) = (observed[i] as f64, expected[i]);
        if e <= 0.0 {
            if o > 0.0 {
                return Chi2Result {
                    statistic: f64::INFINITY,
                    dof: 0,
                    p_value: 0.0,
                };
            }
            continue;
        }
        if pe > 0.0 || e < 5.0 {
            po += o;
            pe += e;
            if pe >= 5.0 {
                bins.push((po, pe));
                po = 0.0;
                pe = 0.0;
            }
        } else {
            bins.push((o, e));
        }
    }
    if pe > 0.0 {
        match bins.last_mut() {
            Some(last) => {
                last.0 += po;
                last.1 += pe;
            }
            None => bins.push((po, pe)),
        }
    }
    let statistic: f64 = bins.iter().map(|&(o, e)| (o - e) * (o - e) / e).sum();
    if bins.len() < 2 {
        return Chi2Result {
            statistic,
            dof: 0,
            p_value: 1.0,
        };
    }
    let dof = bins.len() - 1;
    Chi2Result {
        statistic,
        dof,
        p_value: gamma_q(dof as f64 / 2.0, statistic / 2.0),
    }
}

/// Per-test significance for `num_tests` independent tests at overall level `alpha`
/// (Šidák correction).
pub fn sidak(alpha: f64, num_tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / num_tests as f64)
}

/// ln Γ(x) for x > 0 (Lanczos approximation, g = 7, 9 terms).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
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
        // Reflection: Γ(x)Γ(1−x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, &c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma Q(a, x) = Γ(a, x)/Γ(a).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    if x < a + 1.0 {
        1.0 - gamma_p_series(a, x)
    } else {
        gamma_q_cf(a, x)
    }
}

fn gamma_p_series(a: f64, x: f64) -> f64 {
    let mut term = 1.0 / a;
    let mut sum = term;
    let mut ap = a;
    for _ in 0..10_000 {
        ap += 1.0;
        term *= x / ap;
        sum += term;
        if term.abs() < sum.abs() * 1e-15 {
            break;
        }
    }
    (sum.ln() - x + a * x.ln() - ln_gamma(a)).exp()
}

/// Continued fraction for Q(a, x), modified Lentz.
fn gamma_q_cf(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..10_000 {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_gamma_matches_factorials() {
        let mut f = 1.0f64;
        for n in 1..20 {
            assert!((ln_gamma(n as f64) - f.ln()).abs() < 1e-10, "n={n}");
            f *= n as f64;
        }
        // Γ(1/2) = √π
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-12);
    }

    #[test]
    fn gamma_q_known_values() {
        // Q(1, x) = e^{-x}
        for x in [0.1, 1.0, 3.0, 10.0] {
            assert!((gamma_q(1.0, x) - (-x).exp()).abs() < 1e-12);
        }
        // chi2 with 10 dof at 18.307 has p = 0.05; with 1 dof at 3.841 has p = 0.05.
        assert!((gamma_q(5.0, 18.307 / 2.0) - 0.05).abs() < 1e-4);
        assert!((gamma_q(0.5, 3.841 / 2.0) - 0.05).abs() < 1e-4);
    }

    #[test]
    fn chi2_detects_wrong_distribution_and_accepts_right_one() {
        let expected = [1000.0, 2000.0, 3000.0, 4000.0, 2.0, 1.0, 2.0];
        let good = [990u64, 2040, 2970, 4010, 1, 2, 3];
        assert!(chi2_test(&good, &expected).p_value > 0.1);
        let bad = [1200u64, 2000, 3000, 3800, 2, 1, 2];
        assert!(chi2_test(&bad, &expected).p_value < 1e-3);
        let impossible = [0u64, 0, 0, 0, 0, 0, 1];
        assert_eq!(
            chi2_test(&impossible, &[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0]).p_value,
            0.0
        );
    }
}
