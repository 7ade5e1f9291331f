//! Fourth option for sphere lights (method.md §3.1, the talk's "future work"): sample the point
//! inside the sphere's visible cap by the pivot-transformed BRDF lobe, i.e. uniformly in T(C)
//! and mapped back by T, which is ∝ the SPTD restricted to the cap. It is mixed one-to-one with
//! the light's own uniform-cone sampling (a one-sample balance-heuristic MIS of the two point
//! samplers, which keeps the density bounded where the SPTD under-represents the lobe, e.g. its
//! diffuse part). Other light shapes keep their own sampling.
use super::importance::BoRecord;
use brdf_integrals::cap::Cap;
use brdf_integrals::pivot::{CapSampler, jacobian};
use render_core::light::{Light, LightSample, LightShape};
use render_core::rng::SampleStream;
use render_core::sampling;
use render_core::{Vec2, Vec3};

/// Probability of the pivot sampler in the mixture.
pub const PIVOT_FRACTION: f32 = 0.5;

/// Point sampling on sphere lights by the pivot-transformed lobe, mixed with cone sampling.
#[derive(Clone, Copy, Debug)]
pub struct PivotSphere {
    /// The SPTD pivot in the BSDF's local frame.
    pub pivot: Vec3,
}

/// The visible cap of a sphere light from x, in the local frame, or `None` if x is inside.
fn local_cap<L>(rec: &BoRecord<L>, center: Vec3, radius: f32) -> Option<(Cap, f32)> {
    let d = center - rec.x;
    let dist = d.length();
    if dist <= radius {
        return None;
    }
    let omc = sampling::sphere_cone_one_minus_cos(radius, dist);
    let axis = rec.frame.to_local(d / dist).normalize();
    Some((Cap::new(axis, 1.0 - omc), omc))
}

impl PivotSphere {
    /// A point on `light` seen from the record's shading point (cone sampling for lights that
    /// are not spheres); [`PivotSphere::pdf`] is its density.
    pub fn sample<L>(
        &self,
        rec: &BoRecord<L>,
        light: &Light,
        rng: &mut SampleStream,
    ) -> Option<LightSample> {
        let LightShape::Sphere { center, radius } = light.shape else {
            return light.sample(rec.x, rng.next_2d());
        };
        let choose_pivot = rng.next_f32() < PIVOT_FRACTION;
        let u = rng.next_2d();
        let (cap, _) = local_cap(rec, center, radius)?;
        let mut s = if choose_pivot {
            let (w_local, _) = CapSampler::new(self.pivot, &cap).sample([u.x, u.y]);
            let wi = rec.frame.to_world(w_local).normalize();
            let to_c = center - rec.x;
            let b = wi.dot(to_c);
            let disc = radius * radius - (to_c.length_squared() - b * b);
            if disc < 0.0 || b <= 0.0 {
                return None; // outside the sphere by rounding of the cap
            }
            let t = b - disc.sqrt();
            let point = rec.x + wi * t;
            let normal = (point - center).normalize_or(-wi);
            let radiance = light.emitted(normal, Vec2::ZERO, -wi);
            if radiance == Vec3::ZERO {
                return None;
            }
            LightSample {
                point,
                normal,
                wi,
                dist: t,
                radiance,
                pdf: 0.0,
                is_delta: false,
            }
        } else {
            light.sample(rec.x, u)?
        };
        s.pdf = self.pdf(rec, light, s.point, s.normal, s.wi);
        (s.pdf > 0.0).then_some(s)
    }

    /// Solid-angle density of [`PivotSphere::sample`] for the direction `wi` to `point`.
    pub fn pdf<L>(
        &self,
        rec: &BoRecord<L>,
        light: &Light,
        point: Vec3,
        normal: Vec3,
        wi: Vec3,
    ) -> f32 {
        let LightShape::Sphere { center, radius } = light.shape else {
            return light.pdf(rec.x, point, normal);
        };
        let Some((cap, omc)) = local_cap(rec, center, radius) else {
            return 0.0;
        };
        let cone = sampling::uniform_cone_pdf(omc);
        let w_local = rec.frame.to_local(wi);
        // The SPTD restricted to the cap: J(w)/|T(C)| (points of the sphere's visible side lie
        // in the cap, so no containment test, which would reject rim points by rounding).
        let mass = CapSampler::new(self.pivot, &cap).mass();
        let piv = if mass > 0.0 {
            jacobian(self.pivot, w_local) / (4.0 * std::f32::consts::PI * mass)
        } else {
            0.0
        };
        PIVOT_FRACTION * piv + (1.0 - PIVOT_FRACTION) * cone
    }
}
