//! "Did you mean": the known name closest to a misspelt one, for the error of any name lookup
//! (strategies, built-in scenes, experiments).

/// Edit distance (insertions, deletions, substitutions and swaps of two neighbours, each 1)
/// between `a` and `b`, over characters.
pub fn distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    // d[i][j]: distance between a[..i] and b[..j], kept as three rolling rows.
    let mut before: Vec<usize> = vec![0; b.len() + 1];
    let mut last: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut row = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            row[j] = (last[j] + 1).min(row[j - 1] + 1).min(last[j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                row[j] = row[j].min(before[j - 2] + 1);
            }
        }
        before = std::mem::replace(&mut last, row);
    }
    last[b.len()]
}

/// The candidate closest to `name`, if it is close enough to be a misspelling (at most a third
/// of the name's length, and at least one edit, away).
pub fn closest<'a>(name: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let limit = (name.chars().count() / 3).max(1);
    candidates
        .iter()
        .map(|c| (distance(name, c), *c))
        .filter(|&(d, _)| d <= limit)
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// `"; did you mean `x`?"` for the closest candidate, or an empty string: ready to append to an
/// "unknown name" message.
pub fn did_you_mean(name: &str, candidates: &[&str]) -> String {
    closest(name, candidates)
        .map(|c| format!("; did you mean `{c}`?"))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances() {
        assert_eq!(distance("", "abc"), 3);
        assert_eq!(distance("abc", "abc"), 0);
        assert_eq!(distance("mis3-adaptve", "mis3-adaptive"), 1);
        assert_eq!(
            distance("power+bdsf", "power+bsdf"),
            1,
            "a swap is one edit"
        );
        assert_eq!(distance("kitten", "sitting"), 3);
    }

    #[test]
    fn suggests_only_close_names() {
        let names = ["mis3-adaptive", "mis3-equal", "power+bsdf"];
        assert_eq!(closest("mis3-adaptve", &names), Some("mis3-adaptive"));
        assert_eq!(closest("mis3-equals", &names), Some("mis3-equal"));
        assert_eq!(closest("zzz", &names), None);
        assert!(did_you_mean("powr+bsdf", &names).contains("`power+bsdf`"));
        assert_eq!(did_you_mean("nothing-like-it", &names), "");
    }
}
