//! The pivot transformation of Dupuy, Heitz and Belcour (2017) ("spherical pivot transformed
//! distributions", SPTD).
//!
//! For a pivot `r` inside the unit ball (ρ = |r| < 1), T(w) is the second intersection of the line
//! through w and r with the unit sphere:
//! T(w) = r + (ρ² − 1)/|w − r|² · (w − r). T is an involution and maps caps to caps.
//! The SPTD with uniform base density is D(w) = J(w)/4π with J(w) = ((1 − ρ²)/|w − r|²)², and
//! ∫_C D = |T(C)|/4π for every cap C.

use crate::cap::{Cap, Cap64};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// T(w) for a unit vector `w`.
pub fn transform(pivot: Vec3, w: Vec3) -> Vec3 {
    transform64(pivot.as_dvec3(), w.as_dvec3()).as_vec3()
}

/// |dT(w)/dw| = ((1 − ρ²)/|w − r|²)²: the SPTD density with uniform base is `jacobian/4π`.
pub fn jacobian(pivot: Vec3, w: Vec3) -> f32 {
    jacobian64(pivot.as_dvec3(), w.as_dvec3()) as f32
}

/// SPTD density (uniform base), normalised over the whole sphere: J(w)/4π.
pub fn density(pivot: Vec3, w: Vec3) -> f32 {
    (jacobian64(pivot.as_dvec3(), w.as_dvec3()) / (4.0 * PI)) as f32
}

/// The image T(C) of a cap, itself a cap.
pub fn transform_cap(pivot: Vec3, cap: &Cap) -> Cap {
    transform_cap64(pivot.as_dvec3(), &cap.to64()).to32()
}

#[inline]
pub(crate) fn transform64(p: DVec3, w: DVec3) -> DVec3 {
    let d = w - p;
    let rho2 = p.length_squared();
    p + d * ((rho2 - 1.0) / d.length_squared())
}

#[inline]
pub(crate) fn jacobian64(p: DVec3, w: DVec3) -> f64 {
    let j = (1.0 - p.length_squared()) / (w - p).length_squared();
    j * j
}

/// A unit vector perpendicular to `n`.
#[inline]
pub(crate) fn any_perp(n: DVec3) -> DVec3 {
    let (t, _) = basis(n);
    t
}

/// Orthonormal basis (t, b) with t × b = n (Duff et al. 2017).
#[inline]
pub(crate) fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// T(C) computed in the plane through the cap axis and the pivot: the two boundary points of C in
/// that plane map to two boundary points of T(C), which are diametrically opposite on its rim by
/// symmetry; T(axis of C) tells which of the two caps bounded by that circle is the image.
#[inline]
pub(crate) fn transform_cap64(p: DVec3, c: &Cap64) -> Cap64 {
    if c.sin < 1e-12 {
        return if c.cos > 0.0 {
            Cap64 {
                axis: transform64(p, c.axis),
                cos: 1.0,
                sin: 0.0,
            }
        } else {
            Cap64 {
                axis: c.axis,
                cos: -1.0,
                sin: 0.0,
            }
        };
    }
    let n = c.axis.cross(p);
    let l2 = n.length_squared();
    let n = if l2 > 1e-30 {
        n / l2.sqrt()
    } else {
        any_perp(c.axis)
    };
    let t = n.cross(c.axis);
    let q1 = transform64(p, c.axis * c.cos + t * c.sin);
    let q2 = transform64(p, c.axis * c.cos - t * c.sin);
    let mut a = n.cross(q2 - q1).normalize();
    let mut cos = a.dot(q1);
    let sin = a.cross(q1).length();
    let tc = transform64(p, c.axis);
    if tc.dot(a) < cos {
        a = -a;
        cos = -cos;
    }
    Cap64 {
        axis: a,
        cos: cos.clamp(-1.0, 1.0),
        sin,
    }
}

/// Uniform direction in a cap.
#[inline]
pub(crate) fn sample_uniform_cap64(c: &Cap64, u: [f64; 2]) -> DVec3 {
    // 1 − cos θ = u (1 − cos θc), without cancellation for small caps
    let one_minus_cosc = if c.cos > 0.0 {
        c.sin * c.sin / (1.0 + c.cos)
    } else {
        1.0 - c.cos
    };
    let omc = u[0] * one_minus_cosc;
    let cos_t = 1.0 - omc;
    let sin_t = (omc * (2.0 - omc)).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let (t, b) = basis(c.axis);
    (t * phi.cos() + b * phi.sin()) * sin_t + c.axis * cos_t
}

