//! Chi-square goodness-of-fit testing of sampling routines against their own densities,
//! in the manner of Mitsuba's `chi2` tests: histogram the samples, integrate the density
//! over the same bins, pool sparse bins, and compare the statistic with a significance
//! level corrected for the number of tests (Šidák).
//!
//! Shared by every crate of the workspace (as a dev-dependency where the crate itself must not
//! depend on anything rendering-specific): discrete distributions through [`chi2_test`],
//! direction samplers through [`chi2_directions`] / [`chi2_directions_on`].

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

/// The (cos θ, φ) histogram of directions: `theta_bins × phi_bins` bins over the part of the
/// sphere with cos θ ≥ `cos_min` about `axis`, the density integrated over each bin with
/// `pdf_subdivisions²` midpoint samples (and 16× finer where the density has an edge).
#[derive(Clone, Copy, Debug)]
pub struct DirectionGrid {
    pub theta_bins: usize,
    pub phi_bins: usize,
    pub axis: glam::Vec3,
    pub cos_min: f64,
    pub pdf_subdivisions: usize,
}

impl DirectionGrid {
    /// The whole sphere about +z.
    pub fn sphere(theta_bins: usize, phi_bins: usize, pdf_subdivisions: usize) -> DirectionGrid {
        DirectionGrid {
            theta_bins,
            phi_bins,
            axis: glam::Vec3::Z,
            cos_min: -1.0,
            pdf_subdivisions,
        }
    }
}

/// Histograms directions sampled by `sample` over the whole sphere (see [`DirectionGrid::sphere`])
/// and tests them against `pdf` (a solid-angle density).
pub fn chi2_directions(
    n_samples: usize,
    res_theta: usize,
    res_phi: usize,
    sub: usize,
    sample: impl FnMut(usize) -> Option<glam::Vec3>,
    pdf: impl Fn(glam::Vec3) -> f64,
) -> Chi2Outcome {
    chi2_directions_on(
        &DirectionGrid::sphere(res_theta, res_phi, sub),
        n_samples,
        sample,
        pdf,
    )
}

/// Histograms directions sampled by `sample` on `grid` and tests them against `pdf`.
/// `sample` returns `None` for a rejected sample; rejected samples and samples outside the
/// grid share one extra bin whose expectation is the mass the density leaves off the grid.
pub fn chi2_directions_on(
    grid: &DirectionGrid,
    n_samples: usize,
    mut sample: impl FnMut(usize) -> Option<glam::Vec3>,
    pdf: impl Fn(glam::Vec3) -> f64,
) -> Chi2Outcome {
    use glam::DVec3;
    use std::f64::consts::PI;
    let (nt, np) = (grid.theta_bins, grid.phi_bins);
    let axis = grid.axis.as_dvec3().normalize();
    let tx = if axis.x.abs() < 0.9 {
        DVec3::X.cross(axis)
    } else {
        DVec3::Y.cross(axis)
    }
    .normalize();
    let ty = axis.cross(tx);
    let range = 1.0 - grid.cos_min;
    let bins = nt * np;
    let bin_of = |w: DVec3| -> Option<usize> {
        let c = w.dot(axis).clamp(-1.0, 1.0);
        if c < grid.cos_min {
            return None;
        }
        let t = (((1.0 - c) / range) * nt as f64).min(nt as f64 - 1.0) as usize;
        let mut phi = w.dot(ty).atan2(w.dot(tx));
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let p = ((phi / (2.0 * PI)) * np as f64).min(np as f64 - 1.0) as usize;
        Some(t * np + p)
    };
    let mut observed = vec![0.0; bins + 1];
    for i in 0..n_samples {
        match sample(i)
            .map(|w| w.as_dvec3())
            .filter(|w| w.is_finite())
            .and_then(bin_of)
        {
            Some(b) => observed[b] += 1.0,
            None => observed[bins] += 1.0,
        }
    }
    let mut expected = vec![0.0; bins + 1];
    let mut total = 0.0;
    let sub = grid.pdf_subdivisions.max(1);
    for t in 0..nt {
        for p in 0..np {
            let integrate = |sub: usize| {
                let (mut acc, mut zeros) = (0.0, 0usize);
                for i in 0..sub {
                    let c = 1.0 - range * (t as f64 + (i as f64 + 0.5) / sub as f64) / nt as f64;
                    let r = (1.0 - c * c).max(0.0).sqrt();
                    for j in 0..sub {
                        let phi = 2.0 * PI * (p as f64 + (j as f64 + 0.5) / sub as f64) / np as f64;
                        let w = axis * c + (tx * phi.cos() + ty * phi.sin()) * r;
                        let v = pdf(w.as_vec3());
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
            let mass = mean * 2.0 * PI * range / bins as f64;
            expected[t * np + p] = mass * n_samples as f64;
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

    /// A small deterministic uniform generator for the tests (64-bit LCG, top 24 bits).
    fn lcg(seed: u64) -> impl FnMut() -> f32 {
        let mut k = seed;
        move || {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (k >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    fn uniform_sphere(u: f32, v: f32) -> glam::Vec3 {
        let z = 1.0 - 2.0 * u;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * v;
        glam::Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    #[test]
    fn detects_a_wrong_density() {
        // Uniform samples on the sphere tested against a cosine-weighted hemisphere pdf.
        let mut next = lcg(0);
        let out = chi2_directions(
            20_000,
            10,
            20,
            4,
            |_| Some(uniform_sphere(next(), next())),
            |w| (w.z.max(0.0) as f64) / std::f64::consts::PI,
        );
        assert!(out.p_value < 1e-6, "{out:?}");
        let mut next = lcg(0);
        let ok = chi2_directions(
            20_000,
            10,
            20,
            4,
            |_| Some(uniform_sphere(next(), next())),
            |_| 0.25 / std::f64::consts::PI,
        );
        assert!(ok.p_value > 1e-3, "the right density passes: {ok:?}");
    }

    #[test]
    fn grids_about_other_axes_cover_a_cap() {
        // Uniform directions in a cap of cos 0.9 about a tilted axis, on a grid over that cap.
        let axis = glam::Vec3::new(0.3, -0.4, 0.866).normalize();
        let frame_x = axis.cross(glam::Vec3::X).normalize();
        let frame_y = axis.cross(frame_x);
        let mut next = lcg(7);
        let grid = DirectionGrid {
            theta_bins: 10,
            phi_bins: 20,
            axis,
            cos_min: 0.9,
            pdf_subdivisions: 4,
        };
        let area = 2.0 * std::f64::consts::PI * 0.1;
        let out = chi2_directions_on(
            &grid,
            20_000,
            |_| {
                let c = 1.0 - 0.1 * next();
                let s = (1.0 - c * c).sqrt();
                let phi = 2.0 * std::f32::consts::PI * next();
                Some(axis * c + (frame_x * phi.cos() + frame_y * phi.sin()) * s)
            },
            |w| if w.dot(axis) >= 0.9 { 1.0 / area } else { 0.0 },
        );
        assert!(out.p_value > 1e-3, "{out:?}");
    }
}
