//! RGBA float textures with bilinear filtering and repeat wrapping.
use glam::{Vec2, Vec4};

#[derive(Clone, Debug)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    /// Linear values, row-major, top row first.
    pub texels: Vec<Vec4>,
}

impl Texture {
    pub fn new(width: u32, height: u32, texels: Vec<Vec4>) -> Texture {
        assert_eq!(texels.len(), (width * height) as usize);
        Texture {
            width,
            height,
            texels,
        }
    }

    fn texel(&self, x: i64, y: i64) -> Vec4 {
        let w = self.width as i64;
        let h = self.height as i64;
        self.texels[(y.rem_euclid(h) * w + x.rem_euclid(w)) as usize]
    }

    /// Bilinear lookup at texture coordinates (glTF convention: v down).
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        if !x.is_finite() || !y.is_finite() {
            return self.texels[0];
        }
        let x0 = x.floor();
        let y0 = y.floor();
        let (fx, fy) = (x - x0, y - y0);
        // Wrapped first (texel() wraps again) so that x0 + 1 cannot overflow at huge uvs.
        let (x0, y0) = (
            (x0 as i64).rem_euclid(self.width as i64),
            (y0 as i64).rem_euclid(self.height as i64),
        );
        let a = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let b = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        a.lerp(b, fy)
    }
}

/// sRGB transfer function to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_hits_texel_centres_and_interpolates() {
        let t = Texture::new(2, 1, vec![Vec4::splat(0.0), Vec4::splat(1.0)]);
        assert_eq!(t.sample(Vec2::new(0.25, 0.5)).x, 0.0);
        assert_eq!(t.sample(Vec2::new(0.75, 0.5)).x, 1.0);
        assert!((t.sample(Vec2::new(0.5, 0.5)).x - 0.5).abs() < 1e-6);
        // wraps: halfway between the last and the first texel
        assert!((t.sample(Vec2::new(1.0, 0.5)).x - 0.5).abs() < 1e-6);
    }
}
