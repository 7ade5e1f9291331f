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

/// Why [`Camera::look_at`] refused a camera: the camera's name and the problem, one line.
/// Scene readers wrap it with their file (and line).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("camera `{name}`: {problem}")]
pub struct CameraError {
    pub name: String,
    pub problem: String,
}

/// The sine of the smallest angle between the up vector and the view direction that still
/// gives a well-defined image frame.
const MIN_UP_SINE: f32 = 1e-6;

/// Checks a vertical field of view in radians: finite and strictly between 0 and π (0 sees
/// nothing, π and more is not a pinhole projection). The message gives it in degrees.
pub fn check_yfov(yfov: f32) -> Result<(), String> {
    if yfov > 0.0 && yfov < std::f32::consts::PI {
        Ok(())
    } else {
        Err(format!("yfov {}° is not in (0°, 180°)", yfov.to_degrees()))
    }
}

impl Camera {
    /// A camera at `eye` looking at `target`, its image's up as close to `up` as the view
    /// direction allows, with vertical field of view `yfov` (radians). Every scene reader
    /// builds its cameras here, so this is the one check: `eye` and `target` finite and
    /// distinct, `up` finite and not parallel to the view direction, `yfov` in (0, π), and
    /// the image at least 1 × 1.
    pub fn look_at(
        name: &str,
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        yfov: f32,
        width: u32,
        height: u32,
    ) -> Result<Camera, CameraError> {
        let refuse = |problem: String| CameraError {
            name: name.to_string(),
            problem,
        };
        if !eye.is_finite() || !target.is_finite() {
            return Err(refuse(format!(
                "eye {} and target {} must be finite",
                fmt3(eye),
                fmt3(target)
            )));
        }
        let forward = (target - eye).normalize();
        if !forward.is_finite() {
            return Err(refuse(format!(
                "eye and target are the same point {} (no view direction)",
                fmt3(eye)
            )));
        }
        // (the sine on the unit up; the frame from `up` as given, as it always was)
        let right = forward.cross(up).normalize();
        let sine = forward.cross(up.normalize()).length();
        if !(sine > MIN_UP_SINE) || !right.is_finite() || right == Vec3::ZERO {
            return Err(refuse(format!(
                "up {} must be finite, non-zero and not parallel to the view direction {}",
                fmt3(up),
                fmt3(forward)
            )));
        }
        check_yfov(yfov).map_err(refuse)?;
        if width == 0 || height == 0 {
            return Err(refuse(format!(
                "image size {width} × {height} must be at least 1 × 1"
            )));
        }
        Ok(Camera {
            name: name.to_string(),
            position: eye,
            forward,
            up: right.cross(forward),
            yfov,
            width,
            height,
            mirrored: false,
        })
    }

    /// A camera framing an axis-aligned box from the front-upper side (used when a glTF file
    /// has none). Fails only where the box is so far from the origin that the camera's
    /// distance is lost to rounding.
    pub fn framing(lo: Vec3, hi: Vec3, width: u32, height: u32) -> Result<Camera, CameraError> {
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

/// A vector as `[x, y, z]` for messages.
fn fmt3(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(eye: Vec3, target: Vec3, up: Vec3, yfov_deg: f32) -> Result<Camera, CameraError> {
        Camera::look_at("c", eye, target, up, yfov_deg.to_radians(), 32, 24)
    }

    /// Each degenerate camera is an error naming the camera and what is wrong; before the
    /// check, each made NaN rays (a black image) or no image at all.
    #[test]
    fn degenerate_cameras_are_refused() {
        let (eye, target) = (Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO);
        assert!(camera(eye, target, Vec3::Y, 40.0).is_ok());
        let cases = [
            (camera(eye, eye, Vec3::Y, 40.0), "the same point"),
            (camera(Vec3::NAN, target, Vec3::Y, 40.0), "must be finite"),
            (camera(eye, Vec3::INFINITY, Vec3::Y, 40.0), "must be finite"),
            (camera(eye, target, Vec3::ZERO, 40.0), "parallel"),
            (camera(eye, target, Vec3::NAN, 40.0), "parallel"),
            (camera(eye, target, eye - target, 40.0), "parallel"),
            (camera(Vec3::Y, Vec3::ZERO, Vec3::Y, 40.0), "parallel"),
            (camera(eye, target, Vec3::Y, 0.0), "yfov 0°"),
            (camera(eye, target, Vec3::Y, 180.0), "yfov 180°"),
            (camera(eye, target, Vec3::Y, -10.0), "yfov -10°"),
            (camera(eye, target, Vec3::Y, f32::NAN), "yfov NaN°"),
        ];
        for (k, (result, expected)) in cases.into_iter().enumerate() {
            let e = result.expect_err(&format!("case {k} must be refused"));
            let text = e.to_string();
            assert!(
                text.starts_with("camera `c`: ") && text.contains(expected) && !text.contains('\n'),
                "case {k}: {text}"
            );
        }
        let e = Camera::look_at("c", eye, target, Vec3::Y, 0.7, 0, 24).unwrap_err();
        assert!(e.to_string().contains("0 × 24"), "{e}");
    }

    /// The frame of a valid camera is orthonormal and looks at the target.
    #[test]
    fn a_valid_camera_looks_at_its_target() {
        let c = camera(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        let to_target = (Vec3::ZERO - c.position).normalize();
        assert!((c.forward - to_target).length() < 1e-6);
        assert!(c.forward.dot(c.up).abs() < 1e-6 && (c.up.length() - 1.0).abs() < 1e-6);
        assert!(c.up.y > 0.0);
    }

    /// A box far from the origin whose framing distance is lost to rounding is an error, not
    /// a camera with a NaN view direction.
    #[test]
    fn framing_a_lost_box_is_an_error() {
        assert!(Camera::framing(Vec3::splat(-1.0), Vec3::ONE, 64, 64).is_ok());
        let far = Vec3::splat(1e18);
        assert!(Camera::framing(far, far, 64, 64).is_err());
    }
}
