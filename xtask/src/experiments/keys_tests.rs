//! End to end, with the debug `manylights` on tiny scenes: a run re-renders exactly the cells
//! and references whose inputs changed (a byte of a glTF buffer, of a pbrt include, of a
//! composition's asset; a strategy's resolved parameters; the threads of a time cell; the
//! code), and the report refuses a table of mixed code states.
use super::cell::CellResult;
use super::cell::read_cell;
use super::code_state::CodeState;
use super::config::{Experiment, parse};
use super::execute::{self, Done, RunOptions};
use super::manylights::Manylights;
use super::plan::{self, Budget};
use super::prepare;
use super::provenance::Permissions;
use super::summary;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Nine vertices: a floor quad (y = 0, facing up) and an emissive triangle above it.
fn gltf_buffer() -> Vec<u8> {
    let v: [[f32; 3]; 9] = [
        [-1.0, 0.0, -1.0],
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [-1.0, 0.0, -1.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
        [-0.3, 1.0, -0.3],
        [0.3, 1.0, -0.3],
        [0.0, 1.0, 0.3],
    ];
    v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect()
}

/// A glTF whose geometry is in the external buffer `bin`.
fn gltf_json(bin: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"mesh":0}},{{"mesh":1}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}},
          {{"primitives":[{{"attributes":{{"POSITION":1}},"material":1}}]}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.8,0.8,0.8,1],"metallicFactor":0,"roughnessFactor":0.3}}}},
             {{"emissiveFactor":[1,1,1],"doubleSided":true,"pbrMetallicRoughness":{{"baseColorFactor":[0,0,0,1]}}}}],
"buffers":[{{"uri":"{bin}","byteLength":108}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":72}},{{"buffer":0,"byteOffset":72,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":6,"type":"VEC3","min":[-1,0,-1],"max":[1,0,1]}},
             {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3","min":[-0.3,1,-0.3],"max":[0.3,1,0.3]}}]}}"#
    )
}

/// Writes the three scenes (a glTF with its buffer, a pbrt file with an include, a composition
/// with a glTF asset of its own) into `dir`.
fn write_scenes(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    let w = |name: &str, bytes: &[u8]| std::fs::write(dir.join(name), bytes).unwrap();
    w("g.gltf", gltf_json("g.bin").as_bytes());
    w("g.bin", &gltf_buffer());
    w("asset.gltf", gltf_json("asset.bin").as_bytes());
    w("asset.bin", &gltf_buffer());
    w(
        "c.toml",
        b"[[gltf]]\npath = \"asset.gltf\"\n[[lights]]\nlayout = \"grid\"\nshape = \"sphere\"\ncount = 4\n\
          center = [0.0, 1.5, 0.0]\nextent = [1.0, 0.0, 1.0]\nsize = 0.05\npower = 10.0\n\
          [camera]\neye = [0.0, 2.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\n",
    );
    w(
        "p.pbrt",
        b"LookAt 0 2 3  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n\
          Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n\
          Include \"p-geom.pbrt\"\n",
    );
    w(
        "p-geom.pbrt",
        b"Material \"diffuse\" \"rgb reflectance\" [ 0.5 0.5 0.5 ]\n\
          Shape \"bilinearmesh\" \"point3 P\" [ -1 0 -1  1 0 -1  -1 0 1  1 0 1 ]\n\
          AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 5 5 5 ]\nTranslate 0 1 0\n\
          Shape \"sphere\" \"float radius\" 0.2\nAttributeEnd\n",
    );
}

/// Flips the lowest bit of byte `at` of `file`.
fn flip_byte(file: &Path, at: usize) {
    let mut b = std::fs::read(file).unwrap();
    b[at] ^= 1;
    std::fs::write(file, b).unwrap();
}

fn experiment(dir: &Path) -> Experiment {
    let spec = |f: &str| dir.join(f).to_string_lossy().into_owned();
    parse(
        "keys",
        &format!(
            r#"
            width = 8
            height = 8
            seeds = [0]
            spp = [2]
            time_budgets = [0.02]
            [reference]
            strategy = "power+bsdf"
            spp = 4
            [[scenes]]
            label = "gltf"
            spec = "{}"
            [[scenes]]
            label = "pbrt"
            spec = "{}"
            [[scenes]]
            label = "comp"
            spec = "{}"
            [[strategies]]
            label = "EK"
            name = "tree-split+bsdf"
            [[strategies]]
            label = "MIS"
            name = "mis3-adaptive"
            "#,
            spec("g.gltf"),
            spec("p.pbrt"),
            spec("c.toml")
        ),
    )
    .unwrap()
}

