//! `validate`: accuracy of SPTD and LTC against the reference integrator.

use crate::write_file;
use brdf_integrals::cap::{Cap, Cap64};
use brdf_integrals::fit::CellSamples;
use brdf_integrals::qmc::SplitMix64;
use brdf_integrals::{CapIntegral, Intersection, LobeIntegral, Lookup, Ltc, Sptd, ggx, reference};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

pub const ALPHAS: [f32; 9] = [0.001, 0.003, 0.01, 0.03, 0.1, 0.25, 0.5, 0.75, 1.0];
pub const THETAS_DEG: [f32; 8] = [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0];
pub const HALF_ANGLES: [f32; 7] = [
    0.002,
    0.01,
    0.05,
    0.2,
    0.5,
    1.0,
    std::f32::consts::FRAC_PI_2,
];
pub const POSITIONS: [&str; 5] = ["peak", "near-elevation", "near-azimuth", "far", "horizon"];
/// Relative errors are reported for caps whose reference value is at least this.
pub const REL_FLOOR: f64 = 1e-3;
const SPEARMAN_CAPS: usize = 200;

struct Row {
    alpha: f32,
    theta_deg: f32,
    position: &'static str,
    half_angle: f32,
    cap: Cap,
    reference: f64,
    ref_se: f64,
    values: [f64; 4], // sptd, ltc, sptd-oat-sander, sptd-nearest
}

const METHODS: [&str; 4] = ["sptd", "ltc", "sptd-oatsander", "sptd-nearest"];

/// Mean direction of f·cos and its angular spread.
fn lobe_stats(alpha: f32, wo: Vec3) -> (DVec3, f64) {
    let s = CellSamples::new(alpha as f64, wo.as_dvec3(), 4096, 77);
    let m = s.mean_direction();
    let mean = if m.length_squared() > 0.0 {
        m.normalize()
    } else {
        DVec3::Z
    };
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..s.dirs.len() {
        let a = s.dirs[i].dot(mean).clamp(-1.0, 1.0).acos();
        num += a * a * s.f[i] * s.w[i];
        den += s.f[i] * s.w[i];
    }
    (mean, (num / den.max(1e-30)).sqrt())
}

fn rotate_towards(a: DVec3, b: DVec3, angle: f64) -> DVec3 {
    let t = (b - a * a.dot(b)).normalize_or_zero();
    if t == DVec3::ZERO {
        return a;
    }
    (a * angle.cos() + t * angle.sin()).normalize()
}

fn cap_axis(position: &str, wo: Vec3, mean: DVec3, spread: f64) -> DVec3 {
    let _ = wo;
    match position {
        "peak" => mean,
        // one lobe spread towards the horizon (in the plane of incidence)
        "near-elevation" => rotate_towards(
            mean,
            DVec3::new(mean.x, mean.y, 0.0).normalize_or(DVec3::X),
            spread,
        ),
        // one lobe spread sideways
        "near-azimuth" => rotate_towards(mean, DVec3::Y, spread),
        // on the ωo side, 45° elevation, 90° away in azimuth
        "far" => DVec3::new(0.5, 0.5, std::f64::consts::FRAC_1_SQRT_2).normalize(),
        // on the horizon below the lobe: half the cap is below the surface
        "horizon" => DVec3::new(mean.x, mean.y, 0.0).normalize_or(DVec3::X),
        _ => unreachable!(),
    }
}

fn stats(mut v: Vec<f64>) -> (f64, f64, f64, usize) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN, 0);
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    (
        v.iter().sum::<f64>() / n as f64,
        v[((n as f64 * 0.95).ceil() as usize).clamp(1, n) - 1],
        v[n - 1],
        n,
    )
}

fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        let avg = (i + j) as f64 / 2.0 + 1.0;
        for k in i..=j {
            r[idx[k]] = avg;
        }
        i = j + 1;
    }
    r
}

pub fn spearman(a: &[f64], b: &[f64]) -> f64 {
    let (ra, rb) = (ranks(a), ranks(b));
    let n = a.len() as f64;
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for i in 0..a.len() {
        sab += (ra[i] - ma) * (rb[i] - mb);
        saa += (ra[i] - ma).powi(2);
        sbb += (rb[i] - mb).powi(2);
    }
    sab / (saa * sbb).sqrt()
}

/// The four methods under test, in [`METHODS`] order.
struct Methods {
    sptd: Sptd,
    ltc: Ltc,
    sptd_oat: Sptd,
    sptd_near: Sptd,
}

impl Methods {
    fn new() -> Methods {
        Methods {
            sptd: Sptd::default(),
            ltc: Ltc::default(),
            sptd_oat: Sptd::default().intersection(Intersection::OatSander),
            sptd_near: Sptd::default().lookup(Lookup::Nearest),
        }
    }

