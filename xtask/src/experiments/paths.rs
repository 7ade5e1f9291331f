//! Where an experiment's files are: its TOML, its results, the reference cache.
//!
//! A run writes into `out/<experiment>/` and `out/references/` (ignored by git) unless it is
//! told `--publish`: then into `results/<experiment>/` and `references/`, whose tables, plots
//! and references are the committed ones. A local run starts from the committed references
//! (copied into its own cache when valid there), so a user's run never writes a tracked file.
use super::config::{self, Experiment};
use super::manylights::repo_root;
use std::path::{Path, PathBuf};

pub fn experiments_dir() -> PathBuf {
    repo_root().join("experiments")
}

pub fn resolve_experiment(name: &str) -> PathBuf {
    if name.ends_with(".toml") || name.contains('/') {
        PathBuf::from(name)
    } else {
        experiments_dir().join(format!("{name}.toml"))
    }
}

pub fn load_experiment(name: &str) -> Result<Experiment, String> {
    let path = resolve_experiment(name);
    if !path.exists() {
        let mut names: Vec<String> = std::fs::read_dir(experiments_dir())
            .map(|d| {
                d.filter_map(|e| {
                    let p = e.ok()?.path();
                    (p.extension()? == "toml")
                        .then(|| p.file_stem().map(|s| s.to_string_lossy().into_owned()))?
                })
                .collect()
            })
            .unwrap_or_default();
        names.sort();
        let hint = render_core::suggest::did_you_mean(name, names.iter().map(String::as_str));
        return Err(format!(
            "no experiment `{name}`{hint} ({} does not exist; experiments: {})",
            path.display(),
            names.join(", ")
        ));
    }
    config::load(&path)
}

/// Where a command reads and writes an experiment's results.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct OutputArgs {
    /// Write the published results: results/<experiment>/ and references/, which git tracks
    /// (their tables, plots and references); for regenerating the committed tables.
    #[arg(long, conflicts_with = "results")]
    pub publish: bool,
    /// Results directory (default out/<experiment>/, or results/<experiment>/ with --publish).
    #[arg(long)]
    pub results: Option<PathBuf>,
}

impl OutputArgs {
    /// The results directory.
    pub fn dir(&self, exp: &Experiment) -> PathBuf {
        match (&self.results, self.publish) {
            (Some(d), _) => d.clone(),
            (None, true) => published_dir(exp),
            (None, false) => local_dir(exp),
        }
    }

    /// The reference cache the command writes into.
    pub fn references(&self) -> PathBuf {
        if self.publish {
            references_dir()
        } else {
            local_references_dir()
        }
    }
}

/// The git-ignored root of local runs.
pub fn local_root() -> PathBuf {
    repo_root().join("out")
}

/// `out/<experiment>/`: where a run writes unless told otherwise.
pub fn local_dir(exp: &Experiment) -> PathBuf {
    local_root().join(&exp.name)
}

/// `results/<experiment>/`: the published tables and plots.
pub fn published_dir(exp: &Experiment) -> PathBuf {
    repo_root().join("results").join(&exp.name)
}

/// `out/references/`: the reference cache of local runs.
pub fn local_references_dir() -> PathBuf {
    local_root().join("references")
}

/// The directory of the reference `name` for reading: in `refs_dir` when there, else the
/// committed one of that name (a local report of cells scored against a committed reference).
pub fn reference_path(refs_dir: &Path, name: &str) -> PathBuf {
    let own = refs_dir.join(name);
    let published = references_dir().join(name);
    if !own.join("manifest.json").is_file() && published.join("manifest.json").is_file() {
        published
    } else {
        own
    }
}

/// Copies the committed reference `name` into the local cache `refs_dir` when the cache has
/// none (the copy is then checked as any cached reference: kept if valid, rendered again in the
/// cache if not). The half renders are not committed and not copied.
pub fn seed_reference(refs_dir: &Path, name: &str) -> Result<(), String> {
    let (from, to) = (references_dir().join(name), refs_dir.join(name));
    if from == to || to.join("manifest.json").is_file() || !from.join("manifest.json").is_file() {
        return Ok(());
    }
    std::fs::create_dir_all(&to).map_err(|e| format!("cannot create {}: {e}", to.display()))?;
    // the manifest last: a directory without one is an interrupted copy, rendered again
    for file in ["ref.exr", "mask.png", "ref.png", "manifest.json"] {
        if from.join(file).is_file() {
            std::fs::copy(from.join(file), to.join(file))
                .map_err(|e| format!("cannot copy {}: {e}", from.join(file).display()))?;
        }
    }
    Ok(())
}

