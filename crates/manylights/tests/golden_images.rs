//! Bit-exact regression of every strategy on every scene input: a small render of each (scene,
//! strategy, options) case is hashed and compared with `tests/golden/images.txt`.
//!
//! Refactors must leave these hashes unchanged. A change that is meant to move images (a new
//! default, a different random-number use) regenerates the file with
//! `GOLDEN_UPDATE=1 cargo test -p manylights --test golden_images` and says so in its commit.
use render_core::render::{RenderResult, RenderSettings, render};
use render_core::scene::Scene;
use samplers::StrategyOptions;
use samplers::brdf_oriented::BrdfIntegral;
use scene_formats::load_scene;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const WIDTH: u32 = 24;
const HEIGHT: u32 = 16;
/// Six passes: `mis3-adaptive` learns N_max from the third pass on, so its learning is covered.
const SPP: u32 = 6;

/// FNV-1a over the bits of everything a render returns that depends on the samples.
fn hash_render(r: &RenderResult) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bits: u32| {
        for b in bits.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for (p, v) in r.pixels.iter().zip(&r.variance_of_mean) {
        for x in p.to_array().into_iter().chain(v.to_array()) {
            eat(x.to_bits());
        }
    }
    for f in &r.light_fraction {
        eat(f.to_bits());
    }
    for (_, channel) in &r.aux {
        for x in channel {
            eat(x.to_bits());
        }
    }
    h
}

fn render_case(scene: &Scene, strategy: &str, opts: &StrategyOptions) -> u64 {
    let s = samplers::create(strategy, scene, opts).unwrap_or_else(|e| panic!("{strategy}: {e}"));
    let settings = RenderSettings {
        width: WIDTH,
        height: HEIGHT,
        spp: Some(SPP),
        seed: 7,
        time_budget: None,
        threads: Some(2),
        camera: scene.camera(None).unwrap(),
        sampler: Default::default(),
        filter: Default::default(),
        reconstruction: Default::default(),
        emission_rays: Default::default(),
        engine: Default::default(),
    };
    hash_render(&render(scene, s.as_ref(), &settings, &|_, _| {}).unwrap())
}

/// Option variants beside the defaults: the flags that select other code paths.
fn variants() -> Vec<(&'static str, StrategyOptions)> {
    let d = StrategyOptions::default;
    vec![
        ("default", d()),
        (
            "reproduce",
            StrategyOptions {
                reproduce: true,
                ..d()
            },
        ),
        (
            "ltc",
            StrategyOptions {
                brdf_integral: BrdfIntegral::Ltc,
                ..d()
            },
        ),
        (
            "learned-visibility",
            StrategyOptions {
                learned: samplers::learned::LearnedConfig {
                    target: samplers::learned::LearnTarget::Visibility,
                    ..Default::default()
                },
                ..d()
            },
        ),
        (
            "pivot-independent",
            StrategyOptions {
                pivot_sphere: true,
                stratified: false,
                efficient_total: false,
                ..d()
            },
        ),
    ]
}

const PBRT_SCENE: &str = r#"LookAt 0 1 4  0 0.8 0  0 1 0
Camera "perspective" "float fov" [ 45 ]
WorldBegin
MakeNamedMaterial "walls" "string type" "matte" "rgb Kd" [ .7 .7 .65 ]
MakeNamedMaterial "shiny" "string type" "plastic" "rgb Kd" [ .2 .1 .1 ] "rgb Ks" [ .6 .6 .6 ] "float roughness" 0.01 "bool remaproughness" "false"
NamedMaterial "walls"
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 0 2  -2 0 2 ] "integer indices" [ 0 2 1  0 3 2 ]
Shape "trianglemesh" "point3 P" [ -2 0 -2  2 0 -2  2 2 -2  -2 2 -2 ] "integer indices" [ 0 1 2  0 2 3 ]
AttributeBegin
  NamedMaterial "shiny"
  Translate 0 0.5 0
  Shape "sphere" "float radius" 0.5
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 40 30 20 ]
  Translate -0.8 1.6 0.3
  Shape "sphere" "float radius" 0.05
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 5 5 8 ]
  Shape "trianglemesh" "point3 P" [ 0.5 1.9 -0.5  1.2 1.9 -0.5  0.5 1.9 0.2 ] "integer indices" [ 0 1 2 ]
