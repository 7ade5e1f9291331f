//! Every strategy, in the order `manylights strategies` lists them. A new strategy is a
//! [`Strategy`] value in its own file and one line here.
use crate::strategy::Strategy;
use crate::tree_selection as tree;
use crate::{
    StrategyError, StrategyOptions, brdf_oriented, learned, light_strategy, oracle, ris, rivals, sg,
};
use serde_json::Value;

/// The registry.
pub static STRATEGIES: &[&Strategy] = &[
    &light_strategy::UNIFORM,
    &light_strategy::POWER,
    &light_strategy::BSDF,
    &light_strategy::POWER_BSDF,
    &tree::TREE,
    &tree::TREE_SPLIT,
    &tree::TREE_BSDF,
    &tree::TREE_SPLIT_BSDF,
    &sg::SG_TREE,
    &sg::SG_TREE_BSDF,
    &brdf_oriented::strategies::BRDF_ORIENTED,
    &brdf_oriented::strategies::MIS3_EQUAL,
    &brdf_oriented::strategies::MIS3_ADAPTIVE,
    &brdf_oriented::strategies::MIS3_ADAPTIVE_LEARNED,
    &learned::strategy::LEARNED,
    &learned::strategy::LEARNED_BSDF,
    &learned::strategy::LEARNED_DESCENT,
    &learned::strategy::LEARNED_DESCENT_BSDF,
    &oracle::ORACLE,
    &oracle::ORACLE_SHADOWED,
    &ris::strategy::RIS,
    &ris::strategy::RIS_4,
    &ris::strategy::RIS_32,
    &ris::strategy::RIS_ADAPTIVE,
    &rivals::slc::SLC,
    &rivals::slc::SLC_BSDF,
    &rivals::slc::SLC_BO_BSDF,
    &rivals::rht::RHT,
    &rivals::rht::RHT_BSDF,
    &rivals::rht::RHT_BO_BSDF,
    &rivals::varl::VARL,
    &rivals::varl::VARL_BSDF,
    &crate::reuse::strategy::RESTIR,
    &crate::reuse::strategy::RESTIR_BIASED,
    &crate::reuse::strategy::RESTIR_BO,
];

/// The strategy `--strategy name` means: its own name first, then the other names it answers to;
/// an unknown name is an error with the closest known one.
pub fn find(name: &str) -> Result<&'static Strategy, StrategyError> {
    STRATEGIES
        .iter()
        .find(|s| s.name == name)
        .or_else(|| STRATEGIES.iter().find(|s| s.answers_to(name)))
        .copied()
        .ok_or_else(|| {
            let names: Vec<&str> = STRATEGIES.iter().map(|s| s.name).collect();
            StrategyError::Unknown {
                name: name.into(),
                suggestion: render_core::suggest::did_you_mean(name, names.iter().copied()),
                known: names.join(", "),
            }
        })
}

/// Every parameter strategy `name` renders with under `opts` (an object; `{}` for the
/// strategies without parameters), or the error [`crate::create`] would give for them.
pub fn resolved_parameters(name: &str, opts: &StrategyOptions) -> Result<Value, StrategyError> {
    crate::check_options(opts)?;
    Ok((find(name)?.resolve)(name, opts))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn names_are_unique_and_each_finds_itself() {
        for (i, s) in STRATEGIES.iter().enumerate() {
            assert!(
                STRATEGIES[..i].iter().all(|o| o.name != s.name),
                "{}",
                s.name
            );
            assert!(std::ptr::eq(find(s.name).unwrap(), *s), "{}", s.name);
        }
    }

    #[test]
    fn every_knob_a_strategy_names_exists() {
        for s in STRATEGIES {
            for k in s.knobs {
                assert!(crate::knobs::knob(k).is_some(), "{}: --{k}", s.name);
            }
        }
    }

    #[test]
    fn other_names_and_misspellings() {
        assert_eq!(find("ris-7").unwrap().name, "ris");
        assert_eq!(find("ris-4").unwrap().name, "ris-4");
        assert!(find("ris-0").is_err());
        let e = find("mis3-adaptve").unwrap_err().to_string();
        assert!(e.contains("did you mean `mis3-adaptive`"), "{e}");
        let e = find("zzzzzz").unwrap_err().to_string();
        assert!(!e.contains("did you mean"), "{e}");
    }

    #[test]
    fn a_strategy_refuses_a_knob_it_does_not_take_and_names_its_own() {
        let given = |f: &str, v: &str| vec![(f.to_string(), v.to_string())];
        let e = find("power+bsdf")
            .unwrap()
            .options(&given("delta", "0.3"))
            .unwrap_err();
        let e = e.to_string();
        assert!(e.contains("--delta") && e.contains("--reproduce"), "{e}");
        let o = find("mis3-adaptive")
            .unwrap()
            .options(&given("delta", "0.3"))
            .unwrap();
        assert_eq!(o.delta, 0.3);
        assert!(
            find("mis3-adaptive")
                .unwrap()
                .options(&given("delta", "x"))
                .is_err()
        );
        assert!(
            find("power")
                .unwrap()
                .options(&given("reproduce", ""))
                .unwrap()
                .reproduce
        );
    }

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
