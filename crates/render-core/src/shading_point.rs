//! A camera-ray hit ready for direct lighting: the point, the direction to the viewer and the
//! BSDF there, with the shadow-ray helpers every strategy uses.
use crate::accel::StreamRay;
use crate::bsdf::Bsdf;
use crate::light::LightSample;
use crate::scene::{Scene, SurfaceHit, offset_origin};
use crate::stats::Counters;
use glam::Vec3;

/// A camera-ray hit on a reflecting surface, ready for direct lighting.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint {
    pub hit: SurfaceHit,
    /// Unit direction towards the viewer.
    pub wo: Vec3,
    pub bsdf: Bsdf,
}

impl ShadingPoint {
    pub fn point(&self) -> Vec3 {
        self.hit.point
    }

    /// The shading normal on the viewer's side: the receiver's normal of light sampling.
    pub fn normal(&self) -> Vec3 {
        self.bsdf.frame.z
    }

    /// The normal by which light selection may cull what lies behind the receiver: the
    /// geometric normal on the viewer's side, or zero where the BSDF transmits, whose lights
    /// on both sides count (the light tree's "no receiver term").
    #[inline]
    pub fn cull_normal(&self) -> Vec3 {
        if self.bsdf.transmits() {
            Vec3::ZERO
        } else {
            self.bsdf.ng
        }
    }

    /// Ray origin for a ray leaving in direction `w`: offset to the side `w` leaves on, which
    /// is the far side for a transmitted direction.
    pub fn origin_towards(&self, w: Vec3) -> Vec3 {
        offset_origin(self.hit.point, self.hit.ng, w)
    }

    /// Unoccluded contribution f·cos·L of a light sample, before dividing by any pdf; traces the
    /// shadow ray only when the unshadowed value is non-zero.
    pub fn shade(&self, scene: &Scene, s: &LightSample, counters: &mut Counters) -> Vec3 {
        let f = self.bsdf.eval_cos(self.wo, s.wi) * s.radiance;
        self.unless_occluded(scene, s, f, counters)
    }

    /// [`ShadingPoint::shade`] and the BSDF's sampling density of the light sample's direction
    /// (for its MIS weight), both from one BSDF evaluation.
    pub fn shade_with_pdf(
        &self,
        scene: &Scene,
        s: &LightSample,
        counters: &mut Counters,
    ) -> (Vec3, f32) {
        let (f, pdf) = self.unshadowed_with_pdf(s);
        (self.unless_occluded(scene, s, f, counters), pdf)
    }

    /// [`ShadingPoint::shade_with_pdf`] before its shadow ray: the unshadowed f·cos·L and the
    /// BSDF's density of the direction.
    #[inline]
    pub fn unshadowed_with_pdf(&self, s: &LightSample) -> (Vec3, f32) {
        let v = self.bsdf.eval(self.wo, s.wi);
        (v.f_cos * s.radiance, v.pdf)
    }

    /// The shadow ray of a light sample: the segment [`ShadingPoint::shade`] tests.
    #[inline]
    pub fn shadow_ray(&self, scene: &Scene, s: &LightSample) -> StreamRay {
        let o = self.origin_towards(s.wi);
        scene.shadow_ray(o, s.wi, (s.point - o).length())
    }

    /// `f`, or zero when it is zero or the light sample's shadow ray is blocked.
    #[inline]
    fn unless_occluded(
        &self,
        scene: &Scene,
        s: &LightSample,
        f: Vec3,
        counters: &mut Counters,
    ) -> Vec3 {
        if f == Vec3::ZERO {
            return Vec3::ZERO;
        }
        counters.shadow_rays += 1;
        let r = self.shadow_ray(scene, s);
        if scene.accel.occluded(r.origin, r.dir, r.tmin, r.tmax) {
            Vec3::ZERO
        } else {
            f
        }
    }
}
