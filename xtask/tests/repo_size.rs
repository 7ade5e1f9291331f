//! The repository stops growing: no tracked file above 2 MB, and the tracked results (tables,
//! plots, the few images the docs show) under 40 MB. What the harness writes on every run
//! (viewer bundles, per-cell JSON, strips, maps, HTML reports) is ignored by git.
use std::path::{Path, PathBuf};
use std::process::Command;

const MAX_FILE: u64 = 2_000_000;
const MAX_RESULTS: u64 = 40_000_000;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask sits in the repository root")
        .to_path_buf()
}

/// The tracked files (`git ls-files`), or `None` outside a git checkout.
fn tracked(root: &Path) -> Option<Vec<String>> {
    let out = Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root)
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    Some(
        out.stdout
            .split(|&b| b == 0)
            .filter(|p| !p.is_empty())
            .map(|p| String::from_utf8_lossy(p).into_owned())
            .collect(),
    )
}

#[test]
fn tracked_files_are_small_and_results_bounded() {
    let root = repo_root();
    let Some(files) = tracked(&root) else {
        println!(
            "NOTICE: git is absent or this is not a git checkout: repository size not checked"
        );
        return;
    };
    assert!(!files.is_empty(), "git ls-files listed nothing");
    let mut too_big = Vec::new();
    let mut results = 0u64;
    for f in &files {
        // a tracked file deleted in the working tree is not checked out
        let Ok(meta) = std::fs::metadata(root.join(f)) else {
            continue;
        };
        if meta.len() > MAX_FILE {
            too_big.push(format!("{f} ({:.1} MB)", meta.len() as f64 / 1e6));
        }
        if f.starts_with("results/") {
            results += meta.len();
        }
    }
    assert!(
        too_big.is_empty(),
        "tracked files above {} MB (keep them out of git: .gitignore): {}",
        MAX_FILE / 1_000_000,
        too_big.join(", ")
    );
    assert!(
        results <= MAX_RESULTS,
        "the tracked files under results/ add up to {:.1} MB, above {} MB",
        results as f64 / 1e6,
        MAX_RESULTS / 1_000_000
    );
}
