//! Choosing one of a set of weighted candidates with probability weight / Σ weights.

/// Index chosen for `u` ∈ [0, 1) among `weights` (non-negative, finite) with probability
/// `weights[i] / Σ weights`, and that sum; `None` when every weight is 0.
pub fn pick(weights: &[f32], u: f32) -> Option<(usize, f32)> {
    let total: f32 = weights.iter().sum();
    if !(total > 0.0) || !total.is_finite() {
        return None;
    }
    let target = u * total;
    let mut acc = 0.0f32;
    let mut last = None;
    for (i, &w) in weights.iter().enumerate() {
        if w > 0.0 {
            acc += w;
            last = Some(i);
            if target < acc {
                return Some((i, total));
            }
        }
    }
    // u·total can round up to the sum: the last non-zero weight takes it.
    last.map(|i| (i, total))
}

/// Probability that [`pick`] returns `i`.
pub fn pmf(weights: &[f32], i: usize) -> f32 {
    let total: f32 = weights.iter().sum();
    if total > 0.0 { weights[i] / total } else { 0.0 }
}
