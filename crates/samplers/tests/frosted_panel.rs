//! `builtin:frosted-panel`: a rough dielectric pane lit from behind by many small lights.
//! The strategies converge to the same image on it, and the comparison has the power to
//! catch an estimator that culls the lights behind the pane.
mod common;
use render_core::Vec3;
use render_core::estimator::{DirectLighting, SampleContext, ShadingPoint};
use render_core::render::{RenderResult, RenderSettings, render};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use samplers::StrategyOptions;
use samplers::bsdf_sampling::sample_bsdf;
use samplers::convergence::{compare, region_mean};

const SIZE: Option<(u32, u32)> = Some((32, 32));

fn scene() -> Scene {
    scene_formats::load_scene("builtin:frosted-panel?lights=300", None).unwrap()
}

fn reference(scene: &Scene) -> RenderResult {
    let r = common::render_opts(
        scene,
        "power+bsdf",
        &StrategyOptions::default(),
        512,
        2,
        1,
        SIZE,
    );
    let (mean, se) = region_mean(&r, 0, 0, r.width, r.height, true);
    assert!(
        mean > 0.0 && se < 0.02 * mean,
        "the reference lacks power: {mean} ± {se}"
    );
    r
}

#[test]
fn strategies_converge_to_the_same_image() {
    let scene = scene();
    let reference = reference(&scene);
    let d = StrategyOptions::default();
    for (name, spp) in [
        ("tree+bsdf", 128),
        ("tree-split+bsdf", 64),
        ("mis3-adaptive", 32),
    ] {
        let r = common::render_opts(&scene, name, &d, spp, 2, 2, SIZE);
        let failures = compare(&reference, &r, 2, 3.0);
        assert!(
            failures.is_empty(),
            "{name} vs power+bsdf:\n{}",
            failures.join("\n")
        );
    }
}

/// One light chosen uniformly with a point on it, and one BSDF sample, weighed by the power
/// heuristic. With `cull_behind` the light technique skips a point behind the receiver's
/// geometric surface even where the BSDF transmits, while the BSDF sample's weight still
/// counts on it: the wrong weight of a light selection that culls by the receiver's hemisphere.
struct UniformLightsBsdf {
    cull_behind: bool,
}

impl DirectLighting for UniformLightsBsdf {
    fn name(&self) -> String {
        "uniform lights + bsdf (test)".into()
    }

    fn estimate(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Vec3 {
        let p_pick = 1.0 / scene.lights.len() as f32;
        let heuristic = |a: f32, b: f32| a * a / (a * a + b * b);
        let mut sum = Vec3::ZERO;
        let k = ((rng.next_f32() * scene.lights.len() as f32) as u32)
            .min(scene.lights.len() as u32 - 1);
        if let Some(s) = scene.sample_light(k, sp.point(), sp.normal(), rng.next_2d()) {
            let behind = (s.point - sp.point()).dot(sp.bsdf.ng) <= 0.0;
            let p = p_pick * s.pdf;
            if p > 0.0 && !(self.cull_behind && behind) {
                let (f, p_bsdf) = sp.shade_with_pdf(scene, &s, ctx.counters);
                sum += f * (heuristic(p, p_bsdf) / p);
            }
        }
        if let Some(b) = sample_bsdf(scene, sp, rng, ctx.counters)
            && b.found_light()
        {
            let p_light =
                p_pick * scene.light_pdf(b.light, sp.point(), sp.normal(), b.point, b.normal);
            sum += b.f_cos * b.radiance * (heuristic(b.pdf, p_light) / b.pdf);
        }
        sum
    }
}

fn render_uniform(scene: &Scene, cull_behind: bool) -> RenderResult {
    let mut camera = scene.camera(None).unwrap();
    (camera.width, camera.height) = SIZE.unwrap();
    let settings = RenderSettings {
        width: camera.width,
        height: camera.height,
        spp: Some(256),
        seed: 3,
        time_budget: None,
        threads: Some(2),
        camera,
        sampler: Default::default(),
        filter: Default::default(),
        reconstruction: Default::default(),
        emission_rays: Default::default(),
        engine: Default::default(),
    };
    render(
        scene,
        &UniformLightsBsdf { cull_behind },
        &settings,
        &|_, _| {},
    )
    .unwrap()
}

#[test]
fn the_comparison_catches_culled_lights_behind_the_pane() {
    let scene = scene();
    let reference = reference(&scene);
    let fair = compare(&reference, &render_uniform(&scene, false), 2, 3.0);
    assert!(
        fair.is_empty(),
        "uniform lights + bsdf vs power+bsdf:\n{}",
        fair.join("\n")
    );
    let culled = compare(&reference, &render_uniform(&scene, true), 2, 3.0);
    assert!(
        culled.len() >= 3,
        "culling the lights behind the pane must show: {culled:?}"
    );
}
