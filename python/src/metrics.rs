//! The harness's error metrics on flat pixel buffers: relMSE and MSE (`render_core::metrics`)
//! and HDR-ꟻLIP (`hdr-flip`), so that a notebook's numbers are the tables'.
use crate::{read_buffer, rgb_bytes, to_rgb, value_error};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// An image, its reference and the pixels kept.
type Images = (Vec<glam::Vec3>, Vec<glam::Vec3>, Option<Vec<bool>>);

/// Two images' pixels, checked to be `w` × `h` RGB, and the mask of the pixels to keep.
fn images(
    image: &Bound<'_, PyAny>,
    reference: &Bound<'_, PyAny>,
    mask: Option<&Bound<'_, PyAny>>,
    (w, h): (u32, u32),
) -> PyResult<Images> {
    let n = w as usize * h as usize;
    let x = to_rgb(&read_buffer::<f32>(image, Some(3 * n), "image")?);
    let r = to_rgb(&read_buffer::<f32>(reference, Some(3 * n), "reference")?);
    let keep = match mask {
        Some(m) => Some(
            read_buffer::<u8>(m, Some(n), "mask")?
                .into_iter()
                .map(|b| b != 0)
                .collect(),
        ),
        None => None,
    };
    Ok((x, r, keep))
}

/// `(relMSE, MSE, pixels)` of `image` against `reference` (float32, `h` × `w` × 3) over the
/// pixels where `mask` (uint8, `h` × `w`) is non-zero, all pixels without one.
#[pyfunction]
#[pyo3(signature = (image, reference, width, height, mask=None))]
pub fn error_metrics(
    py: Python<'_>,
    image: &Bound<'_, PyAny>,
    reference: &Bound<'_, PyAny>,
    width: u32,
    height: u32,
    mask: Option<&Bound<'_, PyAny>>,
) -> PyResult<(f64, f64, usize)> {
    let (x, r, keep) = images(image, reference, mask, (width, height))?;
    let m = py.detach(|| render_core::metrics::error_metrics(&x, &r, keep.as_deref()));
    Ok((m.rel_mse, m.mse, m.pixels))
}

/// HDR-ꟻLIP: the per-pixel map (float32 bytes, row-major) and its mean over the pixels where
/// `mask` is non-zero (all pixels without one).
#[pyfunction]
#[pyo3(signature = (image, reference, width, height, mask=None))]
pub fn hdr_flip<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    reference: &Bound<'py, PyAny>,
    width: u32,
    height: u32,
    mask: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyBytes>, f64)> {
    let (x, r, keep) = images(image, reference, mask, (width, height))?;
    let map = py
        .detach(|| ::hdr_flip::hdr_flip_map(&x, &r, width, height))
        .map_err(value_error)?;
    let mean = ::hdr_flip::mean(&map, keep.as_deref());
    Ok((crate::f32_bytes(py, map.into_iter()), mean))
}

/// A file that could not be read: `FileNotFoundError` when it is not there, else `OSError`.
fn file_error(path: &std::path::Path, message: String) -> PyErr {
    if path.exists() {
        pyo3::exceptions::PyOSError::new_err(message)
    } else {
        pyo3::exceptions::PyFileNotFoundError::new_err(message)
    }
}

/// A linear EXR (one `render` wrote, or a reference): `(width, height, RGB float32 bytes)`.
#[pyfunction]
pub fn read_exr<'py>(py: Python<'py>, path: &str) -> PyResult<(u32, u32, Bound<'py, PyBytes>)> {
    let path = std::path::PathBuf::from(path);
    let (w, h, px) = py
        .detach(|| render_core::output::read_exr(&path))
        .map_err(|e| file_error(&path, e))?;
    Ok((w, h, rgb_bytes(py, &px)))
}

/// A light mask PNG's unlit pixels (black ones) as one byte each, 1 where unlit; `width` ×
/// `height` is checked.
#[pyfunction]
pub fn read_mask_png<'py>(
    py: Python<'py>,
    path: &str,
    width: u32,
    height: u32,
) -> PyResult<Bound<'py, PyBytes>> {
    let path = std::path::PathBuf::from(path);
    let unlit = py
        .detach(|| render_core::output::read_mask_png(&path, width, height))
        .map_err(|e| file_error(&path, e))?;
    let bytes: Vec<u8> = unlit.into_iter().map(u8::from).collect();
    Ok(PyBytes::new(py, &bytes))
}
