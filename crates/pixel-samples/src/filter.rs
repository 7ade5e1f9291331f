//! Pixel filters by filter importance sampling (Ernst et al. 2006; pbrt-v4's approach): each
//! camera sample is placed at an offset from its pixel's centre drawn in proportion to |f| and
//! counts for that pixel alone, weighted by f/pdf over ∫f. The pixel's value is then a plain
//! mean of its own samples, so its variance stays estimable from them, and every filter is
//! unbiased for the filtered image.
//!
//! All four filters are separable, f(x, y) = f₁(x) f₁(y), with pbrt's parameters. Box and
//! triangle are sampled exactly (weight 1); Gaussian and Mitchell through a tabulated
//! piecewise-constant density of |f₁| (weight f/pdf, negative in Mitchell's outer lobes).
use glam::Vec2;
use std::sync::Arc;

/// Bins of the tabulated 1D density over [-radius, radius].
const TABLE_BINS: usize = 256;
/// Sub-points per bin at which |f₁| is averaged.
const TABLE_SUBPOINTS: usize = 8;

/// A pixel reconstruction filter.
#[derive(Clone, Debug)]
pub enum PixelFilter {
    /// Constant over the square of half-width `radius` (pbrt default 0.5: the pixel itself).
    Box { radius: f32 },
    /// Tent of half-width `radius` (pbrt-v4 default 2, the authors' scene 1).
    Triangle { radius: f32 },
    /// exp(-x²/2σ²) minus its value at `radius`, clamped at 0 (pbrt-v4: radius 1.5, σ 0.5).
    Gaussian {
        radius: f32,
        sigma: f32,
        table: Arc<Tabulated>,
    },
    /// Mitchell–Netravali with (B, C), stretched over `radius` (pbrt: radius 2, B = C = 1/3).
    Mitchell {
        radius: f32,
        b: f32,
        c: f32,
        table: Arc<Tabulated>,
    },
}

impl Default for PixelFilter {
    /// The box over one pixel: the renderer's original jitter, bit for bit.
    fn default() -> PixelFilter {
        PixelFilter::Box { radius: 0.5 }
    }
}

impl PartialEq for PixelFilter {
    fn eq(&self, other: &PixelFilter) -> bool {
        self.name() == other.name() && self.parameters() == other.parameters()
    }
}

