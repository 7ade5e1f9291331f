//! Fitting machinery shared by the SPTD and LTC tables: per-cell sample sets of the GGX lobe,
//! the L1 objective, and a Nelder–Mead minimiser.
//!
//! Objective: both approximations are normalised so that their mass over the upper hemisphere H
//! equals the GGX directional albedo A (see the crate docs), so the L1 distance
//! ∫_H |f·cos − g| dω (twice the total-variation distance between the normalised lobes, times A)
//! is a direct bound on the absolute error of *every* cap integral: |∫_C (f·cos − g)| ≤ ∫_H |f·cos − g|.
//! It is estimated with a fixed set of samples (3/4 visible-normal samples of the GGX lobe, 1/4
//! uniform on H, combined as a mixture pdf), so the objective is deterministic and smooth enough
//! for Nelder–Mead.
//!
//! Where the approximation cannot match the shape (SPTDs are isotropic, the GGX lobe at grazing
//! angles is not), L1 is flat and leaves the lobe's position undetermined, so the objective also
//! has a term on the cap integrals themselves: the mean squared log-ratio of approximate to
//! reference integrals over a family of caps ([`CellCaps`]). Objective = relative L1 + that term.

use crate::cap::Cap64;
use crate::ggx;
use crate::qmc::{R2, SplitMix64};
use glam::DVec3;
use std::f64::consts::PI;

/// GGX lobe samples for one (θo, α) cell.
///
/// Directions are in the local frame (z = normal) with ωo in the xz-plane; only those above the
/// horizon are kept.
pub struct CellSamples {
    /// Sample directions wi (unit, z > 0).
    pub dirs: Vec<DVec3>,
    /// f·cos at `dirs`.
    pub f: Vec<f64>,
    /// 1 / (N · p_mix) at `dirs`: weights of the L1 estimator.
    pub w: Vec<f64>,
}

/// Share of the `n` samples drawn by visible-normal sampling; the rest are uniform on H.
pub const VNDF_FRACTION: f64 = 0.75;

impl CellSamples {
    /// Draws `n` samples (before dropping those below the horizon) for GGX roughness `alpha`
    /// and the unit view direction `wo`, deterministically from `seed`.
    pub fn new(alpha: f64, wo: DVec3, n: usize, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let s1 = R2::new(&mut rng);
        let s2 = R2::new(&mut rng);
        let n1 = (n as f64 * VNDF_FRACTION) as usize;
        let mut dirs = Vec::with_capacity(n);
        for i in 0..n1 {
            dirs.push(ggx::sample_wi_64(alpha, wo, s1.get(i)));
        }
        for i in 0..n - n1 {
            let u = s2.get(i);
            let z = u[0];
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * PI * u[1];
            dirs.push(DVec3::new(r * phi.cos(), r * phi.sin(), z));
        }
        dirs.retain(|d| d.z > 0.0);
        let f = dirs
            .iter()
            .map(|&d| ggx::eval_cos_64(alpha, wo, d))
            .collect();
        let w = dirs
            .iter()
            .map(|&d| {
                let p = VNDF_FRACTION * ggx::pdf_wi_64(alpha, wo, d)
                    + (1.0 - VNDF_FRACTION) / (2.0 * PI);
                1.0 / (n as f64 * p)
            })
            .collect();
        Self { dirs, f, w }
    }

    /// Estimate of ∫_H |f·cos − g| dω, for `g` a density-like function of a unit local-frame
    /// direction (same units as f·cos, i.e. per steradian).
    pub fn l1(&self, g: impl Fn(DVec3) -> f64) -> f64 {
        let mut s = 0.0;
        for i in 0..self.dirs.len() {
            s += (self.f[i] - g(self.dirs[i])).abs() * self.w[i];
        }
        s
    }

    /// The average direction of f·cos (unnormalised first moment).
    pub fn mean_direction(&self) -> DVec3 {
        let mut m = DVec3::ZERO;
        for i in 0..self.dirs.len() {
            m += self.dirs[i] * self.f[i] * self.w[i];
        }
        m
    }
}

/// A family of test caps for one cell with their reference integrals: centres drawn from the
/// GGX lobe (visible-normal samples), uniformly on H and at the lobe's mean direction; half-angles
/// log-uniform in [0.002, 1] rad.
pub struct CellCaps {
    /// The test caps, in the local frame.
    pub caps: Vec<Cap64>,
    /// Reference ∫_{C∩H} f·cos dω of each cap, same order as `caps`.
    pub refs: Vec<f64>,
    /// Offset added to both sides of the log-ratio (1 % of the mean reference value) so that
    /// caps with near-zero integrals do not dominate.
    pub eps: f64,
}

impl CellCaps {
    /// Builds `count` caps for GGX roughness `alpha`, unit view direction `wo` and the lobe's
    /// unit mean direction `mean_dir`, each with a reference integral of `ref_samples`
    /// samples; deterministic in `seed`.
    pub fn new(
        alpha: f64,
        wo: DVec3,
        mean_dir: DVec3,
        count: usize,
        ref_samples: usize,
        seed: u64,
    ) -> Self {
        let mut rng = SplitMix64::new(seed);
        let mut caps = Vec::with_capacity(count);
        for k in 0..count {
            let axis = if k == 0 {
                mean_dir
            } else if k % 4 == 0 {
                let z = rng.next_f64();
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * PI * rng.next_f64();
                DVec3::new(r * phi.cos(), r * phi.sin(), z)
            } else {
                let w = ggx::sample_wi_64(alpha, wo, [rng.next_f64(), rng.next_f64()]);
                if w.z > 0.0 { w } else { mean_dir }
            };
            let ang = (0.002f64.ln() + rng.next_f64() * (1.0f64.ln() - 0.002f64.ln())).exp();
            caps.push(Cap64::new(axis, ang.cos()));
        }
        let refs: Vec<f64> = caps
            .iter()
            .enumerate()
            .map(|(k, c)| {
                crate::reference::cap_integral_64(wo, alpha, c, ref_samples, seed ^ (k as u64 + 1))
                    .0
            })
            .collect();
        let eps = 0.01 * refs.iter().sum::<f64>() / refs.len() as f64 + 1e-9;
        Self { caps, refs, eps }
    }

