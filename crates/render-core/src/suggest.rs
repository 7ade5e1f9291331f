//! "Did you mean …?" for names a user types: built-in scenes, experiments, strategies.
//!
//! Here rather than in each tool because every crate that resolves a user-typed name already
//! depends on render-core.

/// The candidate closest to `name` by edit distance (case-insensitive; insertions, deletions,
/// substitutions and swaps of neighbours each count 1), if it is close enough to be a likely
/// typo: at most a third of the longer name's characters differ. Ties go to the earlier
/// candidate; an exact match is returned too.
pub fn suggest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let name: Vec<char> = name.to_lowercase().chars().collect();
    let mut best: Option<(usize, &'a str)> = None;
    for c in candidates {
        let lower: Vec<char> = c.to_lowercase().chars().collect();
        let d = distance(&name, &lower);
        let close = 3 * d <= name.len().max(lower.len());
        if close && best.is_none_or(|(b, _)| d < b) {
            best = Some((d, c));
        }
    }
    best.map(|(_, c)| c)
}

/// `"; did you mean `x`?"` for the closest candidate, or an empty string when none is close:
/// to append to an "unknown NAME" message.
pub fn did_you_mean<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    suggest(name, candidates)
        .map(|c| format!("; did you mean `{c}`?"))
        .unwrap_or_default()
}

/// Optimal-string-alignment distance: Levenshtein plus adjacent transpositions.
fn distance(a: &[char], b: &[char]) -> usize {
    // rows[i % 3][j]: distance between a[..i] and b[..j]; three rows for the transposition.
    let mut rows = vec![vec![0usize; b.len() + 1]; 3];
    for (j, cell) in rows[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        let (cur, prev, prev2) = (i % 3, (i - 1) % 3, (i + 1) % 3);
        rows[cur][0] = i;
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut d = (rows[prev][j] + 1)
                .min(rows[cur][j - 1] + 1)
                .min(rows[prev][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                d = d.min(rows[prev2][j - 2] + 1);
            }
            rows[cur][j] = d;
        }
    }
    rows[a.len() % 3][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(a: &str, b: &str) -> usize {
        let v = |s: &str| s.chars().collect::<Vec<_>>();
        distance(&v(a), &v(b))
    }

    #[test]
    fn distances_count_each_kind_of_edit_once() {
        assert_eq!(d("", ""), 0);
        assert_eq!(d("abc", ""), 3);
        assert_eq!(d("", "ab"), 2);
        assert_eq!(d("kitten", "sitting"), 3);
        assert_eq!(d("mis3-adaptve", "mis3-adaptive"), 1);
        assert_eq!(
            d("cornlel", "cornell"),
            1,
            "a swap of neighbours is one edit"
        );
        assert_eq!(d("ab", "ba"), 1);
        assert_eq!(d("équipe", "equipe"), 1, "characters, not bytes");
    }

    #[test]
    fn the_closest_likely_typo_is_suggested() {
        let names = ["quick", "paper", "samplers", "scaling"];
        assert_eq!(suggest("quck", names), Some("quick"));
        assert_eq!(suggest("QUICK", names), Some("quick"));
        assert_eq!(suggest("sampler", names), Some("samplers"));
        assert_eq!(suggest("scalign", names), Some("scaling"));
        assert_eq!(suggest("nosuch", names), None);
        assert_eq!(suggest("x", names), None);
        assert_eq!(suggest("anything", []), None);
        assert_eq!(did_you_mean("papr", names), "; did you mean `paper`?");
        assert_eq!(did_you_mean("zzzzzz", names), "");
    }

    #[test]
    fn ties_go_to_the_earlier_candidate() {
        assert_eq!(suggest("abcx", ["abcd", "abce"]), Some("abcd"));
        assert_eq!(suggest("abcx", ["abce", "abcd"]), Some("abce"));
    }
}
