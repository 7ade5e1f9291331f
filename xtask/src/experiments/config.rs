//! `experiments/NAME.toml`: what an experiment renders.
//!
//! ```toml
//! description = "what it shows"
//! width = 128                # default resolution of every scene
//! height = 96
//! seeds = [0, 1]             # one cell per seed; several give mean ± std
//! spp = [4, 16]              # equal-spp cells
//! time_budgets = [2.0]       # equal-time cells (seconds, `--time-budget`)
//! budget_clock = "cpu"       # what a time budget counts: "cpu" (default: process CPU time per
//!                            # worker thread, fair on a shared machine) or "wall"
//! baseline = "E&K"           # the column speed-ups are measured against
//!
//! [reference]
//! strategy = "power+bsdf"    # a robust unbiased strategy
//! spp = 1024                 # total: two halves of spp/2 with different seeds, averaged
//! seed = 1000000
//!
//! [[scenes]]
//! label = "glossy-spheres"
//! spec = "builtin:glossy-spheres?lights=4096"   # or a glTF path relative to the repository root
//!
//! [[strategies]]
//! label = "E&K"
//! name = "tree-split+bsdf"
//! params = { tau = 0.85 }    # becomes `--tau 0.85`; `args = ["--flag"]` passes raw flags
//! ```
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// File stem; filled in by [`load`].
    #[serde(skip)]
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub width: u32,
    pub height: u32,
    #[serde(default = "default_seeds")]
    pub seeds: Vec<u64>,
    #[serde(default)]
    pub spp: Vec<u32>,
    #[serde(default)]
    pub time_budgets: Vec<f64>,
    /// What the time budgets count (`manylights render --budget-clock`).
    #[serde(default)]
    pub budget_clock: BudgetClock,
    /// Label of the column that speed-ups are relative to (default: the first strategy).
    #[serde(default)]
    pub baseline: Option<String>,
    /// Render threads (default: all cores).
    #[serde(default)]
    pub threads: Option<usize>,
    pub reference: ReferenceSpec,
    pub scenes: Vec<SceneEntry>,
    pub strategies: Vec<StrategyEntry>,
}

/// `cpu`: the render process's CPU seconds divided by its worker threads, so that other jobs on
/// the machine do not shorten some equal-time cells and not others; `wall`: elapsed time.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum BudgetClock {
    #[default]
    Cpu,
    Wall,
}

impl BudgetClock {
    pub fn cli_name(self) -> &'static str {
        match self {
            BudgetClock::Cpu => "cpu",
            BudgetClock::Wall => "wall",
        }
    }
}

fn default_seeds() -> Vec<u64> {
    vec![0]
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    pub strategy: String,
    #[serde(default)]
    pub params: BTreeMap<String, toml::Value>,
    #[serde(default)]
    pub args: Vec<String>,
    /// Total samples per pixel (each of the two halves renders spp / 2).
    pub spp: u32,
    #[serde(default = "default_reference_seed")]
    pub seed: u64,
}

