//! End to end, with the debug `manylights` on two 8×8 built-ins: an experiment run in three
//! shards, each as on a machine of its own (its own results and references), and merged with
//! `merge-results` equals the same experiment run at once: the same cells with the same keys,
//! references, metrics (relMSE and ꟻLIP) and images, and the same cells.csv but for the
//! timings. Also: cells of before ꟻLIP get it from their render, or an empty column without one.
use super::cell::CellResult;
use super::cell::read_cell;
use super::config::{Experiment, parse};
use super::execute::{self, RunOptions};
use super::manylights::Manylights;
use super::merge::merge_into;
use super::plan::{self, Shard};
use super::prepare;
use super::provenance::Permissions;
use super::summary;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn experiment() -> Experiment {
    parse(
        "shards",
        r#"
        width = 8
        height = 8
        seeds = [0, 1]
        spp = [1, 2]
        [reference]
        strategy = "power+bsdf"
        spp = 4
        [[scenes]]
        label = "quads"
        spec = "builtin:diffuse-quads"
        [[scenes]]
        label = "spheres"
        spec = "builtin:glossy-spheres?radius=0.03&roughness=0.25"
        [[strategies]]
        label = "EK"
        name = "tree-split+bsdf"
        [[strategies]]
        label = "MIS"
        name = "mis3-adaptive"
        "#,
    )
    .unwrap()
}

/// Runs `shard` of the experiment (every cell without one) into `out` with references in `refs`.
fn run_into(exp: &Experiment, ml: &Manylights, shard: Option<Shard>, out: &Path, refs: &Path) {
    let mut cells = plan::expand(exp);
    if let Some(s) = shard {
        cells = s.select(cells);
    }
    let options = RunOptions {
        threads: Some(1),
        ..RunOptions::default()
    };
    let p = prepare::prepare(exp, ml, cells, options.threads).unwrap();
    assert!(p.notices.is_empty(), "{:?}", p.notices);
    let done = execute::execute(exp, ml, p, out, refs, &options, Instant::now()).unwrap();
    assert!(!done.failed, "{:?}", done.notices);
}

/// The cell files of `out`, by id.
fn cells(out: &Path) -> BTreeMap<String, CellResult> {
    let mut m = BTreeMap::new();
    for e in std::fs::read_dir(out.join("cells")).unwrap().flatten() {
        let c = read_cell(&e.path()).unwrap();
        m.insert(c.id.clone(), c);
    }
    m
}

/// cells.csv without the columns that time the render (they differ from run to run).
fn csv_without_timings(path: &Path) -> Vec<Vec<String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| !header[i].ends_with("_seconds"))
        .collect();
    let mut rows = vec![keep.iter().map(|&i| header[i].clone()).collect()];
    for rec in r.records() {
        let rec = rec.unwrap();
        rows.push(keep.iter().map(|&i| rec[i].to_string()).collect());
    }
    rows
}

fn exr(out: &Path, id: &str) -> Vec<glam::Vec3> {
    render_core::output::read_exr(&out.join("renders").join(format!("{id}.exr")))
        .unwrap()
        .2
}

