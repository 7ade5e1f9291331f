//! SPTD (spherical pivot-transformed distribution) approximation of the GGX lobe and its closed-form
//! cap integral.
//!
//! Per (θo, √α) cell the table holds a pivot ρ(sin θp, 0, cos θp) (ωo on +x, θp ≤ 0 points to the
//! mirror side) and the albedo A. The lobe is approximated on the upper hemisphere H by
//! g(ω) = A · D_r(ω) / D_r(H), D_r the uniform-base SPTD; so
//!
//! ∫_{C∩H} f·cos ≈ A · |T(C) ∩ T(H)| / |T(H)|      ([`Normalization::Hemisphere`], default)
//!
//! and the hemisphere integrates exactly to the tabulated albedo. The authors' form
//! A · |T(C) ∩ T(H)| / 4π (which loses the SPTD mass below the horizon, 1–20 %) is available as
//! [`Normalization::FullSphere`].

use crate::cap::{Cap, Cap64, lens_area_exact, lens_area_oat_sander};
use crate::fit::{self, CellCaps, CellSamples};
use crate::pivot::{jacobian64, transform_cap64};
use crate::table::{Lookup, Table};
use crate::{CapIntegral, LobeIntegral};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::{Arc, OnceLock};

/// Channels: ρ, θp, albedo A, fitted relative L1 error (∫|f·cos − g| / A).
pub type SptdTable = Table<4>;
/// File magic of a serialised [`SptdTable`] (see [`Table::to_bytes`]).
pub const MAGIC: &[u8; 8] = b"SPTDGGX1";

static DEFAULT_BYTES: &[u8] = include_bytes!("../data/sptd_ggx_64x64.bin");
static DEFAULT: OnceLock<Arc<SptdTable>> = OnceLock::new();

/// The committed table (see `data/sptd_ggx_64x64.txt` for the command that regenerates it).
pub fn default_table() -> Arc<SptdTable> {
    DEFAULT
        .get_or_init(|| {
            Arc::new(SptdTable::from_bytes(DEFAULT_BYTES, MAGIC).expect("committed SPTD table"))
        })
        .clone()
}

/// How an SPTD lobe computes the area of T(C) ∩ T(H), the two-cap intersection behind every
/// integral.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Intersection {
    /// Exact spherical-lens area (default).
    #[default]
    Exact,
    /// Oat–Sander smoothstep approximation (the authors' code).
    OatSander,
}

/// What an SPTD lobe's mass is divided by (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Normalization {
    /// A · |T(C) ∩ T(H)| / |T(H)|: the hemisphere integrates to the albedo (default).
    #[default]
    Hemisphere,
    /// A · |T(C) ∩ T(H)| / 4π, as in the authors' code.
    FullSphere,
}

/// The SPTD cap-integral method: a fitted table plus the evaluation options. Cheap to clone
/// (the table is shared). [`Sptd::default`] uses the committed table and the default of every
/// option.
#[derive(Clone, Debug)]
pub struct Sptd {
    /// Per-cell pivot and albedo over (θo, √α); see [`SptdTable`].
    pub table: Arc<SptdTable>,
    /// How the table is interpolated.
    pub lookup: Lookup,
    /// How cap intersection areas are computed.
    pub intersection: Intersection,
    /// How the lobe is normalised.
    pub normalization: Normalization,
}

impl Default for Sptd {
    fn default() -> Self {
        Self::with_table(default_table())
    }
}

impl Sptd {
    /// The method with a given table (e.g. a refit) and default options.
    pub fn with_table(table: Arc<SptdTable>) -> Self {
        Self {
            table,
            lookup: Lookup::default(),
            intersection: Intersection::default(),
            normalization: Normalization::default(),
        }
    }
    /// Builder: sets [`Sptd::lookup`].
    pub fn lookup(mut self, lookup: Lookup) -> Self {
        self.lookup = lookup;
        self
    }
    /// Builder: sets [`Sptd::intersection`].
    pub fn intersection(mut self, intersection: Intersection) -> Self {
        self.intersection = intersection;
        self
    }
    /// Builder: sets [`Sptd::normalization`].
    pub fn normalization(mut self, normalization: Normalization) -> Self {
        self.normalization = normalization;
        self
    }
    /// Table entry (ρ, θp, A) for view angle θo (radians) and GGX α: pivot distance ρ ∈ [0, 1),
    /// pivot elevation θp in radians (for ωo in the +x half of the xz-plane; negative = mirror
    /// side) and directional albedo A.
    pub fn params(&self, theta_o: f32, alpha: f32) -> (f32, f32, f32) {
        let c = self.table.lookup(theta_o, alpha, self.lookup);
        (c[0], c[1], c[2])
    }
}

