//! The command line as a user meets it: outputs, determinism and every kind of bad input.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn manylights(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(args)
        .output()
        .expect("binary runs")
}

/// A fresh directory under the system's temporary directory, removed with everything in it
/// when dropped (kept when the test fails, to look at).
struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

fn temp_dir(name: &str) -> TempDir {
    let d = std::env::temp_dir().join(format!("manylights-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    TempDir(d)
}

const SCENE: &str = "builtin:glossy-spheres?lights=64";

fn render_to(dir: &Path, name: &str, extra: &[&str]) -> Output {
    render_strategy_to(dir, name, "power+bsdf", extra)
}

/// [`render_to`] with another strategy.
fn render_strategy_to(dir: &Path, name: &str, strategy: &str, extra: &[&str]) -> Output {
    let out = dir.join(format!("{name}.exr"));
    let mut args = vec![
        "render",
        SCENE,
        "--strategy",
        strategy,
        "--spp",
        "2",
        "--width",
        "32",
        "--height",
        "24",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    manylights(&args)
}

#[test]
fn render_writes_exr_png_json_and_aux() {
    let dir = temp_dir("outputs");
    let png = dir.join("a.png");
    let o = render_to(&dir, "a", &["--png", png.to_str().unwrap(), "--aux"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("a.exr").is_file() && png.is_file() && dir.join("a.mask.png").is_file());
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("a.json")).unwrap()).unwrap();
    assert_eq!(meta["spp"], 2);
    assert_eq!(meta["strategy"], "power+bsdf");
    assert_eq!(meta["rays"]["camera"], 2 * 32 * 24);
    assert!(meta["rays"]["shadow"].as_u64().unwrap() > 0);
    assert!(meta["wall_seconds"].as_f64().unwrap() > 0.0);
    let (w, h, px) = render_core::output::read_exr(&dir.join("a.exr")).unwrap();
    assert_eq!((w, h, px.len()), (32, 24, 32 * 24));
    assert!(px.iter().any(|p| p.max_element() > 0.0), "the image is lit");
}

/// Every registered strategy (so strategies added later are covered too) gives the same EXR
/// bytes, and the same auxiliary maps, with 1 and 2 threads. 4 spp so that `mis3-adaptive`'s
/// per-pixel memory (hit/miss tallies carried from sample to sample) is exercised.
#[test]
fn exr_bytes_do_not_depend_on_thread_count() {
    let dir = temp_dir("threads");
    let strategies = samplers::strategies();
    assert!(strategies.len() >= 11, "the registry lists every strategy");
    for s in strategies {
        let mut outputs = Vec::new();
        for threads in ["1", "2"] {
            let sub = dir.join(format!("{}-{threads}", s.name.replace('+', "_")));
            std::fs::create_dir_all(&sub).unwrap();
            let out = sub.join("r.exr");
            let o = manylights(&[
                "render",
                SCENE,
                "--strategy",
                s.name,
                "--spp",
                "4",
                "--width",
                "32",
                "--height",
                "24",
                "--threads",
                threads,
                "--seed",
                "5",
                "--aux",
                "--quiet",
                "--out",
                out.to_str().unwrap(),
            ]);
            assert!(
                o.status.success(),
                "{}: {}",
                s.name,
                String::from_utf8_lossy(&o.stderr)
            );
            outputs.push(sub);
        }
        let files = |d: &Path| {
            let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|x| x != "json"))
                .map(|p| {
                    let name = p.file_name().unwrap().to_string_lossy().into_owned();
                    (name, std::fs::read(&p).unwrap())
                })
                .collect();
            v.sort();
            v
        };
        let (one, two) = (files(&outputs[0]), files(&outputs[1]));
        assert!(one.iter().any(|(n, _)| n == "r.exr"), "{}: {one:?}", s.name);
        assert_eq!(
            one.iter().map(|f| &f.0).collect::<Vec<_>>(),
            two.iter().map(|f| &f.0).collect::<Vec<_>>(),
            "{}",
            s.name
        );
        for ((name, a), (_, b)) in one.iter().zip(&two) {
            assert!(a == b, "{}: {name} differs between 1 and 2 threads", s.name);
        }
    }
}

