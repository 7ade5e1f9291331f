//! The RHT strategies' knobs (`--rht-*`), apart from their code so that the options every
//! strategy shares can hold them without importing the strategies.
use serde::{Deserialize, Serialize};

/// τ of the split probability.
pub const DEFAULT_TAU: f32 = 0.85;
/// Candidates resampled per shading point.
pub const DEFAULT_PICKS: u32 = 1;
/// The most picks accepted.
pub const MAX_PICKS: u32 = 1024;

/// How a candidate's gathering probability is accumulated down the tree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RhtTraversal {
    /// The marginal probability of visiting each node on the path (unbiased; our default).
    #[default]
    Corrected,
    /// A split node's factor left out (the published form's defect; biased dark).
    Biased,
}

impl RhtTraversal {
    /// Every form, in `--rht-traversal`'s order.
    pub const ALL: [RhtTraversal; 2] = [RhtTraversal::Corrected, RhtTraversal::Biased];

    /// The name `--rht-traversal` takes.
    pub fn name(self) -> &'static str {
        match self {
            RhtTraversal::Corrected => "corrected",
            RhtTraversal::Biased => "biased",
        }
    }

    /// The form called `name`.
    pub fn from_name(name: &str) -> Option<RhtTraversal> {
        RhtTraversal::ALL.into_iter().find(|d| d.name() == name)
    }
}

/// The knobs of the RHT strategies.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RhtOptions {
    /// τ of the split probability, in (0, 1].
    pub tau: f32,
    /// Candidates resampled per shading point (R), one shadow ray each.
    pub picks: u32,
    /// How the gathering probability is accumulated.
    pub traversal: RhtTraversal,
}

impl Default for RhtOptions {
    fn default() -> Self {
        RhtOptions {
            tau: DEFAULT_TAU,
            picks: DEFAULT_PICKS,
            traversal: RhtTraversal::Corrected,
        }
    }
}

impl RhtOptions {
    /// An error for τ outside (0, 1] or R outside 1..=[`MAX_PICKS`].
    pub fn check(&self) -> Result<(), String> {
        if !(self.tau > 0.0 && self.tau <= 1.0) {
            return Err(format!("rht: τ must be in (0, 1], got {}", self.tau));
        }
        if !(1..=MAX_PICKS).contains(&self.picks) {
            return Err(format!(
                "rht: the picks must be in 1..={MAX_PICKS}, got {}",
                self.picks
            ));
        }
        Ok(())
    }
}