/// One test's directories and experiment.
struct Bench {
    base: PathBuf,
    exp: Experiment,
    ml: Manylights,
}

impl Drop for Bench {
    /// The test's directories go with it, unless it failed (then they are there to look at).
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.base);
        }
    }
}

impl Bench {
    fn new(name: &str) -> Bench {
        let base = std::env::temp_dir().join(format!("xtask-keys-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        write_scenes(&base.join("scenes"));
        Bench {
            exp: experiment(&base.join("scenes")),
            base,
            ml: Manylights::for_tests(),
        }
    }

    fn out(&self) -> PathBuf {
        self.base.join("results")
    }

    /// A run of every cell, with `threads` render threads.
    fn run(&self, threads: usize, reuse_stale: bool) -> Done {
        let options = RunOptions {
            threads: Some(threads),
            reuse_stale,
            ..RunOptions::default()
        };
        let p = prepare::prepare(
            &self.exp,
            &self.ml,
            plan::expand(&self.exp),
            options.threads,
        )
        .unwrap();
        assert_eq!(p.cells.len(), 12, "{:?}", p.notices);
        let done = execute::execute(
            &self.exp,
            &self.ml,
            p,
            &self.out(),
            &self.base.join("refs"),
            &options,
            Instant::now(),
        )
        .unwrap();
        assert!(!done.failed, "{:?}", done.notices);
        done
    }

    /// The ids of the cells of `scene` (every scene when empty) whose budget `keep` accepts.
    fn ids(&self, scene: &str, keep: impl Fn(&Budget) -> bool) -> BTreeSet<String> {
        plan::expand(&self.exp)
            .iter()
            .filter(|c| (scene.is_empty() || c.scene_label == scene) && keep(&c.budget))
            .map(|c| c.id())
            .collect()
    }

    fn cells(&self) -> Vec<(PathBuf, CellResult)> {
        plan::expand(&self.exp)
            .iter()
            .map(|c| self.out().join("cells").join(format!("{}.json", c.id())))
            .map(|p| (p.clone(), read_cell(&p).unwrap()))
            .collect()
    }

    /// Rewrites the stored cells that `select` picks as `edit` leaves them.
    fn edit_cells(&self, select: impl Fn(&CellResult) -> bool, edit: impl Fn(&mut CellResult)) {
        for (p, mut c) in self.cells() {
            if select(&c) {
                edit(&mut c);
                render_core::output::write_json(&p, &serde_json::to_value(&c).unwrap()).unwrap();
            }
        }
    }
}

fn set(v: &[String]) -> BTreeSet<String> {
    v.iter().cloned().collect()
}

fn reference_of(done: &Done) -> Vec<String> {
    done.references_rendered
        .iter()
        .map(|d| d.split('-').next().unwrap_or("").to_string())
        .collect()
}

#[test]
fn a_changed_file_rerenders_exactly_its_scene() {
    let b = Bench::new("files");
    let first = b.run(1, false);
    assert_eq!(set(&first.rendered), b.ids("", |_| true));
    assert_eq!(first.references_rendered.len(), 3);
    let again = b.run(1, false);
    assert!(again.rendered.is_empty() && again.references_rendered.is_empty());
    assert_eq!(again.reused.len(), 12);

    let scenes = b.base.join("scenes");
    // a byte of the glTF's buffer (the light's first x coordinate)
    flip_byte(&scenes.join("g.bin"), 72);
    let d = b.run(1, false);
    assert_eq!(set(&d.rendered), b.ids("gltf", |_| true));
    assert_eq!(reference_of(&d), vec!["g"]);
    // a byte of the pbrt include (the sphere's radius 0.2 → 0.3)
    let text = std::fs::read_to_string(scenes.join("p-geom.pbrt")).unwrap();
    flip_byte(&scenes.join("p-geom.pbrt"), text.find("0.2").unwrap() + 2);
    let d = b.run(1, false);
    assert_eq!(set(&d.rendered), b.ids("pbrt", |_| true));
    assert_eq!(reference_of(&d), vec!["p"]);
    // a byte of the composition's asset
    flip_byte(&scenes.join("asset.bin"), 72);
    let d = b.run(1, false);
    assert_eq!(set(&d.rendered), b.ids("comp", |_| true));
    assert_eq!(reference_of(&d), vec!["c"]);
    let _ = std::fs::remove_dir_all(&b.base);
}

#[test]
fn threads_strategy_parameters_and_code_rerender_exactly_their_cells() {
    let b = Bench::new("inputs");
    b.run(1, false);
    // the threads of a time cell: its image depends on them, an spp cell's does not
    let d = b.run(2, false);
    assert_eq!(
        set(&d.rendered),
        b.ids("", |b| matches!(b, Budget::Time(_)))
    );
    assert!(d.references_rendered.is_empty());

    // As if MIS's cells were rendered by an older binary whose N_max default differed (a
    // default is code: every cell is of another code state; --reuse-stale keeps E&K's).
    let old = CodeState {
        id: "tree:older".into(),
        commit: Some("0123456789ab".into()),
        dirty: false,
    };
    b.edit_cells(
        |_| true,
        |c| {
            c.code = Some(old.clone());
            if c.strategy == "MIS" {
                let i = c.inputs.as_mut().unwrap();
                i.strategy["parameters"]["method"]["n_max"] = serde_json::json!(40);
            }
        },
    );
    let d = b.run(2, true);
    let mis = |id: &str| id.contains("__MIS__");
    assert_eq!(
        set(&d.rendered),
        b.ids("", |_| true).into_iter().filter(|i| mis(i)).collect()
    );
    assert!(d.references_rendered.is_empty());
    assert!(d.reused.iter().all(|i| !mis(i)) && d.reused.len() == 6);
    // the reused E&K cells are of the older code state: the table marks every row
    let code_of = |label: &str| {
        let c = b.cells().into_iter().find(|(_, c)| c.strategy == label);
        c.unwrap().1.code.unwrap()
    };
    assert_eq!(code_of("EK"), old);
    let current = code_of("MIS");
    assert_ne!(current, old);
    // (allow_dirty: these tests run in a dirty tree too; the refusals below are about mixing)
    let perm = Permissions {
        allow_mixed: true,
        allow_dirty: true,
        current: Some(current.clone()),
    };
    summary::generate(&b.exp, &b.out(), &b.base.join("refs"), &[], &perm).unwrap();
    let md = std::fs::read_to_string(b.out().join("table.md")).unwrap();
    assert!(md.contains("| gltf ‡ |"), "{md}");
    assert!(md.contains("rows marked ‡"), "{md}");

    // a table from mixed code states is refused unless told
    for current in [Some(current), None] {
        let refuse = Permissions {
            allow_dirty: true,
            current,
            ..Permissions::default()
        };
        let e = summary::generate(&b.exp, &b.out(), &b.base.join("refs"), &[], &refuse);
        assert!(e.unwrap_err().contains("several code states"));
    }

    // without --reuse-stale, every cell of the other code state is rendered again, and the
    // references are kept (they do not depend on the strategies' code)
    let d = b.run(2, false);
    assert_eq!(
        set(&d.rendered),
        b.ids("", |_| true)
            .into_iter()
            .filter(|i| !mis(i))
            .collect()
    );
    assert!(d.references_rendered.is_empty());
    summary::generate(
        &b.exp,
        &b.out(),
        &b.base.join("refs"),
        &[],
        &Permissions {
            allow_dirty: true,
            ..Permissions::default()
        },
    )
    .unwrap();

    // a commit that changes nothing under the code paths (docs, results) is the same code
    // state: cells recorded at it are kept, whatever commit they name
    let now = code_of("MIS");
    b.edit_cells(
        |_| true,
        |c| c.code.as_mut().unwrap().commit = Some("fedcba987654".into()),
    );
    let d = b.run(2, false);
    assert!(d.rendered.is_empty(), "{:?}", d.rendered);
    assert_eq!(d.reused.len(), 12);
    assert_eq!(code_of("MIS").id, now.id);
    // and a table of them is one code state: named by the commit that rendered them (the
    // run's own rendered nothing), not refused, no row marked
    let perm = Permissions {
        allow_dirty: true,
        current: Some(now),
        ..Permissions::default()
    };
    summary::generate(&b.exp, &b.out(), &b.base.join("refs"), &[], &perm).unwrap();
    let md = std::fs::read_to_string(b.out().join("table.md")).unwrap();
    assert!(md.contains("rendered by **commit fedcba987654**"), "{md}");
    assert!(!md.contains("with the same code"), "{md}");
    assert!(!md.contains("rows marked ‡"), "{md}");
    let _ = std::fs::remove_dir_all(&b.base);
}
