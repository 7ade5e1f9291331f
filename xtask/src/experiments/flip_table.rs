//! The ꟻLIP tables of table.md: mean HDR-ꟻLIP per scene × strategy at one budget, mean ± std
//! over the seeds, the lowest in the row in bold. No speed-ups: ꟻLIP is not proportional to
//! the variance, so a ratio of ꟻLIP says nothing about time to equal error.
use super::cell::CellResult;
use super::report::{Pixels, Stat};
use std::collections::BTreeMap;
use std::fmt::Write;

/// The ꟻLIP of `cells` (one scene × strategy × budget, its seeds), or `None` when any of them
/// has none (a cell from before ꟻLIP whose render is not on this machine).
pub fn entry(cells: &[&CellResult], pixels: Pixels) -> Option<Stat> {
    let v: Option<Vec<f64>> = cells
        .iter()
        .map(|c| match pixels {
            Pixels::Unlit => c.flip_unlit,
            Pixels::All => c.flip_all,
        })
        .collect();
    v.filter(|v| !v.is_empty()).map(|v| Stat::of(&v))
}

fn value(s: &Stat) -> String {
    if s.n > 1 {
        format!("{:.4} ± {:.4}", s.mean, s.std)
    } else {
        format!("{:.4}", s.mean)
    }
}

/// Rows scenes, columns strategies; `marks` as in [`super::report::format_table`].
pub fn format(
    rows: &[String],
    cols: &[String],
    entries: &BTreeMap<(String, String), Stat>,
    marks: &BTreeMap<String, String>,
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
        match marks.get(r) {
            Some(m) => {
                let _ = write!(s, "| {r} {m} |");
            }
            None => {
                let _ = write!(s, "| {r} |");
            }
        }
        let row: Vec<Option<&Stat>> = cols
            .iter()
            .map(|c| entries.get(&(r.clone(), c.clone())))
            .collect();
        let best = row
            .iter()
            .flatten()
            .map(|e| e.mean)
            .fold(f64::INFINITY, f64::min);
        for e in row {
            match e {
                None => s.push_str(" – |"),
                Some(e) if e.mean == best => {
                    let _ = write!(s, " **{}** |", value(e));
                }
                Some(e) => {
                    let _ = write!(s, " {} |", value(e));
                }
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bolds_the_lowest_and_leaves_gaps() {
        let rows = vec!["s".to_string(), "t".to_string()];
        let cols = vec!["A".to_string(), "B".to_string()];
        let mut m = BTreeMap::new();
        m.insert(("s".into(), "A".into()), Stat::of(&[0.2, 0.3]));
        m.insert(("s".into(), "B".into()), Stat::of(&[0.1]));
        m.insert(("t".into(), "A".into()), Stat::of(&[0.05]));
        let marks = BTreeMap::from([("t".to_string(), "‡".to_string())]);
        let t = format(&rows, &cols, &m, &marks);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines[0], "| scene | A | B |");
        assert_eq!(lines[2], "| s | 0.2500 ± 0.0707 | **0.1000** |");
        assert_eq!(lines[3], "| t ‡ | **0.0500** | – |");
    }

    #[test]
    fn an_entry_needs_every_seed() {
        let mut a = crate::experiments::cell::testing::cell_result("a", "r", "tree:x");
        let mut b = a.clone();
        a.flip_unlit = Some(0.1);
        a.flip_all = Some(0.2);
        b.flip_all = Some(0.4);
        assert_eq!(entry(&[&a], Pixels::Unlit).unwrap().mean, 0.1);
        assert!(entry(&[&a, &b], Pixels::Unlit).is_none());
        assert!((entry(&[&a, &b], Pixels::All).unwrap().mean - 0.3).abs() < 1e-12);
        assert!(entry(&[], Pixels::All).is_none());
    }
}