/// Samples directions inside a cap C with density ∝ the SPTD restricted to C: draw uniformly in
/// T(C) and map back with T. The pdf (solid angle) is J(w)/|T(C)| inside C and 0 outside.
/// Used to sample a point on a sphere light "by the pivot-transformed lobe" (method.md §3.1).
#[derive(Clone, Copy, Debug)]
pub struct CapSampler {
    pivot: DVec3,
    cap: Cap64,
    image: Cap64,
    image_area: f64,
}

impl CapSampler {
    /// A sampler for `cap` under the SPTD with pivot `pivot` (|pivot| < 1), both in the same
    /// frame (the lobe's local frame for [`crate::SptdLobe::cap_sampler`]).
    pub fn new(pivot: Vec3, cap: &Cap) -> Self {
        let pivot = pivot.as_dvec3();
        let cap = cap.to64();
        let image = transform_cap64(pivot, &cap);
        let image_area = if image.cos > 0.0 {
            2.0 * PI * image.sin * image.sin / (1.0 + image.cos)
        } else {
            image.area()
        };
        Self {
            pivot,
            cap,
            image,
            image_area,
        }
    }
    /// The SPTD mass of the cap, |T(C)|/4π.
    pub fn mass(&self) -> f32 {
        (self.image_area / (4.0 * PI)) as f32
    }
    /// A direction in the cap and its solid-angle pdf, for `u` uniform in [0, 1)².
    pub fn sample(&self, u: [f32; 2]) -> (Vec3, f32) {
        let v = sample_uniform_cap64(&self.image, [u[0] as f64, u[1] as f64]);
        let w = transform64(self.pivot, v).normalize();
        (
            w.as_vec3(),
            (jacobian64(self.pivot, w) / self.image_area) as f32,
        )
    }
    /// The pdf of `sample` at `w` (0 outside the cap).
    pub fn pdf(&self, w: Vec3) -> f32 {
        let w = w.as_dvec3();
        if w.dot(self.cap.axis) < self.cap.cos || self.image_area <= 0.0 {
            return 0.0;
        }
        (jacobian64(self.pivot, w) / self.image_area) as f32
    }
}

/// Convenience: one sample of [`CapSampler`].
pub fn sample_cap(pivot: Vec3, cap: &Cap, u: [f32; 2]) -> (Vec3, f32) {
    CapSampler::new(pivot, cap).sample(u)
}

