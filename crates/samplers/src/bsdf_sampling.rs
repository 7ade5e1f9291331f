//! BSDF sampling as a light-sampling technique: sample a direction, trace it, and see
//! which light (if any) it reaches first.
use render_core::Vec3;
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::{NO_LIGHT, Scene};
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
    let s = sp.bsdf.sample(sp.wo, u_lobe, u)?;
    counters.bsdf_rays += 1;
    let origin = sp.origin_towards(s.wi);
    let mut out = BsdfLightHit {
        wi: s.wi,
        f_cos: s.f_cos,
        pdf: s.pdf,
        light: NO_LIGHT,
        point: Vec3::ZERO,
        normal: Vec3::ZERO,
        radiance: Vec3::ZERO,
    };
    if let Some(hit) = scene.intersect(origin, s.wi, 0.0, f32::INFINITY)
        && hit.light != NO_LIGHT
    {
        out.light = hit.light;
        out.point = hit.point;
        out.normal = hit.ng;
        out.radiance = scene.lights[hit.light as usize].emitted(hit.ng, hit.uv, -s.wi);
    }
    Some(out)
}