AttributeEnd
LightSource "point" "rgb I" [ 2 2 2 ] "point3 from" [ 1 1.5 1 ]
LightSource "spot" "rgb I" [ 3 3 3 ] "point3 from" [ -1 1.8 1 ] "point3 to" [ 0 0 0 ] "float coneangle" 30
WorldEnd
"#;

fn temp_dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("manylights-golden-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Every scene input path: each built-in at its defaults, a glTF written from one and read
/// back, and a pbrt file.
fn scenes(dir: &Path) -> Vec<(String, Scene)> {
    let builtins = [
        "glossy-spheres",
        "diffuse-quads",
        "emissive-mesh",
        "car",
        "lamp",
        "statue",
        "cornell",
        "staircase",
        "grid",
        "rooms",
    ];
    let mut out: Vec<(String, Scene)> = builtins
        .iter()
        .map(|b| {
            let spec = format!("builtin:{b}");
            let scene = load_scene(&spec, None).unwrap();
            (spec, scene)
        })
        .collect();
    let glb = dir.join("cornell.glb");
    scene_formats::gltf_writer::write_glb(&out[6].1, &glb).unwrap();
    out.push((
        "glb:cornell".into(),
        load_scene(glb.to_str().unwrap(), None).unwrap(),
    ));
    let pbrt = dir.join("room.pbrt");
    std::fs::write(&pbrt, PBRT_SCENE).unwrap();
    out.push((
        "pbrt:room".into(),
        load_scene(pbrt.to_str().unwrap(), None).unwrap(),
    ));
    out
}

fn golden_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/images.txt")
}

fn read_golden() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(golden_path()).unwrap_or_default();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .filter_map(|l| l.rsplit_once(' '))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

#[test]
fn every_strategy_renders_the_committed_bytes() {
    let dir = temp_dir();
    let mut now = BTreeMap::new();
    for (scene_name, scene) in scenes(&dir) {
        for info in samplers::strategies() {
            for v in info.golden_variants {
                assert!(
                    variants().iter().any(|(name, _)| name == v),
                    "{}: no golden variant `{v}`",
                    info.name
                );
            }
            // The shadowed oracle traces a ray per light and stratum at every point: on the
            // 80,000 lights of emissive-mesh that alone would add a minute to the suite.
            if info.name == "oracle-shadowed" && scene.lights.len() > 10_000 {
                continue;
            }
            for (variant, opts) in variants() {
                if variant == "default" || info.golden_variants.contains(&variant) {
                    let hash = render_case(&scene, info.name, &opts);
                    now.insert(
                        format!("{scene_name} {} {variant}", info.name),
                        format!("{hash:016x}"),
                    );
                }
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    if std::env::var_os("GOLDEN_UPDATE").is_some() {
        let mut text = String::from(
            "# scene strategy variant hash: written by GOLDEN_UPDATE=1 cargo test -p manylights --test golden_images\n",
        );
        for (k, v) in &now {
            text.push_str(&format!("{k} {v}\n"));
        }
        std::fs::create_dir_all(golden_path().parent().unwrap()).unwrap();
        std::fs::write(golden_path(), text).unwrap();
        return;
    }
    let golden = read_golden();
    let changed: Vec<String> = now
        .iter()
        .filter(|(k, v)| golden.get(*k) != Some(v))
        .map(|(k, v)| format!("{k}: {v} (committed {:?})", golden.get(k)))
        .collect();
    let gone: Vec<&String> = golden.keys().filter(|k| !now.contains_key(*k)).collect();
    assert!(
        changed.is_empty() && gone.is_empty(),
        "{} of {} renders differ from tests/golden/images.txt:\n{}\nno longer rendered: {gone:?}",
        changed.len(),
        now.len(),
        changed.join("\n")
    );
}
