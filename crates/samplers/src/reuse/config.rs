//! The reuse strategies' parameters (`--restir-*`), with Bitterli et al. 2020's defaults.
use serde::{Deserialize, Serialize};

/// Where a pixel's light candidates come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CandidateSourceKind {
    /// Lights ∝ power (an alias table), points by each light's own sampling (the paper's
    /// candidates, which it draws ∝ power and area).
    #[default]
    Power,
    /// One descent of the light tree (Conty Estevez & Kulla's importance).
    Tree,
}

impl CandidateSourceKind {
    /// Every source, in the order `--help` lists them.
    pub const ALL: [CandidateSourceKind; 2] =
        [CandidateSourceKind::Power, CandidateSourceKind::Tree];

    /// The name `--restir-source` takes.
    pub fn name(self) -> &'static str {
        match self {
            CandidateSourceKind::Power => "power",
            CandidateSourceKind::Tree => "tree",
        }
    }

    /// The source named `s`.
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// How ReSTIR draws and shares its samples.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ReuseConfig {
    /// Light candidates per pixel (M; the paper's 32), plus one BSDF candidate (`restir`,
    /// `restir-biased`).
    pub candidates: u32,
    /// `restir-bo`'s candidates per pixel (BO + tree), plus one BSDF candidate: fewer than
    /// `restir`'s, since each is drawn from the BRDF-aware mixture and the BO cut is the cost
    /// (measured: docs/notes/reuse.md).
    pub bo_candidates: u32,
    /// Where the light candidates come from.
    pub source: CandidateSourceKind,
    /// Neighbours per round of spatial reuse (the paper's 5).
    pub neighbours: u32,
    /// Radius in pixels the neighbours are drawn from (the paper's 30).
    pub radius: f32,
    /// Rounds of spatial reuse (the paper's 2).
    pub rounds: u32,
    /// Reuse of each pixel's final reservoir of the previous pass, its confidence capped at
    /// this many times the pixel's new candidates (the paper's temporal reuse caps at 20); 0:
    /// none, so that passes are independent (the default, a still image's honest variance).
    pub history: f32,
}

impl Default for ReuseConfig {
    fn default() -> Self {
        ReuseConfig {
            candidates: 32,
            bo_candidates: 4,
            source: CandidateSourceKind::Power,
            neighbours: 5,
            radius: 30.0,
            rounds: 2,
            history: 0.0,
        }
    }
}

impl ReuseConfig {
    /// The parameters `restir-bo` runs with: its own candidate count as `candidates`.
    pub fn for_bo(&self) -> ReuseConfig {
        ReuseConfig {
            candidates: self.bo_candidates,
            ..self.clone()
        }
    }

    /// Refuses values outside what the strategies take.
    pub fn check(&self) -> Result<(), String> {
        if !(1..=1024).contains(&self.candidates) {
            return Err(format!(
                "--restir-candidates must be 1 to 1024, got {}",
                self.candidates
            ));
        }
        if !(1..=1024).contains(&self.bo_candidates) {
            return Err(format!(
                "--restir-bo-candidates must be 1 to 1024, got {}",
                self.bo_candidates
            ));
        }
        if self.neighbours > MAX_NEIGHBOURS as u32 {
            return Err(format!(
                "--restir-neighbours must be 0 to {MAX_NEIGHBOURS}, got {}",
                self.neighbours
            ));
        }
        if !(self.radius >= 1.0 && self.radius <= 1024.0) {
            return Err(format!(
                "--restir-radius must be 1 to 1024 pixels, got {}",
                self.radius
            ));
        }
        if self.rounds > 8 {
            return Err(format!(
                "--restir-rounds must be 0 to 8, got {}",
                self.rounds
            ));
        }
        if !(0.0..=MAX_HISTORY).contains(&self.history) {
            return Err(format!(
                "--restir-history must be 0 (off) to {MAX_HISTORY}, got {}",
                self.history
            ));
        }
        Ok(())
    }
}

/// Largest cap on the previous pass's confidence, in multiples of a pixel's new candidates.
pub const MAX_HISTORY: f32 = 1000.0;

/// Most neighbours per round.
pub const MAX_NEIGHBOURS: usize = 32;
