//! LTC (linearly transformed cosine, Heitz et al. 2016) approximation of the GGX lobe and its cap
//! integral through the cap's tangent disk as an LTC-transformed ellipse (Heitz & Hill 2017).
//!
//! Per (θo, √α) cell the table holds M⁻¹ = [[m0, 0, m1], [0, 1, 0], [m2, 0, m3]] (ωo on +x,
//! normalised so M⁻¹_yy = 1; D is invariant to the scale of M⁻¹) and the albedo A. The LTC density
//! D(ω) = D₀(M⁻¹ω/|M⁻¹ω|) |det M⁻¹| / |M⁻¹ω|³ with D₀ = max(0, z)/π integrates to 1 over the
//! sphere; as for the SPTD, the lobe is normalised on the upper hemisphere:
//! ∫_{C∩H} f·cos ≈ A · D(C) / D(H), with D(H) = (1 + n_z)/2, n = normalize(Mᵀ z) (closed form).
//!
//! Cap integral D(C): the directions of a cap of half-angle θc < π/2 about c are those through
//! the disk at c of radius tan θc. Under M⁻¹ the disk becomes an ellipse and the cone of
//! directions an elliptic cone {x : xᵀQx ≤ 0}, Q ∝ cos²θc MᵀM − (Mᵀc)(Mᵀc)ᵀ. With its eigenvalues
//! λ1 ≥ λ2 > 0 > λ3, the clamped-cosine integral about its own axis e3 (the form factor) is
//! ab/√((1+a²)(1+b²)) = |λ3| / √((λ1−λ3)(λ2−λ3)) (a² = −λ3/λ1, b² = −λ3/λ2). As in Heitz & Hill,
//! the cone is then replaced by the circular cone with the same form factor and axis (sin²σ = ff)
//! and clipped at the LTC horizon z' = 0 with the closed form for a horizon-clipped sphere.
//! Caps larger than a hemisphere use the complement. The shading horizon (z = 0 in the local
//! frame) is handled approximately: the equivalent cone is weighted by its solid-angle fraction on
//! the upper side of the image of z = 0, clamped to D(C) − D(below H) ≤ D(C ∩ H) ≤ min(D(C), D(H));
//! caps entirely below the horizon give 0.

