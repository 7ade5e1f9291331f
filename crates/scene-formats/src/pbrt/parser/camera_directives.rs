//! The camera and the film: `Camera` (perspective; its transform names the `camera`
//! coordinate system), `Film` (the resolution) and, once the file is read, the camera made from
//! both.
use super::Parser;
use super::records::CameraSpec;
use glam::DMat4;
use glam::DVec3;
use render_core::camera::{Camera, check_yfov};
use render_core::error::SceneError;

impl Parser<'_> {
    /// `Camera`: recorded, since the film that shapes it may come later.
    pub(super) fn camera_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let ty = self.string_arg("Camera", line)?;
        let p = self.params()?;
        let world_from_camera = self.state.ctm.inverse();
        self.named_coords.insert("camera".into(), world_from_camera);
        if ty != "perspective" {
            self.warn(line, format!("Camera \"{ty}\" is not supported: a perspective camera with the same transform is used"));
        }
        let fov = p.float("fov", 90.0).map_err(|m| self.err(line, m))? as f64;
        // Checked here for the line (the camera made at the end checks its vertical field of
        // view again); pbrt's fov spans the shorter image axis, so the message says fov.
        check_yfov(fov.to_radians() as f32)
            .map_err(|_| self.err(line, format!("Camera: fov {fov}° is not in (0°, 180°)")))?;
        if p.float("lensradius", 0.0).map_err(|m| self.err(line, m))? > 0.0 {
            self.warn(line, "Camera: depth of field is not supported (pinhole)");
        }
        p.touch("focaldistance");
        self.unused(&format!("Camera \"{ty}\""), &p, &[]);
        self.camera = Some(CameraSpec {
            camera_from_world: self.state.ctm,
            fov_degrees: fov,
            file: self.current_file(),
            line,
        });
        Ok(())
    }

    /// `Film`: its resolution (the output file name is ours to choose).
    pub(super) fn film_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let _ty = self.string_arg("Film", line)?;
        let p = self.params()?;
        let w = p.int("xresolution", 1280).map_err(|m| self.err(line, m))?;
        let h = p.int("yresolution", 720).map_err(|m| self.err(line, m))?;
        if !(1..=65536).contains(&w) || !(1..=65536).contains(&h) {
            return Err(self.err(line, format!("Film resolution {w} × {h} is out of range")));
        }
        self.film = (w as u32, h as u32);
        self.unused("Film", &p, &["filename"]);
        Ok(())
    }

    /// pbrt's camera: camera space looks down +z with +y up and +x to the image's right; the
    /// field of view spans the image's shorter axis.
    pub(super) fn finish_camera(&mut self) -> Result<(), SceneError> {
        let spec = self.camera.take().unwrap_or(CameraSpec {
            camera_from_world: DMat4::IDENTITY,
            fov_degrees: 90.0,
            file: self.current_file(),
            line: 0,
        });
        let w = self.root * spec.camera_from_world.inverse();
        let eye = w.transform_point3(DVec3::ZERO);
        let forward = w.transform_vector3(DVec3::Z);
        let up = w.transform_vector3(DVec3::Y);
        let right = w.transform_vector3(DVec3::X);
        let (fl, ul, rl) = (forward.length(), up.length(), right.length());
        let rigid = (fl - ul).abs() < 1e-6 * fl
            && (fl - rl).abs() < 1e-6 * fl
            && forward.dot(up).abs() < 1e-6 * fl * ul
            && forward.dot(right).abs() < 1e-6 * fl * rl;
        if !rigid {
            let at = format!("{}:{}", spec.file, spec.line);
            self.warnings.push((
                "the camera transform scales or shears: its rotation is used".into(),
                at,
                1,
            ));
        }
        let forward = forward.normalize();
        let up = (up - forward * up.dot(forward)).normalize();
        let mirrored = forward.cross(up).dot(right) < 0.0;
        let (width, height) = self.film;
        let half = (spec.fov_degrees.to_radians() * 0.5).tan();
        // fov spans the shorter axis; ours is vertical
        let yfov = if width >= height {
            spec.fov_degrees.to_radians()
        } else {
            2.0 * (half * height as f64 / width as f64).atan()
        };
        let mut camera = Camera::look_at(
            "pbrt camera",
            eye.as_vec3(),
            (eye + forward).as_vec3(),
            up.as_vec3(),
            yfov as f32,
            width,
            height,
        )
        .map_err(|e| SceneError::Pbrt {
            path: spec.file.clone(),
            line: spec.line,
            message: format!("the camera transform is degenerate: {e}"),
        })?;
        camera.mirrored = mirrored;
        self.builder.add_camera(camera);
        Ok(())
    }
}
