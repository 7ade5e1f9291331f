//! Colour: this renderer works in linear Rec. 709 RGB; luminance weighs light powers, BSDF
//! lobe choices, importances, exposure and error statistics.
use glam::Vec3;

/// Rec. 709 / sRGB luminance weights of linear R, G, B.
pub const LUMINANCE_WEIGHTS: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// Luminance of a linear RGB value.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(LUMINANCE_WEIGHTS)
}