use crate::cap::{Cap64, below_horizon, lens_area_exact};
use crate::fit::{self, CellCaps, CellSamples};
use crate::table::{Lookup, Table};
use crate::{CapIntegral, LobeIntegral};
use glam::{DMat3, DVec3, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::{Arc, OnceLock};

/// Channels: m0, m1, m2, m3 (M⁻¹ entries), albedo A, fitted relative L1 error.
pub type LtcTable = Table<6>;
/// File magic of a serialised [`LtcTable`] (see [`Table::to_bytes`]).
pub const MAGIC: &[u8; 8] = b"LTCGGX01";

static DEFAULT_BYTES: &[u8] = include_bytes!("../data/ltc_ggx_64x64.bin");
static DEFAULT: OnceLock<Arc<LtcTable>> = OnceLock::new();

/// The committed table (see `data/ltc_ggx_64x64.txt` for the command that regenerates it).
pub fn default_table() -> Arc<LtcTable> {
    DEFAULT
        .get_or_init(|| {
            Arc::new(LtcTable::from_bytes(DEFAULT_BYTES, MAGIC).expect("committed LTC table"))
        })
        .clone()
}

/// The LTC cap-integral method: a fitted table plus its lookup mode. Cheap to clone (the table
/// is shared). [`Ltc::default`] uses the committed table with bilinear lookup.
#[derive(Clone, Debug)]
pub struct Ltc {
    /// Per-cell M⁻¹ entries and albedo over (θo, √α); see [`LtcTable`].
    pub table: Arc<LtcTable>,
    /// How the table is interpolated.
    pub lookup: Lookup,
}

impl Default for Ltc {
    fn default() -> Self {
        Self::with_table(default_table())
    }
}

impl Ltc {
    /// The method with a given table (e.g. a refit) and bilinear lookup.
    pub fn with_table(table: Arc<LtcTable>) -> Self {
        Self {
            table,
            lookup: Lookup::default(),
        }
    }
    /// Builder: sets [`Ltc::lookup`].
    pub fn lookup(mut self, lookup: Lookup) -> Self {
        self.lookup = lookup;
        self
    }
}

/// Per-shading-point LTC lobe.
#[derive(Clone, Copy, Debug)]
pub struct LtcLobe {
    /// M⁻¹ in the local frame (azimuth of ωo included).
    pub minv: DMat3,
    m: DMat3,
    /// MᵀM.
    g: DMat3,
    det_g: f64,
    det_minv: f64,
    /// Normal of the image of the shading horizon in the LTC space, and D(H).
    n_h: DVec3,
    mass_h: f64,
    /// Clip at the shading horizon as well as at the LTC's own (default true).
    pub clip_shading_horizon: bool,
    scale: f64,
    albedo: f32,
}

impl LtcLobe {
    /// From M⁻¹ in the local frame (invertible) and the albedo A, the value the lobe
    /// gives the whole upper hemisphere.
    pub fn new(minv: DMat3, albedo: f32) -> Self {
        let m = minv.inverse();
        let n = m.transpose() * DVec3::Z;
        let mass_h = 0.5 * (1.0 + n.z / n.length());
        let scale = if mass_h > 0.0 {
            albedo as f64 / mass_h
        } else {
            0.0
        };
        let det_m = m.determinant();
        Self {
            minv,
            m,
            g: m.transpose() * m,
            det_g: det_m * det_m,
            det_minv: minv.determinant().abs(),
            n_h: n.normalize(),
            mass_h,
            clip_shading_horizon: true,
            scale,
            albedo,
        }
    }

    /// LTC density D(ω) per steradian at the unit local-frame direction `w` (normalised over the
    /// sphere, not the hemisphere).
    pub fn ltc_density(&self, w: DVec3) -> f64 {
        let v = self.minv * w;
        let l2 = v.length_squared();
        let l = l2.sqrt();
        (v.z / l).max(0.0) / PI * self.det_minv / (l2 * l)
    }

    /// The approximating density g(ω) = A D(ω)/D(H) on H (zero below it).
    pub fn density(&self, w: Vec3) -> f32 {
        if w.z <= 0.0 {
            return 0.0;
        }
        (self.scale * self.ltc_density(w.as_dvec3())) as f32
    }

    /// D(C ∩ H): the LTC mass of a cap, clipped at the LTC's own horizon exactly (for the
    /// equivalent circular cone) and at the shading horizon approximately (solid-angle fraction of
    /// the equivalent cone above it).
    #[inline]
    pub(crate) fn cap_mass(&self, cap: &Cap64) -> f64 {
        if cap.cos < 0.0 {
            // larger than a hemisphere: the complement, without the shading-horizon clip (the
            // equivalent-cone fraction is a poor approximation for hemisphere-sized cones)
            let comp = Cap64 {
                axis: -cap.axis,
                cos: -cap.cos,
                sin: cap.sin,
            };
            return (1.0 - self.cap_mass_ltc(&comp, false)).clamp(0.0, self.mass_h);
        }
        self.cap_mass_ltc(cap, self.clip_shading_horizon)
    }

    #[inline]
    fn cap_mass_ltc(&self, cap: &Cap64, clip_shading_horizon: bool) -> f64 {
        if cap.sin <= 0.0 {
            return 0.0;
        }
        let cos = cap.cos;
        let p3 = self.m.transpose() * cap.axis;
        let q = self.g * (cos * cos) - outer(p3, p3);
        // Frobenius normalisation, then eigenvalues; det(Q) is known in closed form by the matrix
        // determinant lemma, det(cos²G − ppᵀ) = −cos⁴ sin² det G (as pᵀG⁻¹p = |c|² = 1), which
        // keeps the form factor accurate for tiny caps and near-hemispherical ones.
        let norm =
            (q.x_axis.length_squared() + q.y_axis.length_squared() + q.z_axis.length_squared())
                .sqrt();
        if norm <= 0.0 {
            return 0.0;
        }
        let q = q * (1.0 / norm);
        let det =
            -(cos * cos) * (cos * cos) * (cap.sin * cap.sin) * self.det_g / (norm * norm * norm);
        let tr = q.x_axis.x + q.y_axis.y + q.z_axis.z;
        let (l1, l2, l3, e3) = eig_neg(q);
        if l3 >= 0.0 {
            return 0.0;
        }
        let (l3, l12, s12) = if -l3 >= l1 {
            // λ3 dominant (large cap): λ1λ2 from the determinant
            (l3, det / l3, tr - l3)
        } else {
            // λ3 small (small cap): λ3 from the determinant
            let p12 = l1 * l2;
            let l3 = if p12 > 0.0 { det / p12 } else { l3 };
            (l3, p12, l1 + l2)
        };
        let den = l12 - l3 * s12 + l3 * l3;
        let ff = if den > 0.0 {
            (-l3 / den.sqrt()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let c_prime = self.minv * cap.axis;
        let e3 = if e3.dot(c_prime) < 0.0 { -e3 } else { e3 };
        let clipped = clipped_sphere_form_factor(e3.z, ff);
        if !clip_shading_horizon || clipped <= 0.0 {
            return clipped;
        }
        // shading horizon: keep the fraction of the equivalent cap on the upper side of the image
        // of z = 0 (normal n_h in the LTC space); exact when the cap does not cross it
        let eq = Cap64 {
            axis: e3,
            cos: (1.0 - ff).sqrt(),
            sin: ff.sqrt(),
        };
        let area = eq.area();
        if area <= 0.0 {
            return if e3.dot(self.n_h) >= 0.0 {
                clipped
            } else {
                0.0
            };
        }
        let frac = lens_area_exact(
            &eq,
            &Cap64 {
                axis: self.n_h,
                cos: 0.0,
                sin: 1.0,
            },
        ) / area;
        // and stay within the rigorous bounds D(C) − D(below H) ≤ D(C ∩ H) ≤ min(D(C), D(H))
        let lo = clipped - (1.0 - self.mass_h);
        let hi = clipped.min(self.mass_h);
        (clipped * frac.clamp(0.0, 1.0)).max(lo).min(hi)
    }

    #[inline]
    pub(crate) fn integral64(&self, cap: &Cap64) -> f64 {
        if below_horizon(cap) {
            return 0.0;
        }
        (self.scale * self.cap_mass(cap)).clamp(0.0, self.albedo as f64)
    }
}

#[inline]
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Eigenvalues λ1 ≥ λ2 ≥ λ3 of a symmetric 3×3 matrix (trigonometric method) and a unit
/// eigenvector of λ3.
#[inline]
pub(crate) fn eig_neg(q: DMat3) -> (f64, f64, f64, DVec3) {
    let (a00, a11, a22) = (q.x_axis.x, q.y_axis.y, q.z_axis.z);
    let (a01, a02, a12) = (q.y_axis.x, q.z_axis.x, q.z_axis.y);
    let p1 = a01 * a01 + a02 * a02 + a12 * a12;
    let tr = (a00 + a11 + a22) / 3.0;
    let p2 = (a00 - tr).powi(2) + (a11 - tr).powi(2) + (a22 - tr).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    if p == 0.0 {
        return (tr, tr, tr, DVec3::Z);
    }
    let b = (q - DMat3::from_diagonal(DVec3::splat(tr))) * (1.0 / p);
    let r = (b.determinant() * 0.5).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let l1 = tr + 2.0 * p * phi.cos();
    let l3 = tr + 2.0 * p * (phi + 2.0 * PI / 3.0).cos();
    let l2 = 3.0 * tr - l1 - l3;
    // eigenvector of l3: cross products of the rows of (Q − λ3 I)
    let m = q - DMat3::from_diagonal(DVec3::splat(l3));
    let (r0, r1, r2) = (m.row(0), m.row(1), m.row(2));
    let c01 = r0.cross(r1);
    let c02 = r0.cross(r2);
    let c12 = r1.cross(r2);
    let (n01, n02, n12) = (
        c01.length_squared(),
        c02.length_squared(),
        c12.length_squared(),
    );
    let v = if n01 >= n02 && n01 >= n12 {
        c01 / n01.sqrt()
    } else if n02 >= n12 {
        c02 / n02.sqrt()
    } else {
        c12 / n12.sqrt()
    };
    (l1, l2, l3, v)
}

/// (1/π) ∫ max(0, ω·z) dω over the cap with axis elevation cosine `cos_t` and sin²(half-angle)
/// `sin2s`: the form factor of a sphere clipped at the horizon (Snyder's closed form).
#[inline]
pub fn clipped_sphere_form_factor(cos_t: f64, sin2s: f64) -> f64 {
    let cos_t = cos_t.clamp(-1.0, 1.0);
    if cos_t * cos_t >= sin2s {
        return (cos_t * sin2s).max(0.0);
    }
    if sin2s >= 1.0 {
        return 0.5 * (1.0 + cos_t);
    }
    let sin_t = (1.0 - cos_t * cos_t).sqrt();
    let x = (1.0 / sin2s - 1.0).sqrt(); // cot σ
    let y = (-x * cos_t / sin_t).clamp(-1.0, 1.0);
    let st_sy = sin_t * (1.0 - y * y).sqrt();
    ((cos_t * y.acos() - x * st_sy) * sin2s + st_sy.atan2(x)) / PI
}

impl LobeIntegral for LtcLobe {
    #[inline]
    fn integral(&self, cap_axis: Vec3, cap_cos: f32) -> f32 {
        self.integral64(&Cap64::new(cap_axis.as_dvec3(), cap_cos as f64)) as f32
    }
    fn hemisphere(&self) -> f32 {
        self.albedo
    }
    fn albedo(&self) -> f32 {
        self.albedo
    }
}

/// M⁻¹ for ωo on +x from the table channels.
#[inline]
fn minv_from(c: &[f32]) -> DMat3 {
    // rows (m0, 0, m1), (0, 1, 0), (m2, 0, m3)
    DMat3::from_cols(
        DVec3::new(c[0] as f64, 0.0, c[2] as f64),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(c[1] as f64, 0.0, c[3] as f64),
    )
}

impl CapIntegral for Ltc {
    type Lobe = LtcLobe;
    fn lobe(&self, wo_local: Vec3, alpha: f32) -> LtcLobe {
        let c = self
            .table
            .lookup(crate::sptd::theta_of(wo_local), alpha, self.lookup);
        let mut minv = minv_from(&c);
        // rotate the local frame so that ωo lies on +x: M⁻¹ · R_z(−φo)
        let r = (wo_local.x as f64).hypot(wo_local.y as f64);
        if r > 0.0 && wo_local.y != 0.0 {
            let (cphi, sphi) = (wo_local.x as f64 / r, wo_local.y as f64 / r);
            let rot = DMat3::from_cols(
                DVec3::new(cphi, -sphi, 0.0),
                DVec3::new(sphi, cphi, 0.0),
                DVec3::Z,
            );
            minv *= rot;
        }
        LtcLobe::new(minv, c[4])
    }
}

/// M⁻¹ for the fit parameters: M = [X Y Z]·K, K = [[m11, 0, m13], [0, m22, 0], [0, 0, 1]],
/// Z = the lobe's mean direction at elevation `theta_z` in the xz-plane.
pub fn minv_from_params(theta_z: f64, m11: f64, m22: f64, m13: f64) -> DMat3 {
    let z = DVec3::new(theta_z.sin(), 0.0, theta_z.cos());
    let x = DVec3::new(theta_z.cos(), 0.0, -theta_z.sin());
    let r = DMat3::from_cols(x, DVec3::Y, z);
    let k = DMat3::from_cols(
        DVec3::new(m11, 0.0, 0.0),
        DVec3::new(0.0, m22, 0.0),
        DVec3::new(m13, 0.0, 1.0),
    );
    let minv = (r * k).inverse();
    minv * (1.0 / minv.y_axis.y)
}

/// Fit report of one LTC cell.
#[derive(Clone, Copy, Debug)]
pub struct LtcCellFit {
    /// Fitted M⁻¹ for ωo on +x, scaled so that M⁻¹_yy = 1.
    pub minv: DMat3,
    /// The optimiser's parameters (ln m11, ln m22, m13), see [`minv_from_params`].
    pub params: [f64; 3],
    /// Reference GGX directional albedo A of the cell.
    pub albedo: f64,
    /// ∫_H |f·cos − g| / A at the fit: relative L1 error of the lobe (0 = exact).
    pub rel_l1: f64,
    /// Mean squared log-ratio of fitted to reference cap integrals ([`CellCaps::log_err`]).
    pub log_err: f64,
    /// The minimised objective, `rel_l1 + log_err` (`f64::MAX` where that was not finite).
    pub objective: f64,
}

fn ltc_objective(
    s: &CellSamples,
    caps: &CellCaps,
    albedo: f64,
    theta_z: f64,
    x: &[f64],
) -> (f64, f64, DMat3) {
    let (m11, m22, m13) = (x[0].exp(), x[1].exp(), x[2]);
    let minv = minv_from_params(theta_z, m11, m22, m13);
    let lobe = LtcLobe::new(minv, albedo as f32);
    let scale = lobe.scale;
    let l1 = s.l1(|w| scale * lobe.ltc_density(w)) / albedo;
    let le = caps.log_err(|c| lobe.integral64(c));
    (l1, le, minv)
}

/// Fits one cell from the given starting parameters (ln m11, ln m22, m13); keeps the best.
pub fn fit_cell(
    theta_o: f64,
    alpha: f64,
    samples: usize,
    albedo_samples: usize,
    starts: &[[f64; 3]],
) -> LtcCellFit {
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
    let theta_z = mean.x.atan2(mean.z);
    let caps = CellCaps::new(
        alpha,
        wo,
        mean,
        crate::sptd::CAPS_PER_CELL,
        crate::sptd::CAP_REF_SAMPLES,
        seed.wrapping_mul(5),
    );
    let obj = |x: &[f64]| {
        let (l1, le, _) = ltc_objective(&s, &caps, albedo, theta_z, x);
        if l1.is_finite() && le.is_finite() {
            l1 + le
        } else {
            f64::MAX
        }
    };
    let mut best: Option<LtcCellFit> = None;
    for x0 in starts {
        let (x, v, _) = fit::nelder_mead(obj, x0, &[0.3, 0.3, 0.1], 600, 1e-7);
        let (rel_l1, log_err, minv) = ltc_objective(&s, &caps, albedo, theta_z, &x);
        let f = LtcCellFit {
            minv,
            params: [x[0], x[1], x[2]],
            albedo,
            rel_l1,
            log_err,
            objective: v,
        };
        if best.is_none_or(|b| f.objective < b.objective) {
            best = Some(f);
        }
    }
    best.unwrap()
}

/// Fits the 64 × 64 table: rows of θo in parallel; along a row from rough to smooth, warm-started
/// from the neighbouring cell and from a heuristic (m11 = m22 = α, m13 = 0).
pub fn fit_table(
    samples: usize,
    albedo_samples: usize,
    progress: impl Fn(usize) + Sync,
) -> LtcTable {
    let n = fit::N;
    let rows: Vec<Vec<[f32; 6]>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut row = vec![[0.0f32; 6]; n];
            let mut prev: Option<[f64; 3]> = None;
            for j in (0..n).rev() {
                let (theta, alpha) = fit::cell_params(i, j);
                let mut starts = vec![[alpha.ln(), alpha.ln(), 0.0]];
                if let Some(p) = prev {
                    starts.push(p);
                }
                let c = fit_cell(theta, alpha, samples, albedo_samples, &starts);
                prev = Some(c.params);
                let m = c.minv;
                row[j] = [
                    m.x_axis.x as f32,
                    m.z_axis.x as f32,
                    m.x_axis.z as f32,
                    m.z_axis.z as f32,
                    c.albedo as f32,
                    c.rel_l1 as f32,
                ];
            }
            progress(i);
            row
        })
        .collect();
    let mut t = LtcTable::new(n, n);
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
    use crate::pivot::sample_uniform_cap64;
    use crate::qmc::SplitMix64;
    use crate::reference;

    fn mc_cap_mass(lobe: &LtcLobe, cap: &Cap64, n: usize, rng: &mut SplitMix64) -> (f64, f64) {
        let area = cap.area();
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let w = sample_uniform_cap64(cap, [rng.next_f64(), rng.next_f64()]);
            let v = lobe.ltc_density(w) * area;
            s += v;
            s2 += v * v;
        }
        let m = s / n as f64;
        (m, ((s2 / n as f64 - m * m) / n as f64).sqrt())
    }

    #[test]
    fn clipped_sphere_matches_quadrature() {
        let mut rng = SplitMix64::new(2);
        for _ in 0..30 {
            let t = rng.next_f64() * PI;
            let sig = rng.next_f64() * 1.5;
            let cap = Cap64::new(DVec3::new(t.sin(), 0.0, t.cos()), sig.cos());
            let n = 40000;
            let (mut s, mut s2) = (0.0, 0.0);
            for _ in 0..n {
                let w = sample_uniform_cap64(&cap, [rng.next_f64(), rng.next_f64()]);
                let v = w.z.max(0.0) / PI * cap.area();
                s += v;
                s2 += v * v;
            }
            let mc = s / n as f64;
            let se = ((s2 / n as f64 - mc * mc) / n as f64).sqrt();
            let cf = clipped_sphere_form_factor(t.cos(), sig.sin().powi(2));
            assert!(
                (mc - cf).abs() < 5.0 * se + 1e-9,
                "θ {t} σ {sig}: {mc} ± {se} vs {cf}"
            );
        }
    }

    #[test]
    fn cap_mass_exact_when_above_ltc_horizon() {
        // for cones entirely above the LTC horizon the elliptic-cone form factor is exact
        let minv = minv_from_params(-0.5, 0.4, 0.25, 0.1);
        let mut lobe = LtcLobe::new(minv, 1.0);
        lobe.clip_shading_horizon = false;
        let mut rng = SplitMix64::new(3);
        let z = lobe.m * DVec3::Z; // direction of the LTC lobe peak
        let z = z.normalize();
        for k in 0..10 {
            let ang = 0.05 + 0.05 * k as f64;
            let axis = (z + DVec3::new(0.1 * (k as f64 - 5.0) / 5.0, 0.05, 0.0)).normalize();
            let cap = Cap64::new(axis, ang.cos());
            let (mc, se) = mc_cap_mass(&lobe, &cap, 40000, &mut rng);
            let v = lobe.cap_mass(&cap);
            assert!(
                (v - mc).abs() < 5.0 * se + 1e-3 * mc,
                "cap {k}: {v} vs {mc} ± {se}"
            );
        }
    }

    #[test]
    fn near_hemisphere_caps_are_continuous() {
        // a sharp lobe: the cone matrix is badly conditioned for caps close to a hemisphere
        let minv = minv_from_params(-0.3, 0.002, 0.0015, 0.0);
        let mut lobe = LtcLobe::new(minv, 1.0);
        lobe.clip_shading_horizon = false;
        let axis = DVec3::new(0.5, 0.5, 0.5f64.sqrt()).normalize();
        let mut prev: Option<f64> = None;
        for k in -6..=6 {
            let cos = k as f64 * 1e-4;
            let v = lobe.cap_mass(&Cap64::new(axis, cos));
            assert!((0.0..=1.0).contains(&v), "{cos}: {v}");
            if let Some(p) = prev {
                assert!((v - p).abs() < 1e-3, "{cos}: {v} after {p}");
            }
            prev = Some(v);
        }
        // the hemisphere about `axis` holds the sharp lobe, the opposite one almost nothing
        assert!(lobe.cap_mass(&Cap64::new(axis, 0.0)) > 0.99);
        assert!(lobe.cap_mass(&Cap64::new(-axis, 0.0)) < 0.01);
    }

    #[test]
    fn identity_ltc_is_clamped_cosine() {
        let lobe = LtcLobe::new(DMat3::IDENTITY, 1.0);
        let cap = Cap64::new(DVec3::new(0.6, 0.0, 0.8), 0.9);
        assert!(lobe.clip_shading_horizon);
        let v = lobe.cap_mass(&cap);
        assert!((v - 0.8 * (1.0 - 0.81)).abs() < 1e-9, "{v}");
        assert!((lobe.cap_mass(&Cap64::new(DVec3::Z, -1.0)) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn table_lookup_reproduces_grid_points() {
        crate::table::assert_lookup_reproduces_grid_points(&default_table(), 5);
    }

    #[test]
    fn hemisphere_and_bounds() {
        let l = Ltc::default();
        let mut rng = SplitMix64::new(12);
        for _ in 0..200 {
            let alpha = (rng.next_f64() as f32).powi(2).max(0.001);
            let wo = wo_from_theta(rng.next_f64() as f32 * 1.55);
            let lobe = l.lobe(wo, alpha);
            let z = 2.0 * rng.next_f64() - 1.0;
            let phi = 2.0 * PI * rng.next_f64();
            let r = (1.0 - z * z).sqrt();
            let axis = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            let v = lobe.integral(axis, (2.0 * rng.next_f64() - 1.0) as f32);
            assert!(v >= 0.0 && v <= lobe.hemisphere(), "{v}");
            let (a, _) = reference::hemisphere(wo, alpha, 1024);
            assert!(v <= a * 1.02 + 1e-4);
            assert!((lobe.hemisphere() / a - 1.0).abs() < 0.02);
        }
    }

    #[test]
    fn azimuth_rotation_is_consistent() {
        let l = Ltc::default();
        let wo = wo_from_theta(0.8);
        let phi = 1.1f32;
        let rot = glam::Quat::from_rotation_z(phi);
        let axis = Vec3::new(-0.5, 0.1, 0.8).normalize();
        let a = l.lobe(wo, 0.2).integral(axis, 0.9);
        let b = l.lobe(rot * wo, 0.2).integral(rot * axis, 0.9);
        assert!((a - b).abs() < 1e-4 * a.max(1e-3), "{a} vs {b}");
        let s = crate::Sptd::default();
        let a = s.lobe(wo, 0.2).integral(axis, 0.9);
        let b = s.lobe(rot * wo, 0.2).integral(rot * axis, 0.9);
        assert!((a - b).abs() < 1e-4 * a.max(1e-3), "{a} vs {b}");
    }
}
