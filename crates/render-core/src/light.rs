//! Lights with bounded extent: emissive triangles, sphere lights, point and spot lights.
//! Each can sample a point as seen from a shading point and evaluate the solid-angle density
//! of any point on it, so every technique can weight any other by MIS.
//! Distant (directional) lights have no extent and live apart in [`DistantLight`].
use crate::colour::luminance;
use crate::frame::Frame;
use crate::sampling;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub enum LightShape {
    /// Vertices counter-clockwise around `normal`; `uv` only matters with an emission texture.
    Triangle {
        p: [Vec3; 3],
        normal: Vec3,
        area: f32,
        uv: [Vec2; 3],
    },
    Sphere {
        center: Vec3,
        radius: f32,
    },
    Point {
        position: Vec3,
    },
}

/// Angular falloff of a spot light (glTF: smooth between inner and outer cone).
#[derive(Clone, Copy, Debug)]
pub struct SpotCone {
    /// Unit emission axis.
    pub direction: Vec3,
    pub cos_inner: f32,
    pub cos_outer: f32,
}

impl SpotCone {
    pub fn falloff(&self, w_out: Vec3) -> f32 {
        let c = self.direction.dot(w_out);
        if c <= self.cos_outer {
            return 0.0;
        }
        if c >= self.cos_inner {
            return 1.0;
        }
        let t = (c - self.cos_outer) / (self.cos_inner - self.cos_outer).max(1e-6);
        t * t
    }
}

#[derive(Clone, Debug)]
pub struct Light {
    pub shape: LightShape,
    /// Radiance (triangles, spheres) or intensity (points), linear RGB.
    pub emission: Vec3,
    /// Triangles only: emission is multiplied by this texture at the point's uv.
    pub texture: Option<Arc<Texture>>,
    /// Mean emission over the surface (equals `emission` without a texture).
    pub mean_emission: Vec3,
    pub two_sided: bool,
    pub spot: Option<SpotCone>,
}

/// A point on a light as seen from a shading point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub point: Vec3,
    /// Unit surface normal at `point` (zero for point lights).
    pub normal: Vec3,
    /// Unit direction from the shading point to `point`.
    pub wi: Vec3,
    pub dist: f32,
    /// Radiance arriving along −wi (for delta lights: intensity / dist², the density being 1).
    pub radiance: Vec3,
    /// Solid-angle density of `wi` (1 for delta lights).
    pub pdf: f32,
    pub is_delta: bool,
}

/// What sampling an untextured triangle light reads, in one 64-byte cache line: the scene
/// keeps one per light beside its [`Light`]s (about 140 bytes each, over three lines), so that
/// a light sampled among tens of thousands costs one memory access. `area` < 0 marks a
/// two-sided emitter, `area` = 0 a light that is not a plain triangle (sampled through [`Light`]).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct TriangleRecord {
    p: [Vec3; 3],
    normal: Vec3,
    area: f32,
    emission: Vec3,
}

impl TriangleRecord {
    pub fn of(light: &Light) -> TriangleRecord {
        match (&light.shape, &light.texture, &light.spot) {
            (
                LightShape::Triangle {
                    p, normal, area, ..
                },
                None,
                None,
            ) => TriangleRecord {
                p: *p,
                normal: *normal,
                area: if light.two_sided { -area } else { *area },
                emission: light.emission,
            },
            _ => TriangleRecord {
                p: [Vec3::ZERO; 3],
                normal: Vec3::ZERO,
                area: 0.0,
                emission: Vec3::ZERO,
            },
        }
    }

    /// Whether this record stands for its light (else sample the [`Light`] itself).
    #[inline]
    pub fn is_plain_triangle(&self) -> bool {
        self.area != 0.0
    }

    /// [`Light::sample`] of the triangle: the same point drawing ([`TrianglePoint`]), so the
    /// results are bit-identical.
    #[inline]
    pub fn sample(&self, x: Vec3, u: Vec2) -> Option<LightSample> {
        let (area, two_sided) = (self.area.abs(), self.area < 0.0);
        let t = TrianglePoint::sample(&self.p, self.normal, area, x, u)?;
        // `Light::emitted` towards −wi: zero from behind a one-sided emitter.
        if t.cos_l <= 0.0 && !two_sided || self.emission == Vec3::ZERO {
            return None;
        }
        Some(t.light_sample(self.normal, self.emission))
    }
}

