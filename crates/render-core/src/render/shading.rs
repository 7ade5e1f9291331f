//! A camera ray's shading: the emission it sees, the strategy's estimate at its hit and the
//! distant lights there.
use crate::accel::StreamRay;
use crate::bsdf::Bsdf;
use crate::camera::{Camera, FilmRays};
use crate::estimator::{DirectLighting, SampleContext, ShadingPoint};
use crate::rng::SampleStream;
use crate::scene::{NO_LIGHT, Scene, SurfaceHit};
use crate::stats::Counters;
use glam::{Vec2, Vec3};

/// What one camera ray found: the emission it sees, the strategy's direct-lighting estimate and
/// the distant lights at its hit (kept apart so that extra emission rays can replace the first).
#[derive(Default)]
pub(super) struct CameraSample {
    pub(super) emitted: Vec3,
    pub(super) direct: Vec3,
    pub(super) distant: Vec3,
    pub(super) sees_light: bool,
}

/// Camera-ray shading: emission seen directly plus direct lighting at the hit.
pub(super) fn shade_camera_sample(
    scene: &Scene,
    strategy: &dyn DirectLighting,
    camera: &Camera,
    aspect: f32,
    film: Vec2,
    rng: &mut SampleStream,
    ctx: &mut SampleContext,
) -> CameraSample {
    let (mut out, sp) = camera_hit(scene, camera, aspect, film, ctx.counters);
    let Some(sp) = sp else {
        return out;
    };
    out.direct = strategy.estimate(scene, &sp, rng, ctx);
    out.distant = distant_lighting(scene, &sp, ctx.counters);
    out
}

/// What a camera ray through `film` sees before any direct lighting: the emission it sees
/// (in `CameraSample::emitted`) and the shading point of its hit, if the hit reflects.
pub(super) fn camera_hit(
    scene: &Scene,
    camera: &Camera,
    aspect: f32,
    film: Vec2,
    counters: &mut Counters,
) -> (CameraSample, Option<ShadingPoint>) {
    let ray = camera_ray(camera, &camera.film_rays(aspect), film);
    let hit = scene.intersect(ray.origin, ray.dir, ray.tmin, ray.tmax);
    seen_by_camera(scene, ray.dir, hit, counters)
}

/// The camera ray through `film` (in [0, 1]²), `lens` being `camera`'s for the image.
pub(super) fn camera_ray(camera: &Camera, lens: &FilmRays, film: Vec2) -> StreamRay {
    StreamRay {
        origin: camera.position,
        dir: lens.direction(film),
        tmin: 0.0,
        tmax: f32::INFINITY,
    }
}

/// [`camera_hit`] once the camera ray along `dir` has been traced to `hit`.
pub(super) fn seen_by_camera(
    scene: &Scene,
    dir: Vec3,
    hit: Option<SurfaceHit>,
    counters: &mut Counters,
) -> (CameraSample, Option<ShadingPoint>) {
    counters.camera_rays += 1;
    let Some(hit) = hit else {
        return (CameraSample::default(), None);
    };
    let wo = -dir;
    let mut out = CameraSample::default();
    if hit.light != NO_LIGHT {
        out.emitted = scene.lights[hit.light as usize].emitted(hit.ng, hit.uv, wo);
        out.sees_light = out.emitted != Vec3::ZERO;
    }
    let sp = shading_point(scene, hit, wo);
    if sp.is_some() {
        counters.shading_points += 1;
    }
    (out, sp)
}

/// Directional lights, each a delta: one shadow ray apiece.
pub(super) fn distant_lighting(scene: &Scene, sp: &ShadingPoint, counters: &mut Counters) -> Vec3 {
    let mut l = Vec3::ZERO;
    for d in &scene.distant_lights {
        let f = sp.bsdf.eval_cos(sp.wo, d.direction) * d.irradiance;
        if f == Vec3::ZERO {
            continue;
        }
        counters.shadow_rays += 1;
        if !scene.accel.occluded(
            sp.origin_towards(d.direction),
            d.direction,
            0.0,
            f32::INFINITY,
        ) {
            l += f;
        }
    }
    l
}

/// A surface hit for tests and tools that shade points directly.
pub fn shading_point(scene: &Scene, hit: SurfaceHit, wo: Vec3) -> Option<ShadingPoint> {
    let m = hit.material?;
    let params = scene.materials[m as usize].params_at(hit.uv);
    Some(ShadingPoint {
        hit,
        wo,
        bsdf: Bsdf::new(hit.ns, hit.ng, wo, params),
    })
}
