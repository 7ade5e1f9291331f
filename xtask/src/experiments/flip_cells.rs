//! ꟻLIP of stored cells, for the report: the cells from before ꟻLIP was measured get it from
//! their render and reference when both are on this machine (in memory, for the tables; the
//! cell files stay as they were measured), and each cell's ꟻLIP map (`renders/<id>.flip.png`,
//! written when the cell is measured) is made there if it is missing.
use super::cell::CellResult;
use super::flip;
use super::paths::reference_path;
use super::reference::Manifest;
use glam::Vec3;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A reference as a cell needs it: its pixels and light mask (true = unlit).
struct RefImage {
    w: u32,
    h: u32,
    pixels: Vec<Vec3>,
    unlit: Vec<bool>,
}

/// The references of the cells, loaded once each.
pub struct Sources<'a> {
    out: &'a Path,
    refs_dir: &'a Path,
    refs: BTreeMap<String, Option<RefImage>>,
}

impl<'a> Sources<'a> {
    pub fn new(out: &'a Path, refs_dir: &'a Path) -> Self {
        Sources {
            out,
            refs_dir,
            refs: BTreeMap::new(),
        }
    }

    /// The reference `cell` was measured against, if it is on this machine and still that one.
    fn reference(&mut self, cell: &CellResult) -> Option<&RefImage> {
        let dir = reference_path(self.refs_dir, &cell.reference_dir);
        self.refs
            .entry(cell.reference.clone())
            .or_insert_with(|| {
                let text = std::fs::read_to_string(dir.join("manifest.json")).ok()?;
                let m: Manifest = serde_json::from_str(&text).ok()?;
                if m.content_id() != cell.reference {
                    return None; // re-rendered in place since: not the cell's reference
                }
                let (w, h, pixels) = render_core::output::read_exr(&dir.join("ref.exr")).ok()?;
                let unlit = render_core::output::read_mask_png(&dir.join("mask.png"), w, h).ok()?;
                Some(RefImage {
                    w,
                    h,
                    pixels,
                    unlit,
                })
            })
            .as_ref()
    }

    fn render(&self, cell: &CellResult, ext: &str) -> PathBuf {
        self.out.join("renders").join(format!("{}.{ext}", cell.id))
    }

    /// HDR-ꟻLIP of `cell` from its render and reference, as the harness measures it (the unlit
    /// pixels: those the reference's mask and the render's own both call unlit).
    pub fn compute(&mut self, cell: &CellResult) -> Option<flip::Flip> {
        let (w, h, px) = render_core::output::read_exr(&self.render(cell, "exr")).ok()?;
        let own = render_core::output::read_mask_png(&self.render(cell, "mask.png"), w, h).ok()?;
        let r = self.reference(cell)?;
        if (r.w, r.h) != (w, h) {
            return None;
        }
        let unlit: Vec<bool> = r.unlit.iter().zip(&own).map(|(&a, &b)| a && b).collect();
        flip::score(&px, &r.pixels, &unlit, w, h).ok()
    }

    /// Fills in the ꟻLIP of the cells that lack it where their render and reference are here
    /// (writing the map beside the render too); returns how many it filled.
    pub fn fill_missing(&mut self, cells: &mut [CellResult]) -> usize {
        let mut n = 0;
        for c in cells
            .iter_mut()
            .filter(|c| c.flip_all.is_none() || c.flip_unlit.is_none())
        {
            if let Some(f) = self.compute(c) {
                c.flip_all = Some(f.all);
                c.flip_unlit = Some(f.unlit);
                let _ = flip::save_map(&self.render(c, "flip.png"), &f.map, c.width, c.height);
                n += 1;
            }
        }
        n
    }

    /// The PNG bytes of `cell`'s ꟻLIP map: the one beside its render, else made from the render
    /// (and kept there); `None` when the render or its reference is not on this machine.
    pub fn map_png(&mut self, cell: &CellResult) -> Option<Vec<u8>> {
        let path = self.render(cell, "flip.png");
        // only beside a render that is still there (a map outlives nothing it was made from)
        if !self.render(cell, "exr").is_file() {
            return None;
        }
        if let Ok(b) = std::fs::read(&path) {
            return Some(b);
        }
        let f = self.compute(cell)?;
        flip::save_map(&path, &f.map, cell.width, cell.height).ok()?;
        std::fs::read(&path).ok()
    }
}