/// A point drawn uniformly by area on a triangle, as seen from `x`: the geometry that
/// [`Light::sample`] and [`TriangleRecord::sample`] share, before the emission is looked up.
pub(crate) struct TrianglePoint {
    /// Barycentric coordinates of the point (of `p[1]` and `p[2]`).
    pub(crate) b: Vec2,
    pub(crate) point: Vec3,
    pub(crate) wi: Vec3,
    pub(crate) dist: f32,
    /// Cosine at the light between its normal and the direction back to `x`.
    pub(crate) cos_l: f32,
    /// Solid-angle density at `x`.
    pub(crate) pdf: f32,
}

impl TrianglePoint {
    /// `None` when `x` lies in the triangle's plane or on the point.
    #[inline]
    pub(crate) fn sample(
        p: &[Vec3; 3],
        normal: Vec3,
        area: f32,
        x: Vec3,
        u: Vec2,
    ) -> Option<TrianglePoint> {
        let b = sampling::uniform_triangle(u);
        let point = p[0] * (1.0 - b.x - b.y) + p[1] * b.x + p[2] * b.y;
        let d = point - x;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let wi = d / dist;
        // The same operations as `Light::pdf`, so that a replayed density is bit-identical even
        // at grazing angles, where cos_l is the difference of nearly equal products.
        let cos_l = normal.dot(-d) / dist;
        if dist2 <= 0.0 || cos_l.abs() <= 0.0 {
            return None;
        }
        Some(TrianglePoint {
            b,
            point,
            wi,
            dist,
            cos_l,
            pdf: dist2 / (area * cos_l.abs()),
        })
    }

    #[inline]
    fn light_sample(&self, normal: Vec3, radiance: Vec3) -> LightSample {
        LightSample {
            point: self.point,
            normal,
            wi: self.wi,
            dist: self.dist,
            radiance,
            pdf: self.pdf,
            is_delta: false,
        }
    }
}

impl Light {
    pub fn is_delta(&self) -> bool {
        matches!(self.shape, LightShape::Point { .. })
    }

    /// Emitted power in watts (luminance of the radiance), in one unit across kinds:
    /// one-sided emitter π·L·A, two-sided 2π·L·A, sphere π·L·4πr², point 4π·I.
    pub fn power(&self) -> f32 {
        let l = luminance(self.mean_emission).max(0.0);
        match &self.shape {
            LightShape::Triangle { area, .. } => {
                l * area * if self.two_sided { 2.0 * PI } else { PI }
            }
            LightShape::Sphere { radius, .. } => l * PI * 4.0 * PI * radius * radius,
            LightShape::Point { .. } => 4.0 * PI * l,
        }
    }

    /// Power in the authors' units (bisml `LeWithArea`, for `--reproduce`): luminance of the
    /// radiance × area for area lights (no π, one side even when two-sided; a sphere's area is
    /// 4πr²), the intensity's luminance for point and spot lights. Not comparable across kinds.
    pub fn power_authors(&self) -> f32 {
        let l = luminance(self.mean_emission).max(0.0);
        match &self.shape {
            LightShape::Triangle { area, .. } => l * area,
            LightShape::Sphere { radius, .. } => l * 4.0 * PI * radius * radius,
            LightShape::Point { .. } => l,
        }
    }

