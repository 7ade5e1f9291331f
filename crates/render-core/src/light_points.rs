//! How the point on a triangle light is drawn, a per-render choice: uniformly by area (the
//! default), uniformly in the solid angle the triangle subtends, or in solid angle warped
//! towards the receiver's cosine. Spheres and point lights are sampled as they always are.
//!
//! Solid-angle sampling removes area sampling's 1/d² and cos θ_light from the estimator, which
//! matters for large or close triangles. For a triangle of tiny solid angle area sampling is
//! already nearly uniform in solid angle (and cheaper), and for one covering nearly a hemisphere
//! the spherical construction loses precision; both fall back to area sampling, at pbrt-v4's
//! thresholds. The same fallback runs in [`LightPoints::pdf`], from the same numbers, so a
//! point's density is the one it was sampled with.
use crate::light::{Light, LightSample, LightShape, TrianglePoint};
use crate::spherical_triangle::{SphericalTriangle, bilinear_pdf, bilinear_sample};
use glam::{DVec3, Vec2, Vec3};

/// Below this solid angle (sr) a triangle is sampled by area.
pub const MIN_SOLID_ANGLE: f64 = 3e-4;
/// Above this solid angle (sr) a triangle is sampled by area.
pub const MAX_SOLID_ANGLE: f64 = 6.22;

/// How points on triangle lights are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LightPoints {
    /// Uniformly by area.
    #[default]
    Area,
    /// Uniformly in solid angle (Arvo 1995).
    SolidAngle,
    /// In solid angle, warped bilinearly towards the receiver's |cos θ| at the corners.
    SolidAngleWarp,
}

impl LightPoints {
    pub const ALL: [LightPoints; 3] = [
        LightPoints::Area,
        LightPoints::SolidAngle,
        LightPoints::SolidAngleWarp,
    ];

    /// The name flags and JSON use.
    pub fn name(self) -> &'static str {
        match self {
            LightPoints::Area => "area",
            LightPoints::SolidAngle => "solid-angle",
            LightPoints::SolidAngleWarp => "solid-angle-warp",
        }
    }

    pub fn parse(s: &str) -> Result<LightPoints, String> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|m| m.name()).collect();
                format!(
                    "unknown light point sampler `{s}` (one of: {})",
                    names.join(", ")
                )
            })
    }

    /// [`Light::sample`] with a triangle's point drawn this way, for a receiver at `x` with
    /// unit normal `n` (zero when it has none: no warp).
    pub fn sample(self, light: &Light, x: Vec3, n: Vec3, u: Vec2) -> Option<LightSample> {
        match (&light.shape, self) {
            (_, LightPoints::Area) | (LightShape::Sphere { .. } | LightShape::Point { .. }, _) => {
                light.sample(x, u)
            }
            (
                LightShape::Triangle {
                    p, normal, area, ..
                },
                _,
            ) => {
                let t = match self.spherical(p, x, n) {
                    Some((st, warp)) => solid_angle_point(p, *normal, &st, warp, x, u)?,
                    None => TrianglePoint::sample(p, *normal, *area, x, u)?,
                };
                light.triangle_sample(&t)
            }
        }
    }

    /// [`Light::pdf`] for points drawn by [`LightPoints::sample`].
    pub fn pdf(self, light: &Light, x: Vec3, n: Vec3, point: Vec3, normal: Vec3) -> f32 {
        let LightShape::Triangle { p, .. } = &light.shape else {
            return light.pdf(x, point, normal);
        };
        let Some((st, warp)) = self.spherical(p, x, n) else {
            return light.pdf(x, point, normal);
        };
        let d = point - x;
        let cos_l = normal.dot(-d);
        if cos_l <= 0.0 && !light.two_sided || cos_l == 0.0 {
            return 0.0;
        }
        let Some(w) = (point.as_dvec3() - x.as_dvec3()).try_normalize() else {
            return 0.0;
        };
        solid_angle_pdf(&st, warp, w)
    }

    /// The spherical triangle and the warp's weights when this sampler draws `p`'s points in
    /// solid angle from `x`; `None` where the area sampling stands in.
    fn spherical(
        self,
        p: &[Vec3; 3],
        x: Vec3,
        n: Vec3,
    ) -> Option<(SphericalTriangle, Option<[f64; 4]>)> {
        if self == LightPoints::Area {
            return None;
        }
        let st = SphericalTriangle::new(x, p)?;
        if !(MIN_SOLID_ANGLE..=MAX_SOLID_ANGLE).contains(&st.solid_angle()) {
            return None;
        }
        let warp =
            (self == LightPoints::SolidAngleWarp && n != Vec3::ZERO).then(|| st.cosine_weights(n));
        Some((st, warp))
    }
}

