//! `manylights._native`: the Rust side of the Python package, thin over the workspace's crates.
//! The package's Python modules (python/manylights/) turn numpy arrays into the flat buffers
//! these functions take and the bytes they return back into arrays; every error is a Python
//! exception with the command line's one-line message, never a panic across the boundary.
// `!(x > 0.0)` is deliberate: it is also true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::nonminimal_bool)]

mod metrics;
mod render;
mod tree;

use pyo3::buffer::PyBuffer;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// A `ValueError` with `message`.
pub(crate) fn value_error(message: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(message.to_string())
}

/// The elements of a C-contiguous buffer of `T` (a numpy array of the matching dtype), checking
/// that there are `len` of them; `what` names the argument in the error.
pub(crate) fn read_buffer<T: pyo3::buffer::Element + Copy>(
    obj: &Bound<'_, PyAny>,
    len: Option<usize>,
    what: &str,
) -> PyResult<Vec<T>> {
    let buf = PyBuffer::<T>::get(obj).map_err(|e| value_error(format!("{what}: {e}")))?;
    if let Some(n) = len
        && buf.item_count() != n
    {
        return Err(value_error(format!(
            "{what} has {} values, expected {n}",
            buf.item_count()
        )));
    }
    buf.to_vec(obj.py())
}

/// Floats as native-endian bytes, for `numpy.frombuffer`.
pub(crate) fn f32_bytes<'py>(py: Python<'py>, v: impl Iterator<Item = f32>) -> Bound<'py, PyBytes> {
    let bytes: Vec<u8> = v.flat_map(f32::to_ne_bytes).collect();
    PyBytes::new(py, &bytes)
}

/// Pixels as `[r, g, b, r, g, b, …]` floats.
pub(crate) fn rgb_bytes<'py>(py: Python<'py>, px: &[glam::Vec3]) -> Bound<'py, PyBytes> {
    f32_bytes(py, px.iter().flat_map(|p| p.to_array()))
}

/// Pixels from `[r, g, b, …]` floats.
pub(crate) fn to_rgb(v: &[f32]) -> Vec<glam::Vec3> {
    v.chunks_exact(3).map(glam::Vec3::from_slice).collect()
}

#[pymodule]
mod _native {
    #[pymodule_export]
    use super::metrics::{error_metrics, hdr_flip, read_exr, read_mask_png};
    #[pymodule_export]
    use super::render::{Scene, load_scene, render, strategies};
    #[pymodule_export]
    use super::tree::LightTree;
}
