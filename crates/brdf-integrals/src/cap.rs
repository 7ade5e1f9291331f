//! Spherical caps and the area of the intersection of two caps.
//!
//! The public type stores `f32`; the arithmetic runs in `f64` ([`Cap64`]) because the exact lens
//! area of two small caps is a difference of O(1) terms that cancel to O(θ²).

use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// The set of unit directions w with `w · axis >= cos_theta`. `axis` must be a unit vector;
/// `cos_theta` in [−1, 1] (negative: larger than a hemisphere).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cap {
    /// Centre direction of the cap (unit length).
    pub axis: Vec3,
    /// Cosine of the cap's half-angle, in [−1, 1]: 1 is a single direction, 0 a hemisphere,
    /// −1 the whole sphere.
    pub cos_theta: f32,
}

impl Cap {
    /// The cap around the unit vector `axis` with half-angle cosine `cos_theta` (stored as
    /// given: neither is normalised or clamped).
    pub fn new(axis: Vec3, cos_theta: f32) -> Self {
        Self { axis, cos_theta }
    }
    /// The upper hemisphere z ≥ 0.
    pub fn upper_hemisphere() -> Self {
        Self {
            axis: Vec3::Z,
            cos_theta: 0.0,
        }
    }
    /// The cap subtended by a sphere of `radius` at `center` (relative to the viewer), or `None`
    /// if the viewer is inside the sphere.
    pub fn from_sphere(center: Vec3, radius: f32) -> Option<Self> {
        let c = center.as_dvec3();
        let d2 = c.length_squared();
        let r2 = (radius as f64).powi(2);
        if d2 <= r2 {
            return None;
        }
        Some(Self {
            axis: (c / d2.sqrt()).as_vec3(),
            cos_theta: ((d2 - r2) / d2).sqrt() as f32,
        })
    }
    /// Solid angle 2π(1 − cos θ), in steradians.
    pub fn solid_angle(&self) -> f32 {
        (2.0 * PI * (1.0 - self.cos_theta as f64)) as f32
    }
    /// Whether the unit direction `w` is in the cap (boundary included).
    pub fn contains(&self, w: Vec3) -> bool {
        w.dot(self.axis) >= self.cos_theta
    }
    pub(crate) fn to64(self) -> Cap64 {
        Cap64::new(self.axis.as_dvec3().normalize(), self.cos_theta as f64)
    }
}

/// `f64` cap used internally (public for the fitting tools); keeps sin θ beside cos θ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cap64 {
    /// Centre direction (unit length).
    pub axis: DVec3,
    /// Cosine of the half-angle, in [−1, 1].
    pub cos: f64,
    /// Sine of the half-angle, in [0, 1]; kept consistent with `cos` by [`Cap64::new`].
    pub sin: f64,
}

impl Cap64 {
    /// The cap around the unit vector `axis` with half-angle cosine `cos` (clamped to
    /// [−1, 1]); computes the matching sine. `axis` is not normalised.
    pub fn new(axis: DVec3, cos: f64) -> Self {
        let cos = cos.clamp(-1.0, 1.0);
        Self {
            axis,
            cos,
            sin: (1.0 - cos * cos).max(0.0).sqrt(),
        }
    }
    /// The same cap in `f32` (drops the sine).
    pub fn to32(self) -> Cap {
        Cap {
            axis: self.axis.as_vec3(),
            cos_theta: self.cos as f32,
        }
    }
    /// Solid angle 2π(1 − cos θ), in steradians.
    #[inline]
    pub fn area(&self) -> f64 {
        2.0 * PI * (1.0 - self.cos)
    }
    /// Half-angle θ in radians, in [0, π].
    #[inline]
    pub fn angle(&self) -> f64 {
        self.sin.atan2(self.cos)
    }
}

/// Area of a ∩ b, exact (spherical lens closed form), in steradians (0 when disjoint). The
/// axes are renormalised in `f64` before use.
pub fn intersection_area_exact(a: &Cap, b: &Cap) -> f32 {
    lens_area_exact(&a.to64(), &b.to64()) as f32
}

/// Area of a ∩ b with the Oat–Sander "ambient aperture" approximation (exact when one cap
/// contains the other or they are disjoint; a smoothstep blend otherwise). This is what the SPTD
/// reference code uses. In steradians, never above the smaller cap's solid angle.
pub fn intersection_area_oat_sander(a: &Cap, b: &Cap) -> f32 {
    lens_area_oat_sander(&a.to64(), &b.to64()) as f32
}

/// True if the cap lies entirely in z ≤ 0 (its highest point is at or below the horizon).
#[inline]
pub(crate) fn below_horizon(c: &Cap64) -> bool {
    // angle of the axis from +z minus the cap radius ≥ π/2
    let beta = c.axis.z.clamp(-1.0, 1.0).acos();
    beta - c.angle() >= std::f64::consts::FRAC_PI_2
}