/// Pivot vector for ωo in the local frame: ρ(sin θp cos φo, sin θp sin φo, cos θp).
#[inline]
fn pivot_vector(wo: Vec3, rho: f64, theta_p: f64) -> DVec3 {
    let (c, s) = azimuth(wo);
    let (sp, cp) = theta_p.sin_cos();
    DVec3::new(rho * sp * c, rho * sp * s, rho * cp)
}

#[inline]
fn azimuth(wo: Vec3) -> (f64, f64) {
    let r = ((wo.x as f64).powi(2) + (wo.y as f64).powi(2)).sqrt();
    if r > 0.0 {
        (wo.x as f64 / r, wo.y as f64 / r)
    } else {
        (1.0, 0.0)
    }
}

/// θo of a local-frame ωo.
#[inline]
pub(crate) fn theta_of(wo: Vec3) -> f32 {
    (wo.z.clamp(-1.0, 1.0)).acos()
}

/// Per-shading-point SPTD lobe: the pivot, T(H) and the scale.
#[derive(Clone, Copy, Debug)]
pub struct SptdLobe {
    /// The pivot r in the local frame (z = normal), |r| < 1; its azimuth follows ωo's.
    pub pivot: Vec3,
    pivot64: DVec3,
    th: Cap64,
    scale: f64,
    albedo: f32,
    intersection: Intersection,
}

impl SptdLobe {
    /// A lobe from its pivot (local frame, |pivot| < 1), its albedo A (the value over the
    /// whole upper hemisphere with [`Normalization::Hemisphere`]) and the options.
    pub fn new(
        pivot: DVec3,
        albedo: f32,
        intersection: Intersection,
        normalization: Normalization,
    ) -> Self {
        let th = transform_cap64(pivot, &Cap64::new(DVec3::Z, 0.0));
        let denom = match normalization {
            Normalization::Hemisphere => th.area(),
            Normalization::FullSphere => 4.0 * PI,
        };
        let scale = if denom > 0.0 {
            albedo as f64 / denom
        } else {
            0.0
        };
        Self {
            pivot: pivot.as_vec3(),
            pivot64: pivot,
            th,
            scale,
            albedo,
            intersection,
        }
    }
    /// A sampler of directions in `cap` distributed ∝ this SPTD restricted to the cap (for sampling
    /// a sphere light by the lobe, method.md §3.1). Its samples may fall below the horizon, where
    /// the lobe is zero.
    pub fn cap_sampler(&self, cap: &Cap) -> crate::pivot::CapSampler {
        crate::pivot::CapSampler::new(self.pivot, cap)
    }
    /// T(H), the pivot-transformed upper hemisphere.
    pub fn transformed_hemisphere(&self) -> Cap {
        self.th.to32()
    }
    /// The factor of g(ω) in front of the pivot Jacobian: g(ω) = this ·
    /// ((1 − |r|²)/|ω − r|²)² on H, for callers that evaluate g in their own lanes.
    pub fn density_scale(&self) -> f64 {
        self.scale
    }
    /// The approximating density g(ω) on H (zero below it).
    pub fn density(&self, w: Vec3) -> f32 {
        if w.z <= 0.0 {
            return 0.0;
        }
        (self.scale * jacobian64(self.pivot64, w.as_dvec3())) as f32
    }
    #[inline]
    pub(crate) fn integral64(&self, cap: &Cap64) -> f64 {
        let tc = transform_cap64(self.pivot64, cap);
        let a = match self.intersection {
            Intersection::Exact => lens_area_exact(&tc, &self.th),
            Intersection::OatSander => lens_area_oat_sander(&tc, &self.th),
        };
        self.scale * a
    }
}

impl LobeIntegral for SptdLobe {
    #[inline]
    fn integral(&self, cap_axis: Vec3, cap_cos: f32) -> f32 {
        self.integral64(&Cap64::new(cap_axis.as_dvec3(), cap_cos as f64)) as f32
    }
    fn hemisphere(&self) -> f32 {
        (self.scale * self.th.area()) as f32
    }
    fn albedo(&self) -> f32 {
        self.albedo
    }
}

impl CapIntegral for Sptd {
    type Lobe = SptdLobe;
    fn lobe(&self, wo_local: Vec3, alpha: f32) -> SptdLobe {
        let (rho, theta_p, a) = self.params(theta_of(wo_local), alpha);
        SptdLobe::new(
            pivot_vector(wo_local, rho as f64, theta_p as f64),
            a,
            self.intersection,
            self.normalization,
        )
    }
}

