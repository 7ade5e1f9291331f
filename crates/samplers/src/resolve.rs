//! A strategy's resolved parameters: every value it renders with, the defaults filled in and
//! what `reproduce` implies applied, without a scene. [`crate::create`] builds the strategies
//! from the same functions, so what this reports is what they use; the render's JSON records
//! it and the experiment harness keys its cells by it (a changed default re-renders the cells
//! of exactly the strategies that use it).
use crate::brdf_oriented::{BoConfig, BoImportance, BrdfIntegral};
use crate::tree_selection::PowerUnits;
use crate::{StrategyError, StrategyOptions};
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

/// Every parameter strategy `name` renders with under `opts` (an object; `{}` for the
/// strategies without parameters), or the error [`crate::create`] would give for them.
pub fn resolved_parameters(name: &str, opts: &StrategyOptions) -> Result<Value, StrategyError> {
    crate::check_options(opts)?;
    Ok((crate::registry::find(name)?.resolve)(name, opts))
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_listed_strategy_resolves() {
        for s in crate::strategies() {
            assert!(
                resolved_parameters(s.name, &StrategyOptions::default()).is_ok(),
                "{}",
                s.name
            );
        }
    }

    use super::*;

    #[test]
    fn defaults_are_filled_in_and_options_reach_only_their_strategies() {
        let d = StrategyOptions::default();
        let ek = resolved_parameters("tree-split+bsdf", &d).unwrap();
        assert_eq!(ek["split"]["tau"], json!(crate::DEFAULT_TAU));
        assert_eq!(ek["split"]["max_cut"], json!(d.max_cut));
        let mis = resolved_parameters("mis3-adaptive", &d).unwrap();
        assert_eq!(mis["method"]["n_max"], json!(d.n_max));
        // n_max is the method's alone: E&K's parameters do not move with it, the method's do
        let other = StrategyOptions {
            n_max: d.n_max + 1,
            ..d.clone()
        };
        assert_eq!(resolved_parameters("tree-split+bsdf", &other).unwrap(), ek);
        assert_ne!(resolved_parameters("mis3-adaptive", &other).unwrap(), mis);
        // reproduce resolves τ to the authors' and changes the cut for E&K too
        let r = StrategyOptions {
            reproduce: true,
            ..d.clone()
        };
        let ek_r = resolved_parameters("tree-split+bsdf", &r).unwrap();
        assert_eq!(ek_r["split"]["tau"], json!(crate::AUTHORS_TAU));
        assert_eq!(ek_r["split"]["max_cut"], Value::Null);
        assert_eq!(
            resolved_parameters("power+bsdf", &r).unwrap(),
            json!({}),
            "power sampling takes none of the options"
        );
    }

    #[test]
    fn every_listed_strategy_resolves_and_bad_input_is_an_error() {
        let d = StrategyOptions::default();
        for s in crate::strategies() {
            assert!(resolved_parameters(s.name, &d).is_ok(), "{}", s.name);
        }
        assert!(matches!(
            resolved_parameters("nope", &d),
            Err(StrategyError::Unknown { .. })
        ));
        let bad = StrategyOptions { lambda: -1.0, ..d };
        assert!(resolved_parameters("tree", &bad).is_err());
    }
}
