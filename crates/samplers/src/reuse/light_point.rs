//! A point on a light as the reuse strategies carry it between pixels, and how a shading point
//! sees it. Samples live in the lights' **area measure** (a counting measure on point lights),
//! so a sample moved to a neighbour needs no Jacobian: the neighbour evaluates the same point.
use render_core::Vec2;
use render_core::Vec3;
use render_core::colour::luminance;
use render_core::estimator::ShadingPoint;
use render_core::light::{Light, LightShape};
use render_core::scene::Scene;

/// A point on light `light` with its surface normal (zero on a point light).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightPoint {
    /// The light's index in the scene.
    pub light: u32,
    /// The point and the light's unit normal there.
    pub point: Vec3,
    #[allow(missing_docs)]
    pub normal: Vec3,
}

/// A light point as seen from a shading point.
#[derive(Clone, Copy, Debug)]
pub struct Seen {
    /// Unit direction from the shading point to the light point, and its distance.
    pub wi: Vec3,
    #[allow(missing_docs)]
    pub dist: f32,
    /// Radiance arriving along −wi (a point light's intensity / dist²).
    pub radiance: Vec3,
    /// From solid angle to the light's measure: |cos θ_y| / dist² (1 on a point light).
    pub g: f32,
    /// A point light.
    pub is_delta: bool,
}

impl Seen {
    /// The point as seen from `x`: `None` where it emits nothing towards `x`.
    pub fn from(scene: &Scene, x: Vec3, y: &LightPoint) -> Option<Seen> {
        let light = &scene.lights[y.light as usize];
        let d = y.point - x;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = d / dist;
        let (radiance, g, is_delta) = match &light.shape {
            LightShape::Point { .. } => (
                light.emitted(Vec3::ZERO, Vec2::ZERO, -wi) / dist2,
                1.0,
                true,
            ),
            _ => {
                let uv = texture_uv(light, y.point);
                let cos_y = y.normal.dot(-wi).abs();
                (light.emitted(y.normal, uv, -wi), cos_y / dist2, false)
            }
        };
        (radiance != Vec3::ZERO && g > 0.0 && g.is_finite()).then_some(Seen {
            wi,
            dist,
            radiance,
            g,
            is_delta,
        })
    }
}

/// The target function p̂ of shading point `sp` at `y`: the luminance of the unshadowed
/// f·cos·L·G, in the lights' measure. Also the unshadowed contribution f·cos·L·G itself.
pub fn target(scene: &Scene, sp: &ShadingPoint, y: &LightPoint) -> Option<(f32, Vec3, Seen)> {
    let seen = Seen::from(scene, sp.point(), y)?;
    let f = sp.bsdf.eval_cos(sp.wo, seen.wi) * seen.radiance * seen.g;
    let p = luminance(f);
    (p > 0.0 && p.is_finite()).then_some((p, f, seen))
}

/// Whether the segment from `sp` to the light point it sees along `seen` is blocked (one
/// shadow ray, counted).
pub fn occluded(
    scene: &Scene,
    sp: &ShadingPoint,
    y: &LightPoint,
    seen: &Seen,
    counters: &mut render_core::stats::Counters,
) -> bool {
    counters.shadow_rays += 1;
    let o = sp.origin_towards(seen.wi);
    scene.occluded(o, seen.wi, (y.point - o).length())
}

/// The texture coordinate of `point` on a textured triangle light (only the texture reads it).
fn texture_uv(light: &Light, point: Vec3) -> Vec2 {
    let (LightShape::Triangle { p, uv, .. }, Some(_)) = (&light.shape, &light.texture) else {
        return Vec2::ZERO;
    };
    let (e1, e2, d) = (p[1] - p[0], p[2] - p[0], point - p[0]);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let den = d11 * d22 - d12 * d12;
    if !(den.abs() > 0.0) {
        return uv[0];
    }
    let b1 = (d22 * d1 - d12 * d2) / den;
    let b2 = (d11 * d2 - d12 * d1) / den;
    uv[0] * (1.0 - b1 - b2) + uv[1] * b1 + uv[2] * b2
}
