//! `cargo xtask yardstick`: the marginal CPU cost of one camera sample, ours against Mitsuba 3,
//! in one sitting (issue 55's first measure; docs/notes/cost.md). The scene is written as a
//! glTF (`manylights convert`) so that both renderers read the same triangles; each round
//! renders it at a low and a high spp with every strategy asked for and with Mitsuba's
//! vectorised `direct` integrator (`../shared/yardsticks/mitsuba/render_mitsuba.py`, power
//! light sampling + BSDF sampling: our `power+bsdf`), one thread, the renderers in turn. The
//! marginal cost is (CPU at high − CPU at low) / ((high − low) · width · height): it leaves out
//! loading, the BVH build and Mitsuba's JIT. Per round and the median over rounds are printed
//! and written to `--out` (CSV, written whole under a temporary name, then renamed).
//!
//! Mitsuba is optional: where its Python cannot run the yardstick, the command says so and
//! measures ours alone. Pin the renders to one core (`--pin`) on a machine shared with others.
use crate::experiments::manylights::{Manylights, repo_root};
use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

#[derive(Parser, Debug)]
#[command(
    name = "cargo xtask yardstick",
    about = "Marginal CPU per camera sample, ours against Mitsuba 3 (llvm_ad_rgb), one thread, in one sitting"
)]
pub struct Args {
    /// Scene to measure (written as glTF for both renderers).
    #[arg(long, default_value = "builtin:emissive-mesh")]
    scene: String,
    /// Our strategies to time (repeat the flag for more).
    #[arg(long = "strategy", default_values_t = ["power+bsdf".to_string()])]
    strategies: Vec<String>,
    /// Rounds; the median over them is reported.
    #[arg(long, default_value_t = 3)]
    rounds: u32,
    /// The low and high sample counts, `LO,HI`.
    #[arg(long, default_value = "64,256", value_parser = parse_spp)]
    spp: (u32, u32),
    #[arg(long, default_value_t = 128)]
    width: u32,
    #[arg(long, default_value_t = 128)]
    height: u32,
    /// Pin every render to this CPU (`taskset -c`).
    #[arg(long)]
    pin: Option<u32>,
    /// The Python that has Mitsuba 3 (`MITSUBA_PYTHON` if set, else `python3`).
    #[arg(long)]
    mitsuba_python: Option<String>,
    /// The yardstick's directory (`render_mitsuba.py`).
    #[arg(long, default_value = "../shared/yardsticks/mitsuba")]
    yardstick: PathBuf,
    /// Time ours only.
    #[arg(long)]
    no_mitsuba: bool,
    /// The CSV to write.
    #[arg(long, default_value = "out/yardstick/marginal.csv")]
    out: PathBuf,
}

impl Args {
    /// `--mitsuba-python`, else `MITSUBA_PYTHON`, else `python3`.
    fn python(&self) -> String {
        (self.mitsuba_python.clone())
            .or_else(|| std::env::var("MITSUBA_PYTHON").ok())
            .unwrap_or_else(|| "python3".into())
    }
}

/// `LO,HI` with 0 < LO < HI.
fn parse_spp(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("--spp wants LO,HI with 0 < LO < HI, got `{s}`");
    let (lo, hi) = s.split_once(',').ok_or_else(bad)?;
    let (lo, hi) = (lo.trim().parse::<u32>(), hi.trim().parse::<u32>());
    match (lo, hi) {
        (Ok(lo), Ok(hi)) if 0 < lo && lo < hi => Ok((lo, hi)),
        _ => Err(bad()),
    }
}

pub fn main(args: &[String]) -> ExitCode {
    crate::run_subcommand(args, run)
}

/// One renderer's CPU seconds at the low and high spp in one round.
#[derive(Debug, Clone, PartialEq)]
pub struct Timing {
    pub renderer: String,
    pub round: u32,
    pub cpu: (f64, f64),
}

impl Timing {
    /// Microseconds of CPU per camera sample between the two spp.
    pub fn marginal_us(&self, (lo, hi): (u32, u32), pixels: u64) -> f64 {
        (self.cpu.1 - self.cpu.0) / ((hi - lo) as u64 * pixels) as f64 * 1e6
    }
}

