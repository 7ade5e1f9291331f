use super::*;
use render_core::light::LightShape;

fn err(r: Result<Scene, SceneError>) -> SceneError {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    }
}

/// A point of every light, in order.
fn light_points(s: &Scene) -> Vec<Vec3> {
    s.lights
        .iter()
        .map(|l| match l.shape {
            LightShape::Sphere { center, .. } => center,
            LightShape::Triangle { p, .. } => p[0],
            LightShape::Point { position } => position,
        })
        .collect()
}

fn lights_of(s: &Scene) -> usize {
    s.stats.sphere_lights + s.stats.triangle_lights + s.stats.point_lights + s.stats.spot_lights
}

/// Light count a scene has for `lights=n` (quads are 2 triangles, car adds 3 panels).
fn expected_lights(name: &str, n: usize) -> usize {
    match name {
        "diffuse-quads" => 2 * n,
        "car" => n + 6,
        "emissive-mesh" => 80 * n,
        _ => n,
    }
}

#[test]
fn every_builtin_builds_is_deterministic_and_follows_its_keys() {
    for info in list_builtins() {
        let name = info.name;
        let has = |k: &str| info.keys.iter().any(|(key, _, _)| *key == k);
        assert!(has("lights") && has("seed"), "{name}");
        let a = load_builtin(&format!("builtin:{name}?lights=300&seed=7")).unwrap();
        let b = load_builtin(&format!("builtin:{name}?seed=7&lights=300")).unwrap();
        let c = load_builtin(&format!("builtin:{name}?lights=300&seed=8")).unwrap();
        assert_eq!(lights_of(&a), expected_lights(name, 300), "{name}");
        assert!(a.triangles.len() > 10, "{name}");
        assert_eq!(a.stats.degenerate_triangles_skipped, 0, "{name}");
        assert_eq!(
            light_points(&a),
            light_points(&b),
            "{name}: same seed, same layout"
        );
        assert_ne!(
            light_points(&a),
            light_points(&c),
            "{name}: another seed, another layout"
        );
        assert_eq!(a.name, b.name);
        assert!(
            a.name.starts_with(&format!("builtin:{name}?")) && a.name.contains("lights=300"),
            "{}",
            a.name
        );
        assert!(a.stats.total_power_w > 0.0 && a.stats.total_power_w.is_finite());
        let cam = a.camera(None).unwrap();
        assert!(
            cam.width >= 200 && cam.height >= 200 && cam.name != "default",
            "{name}"
        );
        // The camera looks at geometry, and every light is above the ground (y = 0).
        assert!(
            a.intersect(cam.position, cam.forward, 0.0, f32::INFINITY)
                .is_some_and(|h| h.material.is_some()),
            "{name}"
        );
        assert!(a.lights.iter().all(|l| l.bounds().0.y > 0.0), "{name}");

        // Emission is normalised: total power depends neither on the count nor on the radius.
        let mut variants = Vec::new();
        if has("radius") {
            let r = load_builtin(&format!("builtin:{name}?lights=50&radius=0.0123")).unwrap();
            let radii: Vec<f32> = r
                .lights
                .iter()
                .filter_map(|l| match l.shape {
                    LightShape::Sphere { radius, .. } => Some(radius),
                    _ => None,
                })
                .collect();
            if r.stats.sphere_lights > 0 {
                assert_eq!(radii.len(), 50, "{name}");
                assert!(radii.iter().all(|&x| x == 0.0123), "{name}");
            } else {
                // Triangles of emissive spheres: no edge longer than the diameter.
                assert_eq!(lights_of(&r), expected_lights(name, 50), "{name}");
                assert!(r.lights.iter().all(|l| {
                    let (lo, hi) = l.bounds();
                    (hi - lo).max_element() <= 2.0 * 0.0123
                }));
            }
            variants.push(r);
        }
        if has("roughness") {
            let r = load_builtin(&format!("builtin:{name}?lights=10&roughness=0.37")).unwrap();
            assert!(r.materials.iter().any(|m| m.roughness == 0.37), "{name}");
            variants.push(r);
        }
        if variants.is_empty() {
            variants.push(load_builtin(&format!("builtin:{name}?lights=100")).unwrap());
        }
        for v in &variants {
            let ratio = v.stats.total_power_w / a.stats.total_power_w;
            assert!(
                (ratio - 1.0).abs() < 0.05,
                "{name}: power ratio {ratio} ({})",
                v.name
            );
        }

        let e = err(load_builtin(&format!("builtin:{name}?bogus=1")));
        assert!(
            matches!(e, SceneError::BadBuiltinParam { .. }) && e.to_string().contains("lights"),
            "{e}"
        );
        for bad in [
            "lights=0",
            "lights=abc",
            "lights=2e6",
            "seed=-1",
            "lights=5&lights=6",
            "lights",
        ] {
            let e = err(load_builtin(&format!("builtin:{name}?{bad}")));
            assert!(
                matches!(e, SceneError::BadBuiltinParam { .. }),
                "{name}?{bad}: {e}"
            );
        }
        if has("radius") {
            for bad in ["radius=0", "radius=-1", "radius=nan", "radius=inf"] {
                assert!(
                    matches!(
                        err(load_builtin(&format!("builtin:{name}?{bad}"))),
                        SceneError::BadBuiltinParam { .. }
                    ),
                    "{bad}"
                );
            }
        }
        if has("roughness") {
            assert!(matches!(
                err(load_builtin(&format!("builtin:{name}?roughness=1.5"))),
                SceneError::BadBuiltinParam { .. }
            ));
        }
    }
}

