//! `scene-formats`: every way a scene reaches the manylights renderer, and the one way out.
//!
//! Readers build a [`render_core::scene::Scene`] through its `SceneBuilder`: glTF 2.0 files
//! ([`gltf_reader`]), pbrt-v4 and pbrt-v3 scene files ([`pbrt`]), TOML compositions placing
//! real assets with overrides and light layouts ([`composition`]) and the procedural
//! `builtin:` scenes ([`builtin`]). [`gltf_writer`] writes a loaded scene back as `.glb`.
//! [`load_scene`] picks the reader from the name given on the command line.

// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod builtin;
pub mod composition;
pub mod gltf_reader;
pub mod gltf_writer;
pub mod pbrt;
#[cfg(test)]
mod scratch;
#[cfg(test)]
mod test_notice;

use render_core::SceneError;
use render_core::scene::Scene;
use std::path::Path;

/// The scene formats a file name can name, by its extension (in any case).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileFormat {
    Gltf,
    Pbrt,
    Composition,
}

/// What the refusal of an unknown extension lists.
pub const SUPPORTED_FORMATS: &str = ".gltf, .glb, .pbrt, .toml, builtin:NAME";

impl FileFormat {
    /// The format of `path` by its extension, compared without case (`.GLB`, `P.PBRT`);
    /// an unknown or missing extension is an error naming the file.
    pub fn of(path: &Path) -> Result<FileFormat, SceneError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("gltf" | "glb") => Ok(FileFormat::Gltf),
            Some("pbrt") => Ok(FileFormat::Pbrt),
            Some("toml") => Ok(FileFormat::Composition),
            _ => Err(SceneError::UnsupportedFormat {
                path: path.display().to_string(),
                what: match path.extension() {
                    Some(e) => format!("format `.{}`", e.to_string_lossy()),
                    None => "format (the name has no extension)".into(),
                },
                supported: SUPPORTED_FORMATS.into(),
            }),
        }
    }
}

/// Loads a scene named on the command line: `builtin:NAME?key=value&…`, a composition file
/// (`.toml`, see [`composition`]), a pbrt scene (`.pbrt`, see [`pbrt`]) or a glTF file
/// (`.gltf`, `.glb`), the extension in any case; and makes the camera called `camera` its
/// first one.
pub fn load_scene(spec: &str, camera: Option<&str>) -> Result<Scene, SceneError> {
    if spec.starts_with("builtin:") {
        let mut scene = builtin::load_builtin(spec)?;
        scene.select_camera(camera)?;
        return Ok(scene);
    }
    let path = Path::new(spec);
    match FileFormat::of(path)? {
        FileFormat::Composition => {
            let mut scene = composition::load_composition(path)?;
            scene.select_camera(camera)?;
            Ok(scene)
        }
        FileFormat::Pbrt => pbrt::load_pbrt(path, camera),
        FileFormat::Gltf => gltf_reader::load_gltf(path, camera),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Extensions match in any case; any other is refused by name before the file is read
    /// (`bunny.ply` was read as glTF: "expected value at line 1 column 1").
    #[test]
    fn formats_follow_the_extension_in_any_case() {
        for (name, format) in [
            ("a.gltf", FileFormat::Gltf),
            ("dir.x/A.GLB", FileFormat::Gltf),
            ("P.PBRT", FileFormat::Pbrt),
            ("scene.Toml", FileFormat::Composition),
        ] {
            assert_eq!(FileFormat::of(Path::new(name)).unwrap(), format, "{name}");
        }
        for (name, want) in [
            ("bunny.ply", "bunny.ply: unsupported scene format `.ply`"),
            ("mesh.obj", "mesh.obj: unsupported scene format `.obj`"),
            (
                "dir.pbrt/noext",
                "noext: unsupported scene format (the name has no extension)",
            ),
            ("p.pbrt.txt", "p.pbrt.txt: unsupported scene format `.txt`"),
        ] {
            // the file does not exist: the name alone is refused
            let e = load_scene(name, None).err().expect(name).to_string();
            assert!(
                e.contains(want)
                    && e.ends_with("(supported: .gltf, .glb, .pbrt, .toml, builtin:NAME)"),
                "{name}: {e}"
            );
        }
    }
}