fn default_reference_seed() -> u64 {
    1_000_000
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneEntry {
    /// Row name in tables and file names (default: derived from `spec`).
    #[serde(default)]
    pub label: Option<String>,
    /// `builtin:NAME?key=value&…`, or a scene file path relative to the repository root.
    pub spec: String,
    #[serde(default)]
    pub camera: Option<String>,
    #[serde(default)]
    pub width: Option<u32>,
    #[serde(default)]
    pub height: Option<u32>,
    /// Inset squares of the comparison strip, `[x, y, size]` in pixels (default: chosen where the
    /// baseline's error is largest).
    #[serde(default)]
    pub insets: Vec<[u32; 3]>,
    /// Reference spp for this scene instead of `[reference] spp` (a scene whose reference
    /// converges slowly, without making every other scene's reference longer).
    #[serde(default)]
    pub reference_spp: Option<u32>,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StrategyEntry {
    /// Column name (unique); ablations of one strategy get one label each.
    pub label: String,
    /// The `manylights render --strategy` name.
    pub name: String,
    /// Strategy parameters, passed as `--key value` (underscores become hyphens; `true` → `--key`).
    #[serde(default)]
    pub params: BTreeMap<String, toml::Value>,
    /// Extra raw flags.
    #[serde(default)]
    pub args: Vec<String>,
    /// Render at the experiment's time budgets too (default); `false` for a strategy measured at
    /// equal spp only (the O(lights)-per-point oracle, too slow for equal time by design).
    #[serde(default = "yes")]
    pub equal_time: bool,
}

fn yes() -> bool {
    true
}

impl StrategyEntry {
    pub fn cli_args(&self) -> Result<Vec<String>, String> {
        params_to_args(&self.params, &self.args)
    }
}

impl ReferenceSpec {
    pub fn cli_args(&self) -> Result<Vec<String>, String> {
        params_to_args(&self.params, &self.args)
    }
}

/// `{ max_cut = 8, reproduce = true }` → `--max-cut 8 --reproduce`, then `extra`.
pub fn params_to_args(
    params: &BTreeMap<String, toml::Value>,
    extra: &[String],
) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    for (k, v) in params {
        let flag = format!("--{}", k.replace('_', "-"));
        match v {
            toml::Value::Boolean(true) => out.push(flag),
            toml::Value::Boolean(false) => {}
            toml::Value::String(s) => out.extend([flag, s.clone()]),
            toml::Value::Integer(i) => out.extend([flag, i.to_string()]),
            toml::Value::Float(f) => out.extend([flag, f.to_string()]),
            other => {
                return Err(format!(
                    "parameter `{k}` must be a string, number or boolean, not {}",
                    other.type_str()
                ));
            }
        }
    }
    out.extend(extra.iter().cloned());
    Ok(out)
}

impl SceneEntry {
    pub fn label(&self) -> String {
        self.label
            .clone()
            .unwrap_or_else(|| label_from_spec(&self.spec))
    }
    pub fn is_builtin(&self) -> bool {
        self.spec.starts_with("builtin:")
    }
}

/// `builtin:grid?lights=100` → `grid-lights=100`; `../shared/scenes/x/y.glb` → `y`.
pub fn label_from_spec(spec: &str) -> String {
    if let Some(rest) = spec.strip_prefix("builtin:") {
        let (name, query) = rest.split_once('?').unwrap_or((rest, ""));
        if query.is_empty() {
            name.to_string()
        } else {
            format!("{name}-{}", query.replace('&', "-"))
        }
    } else {
        Path::new(spec)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| spec.to_string())
    }
}

/// Loads and validates `path`; the experiment's name is the file stem.
pub fn load(path: &Path) -> Result<Experiment, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    parse(&name, &text).map_err(|e| format!("{}: {e}", path.display()))
}

pub fn parse(name: &str, text: &str) -> Result<Experiment, String> {
    let mut exp: Experiment = toml::from_str(text).map_err(|e| e.to_string())?;
    exp.name = name.to_string();
    validate(&exp)?;
    Ok(exp)
}

fn validate(e: &Experiment) -> Result<(), String> {
    if e.width == 0 || e.height == 0 {
        return Err("width and height must be positive".into());
    }
    if e.seeds.is_empty() {
        return Err("`seeds` must list at least one seed".into());
    }
    if e.spp.is_empty() && e.time_budgets.is_empty() {
        return Err("give `spp` (equal-spp cells) and/or `time_budgets` (equal-time cells)".into());
    }
    if e.spp.contains(&0) {
        return Err("every entry of `spp` must be at least 1".into());
    }
    if let Some(t) = e
        .time_budgets
        .iter()
        .find(|t| !(t.is_finite() && **t > 0.0))
    {
        return Err(format!(
            "time budget {t} is not a positive number of seconds"
        ));
    }
    if e.reference.spp < 2 {
        return Err("reference.spp must be at least 2 (it is split into two halves)".into());
    }
    if let Some(s) = e
        .scenes
        .iter()
        .find(|s| s.reference_spp.is_some_and(|n| n < 2))
    {
        return Err(format!(
            "scene {}: reference_spp must be at least 2 (it is split into two halves)",
            s.label()
        ));
    }
    if e.scenes.is_empty() {
        return Err("no [[scenes]]".into());
    }
    if e.strategies.is_empty() {
        return Err("no [[strategies]]".into());
    }
    e.reference
        .cli_args()
        .map_err(|m| format!("reference: {m}"))?;
    let mut labels = std::collections::BTreeSet::new();
    for s in &e.strategies {
        if s.label.trim().is_empty() || s.name.trim().is_empty() {
            return Err("every strategy needs a non-empty `label` and `name`".into());
        }
        if !labels.insert(s.label.clone()) {
            return Err(format!("strategy label `{}` is used twice", s.label));
        }
        s.cli_args()
            .map_err(|m| format!("strategy `{}`: {m}", s.label))?;
    }
    let mut scene_labels = std::collections::BTreeSet::new();
    for s in &e.scenes {
        if s.spec.trim().is_empty() {
            return Err("a scene has an empty `spec`".into());
        }
        if !scene_labels.insert(s.label()) {
            return Err(format!("scene label `{}` is used twice", s.label()));
        }
        if s.width == Some(0) || s.height == Some(0) {
            return Err(format!(
                "scene `{}`: width and height must be positive",
                s.label()
            ));
        }
    }
    if let Some(b) = &e.baseline
        && !labels.contains(b)
    {
        return Err(format!(
            "baseline `{b}` is not a strategy label (labels: {})",
            labels.into_iter().collect::<Vec<_>>().join(", ")
        ));
    }
    Ok(())
}