    /// Each method's integral of the lobe (`wo`, `alpha`) over `cap`.
    fn cap(&self, wo: Vec3, alpha: f32, cap: &Cap) -> [f64; 4] {
        [
            self.sptd.lobe(wo, alpha).integral(cap.axis, cap.cos_theta) as f64,
            self.ltc.lobe(wo, alpha).integral(cap.axis, cap.cos_theta) as f64,
            self.sptd_oat
                .lobe(wo, alpha)
                .integral(cap.axis, cap.cos_theta) as f64,
            self.sptd_near
                .lobe(wo, alpha)
                .integral(cap.axis, cap.cos_theta) as f64,
        ]
    }

    /// Each method's directional albedo of the lobe.
    fn hemisphere(&self, wo: Vec3, alpha: f32) -> [f64; 4] {
        [
            self.sptd.hemisphere(wo, alpha) as f64,
            self.ltc.hemisphere(wo, alpha) as f64,
            self.sptd_oat.hemisphere(wo, alpha) as f64,
            self.sptd_near.hemisphere(wo, alpha) as f64,
        ]
    }
}

/// One shading point's directional albedo: α, θo in degrees, reference, its standard error,
/// the methods' values.
type HemiRow = (f32, f32, f64, f64, [f64; 4]);
/// One shading point's rank correlations: α, θo in degrees, each method's ρ.
type SpearRow = (f32, f32, [f64; 4]);

/// Runs the three comparisons with `samples` reference samples per cap and writes
/// `accuracy.csv` and `accuracy.md` into `out`.
pub fn run(samples: usize, out: &Path) -> Result<(), String> {
    let t0 = Instant::now();
    let methods = Methods::new();
    let mut points = Vec::new();
    for &alpha in &ALPHAS {
        for &th in &THETAS_DEG {
            points.push((alpha, th));
        }
    }
    let rows = cap_grid(&methods, &points, samples);
    let hemi = hemispheres(&methods, &points, samples);
    let spear = rank_correlations(&methods, &points, samples);
    let secs = t0.elapsed().as_secs_f64();

    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    write_file(&out.join("accuracy.csv"), &csv(&rows, &hemi))?;
    let mut md = String::new();
    md_header(&mut md, samples, secs, &rows);
    md_caps(&mut md, &rows);
    md_hemisphere(&mut md, &hemi);
    md_spearman(&mut md, samples, &spear);
    write_file(&out.join("accuracy.md"), &md)?;
    print!("{md}");
    Ok(())
}

/// 1. The grid of caps: every position and half-angle at every shading point.
fn cap_grid(methods: &Methods, points: &[(f32, f32)], samples: usize) -> Vec<Row> {
    points
        .par_iter()
        .flat_map_iter(|&(alpha, th)| {
            let wo = ggx::wo_from_theta(th.to_radians());
            let (mean, spread) = lobe_stats(alpha, wo);
            let mut rows = Vec::new();
            for &position in &POSITIONS {
                for &ha in &HALF_ANGLES {
                    let axis = cap_axis(position, wo, mean, spread);
                    let cap = Cap::new(axis.as_vec3(), ha.cos());
                    let (r, se) = reference::cap_integral(wo, alpha, &cap, samples);
                    rows.push(Row {
                        alpha,
                        theta_deg: th,
                        position,
                        half_angle: ha,
                        cap,
                        reference: r as f64,
                        ref_se: se as f64,
                        values: methods.cap(wo, alpha, &cap),
                    });
                }
            }
            rows.into_iter()
        })
        .collect()
}

/// 2. The hemisphere: each shading point's directional albedo.
fn hemispheres(methods: &Methods, points: &[(f32, f32)], samples: usize) -> Vec<HemiRow> {
    points
        .par_iter()
        .map(|&(alpha, th)| {
            let wo = ggx::wo_from_theta(th.to_radians());
            let (a, se) = reference::hemisphere(wo, alpha, samples * 4);
            (
                alpha,
                th,
                a as f64,
                se as f64,
                methods.hemisphere(wo, alpha),
            )
        })
        .collect()
}

/// 3. Spearman's ρ over random cap sets per shading point.
fn rank_correlations(methods: &Methods, points: &[(f32, f32)], samples: usize) -> Vec<SpearRow> {
    points
        .par_iter()
        .enumerate()
        .map(|(k, &(alpha, th))| {
            let wo = ggx::wo_from_theta(th.to_radians());
            let mut rng = SplitMix64::new(1000 + k as u64);
            let mut refs = Vec::new();
            let mut vals: [Vec<f64>; 4] = Default::default();
            for c in 0..SPEARMAN_CAPS {
                let cap = random_cap(c, alpha, wo, &mut rng);
                let (r, _) =
                    reference::cap_integral_seeded(wo, alpha, &cap, samples / 4, 31 + c as u64);
                refs.push(r as f64);
                let v = methods.cap(wo, alpha, &cap);
                for m in 0..4 {
                    vals[m].push(v[m]);
                }
            }
            let mut rho = [0.0; 4];
            for m in 0..4 {
                rho[m] = spearman(&refs, &vals[m]);
            }
            (alpha, th, rho)
        })
        .collect()
}

