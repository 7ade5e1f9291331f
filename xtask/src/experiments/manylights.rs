//! Runs the release `manylights` binary: every render is its own process, so its wall time is
//! honest and a crash loses only that cell.
use indicatif::ProgressBar;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The repository root (xtask lives in `ROOT/xtask`).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask is inside the repository")
        .to_path_buf()
}

/// Why a render or a scene query did not give a result.
#[derive(Debug, Clone, PartialEq)]
pub enum Failure {
    /// Something that does not exist yet (strategy, built-in scene, flag): reported, not an error.
    Skip(String),
    Error(String),
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::Skip(m) => write!(f, "skipped: {m}"),
            Failure::Error(m) => write!(f, "error: {m}"),
        }
    }
}

/// Classifies manylights' stderr: things that are not there yet are skips.
pub fn classify(stderr: &str) -> Failure {
    let last = stderr
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("")
        .trim()
        .to_string();
    let lower = stderr.to_lowercase();
    if lower.contains("unknown built-in scene") || lower.contains("unknown builtin") {
        Failure::Skip(last)
    } else if lower.contains("no such file or directory") {
        Failure::Skip(format!("a file is absent: {last}"))
    } else if lower.contains("unexpected argument") {
        Failure::Skip(format!(
            "this manylights does not take the flag yet: {last}"
        ))
    } else {
        Failure::Error(if last.is_empty() {
            "manylights failed with no message".into()
        } else {
            stderr.trim().to_string()
        })
    }
}

pub struct Manylights {
    pub exe: PathBuf,
    pub root: PathBuf,
}

impl Manylights {
    /// Builds `manylights` in release mode (with the cargo that runs xtask) and finds it beside
    /// the xtask binary.
    pub fn build() -> Result<Self, String> {
        let root = repo_root();
        eprintln!("building manylights (release)…");
        let status = Command::new(env!("CARGO"))
            .args(["build", "--release", "-p", "manylights"])
            .current_dir(&root)
            .status()
            .map_err(|e| format!("cannot run cargo: {e}"))?;
        if !status.success() {
            return Err("`cargo build --release -p manylights` failed".into());
        }
        let me = std::env::current_exe().map_err(|e| e.to_string())?;
        let mut dir = me.parent().map(Path::to_path_buf).unwrap_or_default();
        if dir.ends_with("deps") {
            dir.pop();
        }
        let exe = dir.join(format!("manylights{}", std::env::consts::EXE_SUFFIX));
        let exe = if exe.exists() {
            exe
        } else {
            root.join("target/release/manylights")
        };
        if !exe.exists() {
            return Err(format!(
                "built manylights but cannot find {}",
                exe.display()
            ));
        }
        Ok(Manylights { exe, root })
    }

    /// The debug `manylights` beside a test binary (target/debug/deps/…), built first: the
    /// harness's tests render tiny scenes with it.
    #[cfg(test)]
    pub fn for_tests() -> Self {
        use std::sync::OnceLock;
        static BUILT: OnceLock<bool> = OnceLock::new();
        let root = repo_root();
        let ok = *BUILT.get_or_init(|| {
            Command::new(env!("CARGO"))
                .args(["build", "--quiet", "-p", "manylights"])
                .current_dir(&root)
                .status()
                .is_ok_and(|s| s.success())
        });
        assert!(ok, "`cargo build -p manylights` failed");
        let me = std::env::current_exe().unwrap();
        let dir = me.parent().unwrap().parent().unwrap();
        let exe = dir.join(format!("manylights{}", std::env::consts::EXE_SUFFIX));
        assert!(exe.exists(), "no {}", exe.display());
        Manylights { exe, root }
    }

    fn command(&self) -> Command {
        let mut c = Command::new(&self.exe);
        c.current_dir(&self.root);
        c
    }

    fn output(&self, args: &[&str]) -> Result<String, Failure> {
        let out = self
            .command()
            .args(args)
            .output()
            .map_err(|e| Failure::Error(format!("cannot run manylights: {e}")))?;
        if out.status.success() {
            Ok(String::from_utf8_lossy(&out.stdout).into_owned())
        } else {
            Err(classify(&String::from_utf8_lossy(&out.stderr)))
        }
    }

    /// The name of every strategy `manylights strategies` lists.
    pub fn strategies(&self) -> Result<Vec<String>, String> {
        let text = self.output(&["strategies"]).map_err(|e| e.to_string())?;
        Ok(parse_strategies(&text))
    }

    /// The text of `manylights render --help`, to check that strategy flags exist.
    pub fn render_help(&self) -> String {
        self.output(&["render", "--help"]).unwrap_or_default()
    }