fn run(a: &Args) -> Result<(), String> {
    let root = repo_root();
    let ml = Manylights::build()?;
    let tmp = std::env::temp_dir().join(format!("manylights-yardstick-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).map_err(|e| e.to_string())?;
    let result = measure(a, &root, &ml.exe, &tmp);
    let _ = std::fs::remove_dir_all(&tmp);
    let timings = result?;
    let pixels = a.width as u64 * a.height as u64;
    print!("{}", summary(&timings, a.spp, pixels));
    let out = if a.out.is_absolute() {
        a.out.clone()
    } else {
        root.join(&a.out)
    };
    write_csv(&out, &timings, a, &commit(&root))?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

/// Every round's timings, ours and (unless unavailable) Mitsuba's.
fn measure(a: &Args, root: &Path, exe: &Path, tmp: &Path) -> Result<Vec<Timing>, String> {
    let glb = tmp.join("scene.glb");
    run_ok(
        Command::new(exe)
            .current_dir(root)
            .arg("convert")
            .arg(&a.scene)
            .arg(&glb),
    )?;
    let script = root.join(&a.yardstick).join("render_mitsuba.py");
    let mitsuba = !a.no_mitsuba && mitsuba_runs(a, &script);
    let mut out = Vec::new();
    for round in 1..=a.rounds {
        let mut cpu: Vec<(String, [f64; 2])> = Vec::new();
        for (k, spp) in [a.spp.0, a.spp.1].into_iter().enumerate() {
            for s in &a.strategies {
                let t = ours(a, exe, (&glb, tmp), s, spp)?;
                slot(&mut cpu, s)[k] = t;
            }
            if mitsuba {
                slot(&mut cpu, "mitsuba llvm_ad_rgb")[k] = theirs(a, &script, (&glb, tmp), spp)?;
            }
        }
        for (renderer, [lo, hi]) in cpu {
            eprintln!("round {round}: {renderer} {lo:.3} / {hi:.3} CPU-s");
            out.push(Timing {
                renderer,
                round,
                cpu: (lo, hi),
            });
        }
    }
    Ok(out)
}

/// The pair of times of `name`, added if new.
fn slot<'a>(cpu: &'a mut Vec<(String, [f64; 2])>, name: &str) -> &'a mut [f64; 2] {
    let i = match cpu.iter().position(|(n, _)| n == name) {
        Some(i) => i,
        None => {
            cpu.push((name.to_string(), [0.0; 2]));
            cpu.len() - 1
        }
    };
    &mut cpu[i].1
}

/// A command, pinned when asked.
fn pinned(a: &Args, program: &Path) -> Command {
    match a.pin {
        Some(cpu) => {
            let mut c = Command::new("taskset");
            c.arg("-c").arg(cpu.to_string()).arg(program);
            c
        }
        None => Command::new(program),
    }
}

/// Our render's CPU seconds (the render itself, from its JSON).
fn ours(
    a: &Args,
    exe: &Path,
    (glb, tmp): (&Path, &Path),
    strategy: &str,
    spp: u32,
) -> Result<f64, String> {
    let exr = tmp.join("ours.exr");
    run_ok(
        pinned(a, exe)
            .args(["render", &glb.to_string_lossy(), "--strategy", strategy])
            .args([
                "--spp",
                &spp.to_string(),
                "--threads",
                "1",
                "--seed",
                "1",
                "--quiet",
            ])
            .args([
                "--width",
                &a.width.to_string(),
                "--height",
                &a.height.to_string(),
            ])
            .arg("--out")
            .arg(&exr),
    )?;
    let json = std::fs::read_to_string(exr.with_extension("json")).map_err(|e| e.to_string())?;
    let v: serde_json::Value = serde_json::from_str(&json).map_err(|e| e.to_string())?;
    v["cpu_seconds"]
        .as_f64()
        .ok_or_else(|| "the render's JSON has no cpu_seconds".to_string())
}

/// Whether the yardstick's Python imports Mitsuba; says why not where it does not.
fn mitsuba_runs(a: &Args, script: &Path) -> bool {
    if !script.exists() {
        eprintln!("no {}: timing ours alone", script.display());
        return false;
    }
    let ok = Command::new(a.python())
        .args(["-c", "import mitsuba"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!(
            "`{} -c 'import mitsuba'` fails (set --mitsuba-python or MITSUBA_PYTHON): timing ours alone",
            a.python()
        );
    }
    ok
}

/// Mitsuba's render CPU seconds (its RESULT line's `render_cpu_s`, after a warm-up render).
fn theirs(a: &Args, script: &Path, (glb, tmp): (&Path, &Path), spp: u32) -> Result<f64, String> {
    let python = a.python();
    let mut c = pinned(a, Path::new(&python));
    c.arg(script)
        .arg(glb)
        .args([
            "--variant",
            "llvm_ad_rgb",
            "--spp",
            &spp.to_string(),
            "--threads",
            "1",
        ])
        .args([
            "--width",
            &a.width.to_string(),
            "--height",
            &a.height.to_string(),
        ])
        .arg("--warmup")
        .arg("--out")
        .arg(tmp.join("mitsuba.exr"));
    result_cpu(&run_ok(&mut c)?)
}

/// `render_cpu_s` of the yardstick's `RESULT {json}` line.
pub fn result_cpu(stdout: &str) -> Result<f64, String> {
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("RESULT "))
        .ok_or("the yardstick printed no RESULT line")?;
    let v: serde_json::Value = serde_json::from_str(line).map_err(|e| e.to_string())?;
    v["render_cpu_s"]
        .as_f64()
        .ok_or_else(|| "the RESULT line has no render_cpu_s".to_string())
}

/// Runs a command, its stdout if it succeeds, its stderr's end if not.
fn run_ok(c: &mut Command) -> Result<String, String> {
    let out = c.output().map_err(|e| format!("cannot run {c:?}: {e}"))?;
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).into_owned())
    } else {
        let err = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = err.lines().rev().take(5).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        Err(format!("{c:?} failed: {}", tail.join("\n")))
    }
}

