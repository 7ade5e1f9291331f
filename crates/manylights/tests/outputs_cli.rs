//! What `render` writes, as a set: every file named before the render starts (a directory in
//! a file's place or two outputs under one name are refused then, not after the work), and
//! the files put in place together, so a failed write leaves the previous render's as they were.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn manylights(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manylights"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("manylights-outputs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small render of the method (it has aux channels) into `dir`, with `extra` flags.
fn render(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "render",
        "builtin:glossy-spheres?lights=16",
        "--strategy",
        "mis3-adaptive",
        "--width",
        "16",
        "--height",
        "12",
        "--threads",
        "1",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    manylights(dir, &args)
}

fn refused(o: &Output, expect: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "should fail: {err}");
    assert!(err.contains(expect), "expected `{expect}` in: {err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
}

#[test]
fn two_outputs_under_one_name_are_refused_before_rendering() {
    let dir = temp_dir("twice");
    for png in ["o.mask.png", "./o.mask.png", "o.bo_share.png"] {
        let o = render(
            &dir,
            &["--spp", "1", "--aux", "--out", "o.exr", "--png", png],
        );
        refused(&o, "would be written twice, by --png and by --aux");
    }
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing written"
    );
    // Without --aux the same --png is an ordinary preview.
    let o = render(
        &dir,
        &["--spp", "1", "--out", "o.exr", "--png", "o.mask.png"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_directory_in_an_outputs_place_is_refused_and_the_last_render_kept_whole() {
    let dir = temp_dir("dir");
    let first = render(&dir, &["--spp", "1", "--aux", "--out", "q.exr"]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let exr = std::fs::read(dir.join("q.exr")).unwrap();
    let json = std::fs::read(dir.join("q.json")).unwrap();
    for (blocked, what) in [
        ("q.mask.png", "--aux's light mask"),
        ("q.json", "the render's record"),
        ("q.exr", "--out"),
    ] {
        let path = dir.join(blocked);
        let kept = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        std::fs::create_dir(&path).unwrap();
        let o = render(&dir, &["--spp", "2", "--aux", "--out", "q.exr"]);
        refused(&o, &format!("{blocked} ({what}) is a directory"));
        std::fs::remove_dir(&path).unwrap();
        std::fs::write(&path, kept).unwrap();
        assert_eq!(
            std::fs::read(dir.join("q.exr")).unwrap(),
            exr,
            "the image is the last render's"
        );
        assert_eq!(
            std::fs::read(dir.join("q.json")).unwrap(),
            json,
            "and so is its record"
        );
    }
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp."))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Ctrl-C (SIGINT) ends a long render as a spent time budget does: the samples done are
/// written with their record, marked interrupted, and the exit code is 130.
#[cfg(unix)]
#[test]
fn ctrl_c_writes_the_samples_done() {
    let dir = temp_dir("ctrl-c");
    let mut child = Command::new(env!("CARGO_BIN_EXE_manylights"))
        .current_dir(&dir)
        .args([
            "render",
            "builtin:glossy-spheres?lights=16",
            "--width",
            "32",
            "--height",
            "24",
            "--threads",
            "1",
            "--spp",
            "10000000",
            "--quiet",
            "--out",
            "c.exr",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("binary runs");
    std::thread::sleep(std::time::Duration::from_secs(2));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(kill.success());
    let out = child.wait_with_output().expect("the render ends");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted by Ctrl-C"), "{err}");
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("c.json")).expect("record written"))
            .unwrap();
    assert_eq!(meta["interrupted"], true, "{meta}");
    let spp = meta["spp"].as_u64().unwrap();
    assert!(spp >= 1 && spp < 10_000_000, "{meta}");
    assert!(dir.join("c.exr").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}
