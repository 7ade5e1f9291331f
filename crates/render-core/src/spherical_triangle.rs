//! The solid angle a triangle subtends, sampled uniformly (Arvo, "Stratified sampling of
//! spherical triangles", SIGGRAPH 1995) and inverted, and a bilinear warp of the unit square
//! that tilts those samples towards a receiver's cosine (as pbrt-v4 does).
//!
//! Everything is computed in f64: the interior angles of a spherical triangle sum to π plus its
//! area, so a small triangle's area is the difference of nearly equal numbers, and Arvo's
//! construction divides by the sine of an angle that is tiny on slivers. Double precision keeps
//! both exact enough down to the smallest solid angle this is used for (see `light_points.rs`).
use glam::{DVec3, Vec3};

/// A spherical triangle: three unit directions from a viewpoint and what sampling reads.
#[derive(Clone, Copy, Debug)]
pub struct SphericalTriangle {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    /// The interior angle at `a`.
    alpha: f64,
    /// Its area, the solid angle (sr).
    area: f64,
}

/// The angle between two vectors of any length (0 when either is zero).
fn angle(u: DVec3, v: DVec3) -> f64 {
    u.cross(v).length().atan2(u.dot(v))
}

/// 1 − cos of the angle between unit vectors, without the cancellation of `1 − u·v`.
fn one_minus_cos(u: DVec3, v: DVec3) -> f64 {
    0.5 * (u - v).length_squared()
}

/// Area of the spherical triangle of unit vectors `a`, `b`, `c`: its angle excess. The interior
/// angle at a vertex is the angle between the planes of its two edges.
fn excess(a: DVec3, b: DVec3, c: DVec3) -> (f64, f64) {
    let alpha = angle(a.cross(b), a.cross(c));
    let beta = angle(b.cross(c), b.cross(a));
    let gamma = angle(c.cross(a), c.cross(b));
    (alpha + beta + gamma - std::f64::consts::PI, alpha)
}

/// The unit vector in the plane of unit `a` and `v`, orthogonal to `a`, towards `v`.
fn towards(a: DVec3, v: DVec3) -> Option<DVec3> {
    (v - a * a.dot(v)).try_normalize()
}

impl SphericalTriangle {
    /// The triangle `p` as seen from `x`; `None` when `x` is on a vertex or the solid angle is
    /// zero or not a number (`x` in the triangle's plane).
    pub fn new(x: Vec3, p: &[Vec3; 3]) -> Option<SphericalTriangle> {
        let x = x.as_dvec3();
        Self::from_directions(p.map(|q| q.as_dvec3() - x))
    }

    /// The spherical triangle of three directions (any lengths); `None` as for
    /// [`SphericalTriangle::new`].
    pub fn from_directions(d: [DVec3; 3]) -> Option<SphericalTriangle> {
        let (a, b, c) = (
            d[0].try_normalize()?,
            d[1].try_normalize()?,
            d[2].try_normalize()?,
        );
        let (area, alpha) = excess(a, b, c);
        (area > 0.0 && area.is_finite()).then_some(SphericalTriangle {
            a,
            b,
            c,
            alpha,
            area,
        })
    }

    /// The solid angle (sr).
    pub fn solid_angle(&self) -> f64 {
        self.area
    }

    /// The three unit directions, in the order of the triangle's vertices.
    pub fn vertices(&self) -> [DVec3; 3] {
        [self.a, self.b, self.c]
    }

    /// The point of the arc from `a` to `c` that cuts off, with `b`, a triangle of area
    /// `sub_area` (Arvo's first step: the sine and cosine of the arc a–c' from the sub-area).
    fn split_point(&self, sub_area: f64) -> Option<DVec3> {
        let (sin_a, cos_a) = self.alpha.sin_cos();
        let (s, t) = (sub_area - self.alpha).sin_cos();
        let u = t - cos_a;
        let v = s + sin_a * self.a.dot(self.b);
        let denom = (v * s + u * t) * sin_a;
        if denom == 0.0 {
            return None;
        }
        let q = (((v * t - u * s) * cos_a - v) / denom).clamp(-1.0, 1.0);
        let side = towards(self.a, self.c)?;
        Some(self.a * q + side * (1.0 - q * q).max(0.0).sqrt())
    }

    /// The unit direction of `u` ∈ [0,1)²: uniform in solid angle over the triangle, with `u.0`
    /// sweeping the area from the edge a–b towards c and `u.1` running from `b` to the arc a–c.
    /// `None` only for a triangle too degenerate to split.
    pub fn sample(&self, u: [f64; 2]) -> Option<DVec3> {
        let c_split = if u[0] >= 1.0 {
            self.c
        } else {
            self.split_point(u[0] * self.area)?
        };
        let h = u[1] * one_minus_cos(self.b, c_split);
        let side = towards(self.b, c_split).unwrap_or(DVec3::ZERO);
        let w = self.b * (1.0 - h) + side * (h * (2.0 - h)).max(0.0).sqrt();
        w.try_normalize()
    }

