//! The checks the report and `merge-results` make before writing one table from many cells
//! (one code state, one reference per scene, no dirty build unless allowed), and how the
//! published results of an experiment stand against today's code (`--list`).
use super::cell::CellResult;
use super::code_state::CodeState;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

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

/// The code states of the cells in a `cells.csv` (empty if there is none): its columns
/// `code_state`, `code_commit`, `code_dirty`.
pub fn cell_code_states(cells_csv: &Path) -> Vec<CodeState> {
    let Ok(mut reader) = csv::Reader::from_path(cells_csv) else {
        return Vec::new();
    };
    let Ok(header) = reader.headers().cloned() else {
        return Vec::new();
    };
    let col = |name: &str| header.iter().position(|h| h == name);
    let (Some(id), Some(commit), Some(dirty)) =
        (col("code_state"), col("code_commit"), col("code_dirty"))
    else {
        return Vec::new();
    };
    reader
        .records()
        .flatten()
        .map(|r| CodeState {
            id: r[id].to_string(),
            commit: (!r[commit].is_empty()).then(|| r[commit].to_string()),
            dirty: &r[dirty] == "true",
        })
        .collect()
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
            *states.entry(c.code_state()).or_default() += 1;
        }
        let most = |same: &dyn Fn(&CodeState) -> bool| {
            states
                .iter()
                .filter(|(s, _)| same(s))
                .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
                .map(|(s, _)| s.clone())
        };
        // A run that rendered nothing (every cell reused from a commit with the same code) names
        // the commit that rendered them, not its own.
        let main = match &perm.current {
            Some(cur) if !states.contains_key(cur) => {
                Some(most(&|s: &CodeState| s.id == cur.id).unwrap_or_else(|| cur.clone()))
            }
            Some(cur) => Some(cur.clone()),
            None => most(&|_: &CodeState| true),
        };
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
            e.0.insert(c.code_state().id);
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

    /// `--list` reads the code states from the published cells.csv.
    #[test]
    fn code_states_from_cells_csv() {
        use crate::experiments::cell::testing::{cell_result, code};
        let path = std::env::temp_dir().join(format!("xtask-states-{}.csv", std::process::id()));
        let mut dirty = cell_result("b", "r", "binary:1");
        dirty.code = Some(code("binary:1", true));
        let cells = [cell_result("a", "r", "tree:x"), dirty];
        crate::experiments::report::write_csv(&path, &cells).unwrap();
        let states = cell_code_states(&path);
        let expected: Vec<CodeState> = cells.iter().map(|c| c.code_state()).collect();
        assert_eq!(states, expected);
        assert!(cell_code_states(&path.with_extension("absent")).is_empty());
        let _ = std::fs::remove_file(&path);
    }
}