    /// Mean squared log-ratio error of the cap integrals `g`.
    pub fn log_err(&self, g: impl Fn(&Cap64) -> f64) -> f64 {
        let mut s = 0.0;
        for (c, r) in self.caps.iter().zip(&self.refs) {
            let e = ((g(c) + self.eps) / (r + self.eps)).ln();
            s += e * e;
        }
        s / self.caps.len() as f64
    }
}

/// Nelder–Mead minimisation from `x0` with initial simplex steps `step`. Returns (x, f(x), evals).
pub fn nelder_mead(
    f: impl Fn(&[f64]) -> f64,
    x0: &[f64],
    step: &[f64],
    max_evals: usize,
    ftol: f64,
) -> (Vec<f64>, f64, usize) {
    let n = x0.len();
    let mut simplex: Vec<Vec<f64>> = vec![x0.to_vec()];
    for i in 0..n {
        let mut x = x0.to_vec();
        x[i] += step[i];
        simplex.push(x);
    }
    let mut vals: Vec<f64> = simplex.iter().map(|x| f(x)).collect();
    let mut evals = n + 1;
    while evals < max_evals {
        // order
        let mut idx: Vec<usize> = (0..=n).collect();
        idx.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]));
        simplex = idx.iter().map(|&i| simplex[i].clone()).collect();
        vals = idx.iter().map(|&i| vals[i]).collect();
        if (vals[n] - vals[0]).abs() <= ftol * (vals[0].abs() + 1e-300) {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|j| simplex[..n].iter().map(|x| x[j]).sum::<f64>() / n as f64)
            .collect();
        let at = |t: f64| -> Vec<f64> {
            (0..n)
                .map(|j| centroid[j] + t * (simplex[n][j] - centroid[j]))
                .collect()
        };
        let xr = at(-1.0);
        let fr = f(&xr);
        evals += 1;
        if fr < vals[0] {
            let xe = at(-2.0);
            let fe = f(&xe);
            evals += 1;
            if fe < fr {
                simplex[n] = xe;
                vals[n] = fe;
            } else {
                simplex[n] = xr;
                vals[n] = fr;
            }
        } else if fr < vals[n - 1] {
            simplex[n] = xr;
            vals[n] = fr;
        } else {
            let (xc, fc) = if fr < vals[n] {
                let x = at(-0.5);
                let v = f(&x);
                (x, v)
            } else {
                let x = at(0.5);
                let v = f(&x);
                (x, v)
            };
            evals += 1;
            if fc < vals[n].min(fr) {
                simplex[n] = xc;
                vals[n] = fc;
            } else {
                // shrink towards the best
                let best = simplex[0].clone();
                for i in 1..=n {
                    for (x, b) in simplex[i].iter_mut().zip(&best) {
                        *x = b + 0.5 * (*x - b);
                    }
                    vals[i] = f(&simplex[i]);
                }
                evals += n;
            }
        }
    }
    let best = (0..=n)
        .min_by(|&a, &b| vals[a].total_cmp(&vals[b]))
        .unwrap();
    (simplex[best].clone(), vals[best], evals)
}

/// The fit grid shared by both tables: 64 × 64 cells, θo = i/63 · π/2 (fitted at
/// min(θo, [`THETA_FIT_MAX`])) and √α = j/63 (fitted at max(α, [`ALPHA_MIN`])).
pub const N: usize = 64;
/// Largest θo (radians, 89.5°) a cell is fitted at; the last row sits at π/2.
pub const THETA_FIT_MAX: f64 = 1.5620696805349; // 89.5°
/// Smallest GGX α a cell is fitted at; the first column sits at α = 0.
pub const ALPHA_MIN: f64 = 0.001;

/// `(θo, α)` at which cell `(i, j)` is fitted, i, j ∈ [0, [`N`]): θo in radians, α the GGX
/// roughness (not √α), both with the limits above applied.
pub fn cell_params(i: usize, j: usize) -> (f64, f64) {
    let theta = (i as f64 / (N - 1) as f64 * std::f64::consts::FRAC_PI_2).min(THETA_FIT_MAX);
    let s = j as f64 / (N - 1) as f64;
    (theta, (s * s).max(ALPHA_MIN))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nelder_mead_rosenbrock() {
        let f = |x: &[f64]| (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2);
        let (x, v, _) = nelder_mead(f, &[-1.0, 1.0], &[0.5, 0.5], 5000, 1e-14);
        assert!(v < 1e-8 && (x[0] - 1.0).abs() < 1e-3, "{x:?} {v}");
    }

    #[test]
    fn l1_of_the_lobe_against_zero_is_the_albedo() {
        let wo = DVec3::new(0.5f64.sin(), 0.0, 0.5f64.cos());
        let s = CellSamples::new(0.2, wo, 4096, 1);
        let l1 = s.l1(|_| 0.0);
        let (a, _) = ggx::albedo_64(0.2, wo, 1 << 14, 8, 2);
        assert!((l1 - a).abs() < 5e-3, "{l1} vs {a}");
    }
}
