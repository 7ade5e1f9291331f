//! Statistical comparison of renders, used by the tests that check every strategy converges
//! to the same image: region means must agree within a number of standard errors.
use render_core::colour::{LUMINANCE_WEIGHTS, luminance};
use render_core::render::RenderResult;

/// Mean luminance over a pixel rectangle and the standard error of that mean, from the
/// per-pixel variances of the render. Pixels whose camera ray sees a light are left out
/// when `unlit_only` (their value is the light's radiance, the same for every strategy).
pub fn region_mean(
    r: &RenderResult,
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    unlit_only: bool,
) -> (f64, f64) {
    region_mean_excluding(r, x0, y0, x1, y1, |i| {
        unlit_only && r.light_fraction[i] > 0.0
    })
}

/// [`region_mean`] leaving out the pixels for which `excluded(index)` holds.
pub fn region_mean_excluding(
    r: &RenderResult,
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    excluded: impl Fn(usize) -> bool,
) -> (f64, f64) {
    let (mut sum, mut var, mut n) = (0.0, 0.0, 0usize);
    for y in y0..y1 {
        for x in x0..x1 {
            let i = (y * r.width + x) as usize;
            if excluded(i) {
                continue;
            }
            sum += luminance(r.pixels[i]) as f64;
            let v = r.variance_of_mean[i];
            // Var of a weighted sum of channels, assuming channels perfectly correlated (conservative).
            let sd = LUMINANCE_WEIGHTS
                .as_dvec3()
                .dot(v.as_dvec3().map(f64::sqrt));
            var += sd * sd;
            n += 1;
        }
    }
    if n == 0 {
        return (0.0, 0.0);
    }
    (sum / n as f64, var.sqrt() / n as f64)
}

/// Compares two renders over a grid of `cells × cells` regions plus the whole image.
/// Returns a description of every region whose means differ by more than `z` combined
/// standard errors. Both means leave out the pixels where *either* render saw a light: the
/// light mask grows with the sample count (more jittered rays graze the lights), and the
/// bright pixels next to lights would otherwise bias the comparison of renders of different
/// sample counts.
pub fn compare(a: &RenderResult, b: &RenderResult, cells: u32, z: f64) -> Vec<String> {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let mut failures = Vec::new();
    let mut regions = vec![(0, 0, a.width, a.height)];
    for cy in 0..cells {
        for cx in 0..cells {
            regions.push((
                cx * a.width / cells,
                cy * a.height / cells,
                (cx + 1) * a.width / cells,
                (cy + 1) * a.height / cells,
            ));
        }
    }
    for (x0, y0, x1, y1) in regions {
        let lit = |i: usize| a.light_fraction[i] > 0.0 || b.light_fraction[i] > 0.0;
        let (ma, sa) = region_mean_excluding(a, x0, y0, x1, y1, lit);
        let (mb, sb) = region_mean_excluding(b, x0, y0, x1, y1, lit);
        let se = (sa * sa + sb * sb).sqrt();
        if (ma - mb).abs() > z * se + 1e-6 * ma.abs().max(mb.abs()) {
            failures.push(format!(
                "region ({x0},{y0})-({x1},{y1}): {ma:.6} ± {sa:.6} vs {mb:.6} ± {sb:.6} ({:.1} SE)",
                (ma - mb).abs() / se
            ));
        }
    }
    failures
}
