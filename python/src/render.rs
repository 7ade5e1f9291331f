//! Scenes, renders and the strategy list: the command line's own code (`manylights::render_cmd`)
//! with the flags given as an argument list, so that a render and its errors are the CLI's.
use crate::{f32_bytes, rgb_bytes, value_error};
use manylights::render_cmd;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use render_core::render::{RenderResult, render_cancellable};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// How often a render's caller wakes to look for Ctrl-C and report progress.
const POLL: Duration = Duration::from_millis(50);

/// A loaded scene: the spec it was loaded from and the camera asked for.
#[pyclass(frozen, module = "manylights._native")]
pub struct Scene {
    inner: Arc<render_core::scene::Scene>,
    #[pyo3(get)]
    spec: String,
    #[pyo3(get)]
    camera: Option<String>,
    /// The scene's content hash, computed once at load for every render's JSON (hashing a
    /// large scene takes longer than a small render).
    hash: String,
}

#[pymethods]
impl Scene {
    /// `--light-points` of the renders of this scene.
    #[getter]
    fn light_points(&self) -> &'static str {
        self.inner.light_points.name()
    }

    /// `manylights info --json` of the scene, as JSON text.
    /// What the scene file holds that the renderer does not model (skipped), one line each, as
    /// the command line prints them.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.stats.warnings.clone()
    }

    fn info_json(&self) -> String {
        manylights::scene_info_json((&self.spec, &self.hash), &self.inner).to_string()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}: {} triangles, {} lights)",
            self.spec,
            self.inner.stats.triangles,
            self.inner.lights.len() + self.inner.distant_lights.len()
        )
    }
}

/// Loads a scene as `manylights render` does (any spec it takes), with `--light-points`'s
/// sampler of points on triangle lights (a property of the loaded scene); the GIL is released
/// meanwhile.
#[pyfunction]
#[pyo3(signature = (spec, camera=None, light_points=None))]
pub fn load_scene(
    py: Python<'_>,
    spec: String,
    camera: Option<String>,
    light_points: Option<String>,
) -> PyResult<Scene> {
    let points = match light_points {
        Some(name) => render_core::light_points::LightPoints::parse(&name).map_err(value_error)?,
        None => Default::default(),
    };
    let (mut scene, hash) = py
        .detach(|| {
            let scene = scene_formats::load_scene(&spec, camera.as_deref())?;
            let hash = scene.content_hash();
            Ok((scene, hash))
        })
        .map_err(scene_error)?;
    scene.light_points = points;
    Ok(Scene {
        inner: Arc::new(scene),
        spec,
        camera,
        hash,
    })
}

/// A scene that cannot be loaded as a Python exception: `FileNotFoundError` for a file that is
/// not there, `OSError` for one that cannot be read, `ValueError` for one that is not a scene
/// (the command line's message in each).
fn scene_error(e: render_core::error::SceneError) -> PyErr {
    use render_core::error::SceneError;
    let missing = match &e {
        SceneError::Io { path, .. } => Some(!std::path::Path::new(path).exists()),
        _ => None,
    };
    let message = format!("{:#}", anyhow::Error::from(e));
    match missing {
        Some(true) => pyo3::exceptions::PyFileNotFoundError::new_err(message),
        Some(false) => pyo3::exceptions::PyOSError::new_err(message),
        None => value_error(message),
    }
}

/// `manylights strategies --json`, as JSON text.
#[pyfunction]
pub fn strategies() -> String {
    manylights::strategies_json().to_string()
}