#[test]
fn unknown_scenes_are_rejected_with_the_known_names() {
    let e = err(load_builtin("builtin:nope"));
    assert!(matches!(e, SceneError::UnknownBuiltin { .. }));
    for info in list_builtins() {
        assert!(e.to_string().contains(info.name), "{e}");
    }
    assert!(matches!(
        load_builtin("builtin:"),
        Err(SceneError::UnknownBuiltin { .. })
    ));
}

#[test]
fn misspelt_scene_names_and_keys_get_a_suggestion() {
    let e = err(load_builtin("builtin:cornel")).to_string();
    assert!(e.contains("did you mean `cornell`?"), "{e}");
    let e = err(load_builtin("builtin:zzzzzzzz")).to_string();
    assert!(!e.contains("did you mean"), "{e}");
    let e = err(load_builtin("builtin:glossy-spheres?light=10")).to_string();
    assert!(e.contains("did you mean `lights`?"), "{e}");
}

#[test]
fn specs_parse_with_and_without_prefix_and_scientific_counts() {
    let p = Params::parse("builtin:glossy-spheres?lights=1e3&seed=3").unwrap();
    assert_eq!(p.lights().unwrap(), 1000);
    assert_eq!(
        p.canonical(),
        "builtin:glossy-spheres?lights=1e3&radius=0.01&roughness=0.1&seed=3"
    );
    assert!(Params::parse("glossy-spheres").is_ok());
    assert!(Params::parse("builtin:glossy-spheres?").is_ok());
    assert_eq!(
        Params::parse("builtin:glossy-spheres?lights=1.5e3")
            .unwrap()
            .lights()
            .unwrap(),
        1500
    );
    assert!(Params::parse("builtin:glossy-spheres?lights=1.25").is_err());
}

#[test]
fn names_are_unique_and_documented() {
    let infos = list_builtins();
    for (i, a) in infos.iter().enumerate() {
        assert!(!a.description.is_empty());
        assert!(infos[i + 1..].iter().all(|b| b.name != a.name));
        for (k, default, help) in &a.keys {
            assert!(!k.is_empty() && !default.is_empty() && !help.is_empty());
        }
    }
    for required in [
        "glossy-spheres",
        "diffuse-quads",
        "car",
        "lamp",
        "statue",
        "cornell",
        "staircase",
        "grid",
        "emissive-mesh",
        "rooms",
    ] {
        assert!(infos.iter().any(|i| i.name == required), "{required}");
    }
}

#[test]
fn emissive_mesh_defaults_are_80000_outward_triangles() {
    let s = load_builtin("builtin:emissive-mesh").unwrap();
    assert_eq!(s.stats.triangle_lights, 80_000);
    assert_eq!(s.stats.sphere_lights, 0);
    // One-sided triangles (the icosphere test checks that they face outward).
    assert!(
        s.lights
            .iter()
            .all(|l| !l.two_sided && matches!(l.shape, LightShape::Triangle { .. }))
    );
    assert!(matches!(
        err(load_builtin("builtin:emissive-mesh?lights=20000")),
        SceneError::BadBuiltinParam { .. }
    ));
    assert!(matches!(
        err(load_builtin("builtin:emissive-mesh?subdivisions=4")),
        SceneError::BadBuiltinParam { .. }
    ));
}

#[test]
fn glossy_spheres_defaults() {
    let s = load_builtin("builtin:glossy-spheres").unwrap();
    assert_eq!(s.stats.sphere_lights, 4096);
    let lo = s
        .lights
        .iter()
        .map(|l| l.bounds().0)
        .fold(Vec3::INFINITY, Vec3::min);
    let hi = s
        .lights
        .iter()
        .map(|l| l.bounds().1)
        .fold(Vec3::NEG_INFINITY, Vec3::max);
    // Spread wide: far more than the objects' extent.
    assert!(hi.x - lo.x > 25.0 && hi.z - lo.z > 25.0);
    assert!(
        s.materials
            .iter()
            .any(|m| m.roughness == 0.1 && m.specular > 0.0)
    );
    assert!(s.materials.iter().any(|m| m.specular == 0.0));
}