    /// Axis-aligned bounds.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match &self.shape {
            LightShape::Triangle { p, .. } => (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2])),
            LightShape::Sphere { center, radius } => {
                (center - Vec3::splat(*radius), center + Vec3::splat(*radius))
            }
            LightShape::Point { position } => (*position, *position),
        }
    }

    /// Orientation cone (axis, θo, θe) in the sense of Conty Estevez & Kulla 2018.
    pub fn orientation(&self) -> (Vec3, f32, f32) {
        match (&self.shape, &self.spot) {
            (LightShape::Triangle { normal, .. }, _) => (*normal, 0.0, PI / 2.0),
            (_, Some(s)) => {
                let inner = s.cos_inner.clamp(-1.0, 1.0).acos();
                let outer = s.cos_outer.clamp(-1.0, 1.0).acos();
                (s.direction, inner, (outer - inner).max(0.0))
            }
            _ => (Vec3::Z, PI, PI / 2.0),
        }
    }

    /// Emitted radiance leaving `point` (normal `normal`, texture coordinate `uv`) in direction `w_out`.
    pub fn emitted(&self, normal: Vec3, uv: Vec2, w_out: Vec3) -> Vec3 {
        let facing = normal.dot(w_out);
        match &self.shape {
            LightShape::Triangle { .. } => {
                if facing <= 0.0 && !self.two_sided {
                    return Vec3::ZERO;
                }
                match &self.texture {
                    Some(t) => self.emission * t.sample(uv).truncate(),
                    None => self.emission,
                }
            }
            LightShape::Sphere { .. } => {
                if facing <= 0.0 {
                    return Vec3::ZERO;
                }
                self.emission * self.spot.map_or(1.0, |s| s.falloff(w_out))
            }
            LightShape::Point { .. } => self.emission * self.spot.map_or(1.0, |s| s.falloff(w_out)),
        }
    }

    /// The sample of a point drawn on this triangle light: its emission towards the receiver
    /// looked up (`None` where it emits nothing that way).
    pub(crate) fn triangle_sample(&self, t: &TrianglePoint) -> Option<LightSample> {
        let LightShape::Triangle { normal, uv, .. } = &self.shape else {
            return None;
        };
        let b = t.b;
        let tuv = uv[0] * (1.0 - b.x - b.y) + uv[1] * b.x + uv[2] * b.y;
        let radiance = self.emitted(*normal, tuv, -t.wi);
        if radiance == Vec3::ZERO {
            return None;
        }
        Some(t.light_sample(*normal, radiance))
    }

    /// Sample a point on the light as seen from `x`: triangles uniformly by area, spheres
    /// uniformly in the cone of directions they subtend. `None` when nothing can be sampled
    /// or the sampled point emits nothing towards `x`.
    pub fn sample(&self, x: Vec3, u: Vec2) -> Option<LightSample> {
        match &self.shape {
            LightShape::Triangle {
                p, normal, area, ..
            } => self.triangle_sample(&TrianglePoint::sample(p, *normal, *area, x, u)?),
            LightShape::Sphere { center, radius } => {
                let d = *center - x;
                let dist_c = d.length();
                if dist_c <= *radius {
                    return None; // the shading point is inside the light: it sees nothing but the light's inside
                }
                let omc = sampling::sphere_cone_one_minus_cos(*radius, dist_c);
                let axis = d / dist_c;
                let local = sampling::uniform_cone(u, omc);
                let wi = Frame::from_normal(axis).to_world(local).normalize();
                let sin2 = local.x * local.x + local.y * local.y;
                let cos_t = local.z;
                let t = (dist_c * cos_t
                    - (radius * radius - dist_c * dist_c * sin2).max(0.0).sqrt())
                .max(0.0);
                let point = x + wi * t;
                let normal = (point - *center).normalize_or(-axis);
                let radiance = self.emitted(normal, Vec2::ZERO, -wi);
                if radiance == Vec3::ZERO {
                    return None;
                }
                Some(LightSample {
                    point,
                    normal,
                    wi,
                    dist: t,
                    radiance,
                    pdf: sampling::uniform_cone_pdf(omc),
                    is_delta: false,
                })
            }
            LightShape::Point { position } => {
                let d = *position - x;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 {
                    return None;
                }
                let dist = dist2.sqrt();
                let wi = d / dist;
                let radiance = self.emitted(Vec3::ZERO, Vec2::ZERO, -wi) / dist2;
                if radiance == Vec3::ZERO {
                    return None;
                }
                Some(LightSample {
                    point: *position,
                    normal: Vec3::ZERO,
                    wi,
                    dist,
                    radiance,
                    pdf: 1.0,
                    is_delta: true,
                })
            }
        }
    }

    /// Solid-angle density with which [`Light::sample`] from `x` produces the point `point`
    /// (normal `normal`) of this light. Zero for delta lights and for points that emit nothing towards `x`.
    pub fn pdf(&self, x: Vec3, point: Vec3, normal: Vec3) -> f32 {
        match &self.shape {
            LightShape::Triangle { area, .. } => {
                let d = point - x;
                let dist2 = d.length_squared();
                let cos_l = normal.dot(-d) / dist2.sqrt();
                if cos_l <= 0.0 && !self.two_sided || cos_l == 0.0 || dist2 <= 0.0 {
                    return 0.0;
                }
                dist2 / (area * cos_l.abs())
            }
            LightShape::Sphere { center, radius } => {
                let dist_c = (*center - x).length();
                if dist_c <= *radius {
                    return 0.0;
                }
                sampling::uniform_cone_pdf(sampling::sphere_cone_one_minus_cos(*radius, dist_c))
            }
            LightShape::Point { .. } => 0.0,
        }
    }
}