/// Cap `c` of a shading point's random set: even ones around a lobe sample, odd ones uniform.
fn random_cap(c: usize, alpha: f32, wo: Vec3, rng: &mut SplitMix64) -> Cap {
    let axis = if c % 2 == 0 {
        sample_lobe_dir(alpha, wo, rng)
    } else {
        // uniform over z > −0.3 (some caps cross or sit below the horizon)
        let z = -0.3 + 1.3 * rng.next_f64();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    let ang = (0.005f64.ln() + rng.next_f64() * (0.5f64.ln() - 0.005f64.ln())).exp();
    Cap64::new(axis, ang.cos()).to32()
}

/// `accuracy.csv`: one line per grid cap, then one per shading point's hemisphere.
fn csv(rows: &[Row], hemi: &[HemiRow]) -> String {
    let mut csv = String::from(
        "alpha,theta_o_deg,position,half_angle,cap_x,cap_y,cap_z,cap_cos,reference,reference_se",
    );
    for m in METHODS {
        write!(csv, ",{m}").unwrap();
    }
    csv.push('\n');
    for r in rows {
        write!(
            csv,
            "{},{},{},{},{},{},{},{},{:.6e},{:.3e}",
            r.alpha,
            r.theta_deg,
            r.position,
            r.half_angle,
            r.cap.axis.x,
            r.cap.axis.y,
            r.cap.axis.z,
            r.cap.cos_theta,
            r.reference,
            r.ref_se
        )
        .unwrap();
        for v in r.values {
            write!(csv, ",{v:.6e}").unwrap();
        }
        csv.push('\n');
    }
    for h in hemi {
        write!(
            csv,
            "{},{},hemisphere,{},0,0,1,0,{:.6e},{:.3e}",
            h.0,
            h.1,
            std::f32::consts::FRAC_PI_2,
            h.2,
            h.3
        )
        .unwrap();
        for v in h.4 {
            write!(csv, ",{v:.6e}").unwrap();
        }
        csv.push('\n');
    }
    csv
}

/// The report's title and what it measured.
fn md_header(md: &mut String, samples: usize, secs: f64, rows: &[Row]) {
    writeln!(md, "# brdf-integrals accuracy\n").unwrap();
    writeln!(
        md,
        "Generated by `cargo xtask validate-brdf-integrals` (= `cargo run --release -p brdf-tool -- validate --samples {samples}`), {secs:.0} s wall on 2 cores.\n"
    )
    .unwrap();
    writeln!(
        md,
        "Quantity: ∫_(C∩H) f·cos dω of the un-Fresnelled GGX lobe (height-correlated Smith). Reference: MIS quasi-Monte Carlo with {samples} samples per cap (standard error from 8 random shifts; median relative standard error {:.1e}).\n",
        stats(rows.iter().filter(|r| r.reference >= REL_FLOOR).map(|r| r.ref_se / r.reference).collect()).0
    )
    .unwrap();
    writeln!(
        md,
        "Grid: α ∈ {ALPHAS:?}; θo ∈ {THETAS_DEG:?}°; cap half-angles {HALF_ANGLES:?} rad; positions {POSITIONS:?} ({} caps). `peak` = axis on the mean direction of f·cos, `near-*` = one angular spread of the lobe away from it, `far` = (0.5, 0.5, 0.71), `horizon` = axis on the horizon below the lobe (half the cap is under the surface). Relative errors only over caps with reference ≥ {REL_FLOOR} (n given).\n",
        rows.len()
    )
    .unwrap();
}

/// The cap integrals' error tables: all, by position, by roughness.
fn md_caps(md: &mut String, rows: &[Row]) {
    writeln!(md, "## Cap integrals, all positions\n").unwrap();
    table(md, rows, |_| true);
    for pos in POSITIONS {
        writeln!(md, "\n## Position `{pos}`\n").unwrap();
        table(md, rows, |r| r.position == pos);
    }
    writeln!(md, "\n## By roughness (all positions)\n").unwrap();
    for (lo, hi) in [(0.0, 0.0101), (0.0101, 0.26), (0.26, 1.01)] {
        writeln!(md, "\nα in [{lo}, {hi}):\n").unwrap();
        table(md, rows, |r| {
            (r.alpha as f64) >= lo && (r.alpha as f64) < hi
        });
    }
}

/// The directional albedo's error table.
fn md_hemisphere(md: &mut String, hemi: &[HemiRow]) {
    writeln!(
        md,
        "\n## Hemisphere (directional albedo), floor: relative error ≤ 2 %\n"
    )
    .unwrap();
    writeln!(
        md,
        "| method | mean rel. error | p95 | max | worst (α, θo) | floor met |"
    )
    .unwrap();
    writeln!(md, "|---|---|---|---|---|---|").unwrap();
    for (m, name) in METHODS.iter().enumerate() {
        let errs: Vec<f64> = hemi.iter().map(|h| (h.4[m] - h.2).abs() / h.2).collect();
        let worst = hemi
            .iter()
            .max_by(|a, b| ((a.4[m] - a.2).abs() / a.2).total_cmp(&((b.4[m] - b.2).abs() / b.2)))
            .unwrap();
        let (mean, p95, max, _) = stats(errs);
        writeln!(
            md,
            "| {name} | {:.3} % | {:.3} % | {:.3} % | ({}, {}°) | {} |",
            mean * 100.0,
            p95 * 100.0,
            max * 100.0,
            worst.0,
            worst.1,
            if max <= 0.02 { "yes" } else { "**no**" }
        )
        .unwrap();
    }
}

/// The rank correlations: per method, then per shading point.
fn md_spearman(md: &mut String, samples: usize, spear: &[SpearRow]) {
    writeln!(
        md,
        "\n## Spearman rank correlation with the reference, floor ≥ 0.95\n"
    )
    .unwrap();
    writeln!(md, "{SPEARMAN_CAPS} random caps per shading point (half from lobe samples, half uniform over z > −0.3; half-angles log-uniform in [0.005, 0.5] rad; reference {} samples each), {} shading points (the α × θo grid).\n", samples / 4, spear.len()).unwrap();
    writeln!(md, "| method | mean ρ | min ρ | worst (α, θo) | shading points with ρ ≥ 0.95 | floor met (mean) |").unwrap();
    writeln!(md, "|---|---|---|---|---|---|").unwrap();
    for (m, name) in METHODS.iter().enumerate() {
        let v: Vec<f64> = spear.iter().map(|s| s.2[m]).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let worst = spear
            .iter()
            .min_by(|a, b| a.2[m].total_cmp(&b.2[m]))
            .unwrap();
        let ok = v.iter().filter(|&&x| x >= 0.95).count();
        writeln!(
            md,
            "| {name} | {mean:.4} | {:.4} | ({}, {}°) | {ok}/{} | {} |",
            worst.2[m],
            worst.0,
            worst.1,
            v.len(),
            if mean >= 0.95 { "yes" } else { "**no**" }
        )
        .unwrap();
    }
    writeln!(md, "\nPer shading point (sptd / ltc):\n").unwrap();
    write!(md, "| α \\ θo |").unwrap();
    for th in THETAS_DEG {
        write!(md, " {th}° |").unwrap();
    }
    writeln!(md).unwrap();
    writeln!(md, "|---|{}", "---|".repeat(THETAS_DEG.len())).unwrap();
    for &alpha in &ALPHAS {
        write!(md, "| {alpha} |").unwrap();
        for &th in &THETAS_DEG {
            let s = spear.iter().find(|s| s.0 == alpha && s.1 == th).unwrap();
            write!(md, " {:.3} / {:.3} |", s.2[0], s.2[1]).unwrap();
        }
        writeln!(md).unwrap();
    }
}

fn sample_lobe_dir(alpha: f32, wo: Vec3, rng: &mut SplitMix64) -> DVec3 {
    // reflect about a visible normal (the lobe's own importance sampling); fall back to +z
    let s = CellSamples::new(alpha as f64, wo.as_dvec3(), 4, rng.next_u64());
    s.dirs.first().copied().unwrap_or(DVec3::Z)
}

fn table(md: &mut String, rows: &[Row], filter: impl Fn(&Row) -> bool) {
    writeln!(
        md,
        "| method | abs mean | abs p95 | abs max | rel mean | rel p95 | rel max | n (rel) |"
    )
    .unwrap();
    writeln!(md, "|---|---|---|---|---|---|---|---|").unwrap();
    for (m, name) in METHODS.iter().enumerate() {
        let sel: Vec<&Row> = rows.iter().filter(|r| filter(r)).collect();
        let (am, ap, ax, _) = stats(
            sel.iter()
                .map(|r| (r.values[m] - r.reference).abs())
                .collect(),
        );
        let (rm, rp, rx, n) = stats(
            sel.iter()
                .filter(|r| r.reference >= REL_FLOOR)
                .map(|r| (r.values[m] - r.reference).abs() / r.reference)
                .collect(),
        );
        writeln!(
            md,
            "| {name} | {am:.2e} | {ap:.2e} | {ax:.2e} | {:.1} % | {:.1} % | {:.1} % | {n} |",
            rm * 100.0,
            rp * 100.0,
            rx * 100.0
        )
        .unwrap();
    }
}
