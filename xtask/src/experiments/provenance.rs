//! What made a cell: the code state of the binary, the loaded scene, the strategy's resolved
//! parameters and (for time budgets) the thread count; and the checks the report and
//! `merge-results` make before writing one table from many cells.
use super::plan::{Budget, hex_hash};
use super::report::CellResult;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
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

/// How the committed results of an experiment stand against the code of today's tree.
#[derive(Debug, PartialEq, Eq)]
pub enum Freshness {
    /// No cell files.
    NoResults,
    /// Every cell was rendered by the code state of today's clean tree.
    Current { commit: String },
    /// One clean code state, not today's (or today's tree is dirty, so none can be current).
    Older { commit: String },
    /// Cells of several code states, or of a dirty build.
    Mixed { states: usize },
}

impl Freshness {
    /// The cells' code states (`code` of each cell JSON, or the legacy commit) against `now`,
    /// today's clean code state if the tree is clean.
    ///
    /// A code state is its `id`: cells of several commits with one id (the same code paths)
    /// are one state, as for reuse and for the table header, and `commit` names them all.
    pub fn of(cells: &[CodeState], now: Option<&CodeState>) -> Freshness {
        let states: BTreeSet<(&str, bool)> =
            cells.iter().map(|c| (c.id.as_str(), c.dirty)).collect();
        let Some(&(id, dirty)) = states.first() else {
            return Freshness::NoResults;
        };
        if states.len() > 1 || dirty {
            return Freshness::Mixed {
                states: states.len(),
            };
        }
        let commits: BTreeSet<&str> = cells
            .iter()
            .map(|c| c.commit.as_deref().unwrap_or("unknown"))
            .collect();
        let commit = commits.into_iter().collect::<Vec<_>>().join(" and ");
        match now {
            Some(n) if n.id == id => Freshness::Current { commit },
            _ => Freshness::Older { commit },
        }
    }

    /// One line for `run-experiments --list`; `tree_clean`: today's tree is clean under
    /// [`CODE_PATHS`].
    pub fn describe(&self, tree_clean: bool) -> String {
        match self {
            Freshness::NoResults => "no results".into(),
            Freshness::Current { commit } => format!("results at {commit}: today's code"),
            Freshness::Older { commit } if tree_clean => {
                format!("results at {commit}: the code has changed since")
            }
            Freshness::Older { commit } => {
                format!("results at {commit} (today's tree is dirty: not compared)")
            }
            Freshness::Mixed { states: 1 } => "results of a dirty build".into(),
            Freshness::Mixed { states } => format!("results of {states} code states"),
        }
    }
}

/// The code states of the cells in `results/NAME/cells.json` (empty if there is none).
pub fn cell_code_states(cells_json: &Path) -> Vec<CodeState> {
    let Ok(text) = std::fs::read_to_string(cells_json) else {
        return Vec::new();
    };
    let Ok(cells) = serde_json::from_str::<Vec<serde_json::Value>>(&text) else {
        return Vec::new();
    };
    cells
        .iter()
        .map(|c| {
            serde_json::from_value::<CodeState>(c["code"].clone())
                .unwrap_or_else(|_| CodeState::legacy(&c["render"]))
        })
        .collect()
}

/// What besides the plan and the code determines a cell's image, as the binary reports it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CellInputs {
    /// `manylights info --json`'s `scene_hash`: the loaded scene.
    pub scene_hash: String,
    /// `manylights strategy --json`: the strategy's every parameter and the sampler.
    pub strategy: serde_json::Value,
    /// Render threads, for time budgets only (an spp render is the same on any count).
    pub threads: Option<usize>,
}

impl CellInputs {
    pub fn new(
        scene_hash: &str,
        strategy: &serde_json::Value,
        threads: usize,
        budget: &Budget,
    ) -> Self {
        CellInputs {
            scene_hash: scene_hash.to_string(),
            strategy: strategy.clone(),
            threads: matches!(budget, Budget::Time(_)).then_some(threads),
        }
    }
}

/// The code state a cell records (the render's commit for cells from before).
pub fn code_of(c: &CellResult) -> CodeState {
    c.code
        .clone()
        .unwrap_or_else(|| CodeState::legacy(&c.render))
}

/// What the report may write a table from.
#[derive(Clone, Debug, Default)]
pub struct Permissions {
    /// Cells rendered by a dirty build (the header then says so).
    pub allow_dirty: bool,
    /// Cells of several code states, or one scene's cells measured against several references
    /// (each such row is then marked).
    pub allow_mixed: bool,
    /// The code state of this run (`run-experiments`); cells of another are the marked ones.
    /// `None` (`merge-results`): the state most cells have.
    pub current: Option<CodeState>,
}

