//! Where an experiment's files are: its TOML, its results, the reference cache.
use super::config::{self, Experiment};
use super::manylights::repo_root;
use std::path::PathBuf;

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
        return Err(format!(
            "no experiment `{name}` ({} does not exist); experiments: {}",
            path.display(),
            names.join(", ")
        ));
    }
    config::load(&path)
}

pub fn results_dir(exp: &Experiment, given: &Option<PathBuf>) -> PathBuf {
    given
        .clone()
        .unwrap_or_else(|| repo_root().join("results").join(&exp.name))
}

/// `references/`: the committed reference cache.
pub fn references_dir() -> PathBuf {
    repo_root().join("references")
}
