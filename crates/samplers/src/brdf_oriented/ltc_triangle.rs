//! BRDF-aware points on triangle lights (after Peters, "BRDF Importance Sampling for Polygonal
//! Lights", 2021): the glossy lobe is a linearly transformed cosine (LTC) D(ω) = D₀(M⁻¹ω)·J(ω),
//! so a direction drawn over the transformed triangle M⁻¹P with density ∝ D₀ = cos⁺/π and mapped
//! back by M has density ∝ D over P. Here the clamped cosine over the transformed triangle is
//! approximated by the bilinear warp of its uniform solid-angle sampling (what pbrt-v4 does for a
//! receiver's cosine), not Peters' exact projected-solid-angle sampling; the density stays exact:
//! the warp's density over M⁻¹P times the Jacobian of the map.
//!
//! Mixed one-to-one with the render's own point sampler (`--light-points`), which keeps the
//! density bounded where the lobe falls off (its diffuse part, the triangle's far side); where
//! the transformed triangle's solid angle is outside the spherical sampler's range, the render's
//! sampler alone draws the point.
use super::importance::BoRecord;
use brdf_integrals::{CapIntegral, Ltc, LtcLobe};
use glam::DMat3;
use render_core::Vec3;
use render_core::light::{Light, LightSample, LightShape};
use render_core::light_points::{
    LightPoints, MAX_SOLID_ANGLE, MIN_SOLID_ANGLE, triangle_point_along,
};
use render_core::rng::SampleStream;
use render_core::spherical_triangle::{SphericalTriangle, bilinear_pdf, bilinear_sample};
use std::sync::OnceLock;

/// Probability of the LTC sampler in the mixture.
pub const LTC_FRACTION: f32 = 0.5;

/// Point sampling on triangle lights by the LTC of a shading point's glossy lobe.
#[derive(Clone, Copy, Debug)]
pub struct LtcTriangle {
    /// M⁻¹ and M in the shading point's local frame.
    minv: DMat3,
    m: DMat3,
    det_minv: f64,
}

/// The committed LTC table, loaded once.
fn ltc() -> &'static Ltc {
    static LTC: OnceLock<Ltc> = OnceLock::new();
    LTC.get_or_init(Ltc::default)
}

impl LtcTriangle {
    /// The LTC of the GGX lobe of roughness `alpha` seen from `wo_local`; `None` when its
    /// matrix is singular.
    pub fn new(wo_local: Vec3, alpha: f32) -> Option<LtcTriangle> {
        let lobe: LtcLobe = ltc().lobe(wo_local, alpha);
        let det = lobe.minv.determinant();
        (det.is_finite() && det != 0.0).then(|| LtcTriangle {
            minv: lobe.minv,
            m: lobe.minv.inverse(),
            det_minv: det.abs(),
        })
    }

    /// The triangle `p` transformed by M⁻¹ as seen from the record's point, and the warp's
    /// corner weights (the clamped cosine about the LTC's z); `None` where its solid angle is
    /// outside the spherical sampler's range.
    fn transformed<L>(
        &self,
        rec: &BoRecord<L>,
        p: &[Vec3; 3],
    ) -> Option<(SphericalTriangle, [f64; 4])> {
        let local = |q: Vec3| self.minv * rec.frame.to_local(q - rec.x).as_dvec3();
        let st = SphericalTriangle::from_directions(p.map(local))?;
        if !(MIN_SOLID_ANGLE..=MAX_SOLID_ANGLE).contains(&st.solid_angle()) {
            return None;
        }
        let weights = st.corner_weights(|d| d.z.max(0.0));
        Some((st, weights))
    }

    /// A point on `light` for the record's shading point: by the LTC with probability
    /// [`LTC_FRACTION`], else by `points`; [`LtcTriangle::pdf`] is its density. Lights that are
    /// not triangles are sampled by `points`.
    pub fn sample<L>(
        &self,
        rec: &BoRecord<L>,
        light: &Light,
        points: LightPoints,
        rng: &mut SampleStream,
    ) -> Option<LightSample> {
        let n = rec.frame.z;
        let LightShape::Triangle { p, .. } = &light.shape else {
            return points.sample(light, rec.x, n, rng.next_2d());
        };
        let choose_ltc = rng.next_f32() < LTC_FRACTION;
        let u = rng.next_2d();
        let mut s = match self.transformed(rec, p) {
            Some((st, weights)) if choose_ltc => {
                let w_ltc = st.sample(bilinear_sample([u.x as f64, u.y as f64], weights))?;
                let w_local = (self.m * w_ltc).try_normalize()?;
                let wi = rec
                    .frame
                    .to_world(w_local.as_vec3())
                    .as_dvec3()
                    .try_normalize()?;
                triangle_point_along(light, rec.x, wi)?
            }
            _ => points.sample(light, rec.x, n, u)?,
        };
        s.pdf = self.pdf(rec, light, points, s.point, s.normal);
        (s.pdf > 0.0).then_some(s)
    }

    /// The solid-angle density of [`LtcTriangle::sample`] at `point` (normal `normal`).
    pub fn pdf<L>(
        &self,
        rec: &BoRecord<L>,
        light: &Light,
        points: LightPoints,
        point: Vec3,
        normal: Vec3,
    ) -> f32 {
        let p_points = points.pdf(light, rec.x, rec.frame.z, point, normal);
        let LightShape::Triangle { p, .. } = &light.shape else {
            return p_points;
        };
        let Some((st, weights)) = self.transformed(rec, p) else {
            return p_points;
        };
        if p_points == 0.0 {
            return 0.0; // emits nothing towards x (the same test as the point sampler's)
        }
        let w_local = rec.frame.to_local(point - rec.x).as_dvec3();
        let v = self.minv * w_local.normalize();
        let len = v.length();
        let Some(w_ltc) = v.try_normalize() else {
            return p_points;
        };
        // Density over the transformed triangle, times dω'/dω = |det M⁻¹| / |M⁻¹ω|³.
        let in_ltc = bilinear_pdf(st.invert(w_ltc), weights) / st.solid_angle();
        let p_ltc = in_ltc * self.det_minv / (len * len * len);
        (LTC_FRACTION as f64 * p_ltc + (1.0 - LTC_FRACTION as f64) * p_points as f64) as f32
    }
}
