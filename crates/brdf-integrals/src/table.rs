//! A 64 × 64 table over (θo, √α) with `C` f32 channels per cell, stored little-endian with a
//! small header, and its bilinear / nearest lookup.
//!
//! File layout: 8-byte magic, then u32 n_theta, n_alpha, channels (LE), then
//! n_theta · n_alpha · channels f32 (LE), row-major \[θ index\]\[√α index\]\[channel\].
//! Grid: θo = i/(n_theta − 1) · π/2, √α = j/(n_alpha − 1).

use std::f32::consts::FRAC_PI_2;

/// A regular grid over θo ∈ [0, π/2] × √α ∈ [0, 1] holding `C` values per cell (what each
/// channel means is up to the user, e.g. [`crate::sptd::SptdTable`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Table<const C: usize> {
    /// Grid points along θo (≥ 2 for lookups), from 0 to π/2 inclusive.
    pub n_theta: usize,
    /// Grid points along √α (≥ 2 for lookups), from 0 to 1 inclusive.
    pub n_alpha: usize,
    /// `n_theta · n_alpha` cells, θo-major: cell (i, j) is at `i · n_alpha + j`.
    pub cells: Vec<[f32; C]>,
}

/// How a table is read between its grid points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Lookup {
    /// Bilinear interpolation between the four surrounding cells (default).
    #[default]
    Bilinear,
    /// The nearest cell (what the authors' renderer does).
    Nearest,
}

impl<const C: usize> Table<C> {
    /// A table of the given size with every channel 0.
    pub fn new(n_theta: usize, n_alpha: usize) -> Self {
        Self {
            n_theta,
            n_alpha,
            cells: vec![[0.0; C]; n_theta * n_alpha],
        }
    }

    /// Cell at θo index `i` and √α index `j` (panics out of range).
    pub fn cell(&self, i: usize, j: usize) -> &[f32; C] {
        &self.cells[i * self.n_alpha + j]
    }

    /// Mutable [`Table::cell`].
    pub fn cell_mut(&mut self, i: usize, j: usize) -> &mut [f32; C] {
        &mut self.cells[i * self.n_alpha + j]
    }

    /// Serialises the table in the file layout of the module docs, starting with `magic`.
    pub fn to_bytes(&self, magic: &[u8; 8]) -> Vec<u8> {
        let mut out = Vec::with_capacity(20 + self.cells.len() * C * 4);
        out.extend_from_slice(magic);
        for v in [self.n_theta as u32, self.n_alpha as u32, C as u32] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for c in &self.cells {
            for v in c {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        out
    }

    /// Parses a table written by [`Table::to_bytes`]. Fails (with a message) on a wrong
    /// magic, a channel count other than `C`, fewer than 2 grid points on an axis or a size
    /// that does not match the header.
    pub fn from_bytes(bytes: &[u8], magic: &[u8; 8]) -> Result<Self, String> {
        if bytes.len() < 20 || &bytes[..8] != magic {
            return Err("bad table header".into());
        }
        let u = |k: usize| {
            u32::from_le_bytes(bytes[8 + 4 * k..12 + 4 * k].try_into().unwrap()) as usize
        };
        let (nt, na, ch) = (u(0), u(1), u(2));
        if ch != C || bytes.len() != 20 + nt * na * C * 4 || nt < 2 || na < 2 {
            return Err(format!(
                "table size mismatch: {nt}×{na}×{ch}, {} bytes",
                bytes.len()
            ));
        }
        let mut t = Self::new(nt, na);
        for (k, c) in t.cells.iter_mut().enumerate() {
            for (ch, v) in c.iter_mut().enumerate() {
                let o = 20 + (k * C + ch) * 4;
                *v = f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
            }
        }
        Ok(t)
    }

    /// Continuous grid coordinates of (θo, α).
    #[inline]
    fn coords(&self, theta_o: f32, alpha: f32) -> (f32, f32) {
        let x = (theta_o / FRAC_PI_2).clamp(0.0, 1.0) * (self.n_theta - 1) as f32;
        let y = alpha.max(0.0).sqrt().clamp(0.0, 1.0) * (self.n_alpha - 1) as f32;
        (x, y)
    }

    /// The channels at view angle `theta_o` (radians) and GGX roughness `alpha` (α, not √α;
    /// the table is indexed by √α). Both are clamped to the grid: θo to [0, π/2], α to [0, 1].
    #[inline]
    pub fn lookup(&self, theta_o: f32, alpha: f32, mode: Lookup) -> [f32; C] {
        let (x, y) = self.coords(theta_o, alpha);
        match mode {
            Lookup::Nearest => *self.cell((x + 0.5) as usize, (y + 0.5) as usize),
            Lookup::Bilinear => {
                let i = (x as usize).min(self.n_theta - 2);
                let j = (y as usize).min(self.n_alpha - 2);
                let (fx, fy) = (x - i as f32, y - j as f32);
                let (a, b, c, d) = (
                    self.cell(i, j),
                    self.cell(i, j + 1),
                    self.cell(i + 1, j),
                    self.cell(i + 1, j + 1),
                );
                let mut out = [0.0; C];
                for k in 0..C {
                    out[k] = (1.0 - fx) * ((1.0 - fy) * a[k] + fy * b[k])
                        + fx * ((1.0 - fy) * c[k] + fy * d[k]);
                }
                out
            }
        }
    }

    /// θo and √α at grid point (i, j).
    pub fn grid_point(&self, i: usize, j: usize) -> (f32, f32) {
        (
            i as f32 / (self.n_theta - 1) as f32 * FRAC_PI_2,
            j as f32 / (self.n_alpha - 1) as f32,
        )
    }
}

/// Both lookup modes return a table's own values at its grid points, for the first
/// `channels` channels (the tests of every fitted table).
#[cfg(test)]
pub(crate) fn assert_lookup_reproduces_grid_points<const C: usize>(t: &Table<C>, channels: usize) {
    for &(i, j) in &[(0usize, 0usize), (5, 40), (63, 63), (31, 2), (62, 17)] {
        let (theta, sa) = t.grid_point(i, j);
        let c = t.cell(i, j);
        for mode in [Lookup::Bilinear, Lookup::Nearest] {
            let l = t.lookup(theta, sa * sa, mode);
            for k in 0..channels {
                assert!(
                    (l[k] - c[k]).abs() <= 1e-5 * c[k].abs().max(1.0),
                    "({i},{j}) ch {k}: {} vs {}",
                    l[k],
                    c[k]
                );
            }
        }
    }
}