impl PixelFilter {
    /// The filter names `--filter` takes.
    pub const NAMES: [&'static str; 4] = ["box", "triangle", "gaussian", "mitchell"];

    /// The filter called `name` with pbrt-v4's default parameters, `radius` replacing the
    /// default radius when given.
    pub fn from_name(name: &str, radius: Option<f32>) -> Result<PixelFilter, String> {
        if let Some(r) = radius
            && !(r.is_finite() && r > 0.0 && r <= 16.0)
        {
            return Err(format!(
                "a filter radius must be in (0, 16] pixels, not {r}"
            ));
        }
        Ok(match name {
            "box" => PixelFilter::Box {
                radius: radius.unwrap_or(0.5),
            },
            "triangle" => PixelFilter::Triangle {
                radius: radius.unwrap_or(2.0),
            },
            "gaussian" => PixelFilter::gaussian(radius.unwrap_or(1.5), 0.5),
            "mitchell" => PixelFilter::mitchell(radius.unwrap_or(2.0), 1.0 / 3.0, 1.0 / 3.0),
            _ => {
                return Err(format!(
                    "unknown pixel filter {name:?} (known: {})",
                    PixelFilter::NAMES.join(", ")
                ));
            }
        })
    }

    /// A radius the filters accept: (0, 16] pixels.
    pub fn check_radius(r: f32) -> Result<(), String> {
        if r.is_finite() && r > 0.0 && r <= 16.0 {
            Ok(())
        } else {
            Err(format!(
                "a filter radius must be in (0, 16] pixels, not {r}"
            ))
        }
    }

    /// `NAME[:RADIUS]`, as `--filter` takes it.
    pub fn parse(spec: &str) -> Result<PixelFilter, String> {
        let (name, radius) = match spec.split_once(':') {
            Some((n, r)) => {
                let r: f32 = r.parse().map_err(|_| format!("bad filter radius {r:?}"))?;
                (n, Some(r))
            }
            None => (spec, None),
        };
        PixelFilter::from_name(name, radius)
    }

    pub fn gaussian(radius: f32, sigma: f32) -> PixelFilter {
        let f = move |x: f32| gaussian_1d(x, radius, sigma);
        let table = Arc::new(Tabulated::new(radius, f));
        PixelFilter::Gaussian {
            radius,
            sigma,
            table,
        }
    }

    pub fn mitchell(radius: f32, b: f32, c: f32) -> PixelFilter {
        let f = move |x: f32| mitchell_1d(2.0 * x / radius, b, c);
        let table = Arc::new(Tabulated::new(radius, f));
        PixelFilter::Mitchell {
            radius,
            b,
            c,
            table,
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            PixelFilter::Box { .. } => "box",
            PixelFilter::Triangle { .. } => "triangle",
            PixelFilter::Gaussian { .. } => "gaussian",
            PixelFilter::Mitchell { .. } => "mitchell",
        }
    }

    pub fn radius(&self) -> f32 {
        match *self {
            PixelFilter::Box { radius }
            | PixelFilter::Triangle { radius }
            | PixelFilter::Gaussian { radius, .. }
            | PixelFilter::Mitchell { radius, .. } => radius,
        }
    }

    /// The parameters as pbrt names them, for the render's JSON.
    pub fn parameters(&self) -> Vec<(&'static str, f32)> {
        match *self {
            PixelFilter::Box { radius } | PixelFilter::Triangle { radius } => {
                vec![("radius", radius)]
            }
            PixelFilter::Gaussian { radius, sigma, .. } => {
                vec![("radius", radius), ("sigma", sigma)]
            }
            PixelFilter::Mitchell { radius, b, c, .. } => {
                vec![("radius", radius), ("B", b), ("C", c)]
            }
        }
    }

    /// The 1D filter f₁ at offset `x` from the pixel centre.
    pub fn eval_1d(&self, x: f32) -> f32 {
        match *self {
            PixelFilter::Box { radius } => (x.abs() <= radius) as u32 as f32,
            PixelFilter::Triangle { radius } => (radius - x.abs()).max(0.0),
            PixelFilter::Gaussian { radius, sigma, .. } => gaussian_1d(x, radius, sigma),
            PixelFilter::Mitchell { radius, b, c, .. } => mitchell_1d(2.0 * x / radius, b, c),
        }
    }

    /// A sample's position from its pixel's corner (so (0.5, 0.5) is the centre) for the
    /// uniform pair `u`, and its weight f/(pdf ∫f).
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (x, wx) = self.sample_1d(u.x);
        let (y, wy) = self.sample_1d(u.y);
        (Vec2::new(x, y), wx * wy)
    }

    /// One axis of [`PixelFilter::sample`], as a position from the pixel's corner.
    #[inline]
    fn sample_1d(&self, u: f32) -> (f32, f32) {
        match self {
            // (0.5 − r) + 2r·u is u itself for the one-pixel box, so the default filter keeps
            // the original jitter bit for bit.
            PixelFilter::Box { radius } => ((0.5 - radius) + 2.0 * radius * u, 1.0),
            PixelFilter::Triangle { radius } => (0.5 + radius * tent_inverse(u), 1.0),
            PixelFilter::Gaussian { table, .. } | PixelFilter::Mitchell { table, .. } => {
                let (x, pdf) = table.sample(u);
                (0.5 + x, self.eval_1d(x) / (pdf * table.integral))
            }
        }
    }

    /// The density of [`PixelFilter::sample`]'s offset from the pixel centre, per axis.
    pub fn pdf_1d(&self, x: f32) -> f32 {
        match self {
            PixelFilter::Box { radius } => (x.abs() <= *radius) as u32 as f32 / (2.0 * radius),
            PixelFilter::Triangle { radius } => (radius - x.abs()).max(0.0) / (radius * radius),
            PixelFilter::Gaussian { table, .. } | PixelFilter::Mitchell { table, .. } => {
                table.pdf(x)
            }
        }
    }
}

