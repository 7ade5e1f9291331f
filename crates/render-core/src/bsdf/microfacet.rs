//! Isotropic GGX (Trowbridge–Reitz) microfacet distribution in the local frame (z = normal),
//! with height-correlated Smith masking-shadowing and visible-normal sampling (Heitz 2018).
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Smallest α the renderer accepts (the paper's own scene uses 0.008).
pub const MIN_ALPHA: f32 = 1e-3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha: f32,
}

impl Ggx {
    pub fn new(alpha: f32) -> Ggx {
        Ggx {
            alpha: alpha.clamp(MIN_ALPHA, 1.0),
        }
    }

    /// Normal distribution D(h).
    pub fn d(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let c2 = h.z * h.z;
        let t = c2 * (a2 - 1.0) + 1.0;
        a2 / (PI * t * t)
    }

    /// Smith Λ(w).
    pub fn lambda(&self, w: Vec3) -> f32 {
        let c2 = w.z * w.z;
        if c2 <= 0.0 {
            return f32::INFINITY;
        }
        let tan2 = ((1.0 - c2) / c2).max(0.0);
        0.5 * ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0)
    }

    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G2(wo, wi).
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Un-Fresnelled BRDF times cos θi: D·G2 / (4 cos θo). Zero when either direction is below the horizon.
    pub fn eval_cos(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        self.eval_cos_at(&self.pair(wo, wi), wo, wi)
    }

    /// What the value and the density of one pair of directions (both above the horizon) share.
    #[inline]
    pub fn pair(&self, wo: Vec3, wi: Vec3) -> PairTerms {
        let h = (wo + wi).normalize();
        PairTerms {
            h,
            d: self.d(h),
            lambda_o: self.lambda(wo),
        }
    }

    /// [`Ggx::eval_cos`] from the shared terms of (wo, wi).
    #[inline]
    pub fn eval_cos_at(&self, t: &PairTerms, wo: Vec3, wi: Vec3) -> f32 {
        let g2 = 1.0 / (1.0 + t.lambda_o + self.lambda(wi));
        t.d * g2 / (4.0 * wo.z)
    }

    /// [`Ggx::reflection_pdf`] from the shared terms of (wo, wi).
    #[inline]
    pub fn reflection_pdf_at(&self, t: &PairTerms, wo: Vec3) -> f32 {
        let g1 = 1.0 / (1.0 + t.lambda_o);
        g1 * t.d / (4.0 * wo.z)
    }

    /// Sample a visible normal for `wo` (wo.z > 0).
    pub fn sample_visible_normal(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let a = self.alpha;
        let vh = Vec3::new(a * wo.x, a * wo.y, wo.z).normalize();
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let p1 = r * phi.cos();
        let mut p2 = r * phi.sin();
        let s = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        Vec3::new(a * nh.x, a * nh.y, nh.z.max(1e-6)).normalize()
    }

    /// Density of the reflected direction produced by visible-normal sampling: G1(wo)·D(h) / (4 cos θo).
    pub fn reflection_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        self.reflection_pdf_at(&self.pair(wo, wi), wo)
    }
}

/// The half vector of a pair of directions, D there and Smith Λ(wo): what the BRDF's value and
/// its sampling density have in common, computed once when both are wanted.
#[derive(Clone, Copy, Debug)]
pub struct PairTerms {
    pub h: Vec3,
    pub d: f32,
    pub lambda_o: f32,
}

pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    2.0 * w.dot(n) * n - w
}