/// Convenience: the pdf of [`sample_cap`].
pub fn pdf_cap(pivot: Vec3, cap: &Cap, w: Vec3) -> f32 {
    CapSampler::new(pivot, cap).pdf(w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cap::lens_area_exact;
    use crate::qmc::SplitMix64;
    use chi2_test::{DirectionGrid, chi2_directions_on, sidak_significance};

    fn uniform_sphere(rng: &mut SplitMix64) -> DVec3 {
        let z = 1.0 - 2.0 * rng.next_f64();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * rng.next_f64();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }
    fn random_pivot(rng: &mut SplitMix64) -> DVec3 {
        uniform_sphere(rng) * rng.next_f64().sqrt().min(0.995)
    }

    #[test]
    fn involution() {
        let mut rng = SplitMix64::new(3);
        for _ in 0..1000 {
            let p = random_pivot(&mut rng);
            let w = uniform_sphere(&mut rng);
            let tw = transform64(p, w);
            assert!((tw.length() - 1.0).abs() < 1e-9);
            assert!((transform64(p, tw) - w).length() < 1e-8, "{p} {w}");
            // the Jacobians of T at w and at T(w) multiply to one
            assert!((jacobian64(p, w) * jacobian64(p, tw) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn caps_map_to_caps() {
        let mut rng = SplitMix64::new(4);
        for _ in 0..200 {
            let p = random_pivot(&mut rng);
            let c = Cap64::new(uniform_sphere(&mut rng), 2.0 * rng.next_f64() - 1.0);
            let tc = transform_cap64(p, &c);
            // every boundary point of C lands on the boundary of T(C)
            let (t, b) = basis(c.axis);
            for k in 0..16 {
                let phi = k as f64 * PI / 8.0;
                let w = c.axis * c.cos + (t * phi.cos() + b * phi.sin()) * c.sin;
                let d = transform64(p, w).dot(tc.axis) - tc.cos;
                assert!(d.abs() < 1e-7, "boundary off by {d}");
            }
            // and interior maps to interior
            for _ in 0..16 {
                let w = uniform_sphere(&mut rng);
                let inside = w.dot(c.axis) >= c.cos;
                let img = transform64(p, w).dot(tc.axis) >= tc.cos;
                let margin = (w.dot(c.axis) - c.cos).abs();
                assert!(inside == img || margin < 1e-7);
            }
        }
    }

    #[test]
    fn cap_mass_is_image_area() {
        // ∫_C J/4π dω = |T(C)|/4π, checked by Monte Carlo with uniform samples in C.
        let mut rng = SplitMix64::new(5);
        for _ in 0..20 {
            let p = random_pivot(&mut rng) * 0.8;
            let c = Cap64::new(uniform_sphere(&mut rng), rng.next_f64() * 1.8 - 0.9);
            let n = 20000;
            let mut s = 0.0;
            let mut s2 = 0.0;
            for _ in 0..n {
                let w = sample_uniform_cap64(&c, [rng.next_f64(), rng.next_f64()]);
                let v = jacobian64(p, w) * c.area();
                s += v;
                s2 += v * v;
            }
            let m = s / n as f64;
            let se = ((s2 / n as f64 - m * m) / n as f64).sqrt();
            let exact = transform_cap64(p, &c).area();
            assert!((m - exact).abs() < 5.0 * se + 1e-9, "{m} ± {se} vs {exact}");
            // intersection areas are preserved up to the density as well: the mass of C ∩ H
            let h = Cap64::new(DVec3::Z, 0.0);
            let _ = lens_area_exact(&transform_cap64(p, &c), &transform_cap64(p, &h));
        }
    }

    #[test]
    fn cap_sampler_chi2() {
        let cases = [
            (
                Vec3::new(-0.5, 0.0, 0.7),
                Cap::new(Vec3::new(-0.3, 0.2, 0.93).normalize(), 0.8),
            ),
            (
                Vec3::new(-0.9, 0.0, 0.4),
                Cap::new(Vec3::new(-0.8, 0.1, 0.59).normalize(), 0.95),
            ),
            (
                Vec3::new(0.0, 0.0, 0.3),
                Cap::new(Vec3::new(0.6, 0.0, 0.8), -0.2),
            ),
            (
                Vec3::new(0.2, -0.1, 0.95),
                Cap::new(Vec3::new(0.0, 0.0, 1.0), 0.99),
            ),
        ];
        let tests = cases.len();
        for (i, (pivot, cap)) in cases.into_iter().enumerate() {
            let s = CapSampler::new(pivot, &cap);
            let mut rng = SplitMix64::new(100 + i as u64);
            let grid = DirectionGrid {
                theta_bins: 20,
                phi_bins: 40,
                axis: cap.axis,
                cos_min: cap.cos_theta as f64,
                pdf_subdivisions: 16,
            };
            let res = chi2_directions_on(
                &grid,
                200_000,
                |_| Some(s.sample([rng.next_f64() as f32, rng.next_f64() as f32]).0),
                |w| s.pdf(w) as f64,
            );
            assert!(
                res.p_value > sidak_significance(0.01, tests),
                "case {i}: {res:?}"
            );
        }
    }

    #[test]
    fn chi2_detects_a_wrong_pdf() {
        let pivot = Vec3::new(-0.5, 0.0, 0.7);
        let cap = Cap::new(Vec3::new(-0.3, 0.2, 0.93).normalize(), 0.8);
        let s = CapSampler::new(pivot, &cap);
        let mut rng = SplitMix64::new(9);
        // claim a uniform pdf in the cap: must be rejected
        let area = cap.solid_angle() as f64;
        let grid = DirectionGrid {
            theta_bins: 20,
            phi_bins: 40,
            axis: cap.axis,
            cos_min: cap.cos_theta as f64,
            pdf_subdivisions: 16,
        };
        let res = chi2_directions_on(
            &grid,
            100_000,
            |_| Some(s.sample([rng.next_f64() as f32, rng.next_f64() as f32]).0),
            |w| if cap.contains(w) { 1.0 / area } else { 0.0 },
        );
        assert!(res.p_value < 0.01, "{res:?}");
    }
}
