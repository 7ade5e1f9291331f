//! Colour: this renderer works in linear Rec. 709 RGB; luminance weighs light powers, BSDF
//! lobe choices, importances, exposure and error statistics.
use glam::Vec3;

/// Rec. 709 / sRGB luminance weights of linear R, G, B.
pub const LUMINANCE_WEIGHTS: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// Luminance of a linear RGB value.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(LUMINANCE_WEIGHTS)
}

/// Linear scale for a preview that maps the 97th percentile of the luminance of the `include`d
/// pixels (all of them when none is included) to 0.9, so that a bright scene is not white and a
/// dim one not black; 1 when nothing is lit. A percentile rather than the maximum, so that a few
/// fireflies or lights seen directly do not darken the rest.
pub fn auto_exposure_scale(px: &[Vec3], include: &[bool]) -> f32 {
    let any = include.iter().any(|&b| b);
    let mut l: Vec<f32> = px
        .iter()
        .enumerate()
        .filter(|(i, _)| !any || include.get(*i).copied().unwrap_or(false))
        .map(|(_, p)| luminance(*p))
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    if l.is_empty() {
        return 1.0;
    }
    l.sort_by(f32::total_cmp);
    let p = l[((l.len() - 1) as f32 * 0.97) as usize];
    if p > 0.0 { 0.9 / p } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_exposure_maps_the_97th_percentile_to_0_9() {
        // 100 pixels of luminance 1..=100: the 97th percentile (index 96) is 97
        let px: Vec<Vec3> = (1..=100).map(|i| Vec3::splat(i as f32)).collect();
        let all = vec![true; 100];
        let s = auto_exposure_scale(&px, &all);
        assert!((s * 97.0 - 0.9).abs() < 1e-5, "{s}");
        // excluded pixels (lights seen directly) do not count
        let mut some = vec![true; 100];
        some[50..].iter_mut().for_each(|b| *b = false);
        let s = auto_exposure_scale(&px, &some);
        assert!((s * 48.0 - 0.9).abs() < 1e-5, "{s}");
        // nothing included: every pixel counts; nothing lit: 1
        assert_eq!(auto_exposure_scale(&px, &[false; 100]), s_all(&px));
        assert_eq!(auto_exposure_scale(&[Vec3::ZERO; 4], &[true; 4]), 1.0);
    }

    fn s_all(px: &[Vec3]) -> f32 {
        auto_exposure_scale(px, &vec![true; px.len()])
    }
}