/// The density in solid angle of the direction `w` (unit, towards the triangle).
fn solid_angle_pdf(st: &SphericalTriangle, warp: Option<[f64; 4]>, w: DVec3) -> f32 {
    let warped = warp.map_or(1.0, |ws| bilinear_pdf(st.invert(w), ws));
    (warped / st.solid_angle()) as f32
}

/// A point of triangle `p` (unit normal `normal`) drawn in the solid angle `st` from `x`.
fn solid_angle_point(
    p: &[Vec3; 3],
    normal: Vec3,
    st: &SphericalTriangle,
    warp: Option<[f64; 4]>,
    x: Vec3,
    u: Vec2,
) -> Option<TrianglePoint> {
    let xi = [u.x as f64, u.y as f64];
    let uu = warp.map_or(xi, |ws| bilinear_sample(xi, ws));
    let mut t = point_along(p, normal, x, st.sample(uu)?)?;
    // The density of the point as stored, by the operations of `LightPoints::pdf`, so that a
    // replayed density is bit-identical.
    let w_stored = (t.point.as_dvec3() - x.as_dvec3()).try_normalize()?;
    t.pdf = solid_angle_pdf(st, warp, w_stored);
    Some(t)
}

/// Where the ray from `x` along unit `w` meets the plane of triangle `p` (unit normal
/// `normal`), with density 0; `None` when it runs parallel to or away from the plane.
fn point_along(p: &[Vec3; 3], normal: Vec3, x: Vec3, w: DVec3) -> Option<TrianglePoint> {
    let (x64, n64) = (x.as_dvec3(), normal.as_dvec3());
    let t = (p[0].as_dvec3() - x64).dot(n64) / w.dot(n64);
    if !(t > 0.0 && t.is_finite()) {
        return None;
    }
    let point = (x64 + w * t).as_vec3();
    let d = point - x;
    let dist = d.length();
    if !(dist > 0.0) {
        return None;
    }
    let cos_l = normal.dot(-d) / dist;
    (cos_l != 0.0).then(|| TrianglePoint {
        b: barycentric(p, point),
        point,
        wi: d / dist,
        dist,
        cos_l,
        pdf: 0.0,
    })
}

/// The point where the ray from `x` along the unit direction `w` meets triangle light
/// `light`, with its emission towards `x` and density 0, for a sampler of directions outside
/// this module to set; `None` for other shapes, a ray that misses the light's plane, or a
/// point that emits nothing towards `x`.
pub fn triangle_point_along(light: &Light, x: Vec3, w: DVec3) -> Option<LightSample> {
    let LightShape::Triangle { p, normal, .. } = &light.shape else {
        return None;
    };
    light.triangle_sample(&point_along(p, *normal, x, w)?)
}

/// The barycentric coordinates (of `p[1]`, `p[2]`) of a point in the triangle's plane.
fn barycentric(p: &[Vec3; 3], q: Vec3) -> Vec2 {
    let (e1, e2, d) = (p[1] - p[0], p[2] - p[0], q - p[0]);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if !(det > 0.0) {
        return Vec2::ZERO;
    }
    Vec2::new(d22 * d1 - d12 * d2, d11 * d2 - d12 * d1) / det
}

#[cfg(test)]
#[path = "light_points_tests.rs"]
mod tests;
