use super::*;
use crate::experiments::config::parse;
use crate::experiments::manylights::repo_root;

fn experiment() -> Experiment {
    parse(
        "t",
        r#"
        width = 8
        height = 4
        seeds = [0, 1]
        spp = [4]
        time_budgets = [1.0, 2.0]
        [reference]
        strategy = "power+bsdf"
        spp = 8
        [[scenes]]
        label = "s"
        spec = "builtin:s"
        [[scenes]]
        label = "u"
        spec = "builtin:u"
        [[strategies]]
        label = "E&K"
        name = "tree-split+bsdf"
        [[strategies]]
        label = "MIS adaptive"
        name = "mis3-adaptive"
        [[strategies]]
        label = "MIS one ray"
        name = "mis3-adaptive"
        args = ["--emission-rays", "1"]
        "#,
    )
    .unwrap()
}

const HEADER: &str = "id,scene,strategy,strategy_name,strategy_args,budget,budget_value,seed,rel_mse_unlit,reference_noise_unlit";

/// A cells.csv of two scenes: the method's cells at the largest time budget are 4× (s) and
/// 1/2× (u) the baseline's; the other budget and the other flags must not count.
fn cells_csv(dir: &Path) -> PathBuf {
    let mut text = format!("{HEADER}\n");
    let rows = [
        ("s", "E&K", "tree-split+bsdf", "", 2.0, [4e-2, 6e-2]),
        (
            "s",
            "MIS adaptive",
            "mis3-adaptive",
            "",
            2.0,
            [1e-2, 1.5e-2],
        ),
        (
            "s",
            "MIS one ray",
            "mis3-adaptive",
            "--emission-rays 1",
            2.0,
            [1.0, 1.0],
        ),
        ("s", "MIS adaptive", "mis3-adaptive", "", 1.0, [9.0, 9.0]),
        ("u", "E&K", "tree-split+bsdf", "", 2.0, [1e-3, 1e-3]),
        ("u", "MIS adaptive", "mis3-adaptive", "", 2.0, [2e-3, 2e-3]),
    ];
    for (scene, label, name, args, t, errs) in rows {
        for (seed, e) in errs.iter().enumerate() {
            let _ = writeln!(
                text,
                "x,{scene},{label},{name},{args},time,{t},{seed},{e:e},1e-6"
            );
        }
    }
    let _ = writeln!(text, "y,s,E&K,tree-split+bsdf,,spp,4,0,5e-1,1e-6");
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("cells.csv");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn the_table_takes_the_largest_time_budget_and_the_default_flags() {
    let dir = std::env::temp_dir().join(format!("xtask-headline-{}", std::process::id()));
    let b = block(&experiment(), &cells_csv(&dir)).unwrap();
    let lines: Vec<&str> = b.lines().filter(|l| l.starts_with('|')).collect();
    assert_eq!(lines[0], "| scene | E&K | MIS adaptive | speed-up |");
    // s: E&K 5e-2 ± 1.41e-2, the method 1.25e-2 ± 3.54e-3: 4×
    assert_eq!(
        lines[2],
        "| s | 5.00e-2 ± 1.41e-2 | **1.25e-2 ± 3.54e-3** | 4.00× |"
    );
    assert_eq!(lines[3], "| u | **1.00e-3 ± 0** | 2.00e-3 ± 0 | 0.50× |");
    // geometric mean of 4 and 1/2
    assert_eq!(lines[4], "| *geometric mean* | | | *1.41×* |");
    assert!(b.contains("Equal time, 2 CPU seconds"), "{b}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn splice_replaces_only_the_block_and_needs_both_markers() {
    let readme = format!("# T\n\nbefore\n{BEGIN}\nold\nrows\n{END}\nafter\n");
    let s = splice(&readme, "new\n").unwrap();
    assert_eq!(s, format!("# T\n\nbefore\n{BEGIN}\nnew\n{END}\nafter\n"));
    assert_eq!(splice(&s, "new\n").unwrap(), s, "idempotent");
    let e = splice("# T\n", "new").unwrap_err();
    assert!(
        e.contains("cargo xtask headline") && e.contains(BEGIN),
        "{e}"
    );
    let e = splice(&format!("{END}\n{BEGIN}\n"), "new").unwrap_err();
    assert!(e.contains("before"), "{e}");
}

/// The published numbers: every entry of the headline is the one `results/paper/table.md`
/// shows in its equal-time table for the same scene and column.
#[test]
fn the_headline_reproduces_the_published_table() {
    let exp = load_experiment(EXPERIMENT).unwrap();
    let dir = published_dir(&exp);
    let Ok(md) = std::fs::read_to_string(dir.join("table.md")) else {
        println!("NOTICE: no {}/table.md: not compared", dir.display());
        return;
    };
    let b = block(&exp, &dir.join("cells.csv")).unwrap();
    let seconds = headline_budget(&exp).unwrap();
    let heading = format!("## relMSE, {}", Budget::Time(seconds).describe());
    let section = md
        .split("\n## ")
        .find(|s| format!("## {s}").starts_with(&heading))
        .unwrap_or_else(|| panic!("table.md has no `{heading}`"));
    let mut compared = 0;
    let rows = b.lines().filter(|l| l.starts_with('|')).skip(2);
    for row in rows.filter(|l| !l.contains("geometric")) {
        let cols: Vec<&str> = row.split(" | ").collect();
        let scene = cols[0].trim_start_matches("| ");
        let published = section
            .lines()
            .find(|l| l.starts_with(&format!("| {scene} |")))
            .unwrap_or_else(|| panic!("no row {scene} in table.md"));
        for v in &cols[1..3] {
            let number = v.trim_matches('*').trim_end_matches(" °").trim_matches('*');
            assert!(
                published.contains(number),
                "{scene}: {number} is not in table.md's row {published}"
            );
            compared += 1;
        }
        let ratio = cols[3].trim_end_matches(" |");
        assert!(
            published.contains(&format!("({ratio})")),
            "{scene}: {ratio} vs {published}"
        );
    }
    assert!(compared > 0, "nothing compared");
}

/// README.md's block is what `cargo xtask headline` writes.
#[test]
fn the_readme_block_is_generated() {
    let readme = repo_root().join("README.md");
    let text = std::fs::read_to_string(&readme).unwrap();
    let exp = load_experiment(EXPERIMENT).unwrap();
    let b = block(&exp, &published_dir(&exp).join("cells.csv")).unwrap();
    let new = splice(&text, &b).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        new == text,
        "README.md's headline table is not the one results/{EXPERIMENT}/cells.csv gives: run `cargo xtask headline`"
    );
}
