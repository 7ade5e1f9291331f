//! Randomly shifted point sets for the several samples one technique takes at one shading
//! point (`mis3-adaptive`'s BRDF-aware samples). Each point is uniform on its own, because the
//! whole set is shifted by one uniform random vector (Cranley–Patterson rotation), so a
//! fixed-count MIS estimator built on them stays unbiased; together the points cover the
//! domain more evenly than independent ones, which lowers the variance of their sum.
use render_core::Vec2;

/// The largest f32 below 1: a shifted coordinate never reaches 1.
const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

/// Point i of n of the shifted 1D lattice frac(shift + i/n): one point per stratum [k/n, (k+1)/n).
pub fn lattice_1d(shift: f32, i: u32, n: u32) -> f32 {
    let u = shift + i as f32 / n as f32;
    let u = if u >= 1.0 { u - 1.0 } else { u };
    u.min(BELOW_ONE)
}

/// Point i of Roberts' R3 sequence, frac(shift + i·(1/φ₃, 1/φ₃², 1/φ₃³)) with φ₃⁴ = φ₃ + 1,
/// as (first coordinate, the other two): evenly spread in 3D for any count (the BSDF's lobe
/// choice and direction).
pub fn r3_point(shift0: f32, shift12: Vec2, i: u32) -> (f32, Vec2) {
    const STEP: [f64; 3] = [
        0.819_172_513_396_164_4,
        0.671_043_606_703_789_2,
        0.549_700_477_901_970_4,
    ];
    let at =
        |shift: f32, step: f64| ((shift as f64 + step * i as f64).fract() as f32).min(BELOW_ONE);
    (
        at(shift0, STEP[0]),
        Vec2::new(at(shift12.x, STEP[1]), at(shift12.y, STEP[2])),
    )
}

/// Variance of the sum of the terms of a [`lattice_1d`] set, `terms[i]` from point i (so that
/// consecutive points lie in neighbouring strata), by collapsed strata: Σ_j (t_2j − t_2j+1)²,
/// each pair's squared difference estimating the sum of its two strata's variances (plus the
/// squared difference of their means: an overestimate, much smaller than the independent-sample
/// formula's, which counts all the differences between strata). An odd last term is left out
/// and the sum scaled up for it; below two terms, the square of the one term.
pub fn lattice_sum_variance(terms: &[f32]) -> f32 {
    let n = terms.len();
    if n < 2 {
        return terms.first().map_or(0.0, |t| t * t);
    }
    let pairs: f32 = terms
        .chunks_exact(2)
        .map(|p| (p[0] - p[1]) * (p[0] - p[1]))
        .sum();
    pairs * n as f32 / (2 * (n / 2)) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use chi2_test::{chi2_test, sidak_significance};
    use render_core::rng::SampleStream;

    #[test]
    fn lattice_puts_one_point_in_each_stratum() {
        let mut rng = SampleStream::new(3, 0, 0);
        for n in [1u32, 2, 3, 7, 32, 101] {
            for _ in 0..50 {
                let shift = rng.next_f32();
                let mut seen = vec![0u32; n as usize];
                for i in 0..n {
                    let u = lattice_1d(shift, i, n);
                    assert!((0.0..1.0).contains(&u), "{u}");
                    seen[((u * n as f32) as usize).min(n as usize - 1)] += 1;
                }
                assert!(
                    seen.iter().all(|&c| c == 1),
                    "n {n} shift {shift}: {seen:?}"
                );
            }
        }
    }

    /// Each point of either set, over random shifts, is uniform (chi-square on a grid).
    #[test]
    fn every_point_is_uniform_on_its_own() {
        let cases = [0u32, 1, 5, 40];
        let sig = sidak_significance(0.01, 2 * cases.len());
        let draws = 40_000u64;
        for &i in &cases {
            // 1D lattice, point i of 48, 20 bins.
            let mut h1 = vec![0.0f64; 20];
            // R3 point i, 4 × 4 × 4 bins.
            let mut h3 = vec![0.0f64; 64];
            for s in 0..draws {
                let mut rng = SampleStream::new(11, s, i as u64);
                let u = lattice_1d(rng.next_f32(), i, 48);
                h1[(u * 20.0) as usize] += 1.0;
                let (a, b) = r3_point(rng.next_f32(), rng.next_2d(), i);
                let bin = |x: f32| (x * 4.0) as usize;
                h3[bin(a) * 16 + bin(b.x) * 4 + bin(b.y)] += 1.0;
            }
            for h in [&h1, &h3] {
                let expected = vec![draws as f64 / h.len() as f64; h.len()];
                let out = chi2_test(h, &expected);
                assert!(out.p_value > sig, "point {i}: {out:?}");
            }
        }
    }

    /// For a smooth integrand the collapsed-strata estimate lies between the actual variance of
    /// a lattice set's sum (measured over many shifts) and the independent-sample formula's
    /// (here about 0.003, 0.017 and 0.053).
    #[test]
    fn lattice_variance_estimate_tracks_the_stratified_variance() {
        let f = |u: f32| 1.0 + 3.0 * u * u;
        let n = 16u32;
        let mut rng = SampleStream::new(9, 0, 0);
        let (mut sum, mut sum_sq, mut est, mut iid) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let sets = 4000;
        let mut terms = vec![0.0f32; n as usize];
        for _ in 0..sets {
            let shift = rng.next_f32();
            for (i, t) in terms.iter_mut().enumerate() {
                *t = f(lattice_1d(shift, i as u32, n)) / n as f32;
            }
            let total: f32 = terms.iter().sum();
            sum += total as f64;
            sum_sq += (total * total) as f64;
            est += lattice_sum_variance(&terms) as f64;
            let mean = total / n as f32;
            let spread: f32 = terms.iter().map(|t| (t - mean) * (t - mean)).sum::<f32>();
            iid += (n as f32 * spread / (n - 1) as f32) as f64;
        }
        let actual = sum_sq / sets as f64 - (sum / sets as f64).powi(2);
        let (est, iid) = (est / sets as f64, iid / sets as f64);
        assert!(
            est >= actual,
            "collapsed strata {est} below the actual {actual}"
        );
        assert!(
            est < 0.5 * iid,
            "collapsed strata {est} vs independent {iid}"
        );
        assert_eq!(lattice_sum_variance(&[2.0]), 4.0);
        assert_eq!(lattice_sum_variance(&[1.0, 3.0, 5.0]), 4.0 * 1.5);
    }

    /// The R3 set covers the cube more evenly than chance: over 64 points, the octant counts'
    /// squared deviation from 8, Σ (c − 8)², averages below half of its value for independent
    /// points, 64 · 7/8 = 56 (about 19 for R3 in a simulation of 2,000 shifts).
    #[test]
    fn r3_set_is_evenly_spread() {
        let mut rng = SampleStream::new(5, 0, 0);
        let sets = 500;
        let mut total = 0.0f64;
        for _ in 0..sets {
            let (s0, s12) = (rng.next_f32(), rng.next_2d());
            let mut octants = [0i32; 8];
            for i in 0..64 {
                let (a, b) = r3_point(s0, s12, i);
                let o = (a >= 0.5) as usize * 4 + (b.x >= 0.5) as usize * 2 + (b.y >= 0.5) as usize;
                octants[o] += 1;
            }
            total += octants
                .iter()
                .map(|&c| ((c - 8) * (c - 8)) as f64)
                .sum::<f64>();
        }
        let mean = total / sets as f64;
        assert!(
            mean < 28.0,
            "mean squared deviation {mean} (independent points: 56)"
        );
    }
}
