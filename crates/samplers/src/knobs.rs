//! Every strategy knob, defined once: its command-line flag, help, kind, how to read it from and
//! write it into [`StrategyOptions`]. `manylights render`/`strategy` make their flags from
//! [`KNOBS`]; a strategy names the knobs it takes in its [`crate::strategy::Strategy::knobs`].
use crate::StrategyOptions;
use crate::brdf_oriented::{BoImportance, BrdfIntegral};
use crate::learned::{LearnTarget, PassWeights};
use crate::reuse::config::CandidateSourceKind;
use crate::rivals::rht_options::RhtTraversal;
use crate::rivals::slc_minmax::SlcDescent;

/// What a knob's flag takes.
#[derive(Clone, Copy, Debug)]
pub enum KnobKind {
    /// A flag without a value: present or not.
    Switch,
    /// A number.
    Number,
    /// One of a few names.
    Choice(fn() -> Vec<&'static str>),
}

/// One knob of the strategies.
pub struct Knob {
    /// The flag without its leading `--` (`n-max`).
    pub flag: &'static str,
    /// One or two sentences for `--help`.
    pub help: &'static str,
    /// What the flag takes.
    pub kind: KnobKind,
    /// The knob's value in `opts`, as the flag spells it (a switch: `true` when it is on).
    pub value: fn(&StrategyOptions) -> String,
    /// Writes the flag's value (ignored for a switch) into `opts`, or says why it is not one.
    pub set: fn(&mut StrategyOptions, &str) -> Result<(), String>,
}

impl Knob {
    /// Checks that `value` is one this knob takes, without options to write it into.
    pub fn parse(&self, value: &str) -> Result<(), String> {
        (self.set)(&mut StrategyOptions::default(), value)
    }

    /// The knob's value under the default options.
    pub fn default_value(&self) -> String {
        (self.value)(&StrategyOptions::default())
    }
}

/// The knob whose flag is `flag` (without `--`).
pub fn knob(flag: &str) -> Option<&'static Knob> {
    KNOBS.iter().find(|k| k.flag == flag)
}

/// The knob every strategy takes: besides a strategy's own parameters, it chooses the sampler,
/// the film and the emission rays of the authors' setup.
pub const REPRODUCE: &str = "reproduce";

fn number<T: std::str::FromStr>(s: &str) -> Result<T, String>
where
    T::Err: std::fmt::Display,
{
    s.parse()
        .map_err(|e| format!("`{s}` is not a number here: {e}"))
}

fn choice<T>(s: &str, names: &[&str], find: impl Fn(&str) -> Option<T>) -> Result<T, String> {
    find(s).ok_or_else(|| format!("`{s}` is not one of {}", names.join(", ")))
}

