//! BSDF sampling as a light-sampling technique: sample a direction, trace it, and see
//! which light (if any) it reaches first.
use render_core::Vec3;
use render_core::accel::StreamRay;
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::{NO_LIGHT, Scene, SurfaceHit};
use render_core::stats::Counters;

/// A BSDF-sampled direction and what it found.
#[derive(Clone, Copy, Debug)]
pub struct BsdfLightHit {
    /// The sampled direction (world space).
    pub wi: Vec3,
    /// f·|cos θ| for `wi`.
    pub f_cos: Vec3,
    /// Solid-angle density of `wi`.
    pub pdf: f32,
    /// The light hit first, or [`NO_LIGHT`] (missed everything, or hit a non-emitter).
    pub light: u32,
    /// Where the ray hit the light.
    pub point: Vec3,
    /// The light's surface normal at `point`.
    pub normal: Vec3,
    /// Radiance arriving from `point` along −wi.
    pub radiance: Vec3,
}

impl BsdfLightHit {
    /// Whether the direction reached an emitting light.
    pub fn found_light(&self) -> bool {
        self.light != NO_LIGHT && self.radiance != Vec3::ZERO
    }
}

/// Draws one BSDF sample (three random numbers) and traces it.
pub fn sample_bsdf(
    scene: &Scene,
    sp: &ShadingPoint,
    rng: &mut SampleStream,
    counters: &mut Counters,
) -> Option<BsdfLightHit> {
    let u_lobe = rng.next_f32();
    let u = rng.next_2d();
    sample_bsdf_at(scene, sp, u_lobe, u, counters)
}

/// [`sample_bsdf`] with its three numbers given (lobe choice, direction).
pub fn sample_bsdf_at(
    scene: &Scene,
    sp: &ShadingPoint,
    u_lobe: f32,
    u: render_core::Vec2,
    counters: &mut Counters,
) -> Option<BsdfLightHit> {
    let d = bsdf_direction(sp, u_lobe, u, counters)?;
    let r = d.ray(sp);
    Some(d.found(scene, scene.intersect(r.origin, r.dir, r.tmin, r.tmax)))
}

/// A BSDF-sampled direction before its ray is traced.
#[derive(Clone, Copy, Debug)]
pub struct BsdfDirection {
    /// The sampled direction (world space).
    pub wi: Vec3,
    /// f·|cos θ| for `wi`.
    pub f_cos: Vec3,
    /// Solid-angle density of `wi`.
    pub pdf: f32,
}

/// The first half of [`sample_bsdf_at`]: the direction, counted as a BSDF ray.
#[inline]
pub fn bsdf_direction(
    sp: &ShadingPoint,
    u_lobe: f32,
    u: render_core::Vec2,
    counters: &mut Counters,
) -> Option<BsdfDirection> {
    let s = sp.bsdf.sample(sp.wo, u_lobe, u)?;
    counters.bsdf_rays += 1;
    Some(BsdfDirection {
        wi: s.wi,
        f_cos: s.f_cos,
        pdf: s.pdf,
    })
}

impl BsdfDirection {
    /// The ray that traces it (closest hit).
    #[inline]
    pub fn ray(&self, sp: &ShadingPoint) -> StreamRay {
        StreamRay {
            origin: sp.origin_towards(self.wi),
            dir: self.wi,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    /// The second half of [`sample_bsdf_at`]: what the traced ray found at `hit`.
    #[inline]
    pub fn found(&self, scene: &Scene, hit: Option<SurfaceHit>) -> BsdfLightHit {
        let mut out = BsdfLightHit {
            wi: self.wi,
            f_cos: self.f_cos,
            pdf: self.pdf,
            light: NO_LIGHT,
            point: Vec3::ZERO,
            normal: Vec3::ZERO,
            radiance: Vec3::ZERO,
        };
        if let Some(hit) = hit
            && hit.light != NO_LIGHT
        {
            out.light = hit.light;
            out.point = hit.point;
            out.normal = hit.ng;
            out.radiance = scene.lights[hit.light as usize].emitted(hit.ng, hit.uv, -self.wi);
        }
        out
    }
}
