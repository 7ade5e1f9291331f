//! Orthonormal frames: the local shading space has z along the normal.
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl Frame {
    /// A frame around a unit normal (Duff et al. 2017, branchless and continuous).
    pub fn from_normal(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { x, y, z: n }
    }

    /// A frame around `n` whose x axis is the projection of `w` onto the tangent plane
    /// (falls back to an arbitrary tangent when `w` is parallel to `n`).
    pub fn from_normal_and_direction(n: Vec3, w: Vec3) -> Frame {
        let t = w - n * n.dot(w);
        let len2 = t.length_squared();
        if len2 < 1e-14 {
            return Frame::from_normal(n);
        }
        let x = t / len2.sqrt();
        Frame {
            x,
            y: n.cross(x),
            z: n,
        }
    }

    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }

    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_and_round_trip() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.5, 0.81).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!((f.x.dot(f.y)).abs() < 1e-6 && (f.x.dot(f.z)).abs() < 1e-6);
            assert!((f.x.cross(f.y) - f.z).length() < 1e-5, "right-handed");
            let v = Vec3::new(0.2, 0.7, -0.1);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-6);
        }
        let f = Frame::from_normal_and_direction(Vec3::Z, Vec3::new(1.0, 1.0, 1.0));
        assert!((f.x - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    }
}