    /// `manylights strategy --strategy NAME ARGS… --json`: the strategy's resolved parameters
    /// and sampler.
    pub fn resolved_strategy(
        &self,
        name: &str,
        args: &[String],
    ) -> Result<serde_json::Value, Failure> {
        let mut all: Vec<&str> = vec!["strategy", "--json", "--strategy", name];
        all.extend(args.iter().map(String::as_str));
        let text = self.output(&all)?;
        serde_json::from_str(&text)
            .map_err(|e| Failure::Error(format!("bad `manylights strategy` JSON: {e}")))
    }

    /// `manylights info SPEC --json`.
    pub fn info(&self, spec: &str) -> Result<serde_json::Value, Failure> {
        let text = self.output(&["info", spec, "--json"])?;
        serde_json::from_str(&text).map_err(|e| Failure::Error(format!("bad info JSON: {e}")))
    }

    /// Runs one render to `out` (an EXR; its JSON is read back and returned), ticking `bar`.
    /// `expected_seconds` (for time budgets) turns the bar into a fraction.
    pub fn render(
        &self,
        args: &[String],
        out: &Path,
        bar: &ProgressBar,
        expected_seconds: Option<f64>,
    ) -> Result<serde_json::Value, Failure> {
        let stderr_path = out.with_extension("stderr.txt");
        let stderr_file = std::fs::File::create(&stderr_path)
            .map_err(|e| Failure::Error(format!("cannot create {}: {e}", stderr_path.display())))?;
        let mut child = self
            .command()
            .arg("render")
            .args(args)
            .arg("--out")
            .arg(out)
            .arg("--quiet")
            .stdout(Stdio::null())
            .stderr(stderr_file)
            .spawn()
            .map_err(|e| Failure::Error(format!("cannot run manylights: {e}")))?;
        let start = Instant::now();
        let status = loop {
            match child.try_wait() {
                Ok(Some(s)) => break s,
                Ok(None) => {
                    if let Some(t) = expected_seconds {
                        let frac = (start.elapsed().as_secs_f64() / t).min(1.0);
                        bar.set_position((frac * 1000.0) as u64);
                    }
                    bar.tick();
                    std::thread::sleep(Duration::from_millis(100));
                }
                Err(e) => return Err(Failure::Error(format!("waiting for manylights: {e}"))),
            }
        };
        let stderr = std::fs::read_to_string(&stderr_path).unwrap_or_default();
        let _ = std::fs::remove_file(&stderr_path);
        if !status.success() {
            return Err(classify(&stderr));
        }
        let json_path = out.with_extension("json");
        let text = std::fs::read_to_string(&json_path)
            .map_err(|e| Failure::Error(format!("cannot read {}: {e}", json_path.display())))?;
        serde_json::from_str(&text)
            .map_err(|e| Failure::Error(format!("bad JSON {}: {e}", json_path.display())))
    }
}

pub fn parse_strategies(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| Some(l.split_whitespace().next()?.to_string()))
        .collect()
}

/// The flags in `args` (words starting with `--`) that `help` does not mention.
pub fn unsupported_flags(args: &[String], help: &str) -> Vec<String> {
    args.iter()
        .filter(|a| a.starts_with("--"))
        .filter(|a| {
            let flag = a.split('=').next().unwrap_or(a);
            !help
                .split(|c: char| c.is_whitespace() || c == ',' || c == '[' || c == '=')
                .any(|w| w == flag)
        })
        .cloned()
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strategies_list() {
        let s = parse_strategies(
            "tree-split+bsdf    adaptive splitting\nmis3-adaptive      Liu et al.\n",
        );
        assert_eq!(s, vec!["tree-split+bsdf", "mis3-adaptive"]);
    }

    #[test]
    fn failures_are_classified() {
        assert!(matches!(
            classify("error: unknown built-in scene `car` (known: a, b)"),
            Failure::Skip(_)
        ));
        assert!(matches!(
            classify("error: unexpected argument '--lambda' found"),
            Failure::Skip(_)
        ));
        assert!(matches!(
            classify(
                "error: cannot read scene file a/../../shared/scenes/x.glb: No such file or directory (os error 2)"
            ),
            Failure::Skip(_)
        ));
        assert!(matches!(classify("error: disk full"), Failure::Error(_)));
    }

    #[test]
    fn flags_are_checked_against_help() {
        let help = "      --spp <SPP>\n      --tau <TAU>  threshold\n  -q, --quiet\n";
        let args: Vec<String> = ["--tau", "0.5", "--lambda", "1", "--quiet"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(unsupported_flags(&args, help), vec!["--lambda".to_string()]);
    }
}