/// Fit report of one cell.
#[derive(Clone, Copy, Debug)]
pub struct CellFit {
    /// Fitted pivot distance ρ ∈ (0, 1).
    pub rho: f64,
    /// Fitted pivot elevation θp in radians, in [−π/2, π/2] (ωo on +x; negative = mirror side).
    pub theta_p: f64,
    /// Reference GGX directional albedo A of the cell.
    pub albedo: f64,
    /// ∫_H |f·cos − g| / A at the fit: relative L1 error of the lobe (0 = exact).
    pub rel_l1: f64,
    /// Mean squared log-ratio of fitted to reference cap integrals ([`CellCaps::log_err`]).
    pub log_err: f64,
    /// The minimised objective, `rel_l1 + log_err`.
    pub objective: f64,
    /// Objective evaluations spent by the winning start.
    pub evals: usize,
}

/// Objective for a pivot (ρ, θp), ωo = (sin θo, 0, cos θo): relative L1 + cap log error.
fn sptd_objective(
    s: &CellSamples,
    caps: &CellCaps,
    albedo: f64,
    rho: f64,
    theta_p: f64,
) -> (f64, f64) {
    let p = DVec3::new(rho * theta_p.sin(), 0.0, rho * theta_p.cos());
    let lobe = SptdLobe::new(
        p,
        albedo as f32,
        Intersection::Exact,
        Normalization::Hemisphere,
    );
    let scale = lobe.scale;
    let l1 = s.l1(|w| scale * jacobian64(p, w)) / albedo;
    let le = caps.log_err(|c| lobe.integral64(c));
    (l1, le)
}

fn logit(x: f64) -> f64 {
    (x / (1.0 - x)).ln()
}
fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// Fits one cell starting from the given guesses; keeps the best.
pub fn fit_cell(
    theta_o: f64,
    alpha: f64,
    samples: usize,
    albedo_samples: usize,
    starts: &[(f64, f64)],
) -> CellFit {
    let wo = DVec3::new(theta_o.sin(), 0.0, theta_o.cos());
    let seed = (theta_o.to_bits() ^ alpha.to_bits().rotate_left(17)) | 1;
    let (albedo, _) = crate::ggx::albedo_64(alpha, wo, albedo_samples, 8, seed);
    let s = CellSamples::new(alpha, wo, samples, seed.wrapping_mul(3));
    let mean = s.mean_direction();
    let mean = if mean.length_squared() > 0.0 {
        mean.normalize()
    } else {
        DVec3::Z
    };
    let caps = CellCaps::new(
        alpha,
        wo,
        mean,
        CAPS_PER_CELL,
        CAP_REF_SAMPLES,
        seed.wrapping_mul(5),
    );
    let obj = |x: &[f64]| {
        let rho = sigmoid(x[0]).clamp(1e-4, 1.0 - 1e-7);
        let tp = x[1].clamp(-FRAC_PI_2_64, FRAC_PI_2_64);
        let (l1, le) = sptd_objective(&s, &caps, albedo, rho, tp);
        l1 + le
    };
    let mut best: Option<CellFit> = None;
    let mean_theta = mean.x.atan2(mean.z);
    let mut starts = starts.to_vec();
    starts.push((initial_guess(theta_o, alpha).0, mean_theta));
    for &(rho0, tp0) in &starts {
        let (x, v, evals) = fit::nelder_mead(
            obj,
            &[logit(rho0.clamp(0.01, 0.99995)), tp0],
            &[0.4, 0.15],
            400,
            1e-7,
        );
        let rho = sigmoid(x[0]).clamp(1e-4, 1.0 - 1e-7);
        let theta_p = x[1].clamp(-FRAC_PI_2_64, FRAC_PI_2_64);
        let (rel_l1, log_err) = sptd_objective(&s, &caps, albedo, rho, theta_p);
        let fit = CellFit {
            rho,
            theta_p,
            albedo,
            rel_l1,
            log_err,
            objective: v,
            evals,
        };
        if best.is_none_or(|b| fit.objective < b.objective) {
            best = Some(fit);
        }
    }
    best.unwrap()
}

const FRAC_PI_2_64: f64 = std::f64::consts::FRAC_PI_2;
/// Test caps per cell in the fit objective (shared by the LTC fit).
pub const CAPS_PER_CELL: usize = 96;
/// Reference-integrator samples per test cap in the fit objective.
pub const CAP_REF_SAMPLES: usize = 2048;