/// The median of `v` (not empty).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Per renderer: µs per camera sample in each round, the median, and the median over
/// Mitsuba's where there is one.
pub fn summary(timings: &[Timing], spp: (u32, u32), pixels: u64) -> String {
    let mut names: Vec<&str> = Vec::new();
    for t in timings {
        if !names.contains(&t.renderer.as_str()) {
            names.push(&t.renderer);
        }
    }
    let per = |name: &str| -> Vec<f64> {
        let of = timings.iter().filter(|t| t.renderer == name);
        of.map(|t| t.marginal_us(spp, pixels)).collect()
    };
    let theirs = names
        .iter()
        .find(|n| n.starts_with("mitsuba"))
        .map(|n| median(per(n)));
    let mut s = String::from(
        "| renderer | µs per camera sample, by round | median | / Mitsuba |\n|---|---|---:|---:|\n",
    );
    for name in names {
        let v = per(name);
        let rounds: Vec<String> = v.iter().map(|x| format!("{x:.3}")).collect();
        let m = median(v);
        let ratio = theirs.map_or("–".to_string(), |t| format!("{:.2}×", m / t));
        s += &format!("| {name} | {} | {m:.3} | {ratio} |\n", rounds.join(" / "));
    }
    s
}

/// The commit measured (with `-dirty` when the tree has changes).
fn commit(root: &Path) -> String {
    Command::new("git")
        .args(["describe", "--always", "--dirty", "--abbrev=12"])
        .current_dir(root)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map_or("unknown".into(), |o| {
            String::from_utf8_lossy(&o.stdout).trim().to_string()
        })
}

/// The rounds as CSV, written under a temporary name and renamed.
fn write_csv(path: &Path, timings: &[Timing], a: &Args, commit: &str) -> Result<(), String> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    }
    let tmp = path.with_extension("csv.tmp");
    let mut w = csv::Writer::from_path(&tmp).map_err(|e| e.to_string())?;
    let pixels = a.width as u64 * a.height as u64;
    w.write_record([
        "commit",
        "scene",
        "width",
        "height",
        "renderer",
        "round",
        "spp_lo",
        "spp_hi",
        "cpu_lo_s",
        "cpu_hi_s",
        "us_per_camera_sample",
    ])
    .map_err(|e| e.to_string())?;
    for t in timings {
        w.write_record([
            commit.to_string(),
            a.scene.clone(),
            a.width.to_string(),
            a.height.to_string(),
            t.renderer.clone(),
            t.round.to_string(),
            a.spp.0.to_string(),
            a.spp.1.to_string(),
            format!("{:.4}", t.cpu.0),
            format!("{:.4}", t.cpu.1),
            format!("{:.4}", t.marginal_us(a.spp, pixels)),
        ])
        .map_err(|e| e.to_string())?;
    }
    w.flush().map_err(|e| e.to_string())?;
    drop(w);
    std::fs::rename(&tmp, path).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spp_pairs_are_checked() {
        assert_eq!(parse_spp("64,256"), Ok((64, 256)));
        assert_eq!(parse_spp(" 1 , 2 "), Ok((1, 2)));
        for bad in ["64", "256,64", "0,4", "4,4", "a,b", "4,"] {
            assert!(parse_spp(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_result_line_gives_mitsubas_cpu() {
        let out = "loading\nRESULT {\"render_s\": 1.0, \"render_cpu_s\": 1.932}\n";
        assert_eq!(result_cpu(out), Ok(1.932));
        assert!(result_cpu("no result\n").is_err());
        assert!(result_cpu("RESULT {\"render_s\": 1}\n").is_err());
    }

    #[test]
    fn the_marginal_cost_and_the_summary() {
        let t = |renderer: &str, round, cpu| Timing {
            renderer: renderer.into(),
            round,
            cpu,
        };
        let pixels = 128 * 128;
        // 192 · 16,384 samples in 3.145728 s: exactly 1 µs each.
        let ours = t("power+bsdf", 1, (1.0, 1.0 + 3.145728));
        assert!((ours.marginal_us((64, 256), pixels) - 1.0).abs() < 1e-12);
        let timings = vec![
            ours,
            t("mitsuba llvm_ad_rgb", 1, (0.5, 0.5 + 1.572864)),
            t("power+bsdf", 2, (1.0, 1.0 + 3.0 * 3.145728)),
            t("mitsuba llvm_ad_rgb", 2, (0.5, 0.5 + 1.572864)),
            t("power+bsdf", 3, (1.0, 1.0 + 2.0 * 3.145728)),
            t("mitsuba llvm_ad_rgb", 3, (0.5, 0.5 + 3.0 * 1.572864)),
        ];
        let s = summary(&timings, (64, 256), pixels);
        assert!(
            s.contains("| power+bsdf | 1.000 / 3.000 / 2.000 | 2.000 | 4.00× |"),
            "{s}"
        );
        assert!(
            s.contains("| mitsuba llvm_ad_rgb | 0.500 / 0.500 / 1.500 | 0.500 | 1.00× |"),
            "{s}"
        );
        assert_eq!(median(vec![3.0, 1.0, 2.0, 10.0]), 2.5);
    }
}