/// Renders `scene` with `render`'s flags `argv` (the scene's spec first, as on the command
/// line; `--out` is required by the parser but nothing is written). The GIL is released while
/// it renders; Ctrl-C cancels it and raises `KeyboardInterrupt`; `progress(spp_done)` is called
/// after each full pass when given. Returns the image, the light fractions and the aux
/// channels as float32 bytes, and the JSON record as text.
#[pyfunction]
#[pyo3(signature = (scene, argv, progress=None))]
pub fn render<'py>(
    py: Python<'py>,
    scene: &Scene,
    argv: Vec<String>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let args = render_cmd::parse_args(&argv).map_err(value_error)?;
    if args.scene != scene.spec || args.camera != scene.camera {
        return Err(value_error(
            "the flags name another scene or camera than the scene given",
        ));
    }
    if args.strategy.light_points != scene.inner.light_points {
        return Err(value_error(format!(
            "the scene was loaded with light_points={}: give light_points to load_scene",
            scene.inner.light_points.name()
        )));
    }
    let cli_error = |e: anyhow::Error| value_error(format!("{e:#}"));
    render_cmd::check_args(&args).map_err(cli_error)?;
    let prepared = render_cmd::prepare(&args, &scene.inner).map_err(cli_error)?;
    let result = run_interruptible(py, &scene.inner, &prepared, progress)?;
    let meta = prepared.metadata(&args, (&scene.inner, &scene.hash), &result);
    let out = PyDict::new(py);
    out.set_item("width", result.width)?;
    out.set_item("height", result.height)?;
    out.set_item("image", rgb_bytes(py, &result.pixels))?;
    out.set_item(
        "light_fraction",
        f32_bytes(py, result.light_fraction.iter().copied()),
    )?;
    let aux: Vec<(String, Bound<'py, PyBytes>)> = result
        .aux
        .iter()
        .map(|(name, v)| (name.clone(), f32_bytes(py, v.iter().copied())))
        .collect();
    out.set_item("aux", aux)?;
    out.set_item("metadata", meta.to_string())?;
    Ok(out)
}

/// The render on a thread of its own while this one, the caller's, waits with the GIL released,
/// waking every [`POLL`] to report progress and to look for a signal: Python raises Ctrl-C's
/// `KeyboardInterrupt` only on its main thread, between bytecodes, which a render never reaches.
fn run_interruptible(
    py: Python<'_>,
    scene: &render_core::scene::Scene,
    prepared: &render_cmd::Prepared,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<RenderResult> {
    let cancel = AtomicBool::new(false);
    let spp_done = AtomicU32::new(0);
    let (tx, mut rx) = mpsc::channel();
    std::thread::scope(|s| {
        s.spawn(|| {
            let run = || {
                render_cancellable(
                    scene,
                    prepared.strategy.as_ref(),
                    &prepared.settings,
                    &|_, spp| spp_done.store(spp, Ordering::Relaxed),
                    &cancel,
                )
            };
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(run));
            let _ = tx.send(outcome);
        });
        let mut interrupted: Option<PyErr> = None;
        let mut reported = 0;
        let outcome = loop {
            let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
            rx = back;
            match received {
                Ok(outcome) => break outcome,
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    break Ok(Err("the render thread ended without a result".into()));
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
            }
            if interrupted.is_some() {
                continue;
            }
            let spp = spp_done.load(Ordering::Relaxed);
            let reported_ok = match (&progress, spp > reported) {
                (Some(f), true) => f.call1((spp,)).map(|_| reported = spp),
                _ => Ok(()),
            };
            if let Err(e) = reported_ok.and_then(|()| py.check_signals()) {
                cancel.store(true, Ordering::Relaxed);
                interrupted = Some(e);
            }
        };
        if let Some(e) = interrupted {
            return Err(e);
        }
        let spp = spp_done.load(Ordering::Relaxed);
        if let Some(f) = progress.as_ref().filter(|_| spp > reported) {
            f.call1((spp,))?;
        }
        match outcome {
            Ok(Ok(result)) => Ok(result),
            Ok(Err(message)) => Err(value_error(message)),
            Err(_) => Err(pyo3::exceptions::PyRuntimeError::new_err(
                "the render panicked (a bug: please report it with the flags)",
            )),
        }
    })
}
