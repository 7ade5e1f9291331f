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

/// Walker's alias table over a discrete distribution: O(1) draws from one cache line.
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

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.bins.len()
    }

    /// Whether the table has no entry.
    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// Index and its probability from 64 uniform bits: the bin is the high word of bits × n and
    /// the keep test uses 24 bits of the low word, so both stay exact for any table size (one
    /// f32 would leave only 24 − log2(n) bits to the keep test: 7 for 80,000 lights).
    #[inline]
    pub fn sample(&self, bits: u64) -> (usize, f32) {
        let n = self.bins.len();
        let prod = bits as u128 * n as u128;
        let i = ((prod >> 64) as usize).min(n - 1);
        let frac = ((prod as u64) >> 40) as f32 * (1.0 / 16_777_216.0);
        let bin = &self.bins[i];
        if frac < bin.keep {
            (i, bin.pmf)
        } else {
            (bin.alias as usize, bin.alias_pmf)
        }
    }

    /// Starts loading the bin [`AliasTable::sample`] reads for `bits`.
    #[inline]
    pub fn prefetch(&self, bits: u64) {
        let n = self.bins.len();
        let i = (((bits as u128 * n as u128) >> 64) as usize).min(n - 1);
        render_core::accel::prefetch(&self.bins[i]);
    }

    /// Probability of entry `i` (what [`AliasTable::sample`] reports with it).
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
                let (k, p) = t.sample(SampleStream::new(c as u64, s, 0).next_u64());
                assert_eq!(p, t.pmf(k));
                assert!(p > 0.0, "zero-weight entries are never drawn");
                observed[k] += 1.0;
            }
            let expected: Vec<f64> = (0..w.len()).map(|i| t.pmf(i) as f64 * n as f64).collect();
            let out = chi2_test(&observed, &expected);
            assert!(out.p_value > sig, "case {c}: {out:?}");
        }
    }

    /// A table of 2^20 bins, the even ones of weight 1 and the odd of weight 2: every even bin
    /// is kept with probability 2/3. One 24-bit number would leave 4 bits to the keep test,
    /// keep 11/16 instead and draw even bins 34.4 % of the time instead of 33.3 %; the
    /// odd/even split of a million draws resolves 0.05 %.
    #[test]
    fn large_tables_keep_their_probabilities() {
        let n = 1usize << 20;
        let w: Vec<f32> = (0..n).map(|i| if i % 2 == 0 { 1.0 } else { 2.0 }).collect();
        let t = AliasTable::new(&w).unwrap();
        let p_even: f64 = (0..n).step_by(2).map(|i| t.pmf(i) as f64).sum();
        let draws = 1_000_000u64;
        let mut even = 0.0;
        for s in 0..draws {
            let (k, _) = t.sample(SampleStream::new(7, s, 0).next_u64());
            if k % 2 == 0 {
                even += 1.0;
            }
        }
        let observed = [even, draws as f64 - even];
        let expected = [p_even * draws as f64, (1.0 - p_even) * draws as f64];
        let out = chi2_test(&observed, &expected);
        assert!(
            out.p_value > 0.01,
            "{out:?}: even share {} vs {p_even}",
            even / draws as f64
        );
    }

    #[test]
    fn rejects_bad_weights() {
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[1.0, f32::NAN]).is_none());
        assert!(AliasTable::new(&[1.0, -1.0]).is_none());
    }
}