/// The inverse CDF of the unit tent on [-1, 1].
#[inline]
fn tent_inverse(u: f32) -> f32 {
    if u < 0.5 {
        -1.0 + (2.0 * u).sqrt()
    } else {
        1.0 - (2.0 - 2.0 * u).sqrt()
    }
}

fn gaussian_1d(x: f32, radius: f32, sigma: f32) -> f32 {
    let g = |x: f32| (-x * x / (2.0 * sigma * sigma)).exp();
    if x.abs() >= radius {
        0.0
    } else {
        (g(x) - g(radius)).max(0.0)
    }
}

/// Mitchell–Netravali on [-2, 2].
fn mitchell_1d(x: f32, b: f32, c: f32) -> f32 {
    let x = x.abs();
    let v = if x < 1.0 {
        (12.0 - 9.0 * b - 6.0 * c) * x.powi(3)
            + (-18.0 + 12.0 * b + 6.0 * c) * x * x
            + (6.0 - 2.0 * b)
    } else if x < 2.0 {
        (-b - 6.0 * c) * x.powi(3)
            + (6.0 * b + 30.0 * c) * x * x
            + (-12.0 * b - 48.0 * c) * x
            + (8.0 * b + 24.0 * c)
    } else {
        0.0
    };
    v / 6.0
}

/// A piecewise-constant density over [-radius, radius] proportional to the bin means of |f₁|,
/// floored so that no bin where f₁ may be non-zero has zero density.
#[derive(Debug)]
pub struct Tabulated {
    radius: f32,
    /// Density of each bin.
    pdf: Vec<f32>,
    /// CDF at the bins' left edges, then 1.
    cdf: Vec<f32>,
    /// ∫f₁ over [-radius, radius] (signed).
    integral: f32,
}

impl Tabulated {
    fn new(radius: f32, f: impl Fn(f32) -> f32) -> Tabulated {
        let width = 2.0 * radius / TABLE_BINS as f32;
        let (mut abs_means, mut integral) = (Vec::with_capacity(TABLE_BINS), 0.0f64);
        for i in 0..TABLE_BINS {
            let (mut a, mut s) = (0.0f64, 0.0f64);
            for j in 0..TABLE_SUBPOINTS {
                let x = -radius + width * (i as f32 + (j as f32 + 0.5) / TABLE_SUBPOINTS as f32);
                let v = f(x) as f64;
                a += v.abs();
                s += v;
            }
            abs_means.push(a / TABLE_SUBPOINTS as f64);
            integral += s / TABLE_SUBPOINTS as f64 * width as f64;
        }
        let floor = 1e-4 * abs_means.iter().cloned().fold(0.0, f64::max);
        let masses: Vec<f64> = abs_means
            .iter()
            .map(|m| m.max(floor) * width as f64)
            .collect();
        let total: f64 = masses.iter().sum();
        let mut cdf = Vec::with_capacity(TABLE_BINS + 1);
        let mut acc = 0.0;
        for m in &masses {
            cdf.push((acc / total) as f32);
            acc += m;
        }
        cdf.push(1.0);
        let pdf = masses
            .iter()
            .map(|m| (m / total / width as f64) as f32)
            .collect();
        Tabulated {
            radius,
            pdf,
            cdf,
            integral: integral as f32,
        }
    }

    /// An offset drawn from the table and its density.
    fn sample(&self, u: f32) -> (f32, f32) {
        let i = self.cdf[1..]
            .partition_point(|&c| c <= u)
            .min(TABLE_BINS - 1);
        let width = 2.0 * self.radius / TABLE_BINS as f32;
        let within = ((u - self.cdf[i]) / (self.cdf[i + 1] - self.cdf[i])).clamp(0.0, 1.0);
        let x = (-self.radius + width * (i as f32 + within)).clamp(-self.radius, self.radius);
        (x, self.pdf[i])
    }