/// Heuristic initial pivot: 1 − ρ ≈ 2α matches the peak height at normal incidence.
pub fn initial_guess(theta_o: f64, alpha: f64) -> (f64, f64) {
    (
        (1.0 - 2.0 * alpha).clamp(0.3, 0.9995),
        -theta_o * (1.0 - alpha),
    )
}

/// Fits the whole 64 × 64 table (rows of θo in parallel; along a row from rough to smooth, each
/// cell warm-started from its neighbour and from the heuristic guess).
pub fn fit_table(
    samples: usize,
    albedo_samples: usize,
    progress: impl Fn(usize) + Sync,
) -> SptdTable {
    let n = fit::N;
    let rows: Vec<Vec<[f32; 4]>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut row = vec![[0.0f32; 4]; n];
            let mut prev: Option<(f64, f64)> = None;
            for j in (0..n).rev() {
                let (theta, alpha) = fit::cell_params(i, j);
                let mut starts = vec![initial_guess(theta, alpha)];
                if let Some(p) = prev {
                    starts.push(p);
                }
                let c = fit_cell(theta, alpha, samples, albedo_samples, &starts);
                prev = Some((c.rho, c.theta_p));
                row[j] = [
                    c.rho as f32,
                    c.theta_p as f32,
                    c.albedo as f32,
                    c.rel_l1 as f32,
                ];
            }
            progress(i);
            row
        })
        .collect();
    let mut t = SptdTable::new(n, n);
    for (i, row) in rows.into_iter().enumerate() {
        for (j, c) in row.into_iter().enumerate() {
            *t.cell_mut(i, j) = c;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ggx::wo_from_theta;
    use crate::reference;

    #[test]
    fn table_lookup_reproduces_grid_points() {
        crate::table::assert_lookup_reproduces_grid_points(&default_table(), 3);
    }

    #[test]
    fn hemisphere_is_albedo() {
        let s = Sptd::default();
        for &(alpha, th) in &[(0.001f32, 0.2f32), (0.05, 1.2), (0.5, 0.7), (1.0, 1.5)] {
            let wo = wo_from_theta(th);
            let lobe = s.lobe(wo, alpha);
            let (a, _) = reference::hemisphere(wo, alpha, 1 << 13);
            assert!(
                (lobe.hemisphere() / a - 1.0).abs() < 0.02,
                "{alpha} {th}: {} vs {a}",
                lobe.hemisphere()
            );
            let h = lobe.integral(Vec3::Z, 0.0);
            assert!((h - lobe.hemisphere()).abs() < 1e-5);
        }
    }

    #[test]
    fn integrals_are_bounded_and_non_negative() {
        let s = Sptd::default();
        let mut rng = crate::qmc::SplitMix64::new(11);
        for _ in 0..300 {
            let alpha = (rng.next_f64() as f32).powi(2).max(0.001);
            let wo = wo_from_theta(rng.next_f64() as f32 * 1.55);
            let z = 2.0 * rng.next_f64() - 1.0;
            let phi = 2.0 * PI * rng.next_f64();
            let r = (1.0 - z * z).sqrt();
            let axis = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            let cos = (2.0 * rng.next_f64() - 1.0) as f32;
            let lobe = s.lobe(wo, alpha);
            let v = lobe.integral(axis, cos);
            assert!(
                v >= 0.0 && v <= lobe.hemisphere() * (1.0 + 1e-5),
                "{v} > {}",
                lobe.hemisphere()
            );
            // and never above the reference hemisphere value by more than the stated 2 %
            let (a, _) = reference::hemisphere(wo, alpha, 1024);
            assert!(v <= a * 1.02 + 1e-4);
        }
    }

    #[test]
    fn close_to_reference_near_the_peak() {
        // a moderately rough lobe, caps around the mirror direction
        let s = Sptd::default();
        let (alpha, th) = (0.2f32, 0.6f32);
        let wo = wo_from_theta(th);
        let lobe = s.lobe(wo, alpha);
        let mirror = Vec3::new(-wo.x, 0.0, wo.z);
        for &ang in &[0.1f32, 0.3, 0.6] {
            let cap = Cap::new(mirror, ang.cos());
            let (r, _) = reference::cap_integral(wo, alpha, &cap, 1 << 12);
            let v = lobe.integral(cap.axis, cap.cos_theta);
            assert!(
                (v - r).abs() < 0.1 * r + 0.01,
                "angle {ang}: sptd {v} ref {r}"
            );
        }
    }
}
