//! The cells of an experiment: scene × strategy × (spp or time budget) × seed, their ids and
//! keys, `--only` and `--shard`.
use super::config::{BudgetClock, Experiment, SceneEntry, StrategyEntry};
use serde::{Deserialize, Serialize};

/// 64-bit FNV-1a: a stable (toolchain-independent) hash for cache keys.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

pub fn hex_hash(bytes: &[u8]) -> String {
    format!("{:016x}", fnv1a(bytes))
}

/// File-name-safe form of a label: letters, digits, `-`, `.`, `=` kept, everything else `_`.
pub fn slug(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '.' | '=') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if out.is_empty() {
        out.push('_');
    }
    out
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Budget {
    Spp(u32),
    /// Seconds of wall time.
    Time(f64),
}

impl Budget {
    pub fn tag(&self) -> String {
        match self {
            Budget::Spp(n) => format!("spp{n}"),
            Budget::Time(t) => format!("t{t}s"),
        }
    }
    pub fn describe(&self) -> String {
        match self {
            Budget::Spp(n) => format!("equal spp = {n}"),
            Budget::Time(t) => format!("equal time = {t} s"),
        }
    }
}

/// The experiment's budgets: its spp counts, then its time budgets.
pub fn budgets(exp: &Experiment) -> Vec<Budget> {
    let mut b: Vec<Budget> = exp.spp.iter().map(|&n| Budget::Spp(n)).collect();
    b.extend(exp.time_budgets.iter().map(|&t| Budget::Time(t)));
    b
}

/// One render to make and measure.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    pub scene: SceneEntry,
    pub scene_label: String,
    pub strategy: StrategyEntry,
    pub budget: Budget,
    /// What a time budget counts (unused by spp cells).
    pub budget_clock: BudgetClock,
    pub seed: u64,
    pub width: u32,
    pub height: u32,
}

impl Cell {
    /// Unique, readable, file-name-safe id.
    pub fn id(&self) -> String {
        format!(
            "{}__{}__{}__seed{}",
            slug(&self.scene_label),
            slug(&self.strategy.label),
            self.budget.tag(),
            self.seed
        )
    }

    /// Everything that determines the cell's result, except the reference (added by the caller):
    /// a stored cell whose key differs is stale and rendered again.
    pub fn key_material(&self) -> String {
        let args = self.strategy.cli_args().unwrap_or_default().join(" ");
        // Only time cells depend on the clock, so spp cells stay valid whatever it is.
        let clock = match self.budget {
            Budget::Time(_) => format!("|clock={}", self.budget_clock.cli_name()),
            Budget::Spp(_) => String::new(),
        };
        format!(
            "scene={}|camera={:?}|strategy={}|args={}|budget={:?}{clock}|seed={}|res={}x{}|unlit=ref-and-own-mask",
            self.scene.spec,
            self.scene.camera,
            self.strategy.name,
            args,
            self.budget,
            self.seed,
            self.width,
            self.height
        )
    }

    /// Matched by `--only`: the id, scene label, strategy label or CLI name.
    pub fn matches(&self, pattern: &str) -> bool {
        let p = pattern.to_lowercase();
        [
            self.id(),
            self.scene_label.clone(),
            self.strategy.label.clone(),
            self.strategy.name.clone(),
            self.budget.tag(),
        ]
        .iter()
        .any(|s| glob_match(&p, &s.to_lowercase()))
    }
}

/// `*` matches any run of characters; a pattern without `*` matches as a substring.
pub fn glob_match(pattern: &str, text: &str) -> bool {
    if !pattern.contains('*') {
        return text.contains(pattern);
    }
    fn rec(p: &[char], t: &[char]) -> bool {
        match p.split_first() {
            None => t.is_empty(),
            Some(('*', rest)) => (0..=t.len()).any(|i| rec(rest, &t[i..])),
            Some((c, rest)) => t.first() == Some(c) && rec(rest, &t[1..]),
        }
    }
    let p: Vec<char> = pattern.chars().collect();
    let t: Vec<char> = text.chars().collect();
    rec(&p, &t)
}

pub fn scene_resolution(exp: &Experiment, scene: &SceneEntry) -> (u32, u32) {
    (
        scene.width.unwrap_or(exp.width),
        scene.height.unwrap_or(exp.height),
    )
}