/// `references/`: the committed reference cache.
pub fn references_dir() -> PathBuf {
    repo_root().join("references")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::process::Command;

    /// What a local run writes is ignored by git, and of the published results only the
    /// tables, plots and references are not.
    #[test]
    fn local_output_is_ignored_by_git() {
        let root = repo_root();
        let exp = load_experiment("quick").unwrap();
        let rel = |p: PathBuf| {
            p.strip_prefix(&root)
                .expect("under the repository")
                .to_string_lossy()
                .into_owned()
        };
        let local = rel(OutputArgs::default().dir(&exp));
        let published = rel(published_dir(&exp));
        let refs = rel(local_references_dir());
        let ignored = |path: &str| -> Option<bool> {
            let out = Command::new("git")
                .args(["check-ignore", "-q", "--no-index", path])
                .current_dir(&root)
                .output()
                .ok()?;
            match out.status.code() {
                Some(0) => Some(true),
                Some(1) => Some(false),
                _ => None,
            }
        };
        if ignored(&local).is_none() {
            println!(
                "NOTICE: git is absent or this is not a git checkout: ignore rules not checked"
            );
            return;
        }
        for f in [
            "",
            "/table.md",
            "/cells.csv",
            "/index.html",
            "/cells/x.json",
            "/plots/s.png",
        ] {
            assert_eq!(ignored(&format!("{local}{f}")), Some(true), "{local}{f}");
        }
        assert_eq!(ignored(&format!("{refs}/s-0/ref.exr")), Some(true));
        for f in [
            "cells/x.json",
            "cells.json",
            "viewer/s.js",
            "index.html",
            "strips/s.png",
            "error-maps/s__a.png",
            "flip-maps/s__a.png",
            "renders/x.exr",
            "notices.json",
        ] {
            assert_eq!(
                ignored(&format!("{published}/{f}")),
                Some(true),
                "{published}/{f}"
            );
        }
        for f in ["table.md", "cells.csv", "plots/s.png"] {
            assert_eq!(
                ignored(&format!("{published}/{f}")),
                Some(false),
                "{published}/{f}"
            );
        }
    }

    /// A local cache starts from a committed reference: its files copied, the manifest among
    /// them; one already there is left alone; a name with no committed reference copies nothing.
    #[test]
    fn a_committed_reference_seeds_the_local_cache() {
        let Some(name) = std::fs::read_dir(references_dir()).ok().and_then(|d| {
            d.flatten()
                .find(|e| e.path().join("manifest.json").is_file())
                .map(|e| e.file_name().to_string_lossy().into_owned())
        }) else {
            println!("NOTICE: no committed reference: seeding not checked");
            return;
        };
        let cache = std::env::temp_dir().join(format!("xtask-seed-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&cache);
        seed_reference(&cache, &name).unwrap();
        for f in ["manifest.json", "ref.exr", "mask.png"] {
            let copy = std::fs::read(cache.join(&name).join(f)).unwrap();
            assert_eq!(
                copy,
                std::fs::read(references_dir().join(&name).join(f)).unwrap()
            );
        }
        assert_eq!(reference_path(&cache, &name), cache.join(&name));
        std::fs::write(cache.join(&name).join("ref.png"), "mine").unwrap();
        seed_reference(&cache, &name).unwrap();
        let kept = std::fs::read_to_string(cache.join(&name).join("ref.png")).unwrap();
        assert_eq!(kept, "mine", "a cached reference is not overwritten");
        seed_reference(&cache, "no-such-reference").unwrap();
        assert!(!cache.join("no-such-reference").exists());
        // a report without the local copy reads the committed one
        let empty = cache.join("empty");
        assert_eq!(reference_path(&empty, &name), references_dir().join(&name));
        std::fs::remove_dir_all(&cache).unwrap();
    }
}