impl Experiment {
    pub fn baseline(&self) -> &str {
        self.baseline
            .as_deref()
            .unwrap_or(self.strategies[0].label.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
        description = "test"
        width = 32
        height = 24
        seeds = [0, 1]
        spp = [4, 16]
        time_budgets = [0.5]
        baseline = "E&K"
        [reference]
        strategy = "power+bsdf"
        spp = 64
        [[scenes]]
        spec = "builtin:glossy-spheres?lights=64"
        [[scenes]]
        label = "cornell-real"
        spec = "../shared/scenes/cornell_box/cornell_box.glb"
        reference_spp = 256
        [[strategies]]
        label = "E&K"
        name = "tree-split+bsdf"
        params = { tau = 0.85, max_cut = 8 }
        [[strategies]]
        label = "ours λ=1"
        name = "mis3-adaptive"
        params = { lambda = 1.0, reproduce = true, brdf_integral = "ltc" }
        args = ["--n-max", "10"]
    "#;

    #[test]
    fn parses_a_good_file() {
        let e = parse("t", GOOD).unwrap();
        assert_eq!(e.name, "t");
        assert_eq!(e.seeds, vec![0, 1]);
        assert_eq!(e.reference.seed, 1_000_000);
        assert_eq!(e.scenes[0].label(), "glossy-spheres-lights=64");
        assert_eq!(e.scenes[1].label(), "cornell-real");
        assert_eq!(
            (e.scenes[0].reference_spp, e.scenes[1].reference_spp),
            (None, Some(256))
        );
        assert_eq!(e.baseline(), "E&K");
        assert_eq!(
            e.strategies[0].cli_args().unwrap(),
            ["--max-cut", "8", "--tau", "0.85"]
        );
        assert_eq!(
            e.strategies[1].cli_args().unwrap(),
            [
                "--brdf-integral",
                "ltc",
                "--lambda",
                "1",
                "--reproduce",
                "--n-max",
                "10"
            ]
        );
    }

    fn err(text: &str) -> String {
        parse("t", text).unwrap_err()
    }

    #[test]
    fn bad_files_give_clear_errors() {
        assert!(err("width = ").contains("line 1"), "{}", err("width = "));
        let unknown = GOOD.replace("seeds = [0, 1]", "seedz = [0, 1]");
        assert!(err(&unknown).contains("seedz"), "{}", err(&unknown));
        let missing = GOOD.replace("width = 32", "");
        assert!(err(&missing).contains("width"), "{}", err(&missing));
        let dup = GOOD.replace("ours λ=1", "E&K");
        assert!(err(&dup).contains("used twice"));
        let base = GOOD.replace("baseline = \"E&K\"", "baseline = \"nope\"");
        assert!(err(&base).contains("baseline `nope`"));
        let nothing = GOOD
            .replace("spp = [4, 16]", "")
            .replace("time_budgets = [0.5]", "");
        assert!(err(&nothing).contains("time_budgets"));
        let zero = GOOD.replace("spp = [4, 16]", "spp = [0]");
        assert!(err(&zero).contains("at least 1"));
        let neg = GOOD.replace("time_budgets = [0.5]", "time_budgets = [-1.0]");
        assert!(err(&neg).contains("positive"));
        let ref1 = GOOD.replace("spp = 64", "spp = 1");
        assert!(err(&ref1).contains("two halves"));
        let scene_ref1 = GOOD.replace("reference_spp = 256", "reference_spp = 1");
        assert!(err(&scene_ref1).contains("cornell-real: reference_spp"));
        let table = GOOD.replace("max_cut = 8", "max_cut = [8]");
        assert!(err(&table).contains("max_cut"), "{}", err(&table));
        let typ = GOOD.replace("width = 32", "width = \"wide\"");
        assert!(err(&typ).contains("width"), "{}", err(&typ));
    }

    #[test]
    fn shipped_experiments_parse() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../experiments");
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let p = entry.unwrap().path();
            if p.extension().is_some_and(|x| x == "toml") {
                load(&p).unwrap();
                n += 1;
            }
        }
        assert!(n >= 5, "expected the five shipped experiments, found {n}");
    }
}
