//! Records the git commit the binary was built from, when there is one, with `-dirty` when a
//! file that builds it (crates/, Cargo.toml, Cargo.lock, .cargo/) differs from the commit;
//! results and documentation do not count. Cargo reruns this only when HEAD or the index
//! change, so the mark can lag an edit: the experiment harness decides dirtiness itself
//! (xtask/src/experiments/provenance.rs).
fn main() {
    let commit = std::process::Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let dirty = std::process::Command::new("git")
        .args([
            "status",
            "--porcelain",
            "--untracked-files=no",
            "--",
            ":/crates",
            ":/Cargo.toml",
            ":/Cargo.lock",
            ":/.cargo",
        ])
        .output()
        .ok()
        .is_some_and(|o| o.status.success() && !o.stdout.is_empty());
    let value = if commit.is_empty() {
        String::new()
    } else if dirty {
        format!("{commit}-dirty")
    } else {
        commit
    };
    println!("cargo:rustc-env=MANYLIGHTS_GIT_COMMIT={value}");
    // In a linked worktree `.git` is a file and HEAD and the index live in the worktree's own
    // git directory; a path that does not exist would make Cargo rerun this on every build.
    let git_dir = std::process::Command::new("git")
        .args(["rev-parse", "--absolute-git-dir"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    match git_dir {
        Some(dir) => {
            println!("cargo:rerun-if-changed={dir}/HEAD");
            println!("cargo:rerun-if-changed={dir}/index");
        }
        None => println!("cargo:rerun-if-changed=build.rs"),
    }
}