/// `--engine` changes how samples are shaded, never the image: the batched and per-sample
/// engines write the same EXR, and the JSON says which engine ran (the method has no batched
/// form yet, so it runs per sample whatever is asked).
#[test]
fn engine_flag_leaves_the_image_alone_and_is_recorded() {
    let dir = temp_dir("engine");
    let mut exrs = Vec::new();
    for (engine, strategy, used) in [
        ("batched", "power+bsdf", "batched"),
        ("per-sample", "power+bsdf", "per-sample"),
        ("batched", "mis3-adaptive", "per-sample"),
    ] {
        let name = format!("{engine}-{}", strategy.replace('+', "_"));
        let o = render_strategy_to(&dir, &name, strategy, &["--engine", engine]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json = std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap();
        let meta: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(meta["engine"], engine);
        assert_eq!(meta["engine_used"], used, "{name}");
        exrs.push(std::fs::read(dir.join(format!("{name}.exr"))).unwrap());
    }
    assert!(exrs[0] == exrs[1], "the engines' images differ");
}

/// Renders SCENE at 16×16 into `dir/t.exr` with a time budget and `extra` flags; its JSON.
fn render_with_budget(dir: &Path, seconds: &str, extra: &[&str]) -> serde_json::Value {
    let out = dir.join("t.exr");
    let mut args = vec![
        "render",
        SCENE,
        "--time-budget",
        seconds,
        "--width",
        "16",
        "--height",
        "16",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = manylights(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_str(&std::fs::read_to_string(dir.join("t.json")).unwrap()).unwrap()
}

#[test]
fn time_budget_records_the_spp_reached() {
    let meta = render_with_budget(&temp_dir("budget"), "0.5", &[]);
    assert!(meta["spp"].as_u64().unwrap() >= 1);
    assert_eq!(meta["time_budget_s"], 0.5);
}

#[test]
fn cpu_clock_budget_stops_after_its_cpu_time_per_thread() {
    let meta = render_with_budget(
        &temp_dir("budget-cpu"),
        "0.3",
        &["--budget-clock", "cpu", "--threads", "1"],
    );
    assert_eq!(meta["budget_clock"], "cpu");
    assert_eq!(meta["worker_threads"], 1);
    // No pass starts once 0.3 s of CPU time is spent, so the render used at least that much
    // however busy the machine was.
    assert!(meta["cpu_seconds"].as_f64().unwrap() >= 0.29, "{meta}");
    assert!(meta["spp"].as_u64().unwrap() >= 2);
}

/// A strategy on the image-space passes stops between passes under a time budget (never inside
/// one: no partial pixels) and records the memory its passes hold per pixel; a bad `--restir-*`
/// value is one line.
#[test]
fn image_space_strategy_keeps_its_budget_and_records_its_memory() {
    let dir = temp_dir("image-space");
    let meta = render_with_budget(&dir, "0.3", &["--strategy", "restir", "--threads", "2"]);
    assert!(meta["spp"].as_u64().unwrap() >= 1, "{meta}");
    assert_eq!(meta["partial_pass_pixels"], 0, "{meta}");
    assert!(
        meta["image_space_bytes_per_pixel"].as_u64().unwrap() > 0,
        "{meta}"
    );
    assert_eq!(meta["passes_correlated"], false, "{meta}");
    let carried = render_with_budget(
        &dir,
        "0.3",
        &["--strategy", "restir", "--restir-history", "20"],
    );
    assert_eq!(carried["passes_correlated"], true, "{carried}");
    assert!(
        carried["image_space_bytes_per_pixel"].as_u64()
            > meta["image_space_bytes_per_pixel"].as_u64(),
        "the history's memory is counted: {carried}"
    );
    let plain = render_with_budget(&dir, "0.1", &[]);
    assert!(plain["image_space_bytes_per_pixel"].is_null());
    assert_eq!(plain["passes_correlated"], false);
    let bad = temp_dir("image-space-bad");
    let out = bad.join("bad.exr");
    assert_clean_failure(
        &bad,
        &[
            "render",
            SCENE,
            "--strategy",
            "restir",
            "--restir-neighbours",
            "99",
            "--out",
            out.to_str().unwrap(),
        ],
        "--restir-neighbours must be 0 to 32",
    );
}

/// Runs a command that must fail with one clear line and leave no output file behind.
fn assert_clean_failure(dir: &Path, args: &[&str], expect: &str) {
    let o = manylights(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{args:?} should fail");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{args:?}: one line expected, got {err}");
    assert!(
        lines[0].starts_with("error:") && lines[0].to_lowercase().contains(expect),
        "{args:?}: {err}"
    );
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert!(left.is_empty(), "{args:?} left files: {left:?}");
}

/// The largest image's bytes overflow 64 bits: the refusal still gives its true size per pixel.
#[test]
fn a_huge_images_refusal_counts_its_bytes() {
    let dir = temp_dir("huge");
    let out = dir.join("x.exr");
    let o = manylights(&[
        "render",
        SCENE,
        "--spp",
        "1",
        "--width",
        "4294967295",
        "--height",
        "4294967295",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(" bytes per pixel)") && !err.contains("(0 bytes"),
        "{err}"
    );
}

#[test]
fn bad_input_fails_cleanly() {
    let dir = temp_dir("bad");
    let inputs = temp_dir("bad-inputs");
    let out = dir.join("x.exr");
    let out = out.to_str().unwrap();
    let garbage = inputs.join("garbage.glb");
    std::fs::write(&garbage, b"this is not a glTF file at all").unwrap();
    let missing = inputs.join("missing.gltf");
    let r = |scene: &str, extra: &[&str]| {
        let mut a = vec![
            "render", scene, "--spp", "1", "--width", "8", "--height", "8", "--quiet", "--out", out,
        ];
        a.extend_from_slice(extra);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let huge: Vec<String> = [
        "render", SCENE, "--spp", "1", "--width", "100000", "--height", "100000", "--quiet",
        "--out", out,
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let cases: Vec<(Vec<String>, &str)> = vec![
        // refused from the memory estimate, before anything is allocated
        (huge, "100000×100000 render needs about"),
        (r(missing.to_str().unwrap(), &[]), "missing.gltf"),
        (r(SCENE, &["--threads", "100000"]), "more than the 4096"),
        (r(garbage.to_str().unwrap(), &[]), "garbage.glb"),
        (
            r(SCENE, &["--strategy", "no-such-strategy"]),
            "unknown strategy",
        ),
        (
            r(SCENE, &["--strategy", "mis3-adaptve"]),
            "did you mean `mis3-adaptive`",
        ),
        (
            r(SCENE, &["--strategy", "power+bsdf", "--delta", "0.3"]),
            "`power+bsdf` does not take `--delta`; it takes --reproduce",
        ),
        (r("builtin:no-such-scene", &[]), "no-such-scene"),
        (r("builtin:glossy-spheres?lightz=4", &[]), "lightz"),
        (r("builtin:glossy-spheres?lights=many", &[]), "lights"),
        (
            vec![
                "render".into(),
                SCENE.into(),
                "--spp".into(),
                "0".into(),
                "--quiet".into(),
                "--out".into(),
                out.into(),
            ],
            "spp",
        ),
        (
            vec![
                "render".into(),
                SCENE.into(),
                "--spp".into(),
                "1".into(),
                "--quiet".into(),
                "--out".into(),
                "/nonexistent-dir/x.exr".into(),
            ],
            "nonexistent-dir",
        ),
        // a zsobol index past 64 bits: refused, not a panic (nor, before, wrapped shifts)
        (
            vec![
                "render".into(),
                SCENE.into(),
                "--sampler".into(),
                "zsobol".into(),
                "--spp".into(),
                "4000000000".into(),
                "--width".into(),
                "1000000".into(),
                "--height".into(),
                "1".into(),
                "--quiet".into(),
                "--out".into(),
                out.into(),
            ],
            "needs 72 bits",
        ),
        // named for another format: refused, not an EXR (or a PNG) behind a misleading name
        (
            vec![
                "render".into(),
                SCENE.into(),
                "--spp".into(),
                "1".into(),
                "--quiet".into(),
                "--out".into(),
                dir.join("x.png").to_str().unwrap().into(),
            ],
            "writes an openexr image",
        ),
        (
            r(SCENE, &["--png", "preview.jpg"]),
            "--png writes a png image",
        ),
    ];
    for (args, expect) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_clean_failure(&dir, &args, expect);
    }
}

#[test]
fn info_and_scenes_list() {
    let o = manylights(&["info", SCENE]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("64 sphere"), "{text}");
    let o = manylights(&["scenes"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("builtin:glossy-spheres") && text.contains("builtin:diffuse-quads"),
        "{text}"
    );
}

/// A reader that stops early (`manylights scenes | head -1`) ends the listing quietly: no panic
/// message about a broken pipe.
#[test]
fn closed_stdout_ends_quietly() {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_manylights"))
        .arg("scenes")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
}

/// A NaN pixel makes compare's errors NaN; it says so, with where.
#[test]
fn compare_warns_of_pixels_that_are_not_finite() {
    let dir = temp_dir("compare-nan");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let mut px = vec![glam::Vec3::ONE; 6];
    render_core::output::write_exr(&b, 3, 2, &px).unwrap();
    px[4] = glam::Vec3::new(f32::NAN, 1.0, 1.0);
    render_core::output::write_exr(&a, 3, 2, &px).unwrap();
    let o = manylights(&["compare", a.to_str().unwrap(), b.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("has 1 pixels that are not finite") && err.contains("the first at (1, 1)"),
        "{err}"
    );
    let o = manylights(&["compare", b.to_str().unwrap(), b.to_str().unwrap()]);
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn compare_reports_error_against_a_reference() {
    let dir = temp_dir("compare");
    assert!(
        render_to(&dir, "a", &["--seed", "1", "--aux"])
            .status
            .success()
    );
    assert!(
        render_to(&dir, "b", &["--seed", "2", "--aux"])
            .status
            .success()
    );
    let (a, b, mask) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("a.mask.png"));
    let o = manylights(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--mask",
        mask.to_str().unwrap(),
        "--json",
        "--worst",
        "3",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(
        v["all"]["rel_mse"].as_f64().unwrap() > 0.0,
        "independent renders differ"
    );
    let unlit = v["unlit"]["pixels"].as_u64().unwrap();
    assert!(unlit <= v["all"]["pixels"].as_u64().unwrap());
    // The worst pixels come largest first, and their shares are those of the unlit error sum:
    // the relMSE of a pixel is its share × (3 channels' mean → the sum over unlit pixels).
    let worst = v["worst"].as_array().unwrap();
    assert_eq!(worst.len(), 3);
    let e: Vec<f64> = worst
        .iter()
        .map(|p| p["rel_mse"].as_f64().unwrap())
        .collect();
    assert!(e[0] >= e[1] && e[1] >= e[2], "{e:?}");
    let total = v["unlit"]["rel_mse"].as_f64().unwrap() * unlit as f64;
    let share = worst[0]["share"].as_f64().unwrap();
    assert!(
        (share * total - e[0]).abs() <= 1e-4 * e[0],
        "{share} × {total} vs {}",
        e[0]
    );
    let o = manylights(&[
        "compare",
        a.to_str().unwrap(),
        a.to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["all"]["rel_mse"].as_f64().unwrap(), 0.0);
    // Several masks: a pixel is unlit only if every mask says so.
    let unlit_with = |masks: &[&std::path::Path]| {
        let mut args = vec![
            "compare",
            a.to_str().unwrap(),
            b.to_str().unwrap(),
            "--json",
        ];
        for m in masks {
            args.extend(["--mask", m.to_str().unwrap()]);
        }
        let o = manylights(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["unlit"]["pixels"].as_u64().unwrap()
    };
    let own_b = dir.join("b.mask.png");
    let both = unlit_with(&[&mask, &own_b]);
    assert_eq!(unlit_with(&[&mask, &mask]), unlit);
    assert!(both <= unlit && both <= unlit_with(&[&own_b]));
}

#[test]
fn mis3_flags_and_false_colour_aux() {
    let dir = temp_dir("mis3");
    for (name, extra) in [
        (
            "adaptive",
            vec![
                "--delta", "0.4", "--n-max", "20", "--lambda", "5", "--tau", "0.8",
            ],
        ),
        (
            "repro",
            vec!["--reproduce", "--pivot-sphere", "--max-cut", "16"],
        ),
        ("noh", vec!["--no-adaptive-total", "--no-adaptive-split"]),
        ("nopilot", vec!["--n-max", "20", "--no-pilot"]),
    ] {
        let out = dir.join(format!("{name}.exr"));
        let mut args = vec![
            "render",
            SCENE,
            "--strategy",
            "mis3-adaptive",
            "--spp",
            "2",
            "--width",
            "16",
            "--height",
            "12",
            "--quiet",
            "--aux",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        let o = manylights(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for suffix in ["n_brdf_aware.png", "bo_share.png", "n_brdf_aware.exr"] {
            assert!(
                dir.join(format!("{name}.{suffix}")).is_file(),
                "{name}.{suffix}"
            );
        }
        let meta: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap(),
        )
        .unwrap();
        assert!(meta["technique_samples"]["bo"].as_u64().unwrap() > 0);
    }
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("adaptive.json")).unwrap()).unwrap();
    assert_eq!(meta["strategy_parameters"]["n_max"], 20);
    // Our defaults: N_max per pass (from pass 1 at --n-max: the image is too small for a
    // pilot), one LS descent at glossy points and stratified BRDF-aware samples; --reproduce
    // keeps the paper's constant N_max, E&K cut and independent samples.
    let params = &meta["strategy_parameters"];
    assert_eq!(params["n_max_by_pass"][0], serde_json::json!([1, 20.0]));
    assert_eq!(params["pilot"], true);
    assert_eq!(meta["pilot_camera_samples"], 0);
    // From 64 × 64 on, a pilot of one pixel in 16 (two samples each) sets N_max for pass 1.
    let out = dir.join("pilot.exr");
    let o = manylights(&[
        "render",
        SCENE,
        "--strategy",
        "mis3-adaptive",
        "--spp",
        "1",
        "--width",
        "64",
        "--height",
        "64",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pilot: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("pilot.json")).unwrap()).unwrap();
    assert_eq!(pilot["pilot_camera_samples"], 2 * 16 * 16);
    let by_pass = pilot["strategy_parameters"]["n_max_by_pass"]
        .as_array()
        .unwrap();
    assert_eq!(by_pass.len(), 1, "{by_pass:?}");
    assert_eq!(by_pass[0][0], 1);
    let nopilot: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("nopilot.json")).unwrap()).unwrap();
    let np = &nopilot["strategy_parameters"];
    assert_eq!(np["n_max_by_pass"][0], serde_json::json!([1, 20.0]));
    assert_eq!(np["pilot"], false);
    assert_eq!(nopilot["pilot_camera_samples"], 0);
    assert_eq!(params["efficient_total"], true);
    assert_eq!(params["single_ls_at_glossy"], true);
    assert_eq!(params["stratified"], true);
    let repro: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("repro.json")).unwrap()).unwrap();
    let params = &repro["strategy_parameters"];
    assert!(params.get("n_max_by_pass").is_none());
    assert_eq!(params["efficient_total"], false);
    assert_eq!(params["pilot"], false);
    assert_eq!(repro["pilot_camera_samples"], 0);
    assert_eq!(params["single_ls_at_glossy"], false);
    assert_eq!(params["stratified"], false);
    // τ: as given; else ours (0.35), or the authors' 0.85 under --reproduce, so that changing
    // our default never moves the reproduced baseline.
    for (name, tau) in [("adaptive", 0.8), ("noh", 0.35), ("repro", 0.85)] {
        let meta: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap(),
        )
        .unwrap();
        let got = meta["strategy_parameters"]["tau"].as_f64().unwrap();
        assert!((got - tau).abs() < 1e-6, "{name}: τ {got}, want {tau}");
    }
    let o = manylights(&[
        "render",
        SCENE,
        "--strategy",
        "mis3-adaptive",
        "--delta",
        "-1",
        "--out",
        dir.join("bad.exr").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
}

#[test]
fn cap_integral_batch_agrees_across_methods() {
    use std::io::Write;
    let run = |method: &str, input: &str| {
        let mut child = Command::new(env!("CARGO_BIN_EXE_manylights"))
            .args(["cap-integral", "--method", method])
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        child
            .stdin
            .take()
            .unwrap()
            .write_all(input.as_bytes())
            .unwrap();
        child.wait_with_output().unwrap()
    };
    // A cap of half-angle ~25° around the mirror direction of θo = 0.5, α = 0.1; and the hemisphere.
    let rows = "0.1,0.5,-0.4794,0,0.8776,0.9\n0.1,0.5,0,0,1,0\n";
    let values = |m: &str| -> Vec<f64> {
        let o = run(m, rows);
        assert!(
            o.status.success(),
            "{m}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .map(|l| l.trim().parse().unwrap())
            .collect()
    };
    let (r, s, l) = (values("reference"), values("sptd"), values("ltc"));
    for k in 0..2 {
        assert!(r[k] > 0.1, "the lobe peak carries mass: {r:?}");
        assert!(
            (s[k] - r[k]).abs() < 0.1 * r[k],
            "sptd {s:?} vs reference {r:?}"
        );
        assert!(
            (l[k] - r[k]).abs() < 0.1 * r[k],
            "ltc {l:?} vs reference {r:?}"
        );
    }
    let o = run("sptd", "0.1,0.5,1,2\n");
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("line 1"));
    let o = run("nope", "");
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("unknown method"));
}

/// A pbrt scene through the command line: `info` lists its warnings with file and line,
/// `convert` writes a glTF that loads back, `render` draws it, and a malformed file is one
/// `error:` line naming file and line.
#[test]
fn pbrt_scenes_info_convert_render_and_errors() {
    let dir = temp_dir("pbrt");
    let scene = dir.join("lamp.pbrt");
    std::fs::write(
        &scene,
        "LookAt 0 1 4  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n\
         Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 12\nWorldBegin\n\
         Material \"plastic\" \"rgb Kd\" [ .3 .1 .2 ] \"rgb Ks\" [ .7 .7 .7 ] \"float roughness\" .01 \"bool remaproughness\" false\n\
         Shape \"bilinearmesh\" \"point3 P\" [ -2 0 -2  2 0 -2  -2 0 2  2 0 2 ]\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 50 50 50 ]\nTranslate 0 1.5 0\n\
         Shape \"sphere\" \"float radius\" 0.05\nAttributeEnd\n\
         LightSource \"infinite\" \"rgb L\" [ 1 1 1 ]\n",
    )
    .unwrap();
    let s = scene.to_str().unwrap();
    let o = manylights(&["info", s]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}");
    assert!(text.contains("1 sphere"), "{text}");
    assert!(
        text.contains("lamp.pbrt:12: LightSource \"infinite\" is not supported"),
        "{text}"
    );
    let gltf = dir.join("lamp.gltf");
    let o = manylights(&["convert", s, gltf.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("must end in .glb"),
        "{err}"
    );
    assert!(!gltf.exists(), "a refused conversion writes nothing");
    for (out, expect) in [
        (dir.join("no-such-dir/x.glb"), "output directory"),
        (dir.to_path_buf(), "must end in .glb"),
        (dir.join("dir.glb"), "(convert's output) is a directory"),
    ] {
        let _ = std::fs::create_dir(dir.join("dir.glb"));
        let o = manylights(&["convert", s, out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(expect), "{err}");
        assert!(!err.contains("cannot read scene file"), "{err}");
    }
    let glb = dir.join("lamp.glb");
    let o = manylights(&["convert", s, glb.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = manylights(&["info", glb.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("1 sphere"));
    let out = dir.join("lamp.exr");
    let o = manylights(&[
        "render",
        s,
        "--strategy",
        "mis3-adaptive",
        "--spp",
        "2",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.exists());

    let bad_dir = temp_dir("pbrt-bad");
    let outputs = temp_dir("pbrt-bad-out");
    let bad = bad_dir.join("bad.pbrt");
    std::fs::write(
        &bad,
        "WorldBegin\nShape \"sphere\" \"float radius\" \"big\"\n",
    )
    .unwrap();
    let out = outputs.join("x.exr");
    assert_clean_failure(
        &outputs,
        &[
            "render",
            bad.to_str().unwrap(),
            "--spp",
            "1",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ],
        "bad.pbrt:2: parameter",
    );
}

/// Without `--sampler` (and no `Sampler` in the scene) the render takes the default the
/// samplers experiment chose, and says so.
#[test]
fn default_sampler_is_lowdiscrepancy_and_recorded_as_default() {
    let dir = temp_dir("sampler-default");
    let o = render_to(&dir, "d", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("d.json")).unwrap()).unwrap();
    assert_eq!(meta["sampler"], "lowdiscrepancy");
    assert_eq!(meta["sampler_from"], "default");
}

#[test]
fn sampler_and_filter_are_chosen_and_recorded() {
    let dir = temp_dir("sampler-filter");
    let o = render_to(&dir, "s", &["--sampler", "sobol", "--filter", "triangle:1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(meta["sampler"], "sobol");
    assert_eq!(meta["filter"]["name"], "triangle");
    assert_eq!(meta["filter"]["parameters"]["radius"], 1.0);
    let bad = manylights(&[
        "render", SCENE, "--spp", "1", "--filter", "lanczos", "--quiet",
    ]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success() && err.contains("unknown pixel filter"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    let empty = temp_dir("sampler-filter-refused");
    let out = empty.join("x.exr");
    assert_clean_failure(
        &empty,
        &[
            "render",
            SCENE,
            "--sampler",
            "stratified",
            "--time-budget",
            "0.1",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ],
        "stratified sampler",
    );
}

/// Mean of the PNG's 8-bit channels and the fraction that are saturated (255).
fn png_brightness(path: &Path) -> (f64, f64) {
    let img = image::open(path).expect("a PNG").to_rgb8();
    let v: Vec<u8> = img.into_raw();
    let mean = v.iter().map(|&c| c as f64).sum::<f64>() / v.len() as f64;
    let white = v.iter().filter(|&&c| c == 255).count() as f64 / v.len() as f64;
    (mean, white)
}

/// Issue 26's paper cuts: `--exposure -3` is taken as a value (not as a flag), and a bright
/// scene's preview is not white when no exposure is given (auto exposure, in the JSON).
#[test]
fn preview_exposure_negative_and_auto() {
    let dir = temp_dir("exposure");
    let scene = dir.join("bright.pbrt");
    std::fs::write(
        &scene,
        "LookAt 0 3 0.01  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 60\n\
         Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24\nWorldBegin\n\
         Material \"diffuse\" \"rgb reflectance\" [ .5 .5 .5 ]\n\
         Shape \"bilinearmesh\" \"point3 P\" [ -4 0 -4  4 0 -4  -4 0 4  4 0 4 ]\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 20000 20000 20000 ]\nTranslate 0.5 1 0\n\
         Shape \"sphere\" \"float radius\" 0.05\nAttributeEnd\n",
    )
    .unwrap();
    let render = |name: &str, extra: &[&str]| -> serde_json::Value {
        let out = dir.join(format!("{name}.exr"));
        let png = dir.join(format!("{name}.png"));
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "2",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
            "--png",
            png.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = manylights(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_str(&std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap())
            .unwrap()
    };
    // at exposure 0 the scene is bright enough to be mostly white
    let zero = render("zero", &["--exposure", "0"]);
    assert_eq!(zero["png_exposure"], 0.0);
    assert_eq!(zero["png_exposure_auto"], false);
    let (_, white0) = png_brightness(&dir.join("zero.png"));
    assert!(white0 > 0.5, "the test scene is bright: {white0}");
    // `--exposure -3` (a separate negative word) is accepted and darkens the preview
    let minus3 = render("minus3", &["--exposure", "-3"]);
    assert_eq!(minus3["png_exposure"], -3.0);
    let (mean3, _) = png_brightness(&dir.join("minus3.png"));
    let (mean0, _) = png_brightness(&dir.join("zero.png"));
    assert!(mean3 < mean0, "{mean3} vs {mean0}");
    // no --exposure: auto exposure, recorded, negative for this bright scene, and the preview
    // is neither white nor black
    let auto = render("auto", &[]);
    assert_eq!(auto["png_exposure_auto"], true);
    let e = auto["png_exposure"].as_f64().unwrap();
    assert!(e < -1.0, "auto exposure {e}");
    let (mean, white) = png_brightness(&dir.join("auto.png"));
    assert!(white < 0.05, "{white} of the channels are white");
    assert!(mean > 20.0 && mean < 235.0, "mean {mean}");
    // the same seed gives the same preview (the exposure is a function of the image)
    render("auto2", &[]);
    assert_eq!(
        std::fs::read(dir.join("auto.png")).unwrap(),
        std::fs::read(dir.join("auto2.png")).unwrap()
    );
    // bad values fail cleanly
    let o = manylights(&[
        "render",
        scene.to_str().unwrap(),
        "--exposure",
        "nan",
        "--quiet",
        "--out",
        dir.join("x.exr").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--exposure must be a finite"));
}

fn json_of(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn scene_hash_covers_included_files_and_render_records_what_strategy_resolves() {
    let dir = temp_dir("hash");
    let scene = dir.join("s.pbrt");
    std::fs::write(
        &scene,
        "LookAt 0 1 4  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\nWorldBegin\nInclude \"geom.pbrt\"\n",
    )
    .unwrap();
    let geom = |radius: &str| {
        std::fs::write(
            dir.join("geom.pbrt"),
            format!(
                "Shape \"bilinearmesh\" \"point3 P\" [ -2 0 -2  2 0 -2  -2 0 2  2 0 2 ]\n\
                 AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 50 50 50 ]\n\
                 Translate 0 1.5 0\nShape \"sphere\" \"float radius\" {radius}\nAttributeEnd\n"
            ),
        )
        .unwrap()
    };
    let s = scene.to_str().unwrap();
    let hash = || json_of(&manylights(&["info", s, "--json"]))["scene_hash"].clone();
    geom("0.05");
    let a = hash();
    assert_eq!(a.as_str().map(str::len), Some(32), "{a}");
    assert_eq!(a, hash(), "the same files, the same hash");
    geom("0.06");
    let b = hash();
    assert_ne!(a, b, "a change in the included file changes the hash");
    // a change that loads to the same scene (a comment) does not
    std::fs::write(dir.join("geom.pbrt"), {
        let mut t = std::fs::read_to_string(dir.join("geom.pbrt")).unwrap();
        t.push_str("# a comment\n");
        t
    })
    .unwrap();
    assert_eq!(b, hash());

    // `strategy --json` gives what the render records, defaults included
    let flags = ["--strategy", "mis3-adaptive", "--lambda", "3"];
    let mut args = vec!["strategy", "--json"];
    args.extend(flags);
    let resolved = json_of(&manylights(&args));
    assert_eq!(resolved["parameters"]["method"]["lambda"], 3.0);
    assert_eq!(resolved["parameters"]["method"]["n_max"], 50, "a default");
    assert_eq!(resolved["emission_rays"], 16, "the method's default");
    let learned = ["strategy", "--json", "--strategy", "mis3-adaptive-learned"];
    assert_eq!(
        json_of(&manylights(&learned))["emission_rays"],
        16,
        "the method's learned variant compares with it like for like"
    );
    for other in [
        vec![
            "strategy",
            "--json",
            "--strategy",
            "mis3-adaptive",
            "--reproduce",
        ],
        vec!["strategy", "--json", "--strategy", "tree-split+bsdf"],
        vec![
            "strategy",
            "--json",
            "--strategy",
            "mis3-adaptive",
            "--emission-rays",
            "1",
        ],
    ] {
        assert_eq!(
            json_of(&manylights(&other))["emission_rays"],
            1,
            "{other:?}"
        );
    }
    let out = dir.join("r.exr");
    let mut args = vec!["render", s, "--spp", "1", "--width", "8", "--height", "6"];
    args.extend(flags);
    args.extend(["--quiet", "--out", out.to_str().unwrap()]);
    let o = manylights(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    assert_eq!(meta["resolved_strategy"], resolved);
    assert_eq!(meta["emission_rays"], 16);
    assert_eq!(meta["scene_hash"], b);
    let o = manylights(&["strategy", "--strategy", "no-such"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown strategy `no-such`"));
}

/// `render --help` documents every flag: each option line has its help on the same line or the
/// next, more indented one.
#[test]
fn render_help_documents_every_flag() {
    let o = manylights(&["render", "--help"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let lines: Vec<&str> = text.lines().collect();
    let mut flags = 0;
    for (i, line) in lines.iter().enumerate() {
        let t = line.trim_start();
        if !(t.starts_with("--") || t.starts_with("-h, ")) {
            continue;
        }
        flags += 1;
        let indent = line.len() - t.len();
        let spec_end = t.find("  ").unwrap_or(t.len());
        let same_line = !t[spec_end..].trim().is_empty();
        let next = lines.get(i + 1).copied().unwrap_or("");
        let next_line = !next.trim().is_empty()
            && next.len() - next.trim_start().len() > indent
            && !next.trim_start().starts_with('-');
        assert!(same_line || next_line, "no help for `{}`", t);
    }
    assert!(flags > 30, "only {flags} flags found in:\n{text}");
}

/// A flag that changes nothing in this render is warned about, not silently dropped.
#[test]
fn flags_that_do_nothing_are_warned_about() {
    let dir = temp_dir("ignored");
    let out = dir.join("x.exr");
    let o = manylights(&[
        "render",
        SCENE,
        "--spp",
        "1",
        "--width",
        "8",
        "--height",
        "8",
        "--exposure",
        "2",
        "--budget-clock",
        "cpu",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("--exposure sets the --png preview's brightness"),
        "{err}"
    );
    assert!(
        err.contains("--budget-clock says what --time-budget counts"),
        "{err}"
    );
    assert!(err.contains("(1 pass)"), "{err}");
}

/// `bsdf` cannot reach delta lights: a scene with one says so instead of a silent black image.
#[test]
fn bsdf_sampling_warns_of_lights_it_cannot_reach() {
    let dir = temp_dir("bsdf-delta");
    let scene = dir.join("point.pbrt");
    std::fs::write(
        &scene,
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [45]\nWorldBegin\n\
         LightSource \"point\" \"rgb I\" [1 1 1] \"point3 from\" [0 0 2]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [-3 -3 -1 3 -3 -1 0 3 -1]\n\
         WorldEnd\n",
    )
    .unwrap();
    let out = dir.join("x.exr");
    let render = |strategy: &str| {
        let o = manylights(&[
            "render",
            scene.to_str().unwrap(),
            "--strategy",
            strategy,
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let err = render("bsdf");
    assert!(
        err.contains("cannot reach the scene's 1 point, spot and distant lights"),
        "{err}"
    );
    assert!(render("power+bsdf").is_empty());
}
