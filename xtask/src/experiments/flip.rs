//! HDR-ꟻLIP of a render against its reference: the `hdr-flip` crate (the Python package's
//! `flip` is the same code), and its error maps written as magma PNGs for the report.
pub use hdr_flip::*;
use std::path::Path;

/// Writes `map` as a magma PNG.
pub fn save_map(path: &Path, map: &[f32], w: u32, h: u32) -> Result<(), String> {
    super::compositing::save_png(path, w, h, &magma_rgb(map, w, h))
}