    fn pdf(&self, x: f32) -> f32 {
        if x.abs() > self.radius {
            return 0.0;
        }
        let width = 2.0 * self.radius / TABLE_BINS as f32;
        let i = (((x + self.radius) / width) as usize).min(TABLE_BINS - 1);
        self.pdf[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all() -> Vec<PixelFilter> {
        let mut v: Vec<PixelFilter> = PixelFilter::NAMES
            .iter()
            .map(|n| PixelFilter::from_name(n, None).unwrap())
            .collect();
        v.push(PixelFilter::from_name("triangle", Some(1.0)).unwrap());
        v.push(PixelFilter::from_name("box", Some(1.5)).unwrap());
        v
    }

    fn uniform(i: u64) -> f32 {
        let mut s = crate::rng::SampleStream::new(7, 0, i);
        s.next_f32()
    }

    /// Each axis's offsets against the density `pdf_1d` claims (chi-square, 40 bins over the
    /// support).
    #[test]
    fn offsets_follow_their_density() {
        let n = 200_000u64;
        for filter in all() {
            let r = filter.radius();
            let bins = 40;
            let mut observed = vec![0.0f64; bins];
            for i in 0..n {
                let (x, _) = filter.sample_1d(uniform(i));
                let d = x - 0.5;
                assert!(
                    d.abs() <= r * 1.0001,
                    "{} offset {d} outside radius {r}",
                    filter.name()
                );
                let b = (((d + r) / (2.0 * r)) * bins as f32) as usize;
                observed[b.min(bins - 1)] += 1.0;
            }
            let expected: Vec<f64> = (0..bins)
                .map(|b| {
                    let steps = 64;
                    let w = 2.0 * r / bins as f32;
                    (0..steps)
                        .map(|k| {
                            let x = -r + w * (b as f32 + (k as f32 + 0.5) / steps as f32);
                            filter.pdf_1d(x) as f64 * w as f64 / steps as f64
                        })
                        .sum::<f64>()
                        * n as f64
                })
                .collect();
            let out = chi2_test::chi2_test(&observed, &expected);
            assert!(out.p_value > 1e-4, "{}: {out:?}", filter.name());
        }
    }

    /// E[weight · g(offset)] equals ∫f·g / ∫f for a smooth test function g: the weights make
    /// the samples an unbiased estimate of the filtered value.
    #[test]
    fn weighted_samples_estimate_the_filtered_value() {
        let g = |x: f32| 1.0 + 0.5 * x + 0.25 * x * x;
        for filter in all() {
            let r = filter.radius();
            let n = 400_000u64;
            let mut est = 0.0f64;
            for i in 0..n {
                let (x, w) = filter.sample_1d(uniform(i));
                est += (w * g(x - 0.5)) as f64;
            }
            est /= n as f64;
            let steps = 20_000;
            let (mut fg, mut f) = (0.0f64, 0.0f64);
            for k in 0..steps {
                let x = -r + 2.0 * r * (k as f32 + 0.5) / steps as f32;
                fg += (filter.eval_1d(x) * g(x)) as f64;
                f += filter.eval_1d(x) as f64;
            }
            let want = fg / f;
            assert!(
                (est - want).abs() < 5e-3 * want,
                "{}: estimate {est}, filtered {want}",
                filter.name()
            );
        }
    }

    #[test]
    fn the_one_pixel_box_is_the_original_jitter() {
        let f = PixelFilter::default();
        for i in 0..1000 {
            let u = Vec2::new(uniform(i), uniform(i + 5000));
            assert_eq!(f.sample(u), (u, 1.0));
        }
    }

    #[test]
    fn specs_parse_and_bad_ones_are_refused() {
        assert_eq!(PixelFilter::parse("triangle:1").unwrap().radius(), 1.0);
        assert_eq!(PixelFilter::parse("mitchell").unwrap().radius(), 2.0);
        assert!(
            PixelFilter::parse("lanczos")
                .unwrap_err()
                .contains("unknown pixel filter")
        );
        assert!(PixelFilter::parse("box:-1").is_err());
        assert!(PixelFilter::parse("box:x").is_err());
    }
}
