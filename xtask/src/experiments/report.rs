//! The statistics and formats of the tables: entries over seeds, speed-ups, the paper-style
//! markdown tables, cells.csv.
use super::cell::CellResult;
use super::config::BudgetClock;
use super::plan::Budget;
use std::collections::BTreeMap;
use std::fmt::Write;

/// Mean and sample standard deviation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stat {
    pub mean: f64,
    pub std: f64,
    pub n: usize,
}

impl Stat {
    pub fn of(v: &[f64]) -> Stat {
        let n = v.len();
        if n == 0 {
            return Stat::default();
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        let std = if n > 1 {
            (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Stat { mean, std, n }
    }
}

/// One table entry: a scene × strategy × budget over its seeds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Entry {
    pub error: Stat,
    pub seconds: f64,
    pub spp: f64,
}

/// What the pixels of a table are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pixels {
    Unlit,
    All,
}

pub fn entry(cells: &[&CellResult], pixels: Pixels, clock: BudgetClock) -> Entry {
    let errs: Vec<f64> = cells
        .iter()
        .map(|c| match pixels {
            Pixels::Unlit => c.unlit.rel_mse,
            Pixels::All => c.all.rel_mse,
        })
        .collect();
    let n = cells.len().max(1) as f64;
    Entry {
        error: Stat::of(&errs),
        seconds: cells.iter().map(|c| c.seconds(clock)).sum::<f64>() / n,
        spp: cells.iter().map(|c| c.spp as f64).sum::<f64>() / n,
    }
}

pub fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:.2e}")
    }
}

/// Speed-up of `e` over the baseline `b`: at equal time the ratio of errors; at equal spp the
/// ratio of error × seconds (the time the baseline needs for the same error, over ours).
pub fn speedup(e: &Entry, b: &Entry, budget: &Budget) -> Option<f64> {
    if e.error.mean <= 0.0 || b.error.mean <= 0.0 {
        return None;
    }
    Some(match budget {
        Budget::Time(_) => b.error.mean / e.error.mean,
        Budget::Spp(_) => {
            if e.seconds <= 0.0 || b.seconds <= 0.0 {
                return None;
            }
            (b.error.mean * b.seconds) / (e.error.mean * e.seconds)
        }
    })
}

/// A cell whose relMSE is at most this many times its reference's own is flagged
/// ([`REF_FLAG`]): the reference's noise is then a large part of what is measured, and
/// speed-ups between such cells are understated.
pub const REF_FLAG_FACTOR: f64 = 3.0;
pub const REF_FLAG: &str = "°";

/// The reference's own relMSE estimated from its half-vs-half relMSE `noise`: each half has
/// twice the variance of their average, their difference four times it.
pub fn reference_own(noise: f64) -> f64 {
    noise / 4.0
}

/// Whether `e` is within [`REF_FLAG_FACTOR`] of the reference's own error (`noise` between halves).
pub fn near_reference(e: &Entry, noise: Option<f64>) -> bool {
    noise.is_some_and(|n| n > 0.0 && e.error.mean <= REF_FLAG_FACTOR * reference_own(n))
}

/// How many entries of a table are [`near_reference`].
pub fn count_near_reference(
    entries: &BTreeMap<(String, String), Entry>,
    ref_noise: &BTreeMap<String, f64>,
) -> usize {
    entries
        .iter()
        .filter(|((r, _), e)| near_reference(e, ref_noise.get(r).copied()))
        .count()
}

