//! [`Strategy`]: everything the renderer, the CLI, the harness and the tests need to know of one
//! strategy, as one value defined beside the strategy's code and listed in
//! [`crate::registry::STRATEGIES`].
use crate::knobs::{self, REPRODUCE};
use crate::{StrategyError, StrategyOptions};
use render_core::estimator::DirectLighting;
use render_core::scene::Scene;
use serde_json::Value;

/// Builds a strategy's estimator for a scene: `(name, scene, options)`; the name is the one asked
/// for (one of the strategy's names).
pub type Build =
    fn(&str, &Scene, &StrategyOptions) -> Result<Box<dyn DirectLighting>, StrategyError>;

/// One direct-lighting strategy.
pub struct Strategy {
    /// The name `--strategy` takes.
    pub name: &'static str,
    /// One line on what it does and whose it is, for `manylights strategies`.
    pub description: &'static str,
    /// The flags of [`knobs::KNOBS`] it reads (without `--`); every strategy also takes
    /// [`REPRODUCE`].
    pub knobs: &'static [&'static str],
    /// Camera rays per sample gathering the emission seen directly, when `--emission-rays` is not
    /// given and `--reproduce` is not (the authors' setup traces one).
    pub emission_rays: u32,
    /// Every parameter it renders with under the options, defaults filled in, without a scene:
    /// `(name, options)`. The render's JSON records it and the harness keys its cells by it.
    pub resolve: fn(&str, &StrategyOptions) -> Value,
    /// Its estimator for a scene.
    pub build: Build,
    /// Further names it answers to (`ris-N`), if any.
    pub other_names: Option<fn(&str) -> bool>,
    /// The option variants of the golden-image test that reach its code (beside `default`).
    pub golden_variants: &'static [&'static str],
}

impl std::fmt::Debug for Strategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Strategy({})", self.name)
    }
}

impl Strategy {
    /// A strategy with no knob, one emission ray, no other name and no golden variant.
    pub const fn new(
        name: &'static str,
        description: &'static str,
        resolve: fn(&str, &StrategyOptions) -> Value,
        build: Build,
    ) -> Strategy {
        Strategy {
            name,
            description,
            knobs: &[],
            emission_rays: 1,
            resolve,
            build,
            other_names: None,
            golden_variants: &[],
        }
    }

    /// Whether `--strategy name` means this strategy.
    pub fn answers_to(&self, name: &str) -> bool {
        self.name == name || self.other_names.is_some_and(|f| f(name))
    }

    /// Every knob it takes (without `--`): [`REPRODUCE`], then its own.
    pub fn all_knobs(&self) -> impl Iterator<Item = &'static str> + '_ {
        std::iter::once(REPRODUCE).chain(self.knobs.iter().copied())
    }

    /// Whether it reads the knob `flag` (without `--`).
    pub fn takes(&self, flag: &str) -> bool {
        self.all_knobs().any(|k| k == flag)
    }

    /// The flags it takes, as `--help` spells them, comma-separated.
    pub fn flags(&self) -> String {
        self.all_knobs()
            .map(|f| format!("--{f}"))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The options with the knobs given on a command line applied, `(flag, value)` in order:
    /// an error names a flag this strategy does not take, with the ones it does, or a bad value.
    pub fn options(&self, given: &[(String, String)]) -> Result<StrategyOptions, StrategyError> {
        let mut opts = StrategyOptions::default();
        for (flag, value) in given {
            let knob = knobs::knob(flag).ok_or_else(|| {
                StrategyError::BadOption(format!("there is no strategy flag `--{flag}`"))
            })?;
            if !self.takes(flag) {
                return Err(StrategyError::BadOption(format!(
                    "`{}` does not take `--{flag}`; it takes {}",
                    self.name,
                    self.flags()
                )));
            }
            (knob.set)(&mut opts, value)
                .map_err(|e| StrategyError::BadOption(format!("--{flag}: {e}")))?;
        }
        Ok(opts)
    }

    /// Its emission rays per camera sample when `--emission-rays` is not given.
    pub fn default_emission_rays(&self, opts: &StrategyOptions) -> u32 {
        if opts.reproduce {
            1
        } else {
            self.emission_rays
        }
    }
}
