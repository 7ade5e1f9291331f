//! The strategies of Liu, Xu & Yan 2019 as registry values: BRDF-oriented sampling alone, and the
//! three-technique MIS with equal or adaptive counts (with the E&K cut or the learned cluster
//! selection as its LS technique).
use super::ls_technique::LsTechnique;
use super::mis3::{Mis3, Mis3Mode};
use super::{BoImportance, BrdfIntegral};
use crate::strategy::Strategy;
use crate::tree_selection::{TreeMode, TreeSelection};
use crate::{StrategyError, StrategyOptions, learned, resolve};
use render_core::estimator::DirectLighting;
use render_core::scene::Scene;
use serde_json::{Value, json};

/// The method's knobs, then the learned cluster selection's (which only the learned variant takes).
const LEARNED_METHOD_KNOBS: &[&str] = &[
    "tau",
    "max-cut",
    "delta",
    "n-max",
    "lambda",
    "brdf-integral",
    "bo-importance",
    "pivot-sphere",
    "ltc-triangles",
    "no-adaptive-total",
    "no-adaptive-split",
    "weighted-ub",
    "fixed-n-max",
    "independent-samples",
    "split-ls-at-glossy",
    "binary-bo-descent",
    "no-pilot",
    "learned-target",
    "learned-clusters",
    "learned-cells",
    "learned-defensive",
    "learned-prior",
];

/// The method's knobs.
const METHOD_KNOBS: &[&str] = LEARNED_METHOD_KNOBS.split_at(17).0;

/// `mis3-adaptive`'s camera rays per sample for the emission seen directly: its few spp per
/// pixel leave the coverage noise of the pixels that see a light (the paper experiment chose it).
pub const METHOD_EMISSION_RAYS: u32 = 16;

fn resolve_method(_: &str, opts: &StrategyOptions) -> Value {
    json!({
        "power_units": resolve::units(opts),
        "ls_split": resolve::split(opts.split_params()),
        "method": resolve::bo_config(opts),
        "integral": resolve::integral(opts),
    })
}

fn resolve_learned_method(_: &str, opts: &StrategyOptions) -> Value {
    json!({
        "power_units": resolve::units(opts),
        "ls": "learned",
        "learned": learned::strategy::cluster_learned(opts),
        "method": resolve::bo_config(opts),
        "integral": resolve::integral(opts),
    })
}

/// The method's estimator in the mode the name asks for, with the tree's E&K cut (or one
/// descent) as its LS technique, or the learned cluster selection for `mis3-adaptive-learned`.
fn build(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    if name == MIS3_ADAPTIVE_LEARNED.name {
        let ls = learned::selection::LearnedSelection::new(scene, opts.power_units(), opts.learned)
            .map_err(StrategyError::BadOption)?;
        with_ls(name, scene, opts, ls)
    } else {
        let split = TreeMode::Split(opts.split_params());
        let ls =
            TreeSelection::new(scene, split, opts.power_units()).map_err(StrategyError::Scene)?;
        with_ls(name, scene, opts, ls)
    }
}

/// [`build`] once its LS technique is made.
fn with_ls<S: LsTechnique + 'static>(
    name: &str,
    scene: &Scene,
    opts: &StrategyOptions,
    ls: S,
) -> Result<Box<dyn DirectLighting>, StrategyError> {
    let mode = match name {
        "brdf-oriented" => Mis3Mode::BoOnly,
        "mis3-equal" => Mis3Mode::Equal,
        _ => Mis3Mode::Adaptive,
    };
    let config = resolve::bo_config(opts);
    let sg_nodes = match (opts.bo_importance, ls.tree()) {
        (BoImportance::Sg, Some(tree)) => Some(
            light_tree::SgNodes::build(tree, &crate::sg::sg_emitters(scene))
                .map_err(|e| StrategyError::BadOption(format!("SG lights: {e}")))?,
        ),
        _ => None,
    };
    Ok(match opts.brdf_integral {
        BrdfIntegral::Sptd => Box::new(Mis3 {
            sg_nodes,
            ..Mis3::new(name.into(), mode, ls, resolve::sptd(opts), config)
        }),
        BrdfIntegral::Ltc => {
            use brdf_integrals::CapIntegral;
            let integral = resolve::ltc(opts);
            // Sanity check of the table (a placeholder build would integrate to 0).
            let probe = integral.hemisphere(render_core::Vec3::new(0.6, 0.0, 0.8), 0.1);
            if !(probe > 0.0) {
                return Err(StrategyError::BadOption(
                    "--brdf-integral ltc: the LTC table integrates to 0".into(),
                ));
            }
            Box::new(Mis3 {
                sg_nodes,
                ..Mis3::new(name.into(), mode, ls, integral, config)
            })
        }
    })
}

/// `brdf-oriented`.
pub const BRDF_ORIENTED: Strategy = Strategy {
    knobs: METHOD_KNOBS,
    ..Strategy::new(
        "brdf-oriented",
        "BRDF-oriented light sampling alone (not complete: see docs)",
        resolve_method,
        build,
    )
};

/// `mis3-equal`.
pub const MIS3_EQUAL: Strategy = Strategy {
    knobs: METHOD_KNOBS,
    golden_variants: &["reproduce"],
    ..Strategy::new(
        "mis3-equal",
        "tree splitting + BRDF-oriented + BSDF sampling, equal counts",
        resolve_method,
        build,
    )
};

/// `mis3-adaptive`: the paper's method.
pub const MIS3_ADAPTIVE: Strategy = Strategy {
    knobs: METHOD_KNOBS,
    emission_rays: METHOD_EMISSION_RAYS,
    golden_variants: &["reproduce", "ltc", "pivot-independent"],
    ..Strategy::new(
        "mis3-adaptive",
        "Liu et al. 2019: three-technique MIS with adaptive allocation",
        resolve_method,
        build,
    )
};

/// `mis3-adaptive-learned`: the method with the learned cluster selection as its LS technique;
/// its emission rays are the method's, so that the two compare like with like.
pub const MIS3_ADAPTIVE_LEARNED: Strategy = Strategy {
    knobs: LEARNED_METHOD_KNOBS,
    emission_rays: METHOD_EMISSION_RAYS,
    golden_variants: &["reproduce", "learned-visibility"],
    ..Strategy::new(
        "mis3-adaptive-learned",
        "mis3-adaptive with the learned cluster selection (issue 25) as its LS technique at every point",
        resolve_learned_method,
        build,
    )
};
