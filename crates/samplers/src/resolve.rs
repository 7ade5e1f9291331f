//! The pieces of a strategy's resolved parameters ([`crate::registry::resolved_parameters`]): every value it renders with, the defaults filled in and
//! what `reproduce` implies applied, without a scene. [`crate::create`] builds the strategies
//! from the same functions, so what this reports is what they use; the render's JSON records
//! it and the experiment harness keys its cells by it (a changed default re-renders the cells
//! of exactly the strategies that use it).
use crate::StrategyOptions;
use crate::brdf_oriented::{BoConfig, BoImportance, BrdfIntegral};
use crate::options::PowerUnits;
use brdf_integrals::{Intersection, Lookup, Ltc, Normalization, Sptd};
use light_tree::SplitParams;
use serde_json::{Value, json};

/// The method's configuration (Liu et al. 2019) from the options.
pub fn bo_config(opts: &StrategyOptions) -> BoConfig {
    BoConfig {
        delta: opts.delta,
        n_max: opts.n_max,
        lambda: opts.lambda,
        tau: opts.tau(),
        max_cut: opts.split_params().max_size,
        max_cut_bo: opts.split_params().max_size,
        brdf_integral: opts.brdf_integral,
        bo_importance: opts.bo_importance,
        reproduce: opts.reproduce,
        pivot_sphere: opts.pivot_sphere,
        ltc_triangles: opts.ltc_triangles,
        adaptive_total: opts.adaptive_total,
        weighted_ub: opts.weighted_ub,
        efficient_total: opts.efficient_total && !opts.reproduce,
        stratified: opts.stratified && !opts.reproduce,
        single_ls_at_glossy: !opts.split_ls_at_glossy && !opts.reproduce,
        adaptive_split: opts.adaptive_split,
        four_wide_bo_descent: !opts.binary_bo_descent
            && !opts.reproduce
            && opts.bo_importance == BoImportance::Cap,
        pilot: opts.pilot && opts.efficient_total && !opts.reproduce,
    }
}

pub(crate) fn units(opts: &StrategyOptions) -> &'static str {
    match opts.power_units() {
        PowerUnits::Watts => "watts",
        PowerUnits::Authors => "authors",
    }
}

pub(crate) fn split(p: SplitParams) -> Value {
    json!({
        "tau": p.tau,
        // usize::MAX (no cap) as null: JSON numbers beyond 2^53 do not round-trip.
        "max_cut": (p.max_size != usize::MAX).then_some(p.max_size),
        "split_criterion": format!("{:?}", p.criterion).to_lowercase(),
    })
}

/// The SPTD method the BO strategies use: the authors' nearest lookup, Oat–Sander cap ∩ cap
/// and full-sphere normalisation under `reproduce`, the defaults otherwise.
pub fn sptd(opts: &StrategyOptions) -> Sptd {
    if opts.reproduce {
        Sptd::default()
            .lookup(Lookup::Nearest)
            .intersection(Intersection::OatSander)
            .normalization(Normalization::FullSphere)
    } else {
        Sptd::default()
    }
}

/// The LTC method the BO strategies use: the nearest lookup under `reproduce`.
pub fn ltc(opts: &StrategyOptions) -> Ltc {
    let mut integral = Ltc::default();
    if opts.reproduce {
        integral.lookup = Lookup::Nearest;
    }
    integral
}

fn lower(x: impl std::fmt::Debug) -> String {
    format!("{x:?}").to_lowercase()
}

/// How the cap integral is evaluated, read off the objects [`sptd`] and [`ltc`] build.
pub(crate) fn integral(opts: &StrategyOptions) -> Value {
    match opts.brdf_integral {
        BrdfIntegral::Sptd => {
            let s = sptd(opts);
            json!({
                "table": "sptd",
                "lookup": lower(s.lookup),
                "intersection": lower(s.intersection),
                "normalization": lower(s.normalization),
            })
        }
        BrdfIntegral::Ltc => json!({ "table": "ltc", "lookup": lower(ltc(opts).lookup) }),
    }
}