/// A directional light: parallel illumination of irradiance `irradiance` (lux) from `direction`.
#[derive(Clone, Copy, Debug)]
pub struct DistantLight {
    /// Unit direction towards the light.
    pub direction: Vec3,
    pub irradiance: Vec3,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SampleStream;
    use chi2_test::{chi2_directions, sidak_significance};

    fn sphere(center: Vec3, radius: f32) -> Light {
        Light {
            shape: LightShape::Sphere { center, radius },
            emission: Vec3::ONE,
            texture: None,
            mean_emission: Vec3::ONE,
            two_sided: false,
            spot: None,
        }
    }

    fn triangle(p: [Vec3; 3], two_sided: bool) -> Light {
        let c = (p[1] - p[0]).cross(p[2] - p[0]);
        Light {
            shape: LightShape::Triangle {
                p,
                normal: c.normalize(),
                area: 0.5 * c.length(),
                uv: [Vec2::ZERO; 3],
            },
            emission: Vec3::ONE,
            texture: None,
            mean_emission: Vec3::ONE,
            two_sided,
            spot: None,
        }
    }

    fn check(light: &Light, x: Vec3, seed: u64, sig: f64) {
        let out = chi2_directions(
            100_000,
            40,
            80,
            8,
            |i| {
                let mut r = SampleStream::new(seed, i as u64, 0);
                light.sample(x, r.next_2d()).map(|s| s.wi)
            },
            |w| {
                // density of the direction w: the point it reaches on the light
                match &light.shape {
                    LightShape::Sphere { center, radius } => {
                        let omc = crate::sampling::sphere_cone_one_minus_cos(
                            *radius,
                            (*center - x).length(),
                        );
                        let axis = (*center - x).normalize();
                        if 1.0 - axis.dot(w) <= omc {
                            light.pdf(x, Vec3::ZERO, Vec3::ZERO) as f64
                        } else {
                            0.0
                        }
                    }
                    LightShape::Triangle { p, normal, .. } => {
                        let t = (p[0] - x).dot(*normal) / w.dot(*normal);
                        let y = x + w * t;
                        let inside = |a: Vec3, b: Vec3| (b - a).cross(y - a).dot(*normal) >= 0.0;
                        if t > 0.0 && inside(p[0], p[1]) && inside(p[1], p[2]) && inside(p[2], p[0])
                        {
                            light.pdf(x, y, *normal) as f64
                        } else {
                            0.0
                        }
                    }
                    LightShape::Point { .. } => 0.0,
                }
            },
        );
        assert!(out.p_value > sig, "{out:?}");
    }

