//! pbrt scene files (`.pbrt`): pbrt-v4 and the pbrt-v3 syntax (e.g. the authors' Cornell box).
//!
//! * [`tokenizer`]: streaming lexer (the text is never held whole);
//! * [`params`]: `"type name" [values]` lists, typed look-ups;
//! * [`parser`]: include stack, graphics state, every directive → [`SceneBuilder`];
//! * [`shapes`], [`ply`]: meshes; [`materials`]: materials and constant textures.
//!
//! Unsupported features are warnings naming the file and line; input we cannot render is an
//! error with file and line. docs/scenes.md maps every directive.
pub mod materials;
pub mod params;
pub mod parser;
pub mod ply;
pub mod shapes;
pub mod tokenizer;

#[cfg(test)]
mod tests;

use glam::Mat4;
use render_core::error::SceneError;
use render_core::scene::{Scene, SceneBuilder};
use std::path::Path;

pub use parser::PbrtReport;

/// Adds a pbrt scene to `builder` under `root` (its camera included).
pub fn add_pbrt(
    builder: &mut SceneBuilder,
    path: &Path,
    root: Mat4,
) -> Result<PbrtReport, SceneError> {
    parser::Parser::new(builder, path, root)?.run()
}

/// Loads a pbrt scene; its warnings are in the scene's stats.
pub fn load_pbrt(path: &Path, camera: Option<&str>) -> Result<Scene, SceneError> {
    Ok(load_pbrt_with_report(path, camera)?.0)
}

pub fn load_pbrt_with_report(
    path: &Path,
    camera: Option<&str>,
) -> Result<(Scene, PbrtReport), SceneError> {
    let mut builder = SceneBuilder::new(&path.display().to_string());
    let report = add_pbrt(&mut builder, path, Mat4::IDENTITY)?;
    if report.triangles == 0 && report.sphere_lights == 0 {
        return Err(SceneError::Pbrt {
            path: path.display().to_string(),
            line: 0,
            message: "no shapes: nothing to render".into(),
        });
    }
    let mut scene = builder.build()?;
    scene.stats.warnings.extend(report.warnings.iter().cloned());
    scene.select_camera(camera)?;
    Ok((scene, report))
}