/// The code states and references behind a set of cells, checked.
#[derive(Clone, Debug, Default)]
pub struct Provenance {
    /// The table's code state and every other one with its cell count.
    pub main: Option<CodeState>,
    pub states: BTreeMap<CodeState, usize>,
    /// Scenes whose row mixes code states or references, with why.
    pub mixed_rows: BTreeMap<String, String>,
    pub dirty: bool,
}

impl Provenance {
    /// The check: refuses dirty cells and mixtures unless `perm` allows them.
    pub fn check(cells: &[CellResult], perm: &Permissions) -> Result<Provenance, String> {
        let mut states: BTreeMap<CodeState, usize> = BTreeMap::new();
        for c in cells {
            *states.entry(code_of(c)).or_default() += 1;
        }
        let main = perm.current.clone().or_else(|| {
            states
                .iter()
                .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
                .map(|(s, _)| s.clone())
        });
        let dirty = states.keys().any(|s| s.dirty);
        if dirty && !perm.allow_dirty {
            let which: Vec<String> = states
                .keys()
                .filter(|s| s.dirty)
                .map(CodeState::describe)
                .collect();
            return Err(format!(
                "refusing to write a table from cells rendered by {}: commit the code and render \
                 again, or pass --allow-dirty (the table then says so)",
                which.join(", ")
            ));
        }
        let mut mixed_rows: BTreeMap<String, String> = BTreeMap::new();
        let mut by_scene: BTreeMap<&str, (BTreeSet<String>, BTreeSet<&str>)> = BTreeMap::new();
        for c in cells {
            let e = by_scene.entry(c.scene.as_str()).or_default();
            e.0.insert(code_of(c).id);
            e.1.insert(c.reference.as_str());
        }
        for (scene, (codes, refs)) in &by_scene {
            let mut why = Vec::new();
            let other_code = main
                .as_ref()
                .is_some_and(|m| codes.iter().any(|c| c != &m.id));
            if other_code {
                why.push("cells of another code state".to_string());
            }
            if refs.len() > 1 {
                why.push(format!("{} references", refs.len()));
            }
            if !why.is_empty() {
                mixed_rows.insert(scene.to_string(), why.join(", "));
            }
        }
        if !mixed_rows.is_empty() && !perm.allow_mixed {
            let list: Vec<String> = mixed_rows
                .iter()
                .map(|(s, w)| format!("{s} ({w})"))
                .collect();
            return Err(format!(
                "refusing to write one table from several code states or references: {}; \
                 code states: {}. Render again at one code state (--rerender), or pass \
                 --allow-mixed (--reuse-stale for a run) to mark those rows",
                list.join("; "),
                states
                    .iter()
                    .map(|(s, n)| format!("{} ({n} cells)", s.describe()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        Ok(Provenance {
            main,
            states,
            mixed_rows,
            dirty,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(id: &str, commit: &str, dirty: bool) -> CodeState {
        CodeState {
            id: id.into(),
            commit: Some(commit.into()),
            dirty,
        }
    }

    /// `--list` says a table is today's only when every cell has today's clean code state.
    #[test]
    fn freshness_of_committed_results() {
        let now = state("tree:a", "c1", false);
        assert_eq!(Freshness::of(&[], Some(&now)), Freshness::NoResults);
        let same = [state("tree:a", "c0", false), state("tree:a", "c0", false)];
        // Another commit with the same code paths renders the same images: current.
        assert_eq!(
            Freshness::of(&same, Some(&now)),
            Freshness::Current {
                commit: "c0".into()
            }
        );
        // Two commits of one code state (only files outside the code paths changed between
        // them) are one state, named by both.
        let two_commits = [state("tree:a", "c0", false), state("tree:a", "c7", false)];
        assert_eq!(
            Freshness::of(&two_commits, Some(&now)),
            Freshness::Current {
                commit: "c0 and c7".into()
            }
        );
        let old = [state("tree:b", "c0", false)];
        assert_eq!(
            Freshness::of(&old, Some(&now)),
            Freshness::Older {
                commit: "c0".into()
            }
        );
        // A dirty tree today: nothing can be called current.
        assert!(matches!(
            Freshness::of(&same, None),
            Freshness::Older { .. }
        ));
        let mixed = [state("tree:a", "c0", false), state("tree:b", "c9", false)];
        assert_eq!(
            Freshness::of(&mixed, Some(&now)),
            Freshness::Mixed { states: 2 }
        );
        let dirty = [state("binary:x", "c0", true)];
        assert_eq!(
            Freshness::of(&dirty, Some(&now)),
            Freshness::Mixed { states: 1 }
        );
    }

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
