//! Errors a user can cause with bad input: each names the problem in one line.
use thiserror::Error;

#[derive(Debug, Error)]
pub enum SceneError {
    #[error("cannot read scene file {path}: {message}")]
    Io { path: String, message: String },
    #[error("malformed glTF {path}: {message}")]
    Gltf { path: String, message: String },
    /// A pbrt scene file: where and what. `line` 0 means the file as a whole.
    #[error("{path}{}: {message}", line_suffix(*line))]
    Pbrt {
        path: String,
        line: usize,
        message: String,
    },
    #[error("malformed scene composition {path}: {message}")]
    Composition { path: String, message: String },
    #[error("scene has no triangles and no lights")]
    Empty,
    #[error("non-finite vertex position in mesh `{mesh}` (or beyond ±1e18 after its transform)")]
    NonFiniteVertex { mesh: String },
    #[error("invalid material `{name}`: {message}")]
    BadMaterial { name: String, message: String },
    #[error("invalid emission in {what}: {value} (must be finite and non-negative)")]
    BadEmission { what: String, value: String },
    /// A light whose emitted power (radiance × area, intensity × 4π) overflows f32.
    #[error(
        "{what}: emission {emission} over {size} emits an infinite power (it must stay below 3.4e38 W: lower the emission or the size)"
    )]
    InfinitePower {
        what: String,
        emission: String,
        size: String,
    },
    #[error("invalid light `{what}`: {message}")]
    BadLight { what: String, message: String },
    /// A camera a scene made (a built-in's, or the default framing one) that cannot image
    /// anything; the readers of files report theirs with the file instead.
    #[error("scene `{scene}`: {error}")]
    BadCamera {
        scene: String,
        error: crate::camera::CameraError,
    },
    /// A scene file whose name says no format we read.
    #[error("{path}: unsupported scene {what} (supported: {supported})")]
    UnsupportedFormat {
        path: String,
        what: String,
        supported: String,
    },
    /// An error of the scene builder (which knows no files), in the file that caused it.
    #[error("{path}: {error}")]
    InFile {
        path: String,
        error: Box<SceneError>,
    },
    /// `known`: the scene's camera names, listed for the message.
    #[error("camera `{name}` not found in the scene{suggestion} ({known})")]
    CameraNotFound {
        name: String,
        suggestion: String,
        known: String,
    },
    /// `suggestion`: empty, or "; did you mean `x`?" ([`crate::suggest::did_you_mean`]).
    #[error("unknown built-in scene `{name}`{suggestion} (known: {known})")]
    UnknownBuiltin {
        name: String,
        suggestion: String,
        known: String,
    },
    #[error("bad parameter `{key}` for built-in scene `{scene}`: {message}")]
    BadBuiltinParam {
        scene: String,
        key: String,
        message: String,
    },
}

impl SceneError {
    /// The error itself, under any [`SceneError::InFile`] that says where it arose.
    pub fn cause(&self) -> &SceneError {
        match self {
            SceneError::InFile { error, .. } => error.cause(),
            e => e,
        }
    }

    /// `self` as an error of the file `path`, unless it names its file already (the errors
    /// of the scene builder do not: it knows no files).
    pub fn in_file(self, path: &std::path::Path) -> SceneError {
        match self {
            SceneError::Empty
            | SceneError::NonFiniteVertex { .. }
            | SceneError::BadMaterial { .. }
            | SceneError::BadEmission { .. }
            | SceneError::BadLight { .. }
            | SceneError::InfinitePower { .. } => SceneError::InFile {
                path: path.display().to_string(),
                error: Box::new(self),
            },
            e => e,
        }
    }
}

/// `:line` after a file name, nothing for line 0 (the file as a whole).
fn line_suffix(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(":{line}")
    }
}
