//! Pinhole perspective camera.
use glam::{Vec2, Vec3};

#[derive(Clone, Debug, serde::Serialize)]
pub struct Camera {
    pub name: String,
    pub position: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// Unit up vector, orthogonal to `forward`.
    pub up: Vec3,
    /// Vertical field of view in radians.
    pub yfov: f32,
    /// Preferred image size; the command line may override it.
    pub width: u32,
    pub height: u32,
    /// The image's right is −(forward × up): a camera whose frame is left-handed in world
    /// space, as pbrt's `LookAt` makes for a right-handed scene.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub mirrored: bool,
}

impl Camera {
    pub fn look_at(
        name: &str,
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        yfov: f32,
        width: u32,
        height: u32,
    ) -> Camera {
        let forward = (target - eye).normalize();
        let right = forward.cross(up).normalize();
        Camera {
            name: name.to_string(),
            position: eye,
            forward,
            up: right.cross(forward),
            yfov,
            width,
            height,
            mirrored: false,
        }
    }

    /// A camera framing an axis-aligned box from the front-upper side (used when a glTF file has none).
    pub fn framing(lo: Vec3, hi: Vec3, width: u32, height: u32) -> Camera {
        let center = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(1e-3);
        let yfov = 45f32.to_radians();
        let dist = radius / (0.5 * yfov).sin() * 1.05;
        let dir = Vec3::new(0.0, 0.35, 1.0).normalize();
        Camera::look_at(
            "default",
            center + dir * dist,
            center,
            Vec3::Y,
            yfov,
            width,
            height,
        )
    }

    /// World direction of the image's +x.
    pub fn right(&self) -> Vec3 {
        let r = self.forward.cross(self.up);
        if self.mirrored { -r } else { r }
    }

    /// World ray through film position `film` in [0,1]² (x right, y down) for an image of the given aspect.
    pub fn ray_direction(&self, film: Vec2, aspect: f32) -> Vec3 {
        self.film_rays(aspect).direction(film)
    }

    /// What every camera ray of an image of the given aspect shares, computed once.
    pub fn film_rays(&self, aspect: f32) -> FilmRays {
        FilmRays {
            forward: self.forward,
            right: self.right(),
            up: self.up,
            tan: (0.5 * self.yfov).tan(),
            aspect,
        }
    }
}

/// A camera's frame and field of view for one image: [`Camera::ray_direction`] without the
/// tangent and the cross product per ray (the same operations, so the same directions).
#[derive(Clone, Copy, Debug)]
pub struct FilmRays {
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan: f32,
    aspect: f32,
}

impl FilmRays {
    /// The unit direction through film position `film` in [0,1]² (x right, y down).
    #[inline]
    pub fn direction(&self, film: Vec2) -> Vec3 {
        let sx = (2.0 * film.x - 1.0) * self.tan * self.aspect;
        let sy = (1.0 - 2.0 * film.y) * self.tan;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }
}