#[test]
fn diffuse_quads_are_one_sided_and_face_down_over_diffuse_geometry() {
    let s = load_builtin("builtin:diffuse-quads?lights=64").unwrap();
    assert_eq!(s.stats.triangle_lights, 128);
    for l in &s.lights {
        let LightShape::Triangle { normal, .. } = l.shape else {
            panic!()
        };
        assert!((normal - Vec3::NEG_Y).length() < 1e-5);
        assert!(!l.two_sided);
    }
    assert!(
        s.materials
            .iter()
            .filter(|m| !m.is_emissive())
            .all(|m| m.specular == 0.0)
    );
}

#[test]
fn cornell_matches_the_authors_layout_at_its_defaults() {
    let s = load_builtin("builtin:cornell").unwrap();
    assert_eq!(s.stats.sphere_lights, 1494);
    assert_eq!(s.camera(None).unwrap().position, Vec3::new(0.0, 1.0, 6.8));
    let mut on_left = 0;
    for l in &s.lights {
        let LightShape::Sphere { center, radius } = l.shape else {
            panic!()
        };
        assert_eq!(radius, 0.001);
        assert!((center.x.abs() - 0.9989).abs() < 1e-4, "{center}");
        assert!(center.y > 0.0 && center.y < 2.0 && center.z.abs() < 1.0);
        on_left += (center.x < 0.0) as usize;
        // The authors' radiances, unscaled at their count and radius.
        let known = [
            Vec3::new(282.0, 196.5, 105.0),
            Vec3::new(67.5, 37.5, 256.5),
            Vec3::new(300.0, 180.0, 225.0),
        ];
        assert!(
            known
                .iter()
                .any(|k| (l.emission - *k).abs().max_element() < 1e-3),
            "{}",
            l.emission
        );
    }
    assert!(on_left > 400 && on_left < 1100, "{on_left}");
    let glossy: Vec<_> = s.materials.iter().filter(|m| m.specular > 0.0).collect();
    assert_eq!(glossy.len(), 2);
    assert!(
        glossy
            .iter()
            .all(|m| (m.params_at(glam::Vec2::ZERO).alpha - 0.01).abs() < 1e-6)
    );
    assert!(
        s.materials
            .iter()
            .filter(|m| m.name == "walls")
            .all(|m| m.specular == 0.0)
    );
}

#[test]
fn car_has_ceiling_spheres_and_three_panels() {
    let s = load_builtin("builtin:car?lights=500").unwrap();
    assert_eq!((s.stats.sphere_lights, s.stats.triangle_lights), (500, 6));
    for l in &s.lights {
        if let LightShape::Triangle { normal, .. } = l.shape {
            assert!((normal - Vec3::NEG_Y).length() < 1e-5);
        } else {
            assert!(l.bounds().0.y > 4.0);
        }
    }
}

#[test]
fn grid_lights_fill_rows_and_scale_their_radius() {
    let s = load_builtin("builtin:grid?lights=100").unwrap();
    let centers: Vec<Vec3> = light_points(&s);
    assert!(
        centers
            .iter()
            .all(|c| c.x.abs() < 5.0 && c.z.abs() < 5.0 && c.y == 2.0)
    );
    // Spacing 1: neighbours stay at least half a cell apart with ±0.25 cell jitter.
    for (i, a) in centers.iter().enumerate() {
        for b in &centers[i + 1..] {
            assert!((*a - *b).length() > 0.49);
        }
    }
    let LightShape::Sphere { radius, .. } = s.lights[0].shape else {
        panic!()
    };
    assert!((radius - 0.05).abs() < 1e-6);
    let s = load_builtin("builtin:grid?lights=10000").unwrap();
    let LightShape::Sphere { radius, .. } = s.lights[0].shape else {
        panic!()
    };
    assert!((radius - 0.005).abs() < 1e-6);
    // 7 lights: a 3 × 3 grid, filled row by row.
    let s = load_builtin("builtin:grid?lights=7").unwrap();
    assert_eq!(s.stats.sphere_lights, 7);
    assert!(matches!(
        err(load_builtin("builtin:glossy-spheres?radius=auto")),
        SceneError::BadBuiltinParam { .. }
    ));
}

/// Uniform light selection, light sampling only: enough to see that light reaches the view.
struct UniformLights;

impl render_core::estimator::DirectLighting for UniformLights {
    fn name(&self) -> String {
        "test-uniform".into()
    }

