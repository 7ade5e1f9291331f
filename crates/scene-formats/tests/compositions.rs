//! Every composition file under experiments/scenes loads, when the shared assets it places are
//! present (CI has no ../shared: then each is skipped with a notice).
use std::path::Path;

#[test]
fn shipped_compositions_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../experiments/scenes");
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    let mut loaded = 0;
    for entry in std::fs::read_dir(&dir).unwrap().flatten() {
        let path = entry.path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        if !shared.is_dir() {
            let name = path.file_name().unwrap().to_string_lossy();
            skipped(&format!("loading experiments/scenes/{name}"));
            continue;
        }
        let scene = scene_formats::load_scene(path.to_str().unwrap(), None)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            scene.lights.len() >= 1000,
            "{}: {} lights",
            path.display(),
            scene.lights.len()
        );
        assert!(!scene.cameras.is_empty(), "{} has a camera", path.display());
        loaded += 1;
    }
    if shared.is_dir() {
        assert!(
            loaded >= 5,
            "expected the five compositions, loaded {loaded}"
        );
    }
}

/// Says on the terminal that a test checked nothing: what `eprintln!` prints in a passing test
/// is captured and never shown, a direct write to stderr is not.
fn skipped(what: &str) {
    use std::io::Write;
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED: {what} (../shared/scenes not found)"
    );
}
