//! Walker/Vose alias table: O(1) sampling of a discrete distribution.

/// One bin: everything a draw reads, in one 16-byte record, so that a draw touches one cache
/// line of a table far larger than the cache (80,000 lights: 1.3 MB).
#[derive(Clone, Copy, Debug)]
struct Bin {
    /// Probability of keeping the bin (else its alias).
    keep: f32,
    alias: u32,
    /// Normalised probabilities of the bin's own index and of its alias.
    pmf: f32,
    alias_pmf: f32,
}

#[derive(Clone, Debug)]
pub struct AliasTable {
    bins: Vec<Bin>,
}

impl AliasTable {
    /// `None` when no weight is positive or a weight is negative or non-finite.
    pub fn new(weights: &[f32]) -> Option<AliasTable> {
        if weights.iter().any(|w| !w.is_finite() || *w < 0.0) {
            return None;
        }
        let total: f64 = weights.iter().map(|&w| w as f64).sum();
        if !(total > 0.0) {
            return None;
        }
        let n = weights.len();
        let pmf: Vec<f32> = weights.iter().map(|&w| (w as f64 / total) as f32).collect();
        let mut scaled: Vec<f64> = weights
            .iter()
            .map(|&w| w as f64 / total * n as f64)
            .collect();
        let mut keep = vec![1.0f32; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) =
            (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
            keep[s] = scaled[s] as f32;
            alias[s] = l as u32;
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // Leftovers are 1 up to rounding.
        let bins = (0..n)
            .map(|i| Bin {
                keep: keep[i],
                alias: alias[i],
                pmf: pmf[i],
                alias_pmf: pmf[alias[i] as usize],
            })
            .collect();
        Some(AliasTable { bins })
    }

    pub fn len(&self) -> usize {
        self.bins.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// Index and its probability from one uniform number.
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let n = self.bins.len();
        let x = u * n as f32;
        let i = (x as usize).min(n - 1);
        let frac = x - i as f32;
        let bin = &self.bins[i];
        if frac < bin.keep {
            (i, bin.pmf)
        } else {
            (bin.alias as usize, bin.alias_pmf)
        }
    }

    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.bins[i].pmf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use chi2_test::{chi2_test, sidak_significance};
    use render_core::rng::SampleStream;

    #[test]
    fn frequencies_match_pmf_chi2() {
        let cases: Vec<Vec<f32>> = vec![
            vec![1.0],
            vec![0.0, 3.0, 1.0, 0.0, 6.0],
            (0..100).map(|i| ((i * 37) % 11) as f32 + 0.01).collect(),
            (0..1000)
                .map(|i| if i % 7 == 0 { 50.0 } else { 0.1 })
                .collect(),
        ];
        let sig = sidak_significance(0.01, cases.len());
        for (c, w) in cases.iter().enumerate() {
            let t = AliasTable::new(w).unwrap();
            let total: f32 = w.iter().sum();
            for (i, &wi) in w.iter().enumerate() {
                assert!((t.pmf(i) - wi / total).abs() < 1e-6);
            }
            let n = 200_000;
            let mut observed = vec![0.0; w.len()];
            for s in 0..n {
                let (k, p) = t.sample(SampleStream::new(c as u64, s, 0).next_f32());
                assert_eq!(p, t.pmf(k));
                assert!(p > 0.0, "zero-weight entries are never drawn");
                observed[k] += 1.0;
            }
            let expected: Vec<f64> = (0..w.len()).map(|i| t.pmf(i) as f64 * n as f64).collect();
            let out = chi2_test(&observed, &expected);
            assert!(out.p_value > sig, "case {c}: {out:?}");
        }
    }

    #[test]
    fn rejects_bad_weights() {
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[1.0, f32::NAN]).is_none());
        assert!(AliasTable::new(&[1.0, -1.0]).is_none());
    }
}