/// A paper-style markdown table: rows scenes, columns strategies (then the reference noise),
/// mean ± std over seeds, the lowest error per row in bold, the speed-up vs the baseline column
/// in parentheses, [`REF_FLAG`] on the entries [`near_reference`]; then the reference's
/// half-vs-half relMSE and its own estimated relMSE; a row in `marks` has its mark after the
/// scene's name.
pub fn format_table(
    rows: &[String],
    cols: &[String],
    entries: &BTreeMap<(String, String), Entry>,
    baseline: &str,
    budget: &Budget,
    ref_noise: &BTreeMap<String, f64>,
    marks: &BTreeMap<String, String>,
) -> String {
    let mut s = String::new();
    let _ = write!(s, "| scene |");
    for c in cols {
        let mark = if c == baseline { " (baseline)" } else { "" };
        let _ = write!(s, " {c}{mark} |");
    }
    let _ = writeln!(s, " ref. noise | ref. own |");
    let _ = write!(s, "|---|");
    for _ in cols {
        let _ = write!(s, "---:|");
    }
    let _ = writeln!(s, "---:|---:|");
    let mut speedups: Vec<Vec<f64>> = vec![Vec::new(); cols.len()];
    for r in rows {
        match marks.get(r) {
            Some(m) => {
                let _ = write!(s, "| {r} {m} |");
            }
            None => {
                let _ = write!(s, "| {r} |");
            }
        }
        let row: Vec<Option<&Entry>> = cols
            .iter()
            .map(|c| entries.get(&(r.clone(), c.clone())))
            .collect();
        let best = row
            .iter()
            .flatten()
            .map(|e| e.error.mean)
            .fold(f64::INFINITY, f64::min);
        let base = entries.get(&(r.clone(), baseline.to_string()));
        for (ci, e) in row.iter().enumerate() {
            match e {
                None => {
                    let _ = write!(s, " – |");
                }
                Some(e) => {
                    let mut v = sci(e.error.mean);
                    if e.error.n > 1 {
                        v = format!("{v} ± {}", sci(e.error.std));
                    }
                    if e.error.mean == best {
                        v = format!("**{v}**");
                    }
                    if let Some(b) = base
                        && let Some(x) = speedup(e, b, budget)
                    {
                        v = format!("{v} ({x:.2}×)");
                        speedups[ci].push(x);
                    }
                    if near_reference(e, ref_noise.get(r).copied()) {
                        v = format!("{v} {REF_FLAG}");
                    }
                    let _ = write!(s, " {v} |");
                }
            }
        }
        match ref_noise.get(r) {
            Some(n) => {
                let _ = writeln!(s, " {} | {} |", sci(*n), sci(reference_own(*n)));
            }
            None => {
                let _ = writeln!(s, " – | – |");
            }
        }
    }
    if rows.len() > 1 && speedups.iter().any(|v| !v.is_empty()) {
        s.push_str(&geomean_row(&speedups, rows.len()));
    }
    s
}

/// The closing row of a table: per column the geometric mean of its speed-ups (the summary a
/// reader computes first), with the number of scenes it covers when some lack one.
fn geomean_row(speedups: &[Vec<f64>], scenes: usize) -> String {
    let mut s = String::from("| *geometric mean* |");
    for v in speedups {
        if v.is_empty() {
            s.push_str(" – |");
            continue;
        }
        let g = (v.iter().map(|x| x.ln()).sum::<f64>() / v.len() as f64).exp();
        if v.len() == scenes {
            let _ = write!(s, " *{g:.2}×* |");
        } else {
            let _ = write!(s, " *{g:.2}×* of {} scenes |", v.len());
        }
    }
    s.push_str(" | |\n");
    s
}

/// Seconds and spp reached, same layout.
pub fn format_time_table(
    rows: &[String],
    cols: &[String],
    entries: &BTreeMap<(String, String), Entry>,
) -> String {
    format_grid(rows, cols, |r, c| {
        let e = entries.get(&(r.to_string(), c.to_string()))?;
        Some(format!("{:.2} s / {:.0} spp", e.seconds, e.spp))
    })
}

/// Each entry's numerator over its denominator (two decimals), same layout.
pub fn format_ratio_table(
    rows: &[String],
    cols: &[String],
    entries: &BTreeMap<(String, String), (f64, f64)>,
) -> String {
    format_grid(rows, cols, |r, c| {
        let &(num, den) = entries.get(&(r.to_string(), c.to_string()))?;
        (den > 0.0).then(|| format!("{:.2}", num / den))
    })
}

