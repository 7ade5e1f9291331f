//! The code a cell was rendered by: a clean tree's `tree:` id (the git objects of the paths
//! that make the `manylights` binary) or a dirty build's `binary:` hash.
use super::plan::hex_hash;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::process::Command;

/// The paths whose content determines the `manylights` binary: a clean tree at two commits
/// that agree on them is one code state (a commit that only adds results re-renders nothing).
pub const CODE_PATHS: [&str; 4] = ["crates", "Cargo.toml", "Cargo.lock", ".cargo"];

/// The code a cell was rendered by.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
pub struct CodeState {
    /// `tree:<hash of the git objects of CODE_PATHS>` for a clean tree, `binary:<hash of the
    /// manylights executable>` for a dirty one (or outside git).
    pub id: String,
    /// HEAD when the cell was rendered (12 hex digits), if in git.
    pub commit: Option<String>,
    /// Some file under CODE_PATHS differed from HEAD.
    pub dirty: bool,
}

impl CodeState {
    /// How a table header names it.
    pub fn describe(&self) -> String {
        match (&self.commit, self.dirty) {
            (Some(c), false) => format!("commit {c}"),
            (Some(c), true) => format!("a dirty tree on {c} ({})", self.id),
            (None, _) => format!("a build outside git ({})", self.id),
        }
    }

    /// The code state of a cell written before cells recorded one: its render's commit.
    pub fn legacy(render: &serde_json::Value) -> CodeState {
        let commit = render["git_commit"].as_str().unwrap_or("unknown");
        let dirty = commit.ends_with("-dirty") || commit == "unknown";
        CodeState {
            id: format!("legacy:{commit}"),
            commit: Some(commit.trim_end_matches("-dirty").to_string()),
            dirty,
        }
    }
}

fn git(root: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .args(args)
        .current_dir(root)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Files under [`CODE_PATHS`] that cannot change the binary: no crate includes a Markdown
/// file (a crate's README is not its doc), so editing one during a run neither dirties the
/// tree nor starts a new code state.
const NOT_CODE: &str = ":(exclude,glob)**/*.md";

/// The code state of a clean tree at `root` (HEAD and its `tree:` id); `None` when the tree
/// is dirty under [`CODE_PATHS`] (Markdown aside) or not in git.
pub fn clean_code_state(root: &Path) -> Option<CodeState> {
    let commit = git(root, &["rev-parse", "--short=12", "HEAD"])?
        .trim()
        .to_string();
    let mut status_args = vec!["status", "--porcelain", "--untracked-files=no", "--"];
    status_args.extend(CODE_PATHS);
    status_args.push(NOT_CODE);
    if !git(root, &status_args)?.trim().is_empty() {
        return None;
    }
    // Every blob under the code paths at HEAD, with its path, Markdown aside.
    let mut ls_args = vec!["ls-tree", "-r", "--full-tree", "HEAD", "--"];
    ls_args.extend(CODE_PATHS);
    let listing: String = git(root, &ls_args)?
        .lines()
        .filter(|line| !line.ends_with(".md"))
        .flat_map(|line| [line, "\n"])
        .collect();
    Some(CodeState {
        id: format!("tree:{}", hex_hash(listing.as_bytes())),
        commit: Some(commit),
        dirty: false,
    })
}

/// The code state of the tree at `root`, whose `manylights` binary is `exe`.
pub fn code_state(root: &Path, exe: &Path) -> Result<CodeState, String> {
    if let Some(clean) = clean_code_state(root) {
        return Ok(clean);
    }
    let commit = git(root, &["rev-parse", "--short=12", "HEAD"]).map(|s| s.trim().to_string());
    let bytes =
        std::fs::read(exe).map_err(|e| format!("cannot read {} to hash it: {e}", exe.display()))?;
    Ok(CodeState {
        id: format!("binary:{}", hex_hash(&bytes)),
        commit,
        dirty: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A README under `crates/` is not code: editing it neither dirties the tree nor makes a
    /// new code state; editing a source file does both.
    #[test]
    fn markdown_under_the_code_paths_is_not_code() {
        let dir = std::env::temp_dir().join(format!("ml-provenance-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("crates/a/src")).unwrap();
        let run = |args: &[&str]| {
            let ok = Command::new("git")
                .args(["-c", "user.name=t", "-c", "user.email=t@t"])
                .args(args)
                .current_dir(&dir)
                .output()
                .map(|o| o.status.success())
                .unwrap_or(false);
            assert!(ok, "git {args:?}");
        };
        let write = |path: &str, text: &str| std::fs::write(dir.join(path), text).unwrap();
        run(&["init", "-q"]);
        write("crates/a/src/lib.rs", "fn a() {}");
        write("crates/a/README.md", "one");
        write("Cargo.toml", "[workspace]");
        run(&["add", "."]);
        run(&["commit", "-q", "-m", "one"]);
        let first = clean_code_state(&dir).expect("a clean tree has a code state");

        write("crates/a/README.md", "two");
        let edited = clean_code_state(&dir).expect("an edited README leaves the tree clean");
        assert_eq!(edited.id, first.id);
        run(&["commit", "-q", "-am", "two"]);
        let committed = clean_code_state(&dir).unwrap();
        assert_eq!(
            committed.id, first.id,
            "a README commit is the same code state"
        );
        assert_ne!(committed.commit, first.commit);

        write("crates/a/src/lib.rs", "fn b() {}");
        assert_eq!(
            clean_code_state(&dir),
            None,
            "an edited source file dirties the tree"
        );
        run(&["commit", "-q", "-am", "three"]);
        assert_ne!(clean_code_state(&dir).unwrap().id, first.id);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
