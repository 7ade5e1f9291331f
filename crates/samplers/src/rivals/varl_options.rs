//! `varl`'s knobs (`--varl-*`), apart from its code so that the options every strategy shares
//! can hold them without importing the strategy.
use serde::{Deserialize, Serialize};

/// Nodes of the cut a region starts from.
pub const INITIAL_CUT: usize = 8;
/// The most nodes a region's cut may reach (the per-point arrays' size).
pub const MAX_CUT: usize = 128;

/// The knobs of `varl`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VarlOptions {
    /// Most nodes in a region's cut.
    pub max_cut: usize,
    /// Regions per scene diagonal (cell edge = diagonal / this).
    pub cells_per_diagonal: f32,
    /// Share α of the prior alone in the pmf.
    pub defensive: f32,
    /// Most regions kept.
    pub max_regions: usize,
}

impl Default for VarlOptions {
    fn default() -> Self {
        VarlOptions {
            max_cut: 64,
            cells_per_diagonal: 16.0,
            defensive: 0.2,
            max_regions: 1 << 16,
        }
    }
}

impl VarlOptions {
    /// An error for a cut outside INITIAL_CUT..=MAX_CUT, α outside (0, 1] or a bad cell size.
    pub fn check(&self) -> Result<(), String> {
        if !(INITIAL_CUT..=MAX_CUT).contains(&self.max_cut) {
            return Err(format!(
                "varl: the most nodes per region must be in {INITIAL_CUT}..={MAX_CUT}, got {}",
                self.max_cut
            ));
        }
        if !(self.defensive > 0.0 && self.defensive <= 1.0) {
            return Err(format!(
                "varl: the defensive share must be in (0, 1], got {}",
                self.defensive
            ));
        }
        if !(self.cells_per_diagonal >= 1.0 && self.cells_per_diagonal <= 1e5) {
            return Err(format!(
                "varl: cells per scene diagonal must be in [1, 100000], got {}",
                self.cells_per_diagonal
            ));
        }
        Ok(())
    }
}
