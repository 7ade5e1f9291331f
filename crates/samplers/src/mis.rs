//! Multiple importance sampling weights.

/// Power heuristic (β = 2) with sample counts: weight of technique `t` among (count, pdf) pairs.
pub fn power_heuristic(t: usize, techniques: &[(f32, f32)]) -> f32 {
    // Scale by the largest n·p so that squares neither overflow nor underflow.
    let m = techniques
        .iter()
        .map(|&(n, p)| n * p)
        .fold(0.0f32, f32::max);
    let (nt, pt) = techniques[t];
    if !(nt * pt > 0.0) || !(m > 0.0) {
        return 0.0;
    }
    if m.is_infinite() {
        let infinite = techniques
            .iter()
            .filter(|&&(n, p)| (n * p).is_infinite())
            .count();
        return if (nt * pt).is_infinite() {
            1.0 / infinite as f32
        } else {
            0.0
        };
    }
    let q = nt * pt / m;
    let den: f32 = techniques
        .iter()
        .map(|&(n, p)| (n * p / m) * (n * p / m))
        .sum();
    q * q / den
}

/// Two techniques with one sample each.
pub fn power2(pa: f32, pb: f32) -> f32 {
    power_heuristic(0, &[(1.0, pa), (1.0, pb)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one() {
        let sets: [&[(f32, f32)]; 3] = [
            &[(1.0, 0.3), (1.0, 2.0)],
            &[(1.0, 1e-30), (3.0, 5.0), (7.0, 0.01)],
            &[(1.0, 1e20), (2.0, 1e19)],
        ];
        for s in sets {
            let sum: f32 = (0..s.len()).map(|t| power_heuristic(t, s)).sum();
            assert!((sum - 1.0).abs() < 1e-5, "{s:?}: {sum}");
        }
        assert_eq!(power2(0.0, 1.0), 0.0);
        assert_eq!(power2(1.0, 0.0), 1.0);
    }

    #[test]
    fn weights_with_counts_sum_to_one_over_random_pdf_sets() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(17);
        for _ in 0..20_000 {
            let k = rng.random_range(1..5usize);
            let set: Vec<(f32, f32)> = (0..k)
                .map(|_| {
                    let n = rng.random_range(0..60u32) as f32;
                    let e = rng.random_range(-30.0f32..30.0);
                    let p = if rng.random::<f32>() < 0.1 {
                        0.0
                    } else {
                        10f32.powf(e)
                    };
                    (n, p)
                })
                .collect();
            let any = set.iter().any(|&(n, p)| n * p > 0.0);
            let sum: f32 = (0..k).map(|t| power_heuristic(t, &set)).sum();
            if any {
                assert!((sum - 1.0).abs() < 1e-4, "{set:?}: {sum}");
            } else {
                assert_eq!(sum, 0.0);
            }
        }
    }
}
