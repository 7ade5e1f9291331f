//! Perspective cameras, looking down the node's −Z with +Y up; orthographic ones are skipped.
use super::{DEFAULT_CAMERA_HEIGHT, Loader};
use glam::{Mat4, Vec3};
use render_core::camera::Camera;
use render_core::error::SceneError;

impl Loader<'_> {
    /// Adds the node's camera (named for the camera, else the node).
    pub(super) fn add_camera(
        &mut self,
        node: &gltf::Node,
        camera: &gltf::Camera,
        world: Mat4,
    ) -> Result<(), SceneError> {
        let name = camera
            .name()
            .or(node.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("camera {}", camera.index()));
        let gltf::camera::Projection::Perspective(p) = camera.projection() else {
            self.report
                .warn(format!("orthographic camera `{name}` ignored"));
            return Ok(());
        };
        let yfov = p.yfov();
        let aspect = p
            .aspect_ratio()
            .filter(|a| a.is_finite() && *a > 0.0)
            .unwrap_or(1.0);
        let height = DEFAULT_CAMERA_HEIGHT;
        let width = ((height as f32 * aspect).round() as u32).clamp(1, 16384);
        let eye = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        let camera = Camera::look_at(&name, eye, eye + forward, up, yfov, width, height)
            .map_err(|e| self.err(e.to_string()))?;
        self.builder.add_camera(camera);
        self.report.cameras += 1;
        Ok(())
    }
}