    fn estimate(
        &self,
        scene: &Scene,
        sp: &render_core::estimator::ShadingPoint,
        rng: &mut render_core::rng::SampleStream,
        ctx: &mut render_core::estimator::SampleContext,
    ) -> Vec3 {
        let n = scene.lights.len();
        let i = ((rng.next_f32() * n as f32) as usize).min(n - 1);
        match scene.lights[i].sample(sp.point(), rng.next_2d()) {
            Some(s) => sp.shade(scene, &s, ctx.counters) * n as f32 / s.pdf,
            None => Vec3::ZERO,
        }
    }
}

#[test]
fn every_builtin_renders_a_lit_image() {
    use render_core::render::{RenderSettings, render};
    for info in list_builtins() {
        let scene = load_builtin(&format!("builtin:{}?lights=200", info.name)).unwrap();
        let camera = scene.camera(None).unwrap();
        let settings = RenderSettings {
            width: 32,
            height: 24,
            spp: Some(4),
            seed: 1,
            time_budget: None,
            threads: Some(1),
            camera,
            sampler: Default::default(),
            filter: Default::default(),
            reconstruction: Default::default(),
            emission_rays: Default::default(),
            engine: Default::default(),
        };
        let r = render(&scene, &UniformLights, &settings, &|_, _| {}).unwrap();
        // Leave out pixels that see a light directly: the rest is reflected light.
        let lit: Vec<f32> = r
            .pixels
            .iter()
            .zip(&r.light_fraction)
            .filter(|(_, f)| **f == 0.0)
            .map(|(p, _)| render_core::colour::luminance(*p))
            .collect();
        assert!(
            lit.iter().all(|v| v.is_finite() && *v >= 0.0),
            "{}",
            info.name
        );
        let mean = lit.iter().sum::<f32>() / lit.len() as f32;
        let nonzero = lit.iter().filter(|v| **v > 0.0).count() as f32 / lit.len() as f32;
        assert!(
            mean > 0.01 && nonzero > 0.3,
            "{}: mean {mean}, lit fraction {nonzero}",
            info.name
        );
    }
}

#[test]
fn rooms_hide_most_lights_from_the_camera() {
    let s = load_builtin("builtin:rooms").unwrap();
    assert_eq!(lights_of(&s), 3000);
    // Both kinds of light, the triangles one-sided and facing down.
    assert!(s.stats.sphere_lights > 1200 && s.stats.triangle_lights > 800);
    let eye = s.camera(None).unwrap().position;
    let mut visible = 0;
    for l in &s.lights {
        let (target, shorten) = match l.shape {
            LightShape::Sphere { center, radius } => (center, radius + 1e-3),
            LightShape::Triangle { p, normal, .. } => {
                assert!((normal - Vec3::NEG_Y).length() < 1e-5 && !l.two_sided);
                ((p[0] + p[1] + p[2]) / 3.0, 1e-3)
            }
            LightShape::Point { position } => (position, 0.0),
        };
        let d = target - eye;
        assert!(d.length() > 0.8, "a light right in front of the camera");
        if !s.occluded(eye, d.normalize(), d.length() - shorten) {
            visible += 1;
        }
    }
    // Walls decide: most lights are hidden from the camera, some are seen.
    let share = visible as f32 / 3000.0;
    assert!(share > 0.05 && share < 0.35, "visible share {share}");
}

/// The pane is a rough dielectric facing the camera, 9 lights in 10 lie behind it, and the
/// keys reach the material.
#[test]
fn frosted_panel_is_lit_from_behind() {
    use render_core::material::Model;
    let s = load_builtin("builtin:frosted-panel?lights=400&frost=0.3&ior=1.4").unwrap();
    assert_eq!(lights_of(&s), 400);
    let behind = s.lights.iter().filter(|l| l.bounds().1.z < 0.0).count();
    assert_eq!(behind, 360);
    let glass: Vec<_> = s
        .materials
        .iter()
        .filter(|m| matches!(m.model, Model::Dielectric { .. }))
        .collect();
    assert_eq!(glass.len(), 1);
    assert_eq!(
        glass[0].model,
        Model::Dielectric {
            ior: 1.4,
            alpha: 0.3
        }
    );
    let cam = s.camera(None).unwrap();
    let hit = s
        .intersect(cam.position, cam.forward, 0.0, f32::INFINITY)
        .unwrap();
    assert!(s.materials[hit.material.unwrap() as usize].model == glass[0].model);
    for bad in ["ior=1", "ior=1.005", "frost=0", "frost=2"] {
        assert!(
            load_builtin(&format!("builtin:frosted-panel?{bad}")).is_err(),
            "{bad}"
        );
    }
}