/// A scene × column table whose cells `cell(row, column)` writes ("–" where it has none).
fn format_grid(
    rows: &[String],
    cols: &[String],
    cell: impl Fn(&str, &str) -> Option<String>,
) -> String {
    let mut s = String::from("| scene |");
    for c in cols {
        let _ = write!(s, " {c} |");
    }
    s.push_str("\n|---|");
    for _ in cols {
        s.push_str("---:|");
    }
    s.push('\n');
    for r in rows {
        let _ = write!(s, "| {r} |");
        for c in cols {
            let _ = write!(s, " {} |", cell(r, c).as_deref().unwrap_or("–"));
        }
        s.push('\n');
    }
    s
}

pub const CSV_HEADER: [&str; 31] = [
    "id",
    "scene",
    "strategy",
    "strategy_name",
    "strategy_args",
    "budget",
    "budget_value",
    "seed",
    "width",
    "height",
    "spp",
    "wall_seconds",
    "cpu_seconds",
    "rel_mse_unlit",
    "mse_unlit",
    "rel_mse_all",
    "mse_all",
    "flip_unlit",
    "flip_all",
    "unlit_pixels",
    "reference_noise_unlit",
    "rays_camera",
    "rays_shadow",
    "rays_bsdf",
    "shading_points",
    "technique_samples",
    "strategy_parameters",
    "git_commit",
    "code_state",
    "code_commit",
    "code_dirty",
];

/// A value that old cells may lack: empty then.
fn optional(v: Option<f64>) -> String {
    v.map(|v| format!("{v:e}")).unwrap_or_default()
}

