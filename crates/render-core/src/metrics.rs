//! Error metrics of a render against a reference.
use glam::Vec3;
use serde::Serialize;

/// The ε of relMSE: (x − r)² / (r² + ε).
pub const REL_MSE_EPSILON: f64 = 0.01;

#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct ErrorMetrics {
    /// Mean over pixels and channels of (x − r)² / (r² + 0.01).
    pub rel_mse: f64,
    /// Mean over pixels and channels of (x − r)².
    pub mse: f64,
    /// Pixels that entered the means.
    pub pixels: usize,
}

/// Metrics over the pixels where `mask` is true (all pixels when `None`).
pub fn error_metrics(image: &[Vec3], reference: &[Vec3], mask: Option<&[bool]>) -> ErrorMetrics {
    assert_eq!(
        image.len(),
        reference.len(),
        "image and reference differ in size"
    );
    let (mut rel, mut abs, mut n) = (0.0f64, 0.0f64, 0usize);
    for (i, (x, r)) in image.iter().zip(reference).enumerate() {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        for k in 0..3 {
            let (x, r) = (x[k] as f64, r[k] as f64);
            let d2 = (x - r) * (x - r);
            abs += d2;
            rel += d2 / (r * r + REL_MSE_EPSILON);
        }
        n += 1;
    }
    if n == 0 {
        return ErrorMetrics::default();
    }
    let m = 3.0 * n as f64;
    ErrorMetrics {
        rel_mse: rel / m,
        mse: abs / m,
        pixels: n,
    }
}

/// Per-pixel relative squared error (mean over channels), for error maps.
pub fn rel_mse_map(image: &[Vec3], reference: &[Vec3]) -> Vec<f32> {
    image
        .iter()
        .zip(reference)
        .map(|(x, r)| {
            let mut e = 0.0f64;
            for k in 0..3 {
                let (x, r) = (x[k] as f64, r[k] as f64);
                e += (x - r) * (x - r) / (r * r + REL_MSE_EPSILON);
            }
            (e / 3.0) as f32
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_follow_their_definitions() {
        let r = [Vec3::splat(1.0), Vec3::splat(0.0)];
        let x = [Vec3::splat(1.1), Vec3::splat(0.1)];
        let m = error_metrics(&x, &r, None);
        assert!((m.mse - 0.01).abs() < 1e-6);
        let expected = (0.01 / 1.01 + 0.01 / 0.01) / 2.0;
        assert!((m.rel_mse - expected).abs() < 1e-6);
        let masked = error_metrics(&x, &r, Some(&[true, false]));
        assert_eq!(masked.pixels, 1);
        assert!((masked.rel_mse - 0.01 / 1.01).abs() < 1e-6);
    }
}