#[test]
fn shards_merged_equal_the_single_run() {
    let base = std::env::temp_dir().join(format!("xtask-shards-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let (exp, ml) = (experiment(), Manylights::for_tests());
    let single = base.join("single/results");
    run_into(&exp, &ml, None, &single, &base.join("single/refs"));
    let n = 3;
    let shard_dirs: Vec<PathBuf> = (1..=n)
        .map(|i| {
            let dir = base.join(format!("shard{i}"));
            let shard = Shard { index: i, count: n };
            run_into(
                &exp,
                &ml,
                Some(shard),
                &dir.join("results"),
                &dir.join("refs"),
            );
            dir.join("results")
        })
        .collect();
    let merged = base.join("merged");
    // (allow_dirty: these tests run in a dirty tree too)
    let perm = Permissions {
        allow_dirty: true,
        ..Permissions::default()
    };
    let copied = merge_into(&shard_dirs, &merged, &mut vec![], &perm).unwrap();
    assert_eq!(copied, plan::expand(&exp).len());

    let (a, b) = (cells(&single), cells(&merged));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    assert_eq!(a.len(), 16);
    for (id, x) in &a {
        let y = &b[id];
        assert_eq!(x.key, y.key, "{id}");
        assert_eq!(x.reference, y.reference, "{id}");
        assert_eq!(x.reference_noise_unlit, y.reference_noise_unlit, "{id}");
        assert_eq!((x.all, x.unlit), (y.all, y.unlit), "{id}");
        assert!(x.flip_all.is_some() && x.flip_unlit.is_some(), "{id}");
        assert_eq!(
            (x.flip_all, x.flip_unlit),
            (y.flip_all, y.flip_unlit),
            "{id}"
        );
        assert_eq!(
            (x.spp, &x.code, &x.inputs),
            (y.spp, &y.code, &y.inputs),
            "{id}"
        );
        assert_eq!(x.render["rays"], y.render["rays"], "{id}");
        assert_eq!(exr(&single, id), exr(&merged, id), "{id}");
        for sibling in ["mask.png", "flip.png"] {
            let f = |d: &Path| std::fs::read(d.join("renders").join(format!("{id}.{sibling}")));
            assert_eq!(f(&single).unwrap(), f(&merged).unwrap(), "{id}.{sibling}");
        }
    }

    // the reports of both, from the references of a machine that has them
    let refs = base.join("single/refs");
    for out in [&single, &merged] {
        summary::generate(&exp, out, &refs, &[], &perm).unwrap();
    }
    let csv = |d: &Path| csv_without_timings(&d.join("cells.csv"));
    assert_eq!(csv(&single), csv(&merged));
    let md = std::fs::read_to_string(merged.join("table.md")).unwrap();
    assert!(md.contains("## HDR-ꟻLIP, equal spp = 2"), "{md}");
    assert!(merged.join("flip-maps/spheres__MIS.png").is_file());

    // Cells of before ꟻLIP: one whose render is here gets exactly what was measured, one
    // whose render is not has an empty column.
    let (id_here, id_gone) = ("quads__EK__spp2__seed0", "spheres__MIS__spp1__seed1");
    for id in [id_here, id_gone] {
        let path = merged.join("cells").join(format!("{id}.json"));
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let o = v.as_object_mut().unwrap();
        o.remove("flip_all");
        o.remove("flip_unlit");
        std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
        let _ = std::fs::remove_file(merged.join("renders").join(format!("{id}.flip.png")));
    }
    for f in std::fs::read_dir(merged.join("renders")).unwrap().flatten() {
        if f.file_name()
            .to_string_lossy()
            .starts_with(&format!("{id_gone}."))
        {
            std::fs::remove_file(f.path()).unwrap();
        }
    }
    summary::generate(&exp, &merged, &refs, &[], &perm).unwrap();
    let rows = csv(&merged);
    let col = |name: &str| rows[0].iter().position(|h| h == name).unwrap();
    let row = |id: &str| rows.iter().find(|r| r[0] == id).unwrap().clone();
    let (fu, fa) = (col("flip_unlit"), col("flip_all"));
    let measured = csv(&single).into_iter().find(|r| r[0] == id_here).unwrap();
    // The measured value went through the cell file, and serde_json's float parsing (without
    // its `float_roundtrip` feature) can be one ulp off; the value computed now did not: so
    // compare it as the cell file would give it back.
    let via_cell_file = |v: &str| -> String {
        let x: f64 = v.parse().unwrap();
        let back: f64 = serde_json::from_str(&serde_json::to_string(&x).unwrap()).unwrap();
        format!("{back:e}")
    };
    let mut now = row(id_here);
    for i in [fu, fa] {
        now[i] = via_cell_file(&now[i]);
    }
    assert_eq!(now, measured);
    assert!(merged.join(format!("renders/{id_here}.flip.png")).is_file());
    assert_eq!(
        (row(id_gone)[fu].as_str(), row(id_gone)[fa].as_str()),
        ("", "")
    );
    // its table entry (one of its seeds has no ꟻLIP) is left empty rather than half measured
    let md = std::fs::read_to_string(merged.join("table.md")).unwrap();
    let flip_spp1 = md.split("## HDR-ꟻLIP, equal spp = 1").nth(1).unwrap();
    let spheres = flip_spp1
        .lines()
        .find(|l| l.starts_with("| spheres"))
        .unwrap();
    assert!(spheres.trim_end().ends_with("| – |"), "{spheres}");
    let _ = std::fs::remove_dir_all(&base);
}

/// Runs `script` (under xtask/slurm/) with bash, `args` and `env`, with stand-ins for `cargo`
/// and `sbatch` that record their arguments (one call a line) in `base/calls`, and for the
/// Slurm queries: `sinfo` (one node of 8 CPUs) and `squeue`, `scontrol`, `scancel` (nothing
/// pending), so that a Slurm installed on the machine is never asked.
fn run_script(base: &Path, script: &str, args: &[&str], env: &[(&str, &str)]) -> Vec<String> {
    let bin = base.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let calls = base.join("calls");
    let _ = std::fs::remove_file(&calls);
    let c = calls.display();
    let stubs = [
        ("cargo", format!("echo \"cargo $*\" >> '{c}'")),
        // a submission answers a job id, as with --parsable (41, 42, …); --test-only nothing
        (
            "sbatch",
            format!(
                "echo \"sbatch $*\" >> '{c}'\ncase \"$*\" in *--parsable*) echo 4$(grep -c -- --parsable '{c}');; esac"
            ),
        ),
        ("sinfo", "echo 8".to_string()),
        ("squeue", String::new()),
        ("scontrol", String::new()),
        ("scancel", String::new()),
    ];
    for (tool, body) in stubs {
        let p = bin.join(tool);
        std::fs::write(&p, format!("#!/bin/sh\n{body}\nexit 0\n")).unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let script = super::manylights::repo_root()
        .join("xtask/slurm")
        .join(script);
    let status = std::process::Command::new("bash")
        .arg(&script)
        .args(args)
        .env("PATH", path)
        .env_remove("SHARDS_DIR")
        .envs(env.iter().copied())
        .current_dir(base)
        .status()
        .unwrap();
    assert!(status.success(), "{} failed", script.display());
    std::fs::read_to_string(&calls)
        .unwrap()
        .lines()
        .map(String::from)
        .collect()
}

#[test]
fn slurm_scripts_run_one_shard_per_task_then_merge() {
    let base = std::env::temp_dir().join(format!("xtask-slurm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let dir = base.to_string_lossy().into_owned();
    // task 6 of an array 5-8: shard 2 of 4, with the task's CPUs as threads
    let calls = run_script(
        &base,
        "run-experiments.sbatch",
        &["paper"],
        &[
            ("SLURM_ARRAY_TASK_ID", "6"),
            ("SLURM_ARRAY_TASK_MIN", "5"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_CPUS_PER_TASK", "3"),
            ("SLURM_SUBMIT_DIR", &dir),
        ],
    );
    assert_eq!(
        calls,
        [
            "cargo xtask run-experiments --experiment paper --shard 2/4 --threads 3 \
          --results target/experiment-shards/paper/2"
        ]
    );
    // the array's shard indices are 1..=N whatever its range, and the shards partition
    let calls: Vec<String> = (0..3)
        .flat_map(|k| {
            let id = k.to_string();
            run_script(
                &base,
                "run-experiments.sbatch",
                &["quick"],
                &[
                    ("SLURM_ARRAY_TASK_ID", &id),
                    ("SLURM_ARRAY_TASK_MIN", "0"),
                    ("SLURM_ARRAY_TASK_COUNT", "3"),
                    ("SLURM_SUBMIT_DIR", &dir),
                ],
            )
        })
        .collect();
    let shards: Vec<Shard> = calls
        .iter()
        .map(|c| {
            c.split("--shard ")
                .nth(1)
                .unwrap()
                .split(' ')
                .next()
                .unwrap()
        })
        .map(|s| s.parse().unwrap())
        .collect();
    assert_eq!(
        shards
            .iter()
            .map(|s| (s.index, s.count))
            .collect::<Vec<_>>(),
        [(1, 3), (2, 3), (3, 3)]
    );
    // submit.sh: the references, then the array (after them), then the merge (after it)
    let calls = run_script(&base, "submit.sh", &["paper", "4", "--partition=cpu"], &[]);
    // first a dry run that Slurm refuses if no node can ever take the jobs
    assert!(
        calls[0].starts_with("sbatch --test-only --partition=cpu --cpus-per-task=8"),
        "{calls:?}"
    );
    let calls: Vec<String> = calls
        .into_iter()
        .filter(|c| c.contains("--parsable"))
        .collect();
    assert_eq!(calls.len(), 3, "{calls:?}");
    assert!(
        calls
            .iter()
            .all(|c| c.starts_with("sbatch --parsable --partition=cpu"))
    );
    assert!(calls[0].contains("--references-only"), "{}", calls[0]);
    assert!(
        calls[1].contains("--dependency=afterok:41 --array=1-4")
            && calls[1].ends_with("run-experiments.sbatch paper"),
        "{}",
        calls[1]
    );
    assert!(
        calls[2].contains("--dependency=afterok:42")
            && calls[2]
                .ends_with("merge-results --experiment paper target/experiment-shards/paper/*"),
        "{}",
        calls[2]
    );
    let _ = std::fs::remove_dir_all(&base);
}
