//! The light-selection work the light-tree strategies and the method count per shading point
//! (declared to the render through `DirectLighting::counters`): the points with a glossy lobe,
//! the clusters of the LS (E&K) and BO cuts, and the BRDF-aware samples (BO + BRDF sampling).
use render_core::stats::{Counters, StrategyCounter};

const GLOSSY_POINTS: usize = 0;
const LS_CLUSTERS: usize = 1;
const LS_CLUSTERS_GLOSSY: usize = 2;
const BO_CLUSTERS: usize = 3;
const BRDF_AWARE: usize = 4;
const BRDF_AWARE_GLOSSY: usize = 5;

const _: () = assert!(BRDF_AWARE_GLOSSY < render_core::stats::MAX_STRATEGY_COUNTERS);

/// The name of the glossy-point counter, which the per-glossy-point means are per.
pub const GLOSSY: &str = "glossy points";

/// The counters, in their slots' order.
pub fn names() -> Vec<StrategyCounter> {
    let c = |name, per| StrategyCounter { name, per };
    vec![
        c(GLOSSY, None),
        c("LS clusters", None),
        c("LS clusters at glossy points", Some(GLOSSY)),
        c("BO clusters", Some(GLOSSY)),
        c("BRDF-aware samples", None),
        c("BRDF-aware samples at glossy points", Some(GLOSSY)),
    ]
}

/// Records one shading point's work (`glossy`: its BSDF has a glossy lobe, where BO runs).
pub fn record(
    counters: &mut Counters,
    glossy: bool,
    ls_clusters: usize,
    bo_clusters: usize,
    brdf_aware: usize,
) {
    let s = &mut counters.strategy;
    s[GLOSSY_POINTS] += glossy as u64;
    s[LS_CLUSTERS] += ls_clusters as u64;
    s[BO_CLUSTERS] += bo_clusters as u64;
    s[BRDF_AWARE] += brdf_aware as u64;
    if glossy {
        s[LS_CLUSTERS_GLOSSY] += ls_clusters as u64;
        s[BRDF_AWARE_GLOSSY] += brdf_aware as u64;
    }
}

/// The totals of one render, for tests: (glossy points, LS clusters, LS clusters at glossy
/// points, BO clusters, BRDF-aware samples, BRDF-aware samples at glossy points).
pub fn totals(counters: &Counters) -> [u64; 6] {
    let s = &counters.strategy;
    [
        s[GLOSSY_POINTS],
        s[LS_CLUSTERS],
        s[LS_CLUSTERS_GLOSSY],
        s[BO_CLUSTERS],
        s[BRDF_AWARE],
        s[BRDF_AWARE_GLOSSY],
    ]
}