/// Exact area of the intersection of two caps.
///
/// The disjoint / nested / complementary tests compare cosines (no inverse trigonometry); only
/// a partial overlap pays for the three `acos` of the lens formula.
#[inline]
pub(crate) fn lens_area_exact(a: &Cap64, b: &Cap64) -> f64 {
    let cd = a.axis.dot(b.axis).clamp(-1.0, 1.0);
    // cos and sin of ra + rb, cos of |ra − rb|
    let c_sum = a.cos * b.cos - a.sin * b.sin;
    let s_sum = a.sin * b.cos + a.cos * b.sin;
    let c_diff = a.cos * b.cos + a.sin * b.sin;
    if cd <= c_sum {
        // d ≥ ra + rb (disjoint) when ra + rb < π; otherwise d ≥ 2π − ra − rb: the complements
        // are disjoint and the union is the whole sphere
        return if s_sum >= 0.0 {
            0.0
        } else {
            (a.area() + b.area() - 4.0 * PI).max(0.0)
        };
    }
    let sd = a.axis.cross(b.axis).length();
    if cd >= c_diff - 1e-15 || sd <= 1e-300 {
        // d ≤ |ra − rb|: one cap inside the other
        return a.area().min(b.area());
    }
    // Partial overlap: 0 < d < π and 0 < ra, rb < π. Area = 2[π − γ − cos ra · α − cos rb · β]
    // with the angle γ at the intersection points and the half-angles α, β at the two axes.
    let x = ((cd - a.cos * b.cos) / (a.sin * b.sin)).clamp(-1.0, 1.0);
    let ya = ((b.cos - cd * a.cos) / (sd * a.sin)).clamp(-1.0, 1.0);
    let yb = ((a.cos - cd * b.cos) / (sd * b.sin)).clamp(-1.0, 1.0);
    let area = 2.0 * (PI - x.acos() - a.cos * ya.acos() - b.cos * yb.acos());
    area.clamp(0.0, a.area().min(b.area()))
}

/// Oat–Sander approximation of the intersection area (exact nested / disjoint cases by cosine
/// tests; the angles are only computed in the smoothstep band).
#[inline]
pub(crate) fn lens_area_oat_sander(a: &Cap64, b: &Cap64) -> f64 {
    let cd = a.axis.dot(b.axis).clamp(-1.0, 1.0);
    let c_sum = a.cos * b.cos - a.sin * b.sin;
    let s_sum = a.sin * b.cos + a.cos * b.sin;
    let c_diff = a.cos * b.cos + a.sin * b.sin;
    let small = a.area().min(b.area());
    if cd >= c_diff {
        return small;
    }
    if cd <= c_sum && s_sum >= 0.0 {
        return 0.0;
    }
    let d = cd.acos();
    let (ra, rb) = (a.angle(), b.angle());
    let rdiff = (ra - rb).abs();
    let t = ((d - rdiff) / (ra + rb - rdiff)).clamp(0.0, 1.0);
    let x = 1.0 - t;
    x * x * (3.0 - 2.0 * x) * small
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qmc::SplitMix64;

    fn uniform_sphere(rng: &mut SplitMix64) -> DVec3 {
        let z = 1.0 - 2.0 * rng.next_f64();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * rng.next_f64();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    fn mc_area(a: &Cap64, b: &Cap64, n: usize, rng: &mut SplitMix64) -> (f64, f64) {
        let mut hits = 0usize;
        for _ in 0..n {
            let w = uniform_sphere(rng);
            if w.dot(a.axis) >= a.cos && w.dot(b.axis) >= b.cos {
                hits += 1;
            }
        }
        let p = hits as f64 / n as f64;
        (4.0 * PI * p, 4.0 * PI * (p * (1.0 - p) / n as f64).sqrt())
    }

    #[test]
    fn exact_lens_matches_monte_carlo() {
        let mut rng = SplitMix64::new(7);
        for _ in 0..60 {
            let a = Cap64::new(uniform_sphere(&mut rng), 2.0 * rng.next_f64() - 1.0);
            let b = Cap64::new(uniform_sphere(&mut rng), 2.0 * rng.next_f64() - 1.0);
            let exact = lens_area_exact(&a, &b);
            let (mc, se) = mc_area(&a, &b, 40_000, &mut rng);
            assert!(
                (exact - mc).abs() <= 5.0 * se + 1e-3,
                "exact {exact} mc {mc} ± {se}: {a:?} {b:?}"
            );
        }
    }

    #[test]
    fn exact_lens_special_cases() {
        // two hemispheres at angle d: a lune of area 2(π − d)
        for &d in &[0.1f64, 1.0, 2.5] {
            let a = Cap64::new(DVec3::Z, 0.0);
            let b = Cap64::new(DVec3::new(d.sin(), 0.0, d.cos()), 0.0);
            assert!((lens_area_exact(&a, &b) - 2.0 * (PI - d)).abs() < 1e-9);
        }
        // symmetric and bounded; tiny caps do not lose precision
        let r = 1e-3f64;
        let a = Cap64::new(DVec3::Z, r.cos());
        let off = 1e-3f64;
        let b = Cap64::new(DVec3::new(off.sin(), 0.0, off.cos()), r.cos());
        let ab = lens_area_exact(&a, &b);
        // planar lens of two discs of radius r at distance r: r²(2π/3 − √3/2)
        let planar = r * r * (2.0 * PI / 3.0 - 3f64.sqrt() / 2.0);
        assert!((ab / planar - 1.0).abs() < 1e-4, "{ab} vs {planar}");
        assert_eq!(ab, lens_area_exact(&b, &a));
    }

    #[test]
    fn oat_sander_exact_in_limits() {
        let a = Cap64::new(DVec3::Z, 0.5);
        let b = Cap64::new(DVec3::Z, 0.9);
        assert!((lens_area_oat_sander(&a, &b) - b.area()).abs() < 1e-12);
        let c = Cap64::new(-DVec3::Z, 0.9);
        assert_eq!(lens_area_oat_sander(&a, &c), 0.0);
    }

    #[test]
    fn from_sphere_matches_geometry() {
        let c = Cap::from_sphere(Vec3::new(0.0, 0.0, 2.0), 1.0).unwrap();
        assert!((c.cos_theta - 3f32.sqrt() / 2.0).abs() < 1e-6);
        assert!(Cap::from_sphere(Vec3::new(0.0, 0.0, 0.5), 1.0).is_none());
    }
}