pub fn write_csv(path: &std::path::Path, cells: &[CellResult]) -> Result<(), String> {
    render_core::output::write_atomically(path, |tmp| {
        let mut w = csv::Writer::from_path(tmp).map_err(|e| e.to_string())?;
        w.write_record(CSV_HEADER).map_err(|e| e.to_string())?;
        for c in cells {
            let code = c.code_state();
            let (kind, value) = match c.budget {
                Budget::Spp(n) => ("spp", n.to_string()),
                Budget::Time(t) => ("time", t.to_string()),
            };
            w.write_record([
                c.id.clone(),
                c.scene.clone(),
                c.strategy.clone(),
                c.strategy_name.clone(),
                c.strategy_args.join(" "),
                kind.to_string(),
                value,
                c.seed.to_string(),
                c.width.to_string(),
                c.height.to_string(),
                c.spp.to_string(),
                format!("{:.4}", c.wall_seconds),
                format!("{:.4}", c.cpu_seconds),
                format!("{:e}", c.unlit.rel_mse),
                format!("{:e}", c.unlit.mse),
                format!("{:e}", c.all.rel_mse),
                format!("{:e}", c.all.mse),
                optional(c.flip_unlit),
                optional(c.flip_all),
                c.unlit.pixels.to_string(),
                format!("{:e}", c.reference_noise_unlit),
                c.render["rays"]["camera"].to_string(),
                c.render["rays"]["shadow"].to_string(),
                c.render["rays"]["bsdf"].to_string(),
                c.render["shading_points"].to_string(),
                c.render["technique_samples"].to_string(),
                c.render["strategy_parameters"].to_string(),
                c.render["git_commit"].as_str().unwrap_or("").to_string(),
                code.id.clone(),
                code.commit.clone().unwrap_or_default(),
                code.dirty.to_string(),
            ])
            .map_err(|e| e.to_string())?;
        }
        w.flush().map_err(|e| e.to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(mean: f64, std: f64, n: usize, seconds: f64) -> Entry {
        Entry {
            error: Stat { mean, std, n },
            seconds,
            spp: 16.0,
        }
    }

    #[test]
    fn stats() {
        let s = Stat::of(&[1.0, 2.0, 3.0]);
        assert_eq!((s.mean, s.std, s.n), (2.0, 1.0, 3));
        assert_eq!(Stat::of(&[5.0]).std, 0.0);
    }

    #[test]
    fn table_bolds_the_best_and_gives_speedups() {
        let rows = vec!["sceneA".to_string(), "sceneB".to_string()];
        let cols = vec!["E&K".to_string(), "ours".to_string(), "missing".to_string()];
        let mut m = BTreeMap::new();
        m.insert(("sceneA".into(), "E&K".into()), e(0.04, 0.004, 2, 1.0));
        m.insert(("sceneA".into(), "ours".into()), e(0.01, 0.001, 2, 2.0));
        m.insert(("sceneB".into(), "E&K".into()), e(0.02, 0.0, 1, 1.0));
        m.insert(("sceneB".into(), "ours".into()), e(0.03, 0.0, 1, 1.0));
        let noise = BTreeMap::from([("sceneA".to_string(), 0.0004)]);
        // equal spp: speed-up = (0.04 * 1) / (0.01 * 2) = 2
        let marks = BTreeMap::from([("sceneB".to_string(), "‡".to_string())]);
        let t = format_table(&rows, &cols, &m, "E&K", &Budget::Spp(16), &noise, &marks);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(
            lines[0],
            "| scene | E&K (baseline) | ours | missing | ref. noise | ref. own |"
        );
        assert_eq!(
            lines[2],
            "| sceneA | 4.00e-2 ± 4.00e-3 (1.00×) | **1.00e-2 ± 1.00e-3** (2.00×) | – | 4.00e-4 | 1.00e-4 |"
        );
        assert_eq!(
            lines[3],
            "| sceneB ‡ | **2.00e-2** (1.00×) | 3.00e-2 (0.67×) | – | – | – |"
        );
        // equal time: speed-up = error ratio = 4
        // geometric means of (1.00, 1.00) and of (2.00, 0.67): 1 and sqrt(2 · 2/3)
        assert_eq!(lines[4], "| *geometric mean* | *1.00×* | *1.15×* | – | | |");
        let t = format_table(&rows, &cols, &m, "E&K", &Budget::Time(1.0), &noise, &marks);
        assert!(t.contains("**1.00e-2 ± 1.00e-3** (4.00×)"), "{t}");
        assert_eq!(count_near_reference(&m, &noise), 0);
    }

    #[test]
    fn cells_near_the_reference_error_are_flagged() {
        let rows = vec!["s".to_string()];
        let cols = vec!["a".to_string(), "b".to_string()];
        // noise 4e-3 between halves: the reference's own 1e-3; 3× that = 3e-3
        let noise = BTreeMap::from([("s".to_string(), 4e-3)]);
        let mut m = BTreeMap::new();
        m.insert(("s".into(), "a".into()), e(2.9e-3, 0.0, 1, 1.0));
        m.insert(("s".into(), "b".into()), e(3.1e-3, 0.0, 1, 1.0));
        let t = format_table(
            &rows,
            &cols,
            &m,
            "b",
            &Budget::Spp(4),
            &noise,
            &BTreeMap::new(),
        );
        let row = t.lines().nth(2).unwrap();
        assert_eq!(
            row,
            "| s | **2.90e-3** (1.07×) ° | 3.10e-3 (1.00×) | 4.00e-3 | 1.00e-3 |"
        );
        assert_eq!(count_near_reference(&m, &noise), 1);
    }

    #[test]
    fn csv_round_trips_flip_and_leaves_it_empty_for_old_cells() {
        let mut a = crate::experiments::cell::testing::cell_result("a", "r", "tree:x");
        a.flip_unlit = Some(0.123_456_789_012_345_6);
        a.flip_all = Some(1.0 / 3.0);
        a.unlit.rel_mse = 2.5e-3;
        let b = crate::experiments::cell::testing::cell_result("b", "r", "tree:x");
        let path = std::env::temp_dir().join(format!("xtask-csv-{}.csv", std::process::id()));
        write_csv(&path, &[a.clone(), b]).unwrap();
        let mut r = csv::Reader::from_path(&path).unwrap();
        let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
        assert_eq!(header, CSV_HEADER);
        let col = |name: &str| header.iter().position(|h| h == name).unwrap();
        let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
        let parse = |row: &csv::StringRecord, name: &str| -> Option<f64> {
            let v = &row[col(name)];
            (!v.is_empty()).then(|| v.parse().unwrap())
        };
        assert_eq!(rows.len(), 2);
        assert_eq!(&rows[0][col("id")], "a");
        // exactly the values written, and nothing for a cell measured before ꟻLIP
        assert_eq!(parse(&rows[0], "flip_unlit"), a.flip_unlit);
        assert_eq!(parse(&rows[0], "flip_all"), a.flip_all);
        assert_eq!(parse(&rows[0], "rel_mse_unlit"), Some(a.unlit.rel_mse));
        assert_eq!(parse(&rows[1], "flip_unlit"), None);
        assert_eq!(parse(&rows[1], "flip_all"), None);
        // and a cell file of before ꟻLIP (no such keys) still loads
        let mut old = serde_json::to_value(&a).unwrap();
        let o = old.as_object_mut().unwrap();
        o.remove("flip_all");
        o.remove("flip_unlit");
        let back: CellResult = serde_json::from_value(old).unwrap();
        assert_eq!((back.flip_all, back.flip_unlit), (None, None));
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn time_table() {
        let rows = vec!["s".to_string()];
        let cols = vec!["a".to_string()];
        let m = BTreeMap::from([(("s".to_string(), "a".to_string()), e(0.1, 0.0, 1, 1.5))]);
        assert!(format_time_table(&rows, &cols, &m).contains("| s | 1.50 s / 16 spp |"));
        let rays = BTreeMap::from([(("s".to_string(), "a".to_string()), (39.0, 10.0))]);
        assert!(format_ratio_table(&rows, &cols, &rays).contains("| s | 3.90 |"));
        assert!(format_ratio_table(&rows, &cols, &BTreeMap::new()).contains("| s | – |"));
    }
}

/// Each strategy's relMSE as a multiple of the `oracle` column's in the same row (same scene and
/// spp): how far each is from the best light selection at equal samples. Same layout as
/// [`format_table`], without the oracle column itself.
pub fn format_oracle_table(
    rows: &[String],
    cols: &[String],
    entries: &BTreeMap<(String, String), Entry>,
    oracle: &str,
) -> String {
    let others: Vec<&String> = cols.iter().filter(|c| c.as_str() != oracle).collect();
    let mut s = String::from("| scene |");
    for c in &others {
        let _ = write!(s, " {c} |");
    }
    s.push_str("\n|---|");
    for _ in &others {
        s.push_str("---:|");
    }
    s.push('\n');
    for r in rows {
        let _ = write!(s, "| {r} |");
        let base = entries
            .get(&(r.clone(), oracle.to_string()))
            .map(|e| e.error.mean);
        for c in &others {
            match (entries.get(&(r.clone(), (*c).clone())), base) {
                (Some(e), Some(o)) if o > 0.0 => {
                    let _ = write!(s, " {:.2}× |", e.error.mean / o);
                }
                _ => s.push_str(" – |"),
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod oracle_table_tests {
    use super::*;

    #[test]
    fn multiples_of_the_oracle_per_row() {
        let e = |m: f64| Entry {
            error: Stat::of(&[m]),
            seconds: 1.0,
            spp: 4.0,
        };
        let mut g = BTreeMap::new();
        g.insert(("s".to_string(), "A".to_string()), e(0.3));
        g.insert(("s".to_string(), "O".to_string()), e(0.1));
        g.insert(("t".to_string(), "A".to_string()), e(0.2));
        let rows = vec!["s".to_string(), "t".to_string()];
        let cols = vec!["A".to_string(), "O".to_string()];
        let md = format_oracle_table(&rows, &cols, &g, "O");
        assert!(md.starts_with("| scene | A |\n|---|---:|\n"), "{md}");
        assert!(md.contains("| s | 3.00× |"), "{md}");
        assert!(md.contains("| t | – |"), "{md}");
    }
}