    #[test]
    fn sphere_cap_and_triangle_sampling_match_their_pdfs() {
        let sig = sidak_significance(0.01, 4);
        check(&sphere(Vec3::new(0.3, 0.2, 2.0), 1.0), Vec3::ZERO, 1, sig);
        check(&sphere(Vec3::new(-1.0, 0.5, 0.4), 0.4), Vec3::ZERO, 2, sig);
        check(
            &triangle(
                [
                    Vec3::new(-1.0, -1.0, 1.0),
                    Vec3::new(2.0, -0.5, 1.5),
                    Vec3::new(0.0, 1.5, 0.8),
                ],
                false,
            ),
            Vec3::ZERO,
            3,
            sig,
        );
        // seen from behind: a two-sided triangle still emits
        check(
            &triangle(
                [
                    Vec3::new(-1.0, -1.0, 1.0),
                    Vec3::new(0.0, 1.5, 0.8),
                    Vec3::new(2.0, -0.5, 1.5),
                ],
                true,
            ),
            Vec3::ZERO,
            4,
            sig,
        );
    }

    #[test]
    fn sampled_pdf_equals_evaluated_pdf() {
        let lights = [
            sphere(Vec3::new(0.0, 0.0, 10.0), 0.001),
            triangle(
                [
                    Vec3::new(0.0, 0.0, 1.0),
                    Vec3::new(0.0, 1.0, 1.0),
                    Vec3::new(1.0, 0.0, 1.0),
                ],
                false,
            ),
        ];
        for l in &lights {
            let mut r = SampleStream::new(5, 0, 0);
            for _ in 0..100 {
                let s = l.sample(Vec3::ZERO, r.next_2d()).expect("faces the origin");
                let p = l.pdf(Vec3::ZERO, s.point, s.normal);
                assert!((p - s.pdf).abs() <= 1e-4 * s.pdf, "{p} vs {}", s.pdf);
                assert!((s.point.length() - s.dist).abs() < 1e-4 * s.dist);
            }
        }
    }

    #[test]
    fn tiny_sphere_points_lie_on_the_sphere() {
        let l = sphere(Vec3::new(0.0, 0.0, 5.0), 0.001);
        let mut r = SampleStream::new(6, 0, 0);
        for _ in 0..100 {
            let s = l.sample(Vec3::ZERO, r.next_2d()).unwrap();
            let d = (s.point - Vec3::new(0.0, 0.0, 5.0)).length();
            assert!((d - 0.001).abs() < 2e-5, "{d}");
            assert!(s.normal.dot(-s.wi) > -1e-3, "visible side");
        }
    }

    /// The compact record samples exactly what the light samples, bit for bit.
    #[test]
    fn triangle_records_sample_what_their_lights_sample() {
        let p = [
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.3, 1.1, 0.1),
            Vec3::new(0.1, 1.0, 0.4),
        ];
        for two_sided in [false, true] {
            let light = triangle(p, two_sided);
            let rec = TriangleRecord::of(&light);
            assert!(rec.is_plain_triangle());
            let mut rng = SampleStream::new(5, two_sided as u64, 0);
            for k in 0..2000 {
                let x = Vec3::new(k as f32 * 0.001 - 1.0, (k % 7) as f32 * 0.5 - 1.0, 0.2);
                let u = rng.next_2d();
                let (a, b) = (light.sample(x, u), rec.sample(x, u));
                assert_eq!(a.is_some(), b.is_some());
                if let (Some(a), Some(b)) = (a, b) {
                    assert_eq!(
                        (a.point, a.normal, a.wi, a.dist, a.radiance, a.pdf),
                        (b.point, b.normal, b.wi, b.dist, b.radiance, b.pdf)
                    );
                }
            }
        }
        assert!(!TriangleRecord::of(&sphere(Vec3::ZERO, 1.0)).is_plain_triangle());
        assert_eq!(std::mem::size_of::<TriangleRecord>(), 64);
    }

    #[test]
    fn one_sided_triangle_is_dark_from_behind() {
        let l = triangle(
            [
                Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(0.0, 1.0, 1.0),
            ],
            false,
        );
        // normal +z, the origin is behind it
        let mut r = SampleStream::new(7, 0, 0);
        assert!((0..50).all(|_| l.sample(Vec3::ZERO, r.next_2d()).is_none()));
        assert_eq!(l.pdf(Vec3::ZERO, Vec3::new(0.2, 0.2, 1.0), Vec3::Z), 0.0);
    }
}
