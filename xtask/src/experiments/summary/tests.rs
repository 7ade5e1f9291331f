//! The whole report from synthetic cell files.
use super::*;
use crate::experiments::config::parse;
use crate::experiments::plan::Budget;
use crate::experiments::reference::Metric;

/// The whole report from cell files alone (no renders, no references): what
/// `merge-results` does on a machine that rendered nothing.
#[test]
fn report_from_cell_files() {
    let exp = parse(
        "t",
        r#"
        width = 8
        height = 4
        seeds = [0, 1]
        spp = [4, 16]
        time_budgets = [1.0]
        baseline = "B"
        [reference]
        strategy = "power+bsdf"
        spp = 8
        [[scenes]]
        label = "s"
        spec = "builtin:s"
        [[strategies]]
        label = "A"
        name = "tree"
        [[strategies]]
        label = "B"
        name = "power"
        "#,
    )
    .unwrap();
    let out = std::env::temp_dir().join(format!("xtask-summary-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(out.join("cells")).unwrap();
    let cells = plan::expand(&exp);
    // one stale cell (another key) must be left out
    for (k, cell) in cells.iter().enumerate() {
        let spp = match cell.budget {
            Budget::Spp(n) => n as u64,
            Budget::Time(_) => 10,
        };
        let err = if cell.strategy.label == "A" { 0.1 } else { 0.4 } / spp as f64;
        let r = CellResult {
            id: cell.id(),
            key: if k == 0 {
                "stale".into()
            } else {
                cell_key(cell)
            },
            experiment: "t".into(),
            scene: cell.scene_label.clone(),
            scene_spec: cell.scene.spec.clone(),
            strategy: cell.strategy.label.clone(),
            strategy_name: cell.strategy.name.clone(),
            strategy_args: vec![],
            budget: cell.budget,
            seed: cell.seed,
            width: 8,
            height: 4,
            reference: "r".into(),
            reference_dir: "absent".into(),
            reference_noise_unlit: 1e-4,
            all: Metric {
                rel_mse: err * 2.0,
                mse: err,
                pixels: 32,
            },
            unlit: Metric {
                rel_mse: err * (1.0 + cell.seed as f64 * 0.1),
                mse: err,
                pixels: 30,
            },
            spp,
            wall_seconds: spp as f64 * 0.1,
            cpu_seconds: spp as f64 * 0.2,
            render: serde_json::json!({ "git_commit": "abc" }),
            code: None,
            inputs: None,
            flip_all: None,
            flip_unlit: None,
        };
        render_core::output::write_json(
            &out.join("cells").join(format!("{}.json", r.id)),
            &serde_json::to_value(&r).unwrap(),
        )
        .unwrap();
    }
    let notices = vec![Notice {
        what: "strategy C".into(),
        skipped: true,
        message: "not implemented yet".into(),
    }];
    generate(
        &exp,
        &out,
        &out.join("no-refs"),
        &notices,
        &Permissions::default(),
    )
    .unwrap();
    assert_eq!(load_cells(&exp, &out).len(), cells.len() - 1);
    let md = std::fs::read_to_string(out.join("table.md")).unwrap();
    assert!(md.contains("## relMSE, equal spp = 16"), "{md}");
    assert!(
        md.contains("| scene | A | B (baseline) | ref. noise | ref. own |"),
        "{md}"
    );
    // A: 0.1/16 and 0.11/16 → mean 6.56e-3, 4× better than B at the same seconds
    assert!(md.contains("**6.56e-3 ± 4.42e-4** (4.00×)"), "{md}");
    assert!(
        md.contains("skipped strategy C: not implemented yet"),
        "{md}"
    );
    assert!(md.contains("1 planned cells have no result"), "{md}");
    assert!(out.join("plots/s.png").is_file());
    let csv = std::fs::read_to_string(out.join("cells.csv")).unwrap();
    assert_eq!(csv.lines().count(), cells.len());
    // cells from before code states were recorded: their render's commit stands in
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .ends_with("code_state,code_commit,code_dirty")
    );
    assert!(
        csv.lines()
            .nth(1)
            .unwrap()
            .ends_with("legacy:abc,abc,false"),
        "{csv}"
    );
    assert!(md.contains("rendered by **commit abc**"), "{md}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn table_md_links_the_plots_not_the_strips() {
    let md =
        "## Plots\n\n![s: convergence](plots/s.png)\n\n![s: comparison](strips/s.png)\n\n## Next\n";
    assert_eq!(
        without_strips(md),
        "## Plots\n\n![s: convergence](plots/s.png)\n\n## Next\n"
    );
}
