//! The node hierarchy: the default scene's nodes (else the first scene's, else every root
//! node), each under its full world transform, and what each node carries.
use super::{Loader, gltf_err};
use glam::Mat4;
use render_core::error::SceneError;

impl Loader<'_> {
    /// An error naming the file.
    pub(super) fn err(&self, message: impl Into<String>) -> SceneError {
        gltf_err(self.path, message)
    }

    /// Walks the nodes under `root` (depth first, in file order), adding their meshes, lights
    /// and cameras.
    pub(super) fn load(&mut self, root: Mat4) -> Result<(), SceneError> {
        self.read_render_hints()?;
        let doc = self.doc;
        let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(scene) => scene.nodes().collect(),
            None => {
                // No scene at all: every node that is nobody's child.
                let mut is_child = vec![false; doc.nodes().len()];
                for n in doc.nodes() {
                    for c in n.children() {
                        is_child[c.index()] = true;
                    }
                }
                doc.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };
        let max_depth = doc.nodes().len();
        let mut stack: Vec<(gltf::Node, Mat4, usize)> =
            roots.into_iter().rev().map(|n| (n, root, 0)).collect();
        while let Some((node, parent, depth)) = stack.pop() {
            if depth > max_depth {
                return Err(self.err("the node hierarchy has a cycle"));
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            let world = parent * local;
            if let Some(mesh) = node.mesh() {
                self.add_mesh(&node, &mesh, world)?;
            }
            if let Some(light) = node.light() {
                self.add_light(&node, &light, world)?;
            }
            if let Some(camera) = node.camera() {
                self.add_camera(&node, &camera, world)?;
            }
            if node.skin().is_some() {
                self.report
                    .warn("skins are ignored (meshes are read in their bind pose)".into());
            }
            let children: Vec<gltf::Node> = node.children().collect();
            for c in children.into_iter().rev() {
                stack.push((c, world, depth + 1));
            }
        }
        Ok(())
    }
}