/// Every cell in a fixed order: scene, budget (spp ascending, then time), strategy, seed.
pub fn expand(exp: &Experiment) -> Vec<Cell> {
    let budgets = budgets(exp);
    let mut cells = Vec::new();
    for scene in &exp.scenes {
        let (width, height) = scene_resolution(exp, scene);
        for budget in &budgets {
            for strategy in &exp.strategies {
                if matches!(budget, Budget::Time(_)) && !strategy.equal_time {
                    continue;
                }
                for &seed in &exp.seeds {
                    cells.push(Cell {
                        scene: scene.clone(),
                        scene_label: scene.label(),
                        strategy: strategy.clone(),
                        budget: *budget,
                        budget_clock: exp.budget_clock,
                        seed,
                        width,
                        height,
                    });
                }
            }
        }
    }
    cells
}

/// `--shard i/n`, 1-based: shard i of n.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("--shard expects i/n with 1 ≤ i ≤ n (e.g. 2/4), got `{s}`");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl Shard {
    /// Round-robin over the expansion order sorted by id: every cell in exactly one shard, the
    /// shards within one cell of each other in size, the same split on every machine.
    pub fn select(&self, cells: Vec<Cell>) -> Vec<Cell> {
        let mut ids: Vec<(String, Cell)> = cells.into_iter().map(|c| (c.id(), c)).collect();
        ids.sort_by(|a, b| a.0.cmp(&b.0));
        ids.into_iter()
            .enumerate()
            .filter(|(k, _)| k % self.count == self.index - 1)
            .map(|(_, (_, c))| c)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::config::parse;

    fn exp() -> Experiment {
        parse(
            "t",
            r#"
            width = 16
            height = 8
            seeds = [0, 1, 2]
            spp = [1, 4]
            time_budgets = [0.25]
            [reference]
            strategy = "power+bsdf"
            spp = 8
            [[scenes]]
            spec = "builtin:a"
            [[scenes]]
            spec = "builtin:b"
            width = 4
            [[strategies]]
            label = "A"
            name = "tree"
            [[strategies]]
            label = "B c"
            name = "power"
            params = { tau = 0.5 }
            "#,
        )
        .unwrap()
    }

    #[test]
    fn expansion_is_complete_and_ids_unique() {
        let cells = expand(&exp());
        assert_eq!(cells.len(), 2 * 3 * 2 * 3);
        let ids: std::collections::BTreeSet<_> = cells.iter().map(Cell::id).collect();
        assert_eq!(ids.len(), cells.len());
        assert!(ids.contains("b__B_c__t0.25s__seed2"));
        assert_eq!(cells.iter().filter(|c| c.width == 4).count(), 18);
        let keys: std::collections::BTreeSet<_> = cells.iter().map(Cell::key_material).collect();
        assert_eq!(keys.len(), cells.len());
    }

    #[test]
    fn shards_partition_deterministically() {
        let cells = expand(&exp());
        for n in 1..=7 {
            let mut seen = Vec::new();
            let mut sizes = Vec::new();
            for i in 1..=n {
                let shard = Shard { index: i, count: n };
                let a: Vec<String> = shard.select(cells.clone()).iter().map(Cell::id).collect();
                // the same on a second call and whatever the input order
                let mut rev = cells.clone();
                rev.reverse();
                let b: Vec<String> = shard.select(rev).iter().map(Cell::id).collect();
                assert_eq!(a, b);
                sizes.push(a.len());
                seen.extend(a);
            }
            seen.sort();
            let mut all: Vec<String> = cells.iter().map(Cell::id).collect();
            all.sort();
            assert_eq!(seen, all, "shards of {n} must partition the cells");
            let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
            assert!(hi - lo <= 1, "{sizes:?}");
        }
    }

    #[test]
    fn shard_syntax() {
        assert_eq!(
            "2/4".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 4 }
        );
        for bad in ["0/4", "5/4", "1/0", "a/b", "3", ""] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    #[test]
    fn only_patterns() {
        let cells = expand(&exp());
        let count = |p: &str| cells.iter().filter(|c| c.matches(p)).count();
        assert_eq!(count("B c"), 18);
        assert_eq!(count("power"), 18);
        assert_eq!(count("a__*seed0"), 6);
        assert_eq!(count("a__A__*seed0"), 3);
        assert_eq!(count("t0.25s"), 12);
        assert_eq!(count("nothing"), 0);
    }

    #[test]
    fn glob() {
        assert!(glob_match("a*c", "abbbc"));
        assert!(!glob_match("a*c", "abbb"));
        assert!(glob_match("*", ""));
        assert!(glob_match("bb", "abbbc"));
    }
}
