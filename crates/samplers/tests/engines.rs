//! The batched engine (`render_core::batch`) against the per-sample one: every registered
//! strategy renders the same image bit for bit, with the same counters, in both engines and
//! for one and two threads, on a scene with triangle, sphere, point and distant lights, under
//! the sampled reconstruction with extra emission rays and under splatting, and on a rough
//! dielectric pane lit from behind (light through a transmitting surface). The light
//! strategies must actually run batched (a strategy that silently fell back to the per-sample
//! path would pass the equality without testing anything).
mod common;

use render_core::Vec3;
use render_core::emission_rays::EmissionRays;
use render_core::render::{Engine, RenderResult, RenderSettings, render};
use render_core::scene::Scene;
use render_core::splat::Reconstruction;
use samplers::StrategyOptions;

fn scene() -> Scene {
    let mut b = common::mixed_scene_builder(24);
    b.add_point_light(Vec3::new(0.3, 1.2, 0.2), Vec3::splat(0.4), None)
        .unwrap();
    b.add_distant_light(Vec3::new(0.2, 1.0, 0.4), Vec3::splat(0.3))
        .unwrap();
    b.build().unwrap()
}

fn render_with(
    scene: &Scene,
    name: &str,
    engine: Engine,
    threads: usize,
    reconstruction: Reconstruction,
) -> RenderResult {
    let strategy = samplers::create(name, scene, &StrategyOptions::default()).unwrap();
    let mut camera = scene.camera(None).unwrap();
    (camera.width, camera.height) = (24, 16);
    let emission_rays = match reconstruction {
        Reconstruction::Sampled => EmissionRays::new(4).unwrap(),
        Reconstruction::Splat => EmissionRays::default(),
    };
    let settings = RenderSettings {
        width: camera.width,
        height: camera.height,
        spp: Some(3),
        seed: 11,
        time_budget: None,
        threads: Some(threads),
        camera,
        sampler: Default::default(),
        filter: Default::default(),
        reconstruction,
        emission_rays,
        engine,
    };
    render(scene, strategy.as_ref(), &settings, &|_, _| {}).unwrap()
}

fn same(a: &RenderResult, b: &RenderResult, what: &str) {
    let bits = |r: &RenderResult| -> Vec<[u32; 3]> {
        r.pixels
            .iter()
            .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect()
    };
    assert!(bits(a) == bits(b), "{what}: the images differ");
    assert_eq!(a.variance_of_mean, b.variance_of_mean, "{what}: variances");
    assert_eq!(a.counters, b.counters, "{what}: counters");
}

#[test]
fn every_strategy_renders_the_same_image_in_both_engines() {
    let scene = scene();
    let mut batched = Vec::new();
    let pane = scene_formats::load_scene("builtin:frosted-panel?lights=60", None).unwrap();
    for s in samplers::registry::STRATEGIES {
        let per_sample = render_with(&pane, s.name, Engine::PerSample, 1, Reconstruction::Sampled);
        let b = render_with(&pane, s.name, Engine::Batched, 2, Reconstruction::Sampled);
        same(&per_sample, &b, &format!("{} (frosted panel)", s.name));
        let strategy = samplers::create(s.name, &scene, &StrategyOptions::default()).unwrap();
        if Engine::Batched.used_for(strategy.as_ref()) == "batched" {
            batched.push(s.name);
        }
        for reconstruction in [Reconstruction::Sampled, Reconstruction::Splat] {
            let per_sample = render_with(&scene, s.name, Engine::PerSample, 1, reconstruction);
            for threads in [1, 2] {
                let b = render_with(&scene, s.name, Engine::Batched, threads, reconstruction);
                let what = format!("{} ({reconstruction:?}, {threads} threads)", s.name);
                same(&per_sample, &b, &what);
            }
        }
    }
    for name in [
        "power",
        "power+bsdf",
        "tree",
        "tree+bsdf",
        "tree-split+bsdf",
    ] {
        assert!(batched.contains(&name), "{name} has no batched form");
    }
}