/// Every knob, in the order `--help` lists them.
pub static KNOBS: &[Knob] = &[
    Knob {
        flag: "tau",
        help: "Adaptive tree splitting threshold τ, in [0, 1] (tree-split and mis3 strategies); the authors' 0.85 under --reproduce.",
        kind: KnobKind::Number,
        value: |o| o.tau().to_string(),
        set: |o, s| {
            o.tau = Some(number(s)?);
            Ok(())
        },
    },
    Knob {
        flag: "max-cut",
        help: "Most clusters in an adaptive light cut (tree-split strategies; mis3: both cuts; ris: the BO cut).",
        kind: KnobKind::Number,
        value: |o| o.max_cut.to_string(),
        set: |o, s| {
            o.max_cut = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "delta",
        help: "BRDF-oriented cut: split a node whose cap integral of the glossy lobe exceeds δ.",
        kind: KnobKind::Number,
        value: |o| o.delta.to_string(),
        set: |o, s| {
            o.delta = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "n-max",
        help: "Most BRDF-aware samples beyond the forced two (N = floor(N_max·UB)); with the default efficient N_max, its value for the first two passes.",
        kind: KnobKind::Number,
        value: |o| o.n_max.to_string(),
        set: |o, s| {
            o.n_max = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "lambda",
        help: "Weight of a BRDF-sampling hit in P(BO) = n_nohit / (n_nohit + λ·n_hit).",
        kind: KnobKind::Number,
        value: |o| o.lambda.to_string(),
        set: |o, s| {
            o.lambda = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "brdf-integral",
        help: "Cap-integral approximation behind BRDF-oriented sampling.",
        kind: KnobKind::Choice(|| BrdfIntegral::ALL.map(BrdfIntegral::name).to_vec()),
        value: |o| o.brdf_integral.name().to_string(),
        set: |o, s| {
            let names = BrdfIntegral::ALL.map(BrdfIntegral::name);
            o.brdf_integral = choice(s, &names, |s| s.parse().ok())?;
            Ok(())
        },
    },
    Knob {
        flag: "bo-importance",
        help: "Node importance of BRDF-oriented sampling's cluster choice and descent: `cap` (I_BO from the cap integrals, the paper) or `sg` (the spherical-Gaussian importance of sg-tree); the BO cut and heuristic 1's UB use the cap integrals either way.",
        kind: KnobKind::Choice(|| BoImportance::ALL.map(BoImportance::name).to_vec()),
        value: |o| o.bo_importance.name().to_string(),
        set: |o, s| {
            let names = BoImportance::ALL.map(BoImportance::name);
            o.bo_importance = choice(s, &names, |s| s.parse().ok())?;
            Ok(())
        },
    },
    Knob {
        flag: REPRODUCE,
        help: "The authors' setup: their power units, σ and τ, no cap on the cuts; for the method also the nearest SPTD lookup, Oat–Sander cap ∩ cap, glossy-only importance, one rescaled random number per descent and the in-sample (biased) allocation; for every strategy pbrt-v3's sampler and splatting film and one emission ray.",
        kind: KnobKind::Switch,
        value: |o| o.reproduce.to_string(),
        set: |o, _| {
            o.reproduce = true;
            Ok(())
        },
    },
    Knob {
        flag: "pivot-sphere",
        help: "Sample points on sphere lights by the pivot-transformed lobe (mixed with cone sampling).",
        kind: KnobKind::Switch,
        value: |o| o.pivot_sphere.to_string(),
        set: |o, _| {
            o.pivot_sphere = true;
            Ok(())
        },
    },
    Knob {
        flag: "ltc-triangles",
        help: "BRDF-aware points on triangle lights: BO at glossy points draws the point by the glossy lobe's LTC over the triangle (Peters 2021, with a bilinear warp for the cosine), mixed one-to-one with --light-points.",
        kind: KnobKind::Switch,
        value: |o| o.ltc_triangles.to_string(),
        set: |o, _| {
            o.ltc_triangles = true;
            Ok(())
        },
    },
    Knob {
        flag: "no-adaptive-total",
        help: "Turn off heuristic 1 (N = floor(N_max·UB)); N = N_max/2 instead.",
        kind: KnobKind::Switch,
        value: |o| (!o.adaptive_total).to_string(),
        set: |o, _| {
            o.adaptive_total = false;
            Ok(())
        },
    },
    Knob {
        flag: "no-adaptive-split",
        help: "Turn off heuristic 2 (P(BO) from hits and misses); P(BO) = 1/2 instead.",
        kind: KnobKind::Switch,
        value: |o| (!o.adaptive_split).to_string(),
        set: |o, _| {
            o.adaptive_split = false;
            Ok(())
        },
    },
    Knob {
        flag: "weighted-ub",
        help: "Heuristic 1 with UB times the glossy lobe's weight (Ks·F at θo).",
        kind: KnobKind::Switch,
        value: |o| o.weighted_ub.to_string(),
        set: |o, _| {
            o.weighted_ub = true;
            Ok(())
        },
    },
    Knob {
        flag: "fixed-n-max",
        help: "Keep N_max constant (the paper's heuristic 1) instead of choosing it after each pass by variance × cost from the samples so far (--reproduce implies it).",
        kind: KnobKind::Switch,
        value: |o| (!o.efficient_total).to_string(),
        set: |o, _| {
            o.efficient_total = false;
            Ok(())
        },
    },
    Knob {
        flag: "independent-samples",
        help: "Draw a shading point's BRDF-aware samples independently instead of as one stratified set per technique.",
        kind: KnobKind::Switch,
        value: |o| (!o.stratified).to_string(),
        set: |o, _| {
            o.stratified = false;
            Ok(())
        },
    },
    Knob {
        flag: "split-ls-at-glossy",
        help: "Keep the E&K cut (one light per cluster) for LS at glossy points, as the paper, instead of one descent there (--reproduce implies it).",
        kind: KnobKind::Switch,
        value: |o| o.split_ls_at_glossy.to_string(),
        set: |o, _| {
            o.split_ls_at_glossy = true;
            Ok(())
        },
    },
    Knob {
        flag: "binary-bo-descent",
        help: "BO descends below its cut one binary level at a time, as the paper, instead of the tree's four-wide descent (--reproduce implies it).",
        kind: KnobKind::Switch,
        value: |o| o.binary_bo_descent.to_string(),
        set: |o, _| {
            o.binary_bo_descent = true;
            Ok(())
        },
    },
    Knob {
        flag: "no-pilot",
        help: "No pilot: N_max stays --n-max until two passes are done, then is learnt (the pilot, one pixel in 16 with two samples before the first pass, learns it at once).",
        kind: KnobKind::Switch,
        value: |o| (!o.pilot).to_string(),
        set: |o, _| {
            o.pilot = false;
            Ok(())
        },
    },
    Knob {
        flag: "learned-target",
        help: "Learned selection: what a region learns of each cluster, `contribution` (its observed contribution over its prior) or `visibility` (its shadow rays' hit rate).",
        kind: KnobKind::Choice(|| LearnTarget::ALL.map(LearnTarget::name).to_vec()),
        value: |o| o.learned.target.name().to_string(),
        set: |o, s| {
            let names = LearnTarget::ALL.map(LearnTarget::name);
            o.learned.target = choice(s, &names, LearnTarget::from_name)?;
            Ok(())
        },
    },
    Knob {
        flag: "learned-clusters",
        help: "Learned selection: clusters of its fixed cut (1–256).",
        kind: KnobKind::Number,
        value: |o| o.learned.clusters.to_string(),
        set: |o, s| {
            o.learned.clusters = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "learned-cells",
        help: "Learned selection: region cells per scene diagonal.",
        kind: KnobKind::Number,
        value: |o| o.learned.cells_per_diagonal.to_string(),
        set: |o, s| {
            o.learned.cells_per_diagonal = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "learned-defensive",
        help: "Learned selection: share of the unlearnt prior in its pmf, in (0, 1].",
        kind: KnobKind::Number,
        value: |o| o.learned.defensive.to_string(),
        set: |o, s| {
            o.learned.defensive = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "learned-samples",
        help: "Learned strategies: light samples per shading point (beside one BSDF sample).",
        kind: KnobKind::Number,
        value: |o| o.learned.light_samples.to_string(),
        set: |o, s| {
            o.learned.light_samples = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "learned-prior",
        help: "Learned selection: the prior's strength a, in rays (what a cluster or node not yet observed in a region keeps, and how fast its observations take over).",
        kind: KnobKind::Number,
        value: |o| o.learned.prior_strength.to_string(),
        set: |o, s| {
            o.learned.prior_strength = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "learned-pass-weights",
        help: "learned-descent: how its passes are weighed in each pixel's average, `sqrt` (pass i by √i: the later, better-learnt passes count more; unbiased) or `equal`.",
        kind: KnobKind::Choice(|| PassWeights::ALL.map(PassWeights::name).to_vec()),
        value: |o| o.learned.pass_weights.name().to_string(),
        set: |o, s| {
            let names = PassWeights::ALL.map(PassWeights::name);
            o.learned.pass_weights = choice(s, &names, PassWeights::from_name)?;
            Ok(())
        },
    },
    Knob {
        flag: "slc-cut-size",
        help: "Stochastic lightcuts: most nodes in a cut (K), one light and one shadow ray each.",
        kind: KnobKind::Number,
        value: |o| o.slc_cut_size.to_string(),
        set: |o, s| {
            o.slc_cut_size = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "slc-descent",
        help: "Stochastic lightcuts: how a cut node's light is drawn down its subtree, `tree` (the tree's importance, ours) or `minmax` (the mean of the nearest- and farthest-distance weights of Lin & Yuksel's real-time code).",
        kind: KnobKind::Choice(|| SlcDescent::ALL.map(SlcDescent::name).to_vec()),
        value: |o| o.slc_descent.name().to_string(),
        set: |o, s| {
            let names = SlcDescent::ALL.map(SlcDescent::name);
            o.slc_descent = choice(s, &names, SlcDescent::from_name)?;
            Ok(())
        },
    },
    Knob {
        flag: "restir-candidates",
        help: "ReSTIR: light candidates per pixel (M), resampled with one BSDF candidate into the pixel's first reservoir.",
        kind: KnobKind::Number,
        value: |o| o.reuse.candidates.to_string(),
        set: |o, s| {
            o.reuse.candidates = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "restir-bo-candidates",
        help: "ReSTIR BO: candidates per pixel from the paper's techniques (BO + tree at glossy points), resampled with one BSDF candidate into the pixel's first reservoir.",
        kind: KnobKind::Number,
        value: |o| o.reuse.bo_candidates.to_string(),
        set: |o, s| {
            o.reuse.bo_candidates = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "restir-source",
        help: "ReSTIR: where the light candidates come from, `power` (lights by power, as the paper) or `tree` (one light-tree descent).",
        kind: KnobKind::Choice(|| {
            CandidateSourceKind::ALL
                .map(CandidateSourceKind::name)
                .to_vec()
        }),
        value: |o| o.reuse.source.name().to_string(),
        set: |o, s| {
            let names = CandidateSourceKind::ALL.map(CandidateSourceKind::name);
            o.reuse.source = choice(s, &names, CandidateSourceKind::from_name)?;
            Ok(())
        },
    },
    Knob {
        flag: "restir-neighbours",
        help: "ReSTIR: neighbours drawn per round of spatial reuse (0 to 32).",
        kind: KnobKind::Number,
        value: |o| o.reuse.neighbours.to_string(),
        set: |o, s| {
            o.reuse.neighbours = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "restir-radius",
        help: "ReSTIR: radius in pixels of the disk the neighbours are drawn from.",
        kind: KnobKind::Number,
        value: |o| o.reuse.radius.to_string(),
        set: |o, s| {
            o.reuse.radius = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "restir-rounds",
        help: "ReSTIR: rounds of spatial reuse, each reading only the previous round's reservoirs (0 to 8).",
        kind: KnobKind::Number,
        value: |o| o.reuse.rounds.to_string(),
        set: |o, s| {
            o.reuse.rounds = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "restir-history",
        help: "ReSTIR: reuse each pixel's reservoir of the previous pass, its confidence capped at this many times the pixel's new candidates (the paper's temporal reuse: 20); 0 (default): none, passes independent. Passes are then correlated: the render's variance no longer estimates its error.",
        kind: KnobKind::Number,
        value: |o| o.reuse.history.to_string(),
        set: |o, s| {
            o.reuse.history = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "rht-tau",
        help: "Resampled hierarchical tree: a node whose E&K variance measure ρ is below τ is split (both children gathered) with probability 1 − ρ/τ, in (0, 1].",
        kind: KnobKind::Number,
        value: |o| o.rht.tau.to_string(),
        set: |o, s| {
            o.rht.tau = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "rht-picks",
        help: "Resampled hierarchical tree: candidates resampled (with replacement) per shading point, one shadow ray each.",
        kind: KnobKind::Number,
        value: |o| o.rht.picks.to_string(),
        set: |o, s| {
            o.rht.picks = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "rht-traversal",
        help: "Resampled hierarchical tree: a candidate's gathering probability, `corrected` (the marginal probability, unbiased) or `biased` (a split node's factor left out, the published form's defect: darkens).",
        kind: KnobKind::Choice(|| RhtTraversal::ALL.map(RhtTraversal::name).to_vec()),
        value: |o| o.rht.traversal.name().to_string(),
        set: |o, s| {
            let names = RhtTraversal::ALL.map(RhtTraversal::name);
            o.rht.traversal = choice(s, &names, RhtTraversal::from_name)?;
            Ok(())
        },
    },
    Knob {
        flag: "varl-max-cut",
        help: "Learning to cluster: most nodes in a region's cut (it starts from 8 and is refined between passes).",
        kind: KnobKind::Number,
        value: |o| o.varl.max_cut.to_string(),
        set: |o, s| {
            o.varl.max_cut = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "varl-cells",
        help: "Learning to cluster: regions per scene diagonal (cell edge = diagonal / this), each with its own cut.",
        kind: KnobKind::Number,
        value: |o| o.varl.cells_per_diagonal.to_string(),
        set: |o, s| {
            o.varl.cells_per_diagonal = number(s)?;
            Ok(())
        },
    },
    Knob {
        flag: "varl-defensive",
        help: "Learning to cluster: share of the tree's importance alone in the pmf, in (0, 1].",
        kind: KnobKind::Number,
        value: |o| o.varl.defensive.to_string(),
        set: |o, s| {
            o.varl.defensive = number(s)?;
            Ok(())
        },
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_are_unique_and_defaults_parse_back() {
        for (i, k) in KNOBS.iter().enumerate() {
            assert!(
                KNOBS[..i].iter().all(|o| o.flag != k.flag),
                "--{} twice",
                k.flag
            );
            if !matches!(k.kind, KnobKind::Switch) {
                let mut o = StrategyOptions::default();
                (k.set)(&mut o, &k.default_value()).unwrap();
                assert_eq!((k.value)(&o), k.default_value(), "--{}", k.flag);
            } else {
                assert_eq!(k.default_value(), "false", "--{} is off by default", k.flag);
            }
        }
    }

    #[test]
    fn a_set_knob_reads_back_and_bad_values_are_refused() {
        let mut o = StrategyOptions::default();
        (knob("n-max").unwrap().set)(&mut o, "7").unwrap();
        assert_eq!(o.n_max, 7);
        (knob("no-pilot").unwrap().set)(&mut o, "").unwrap();
        assert!(!o.pilot);
        (knob("learned-target").unwrap().set)(&mut o, "visibility").unwrap();
        assert_eq!(o.learned.target, LearnTarget::Visibility);
        assert!(knob("n-max").unwrap().parse("many").is_err());
        let e = knob("brdf-integral").unwrap().parse("exact").unwrap_err();
        assert!(e.contains("sptd") && e.contains("ltc"), "{e}");
    }
}