    /// The `u` that [`SphericalTriangle::sample`] maps to the direction `w` (unit, inside the
    /// triangle; one outside maps to the nearest edge of the square).
    pub fn invert(&self, w: DVec3) -> [f64; 2] {
        // The great circle through b and w meets the arc a–c at the split point.
        let cut = self.b.cross(w).cross(self.a.cross(self.c));
        let c_split = match cut.try_normalize() {
            Some(d) if d.dot(self.a + self.c) >= 0.0 => d,
            Some(d) => -d,
            None => self.c,
        };
        let u0 = excess(self.a, self.b, c_split).0.max(0.0) / self.area;
        let full = one_minus_cos(self.b, c_split);
        let u1 = if full > 0.0 {
            one_minus_cos(self.b, w) / full
        } else {
            0.0
        };
        [u0.clamp(0.0, 1.0), u1.clamp(0.0, 1.0)]
    }

    /// The weights of the bilinear warp at the square's corners (u = (0,0), (1,0), (0,1),
    /// (1,1), i.e. the directions b, b, a, c): the receiver's |cos| with normal `n`.
    pub fn cosine_weights(&self, n: Vec3) -> [f64; 4] {
        let n = n.as_dvec3();
        self.corner_weights(|d| n.dot(d).abs())
    }

    /// The weights of a bilinear warp by `f` at the corners (as
    /// [`SphericalTriangle::cosine_weights`]), floored at [`WARP_FLOOR`].
    pub fn corner_weights(&self, f: impl Fn(DVec3) -> f64) -> [f64; 4] {
        let w = |d: DVec3| f(d).max(WARP_FLOOR);
        let (wa, wb, wc) = (w(self.a), w(self.b), w(self.c));
        [wb, wb, wa, wc]
    }
}

/// The least weight of a corner of a warp: no direction of the triangle gets zero density.
pub const WARP_FLOOR: f64 = 0.01;

/// Inverse CDF of the density on [0,1] linear from `a` at 0 to `b` at 1 (both ≥ 0, not both 0),
/// in a form without cancellation.
fn sample_linear(u: f64, a: f64, b: f64) -> f64 {
    if a == b {
        return u;
    }
    let root = (a * a + u * (b * b - a * a)).max(0.0).sqrt();
    let denom = a + root;
    if denom <= 0.0 {
        return 0.0;
    }
    (u * (a + b) / denom).clamp(0.0, 1.0)
}

/// The CDF of that density at `x`.
fn linear_cdf(x: f64, a: f64, b: f64) -> f64 {
    if a + b <= 0.0 {
        return x;
    }
    (x * (a * (2.0 - x) + b * x) / (a + b)).clamp(0.0, 1.0)
}

/// The bilinear interpolation of corner weights `w` (order as in
/// [`SphericalTriangle::cosine_weights`]) at `u`.
fn bilerp(u: [f64; 2], w: [f64; 4]) -> f64 {
    let (x, y) = (u[0], u[1]);
    (1.0 - x) * (1.0 - y) * w[0] + x * (1.0 - y) * w[1] + (1.0 - x) * y * w[2] + x * y * w[3]
}

/// A point of the unit square drawn with density ∝ the bilinear interpolation of `w`: the
/// second coordinate from its marginal, then the first given the second.
pub fn bilinear_sample(xi: [f64; 2], w: [f64; 4]) -> [f64; 2] {
    let y = sample_linear(xi[1], w[0] + w[1], w[2] + w[3]);
    let x = sample_linear(xi[0], w[0] + y * (w[2] - w[0]), w[1] + y * (w[3] - w[1]));
    [x, y]
}

/// The density of [`bilinear_sample`] at `u`.
pub fn bilinear_pdf(u: [f64; 2], w: [f64; 4]) -> f64 {
    let sum = w[0] + w[1] + w[2] + w[3];
    if !(sum > 0.0) {
        return 1.0;
    }
    4.0 * bilerp(u, w) / sum
}

/// The `xi` that [`bilinear_sample`] maps to `u`.
pub fn bilinear_invert(u: [f64; 2], w: [f64; 4]) -> [f64; 2] {
    let (x, y) = (u[0], u[1]);
    let yi = linear_cdf(y, w[0] + w[1], w[2] + w[3]);
    let xi = linear_cdf(x, w[0] + y * (w[2] - w[0]), w[1] + y * (w[3] - w[1]));
    [xi, yi]
}

#[cfg(test)]
#[path = "spherical_triangle_tests.rs"]
mod tests;
