//! The `manylights` command line's library side: what `render` makes of its flags (the strategy,
//! the settings, the JSON record), shared by the binary and by the Python package (`python/`),
//! which parses the same flags so that its renders and its errors are the command line's.
pub mod render_cmd;

use render_core::scene::Scene;

/// Every registered strategy with its description, its knobs (flag, default, help) and its
/// emission rays: `manylights strategies --json`.
pub fn strategies_json() -> serde_json::Value {
    let defaults = samplers::StrategyOptions::default();
    samplers::strategies()
        .iter()
        .map(|s| {
            let knobs: Vec<serde_json::Value> = s
                .all_knobs()
                .filter_map(samplers::knobs::knob)
                .map(|k| serde_json::json!({ "flag": format!("--{}", k.flag), "default": k.default_value(), "help": k.help }))
                .collect();
            serde_json::json!({
                "name": s.name,
                "description": s.description,
                "knobs": knobs,
                "emission_rays": s.default_emission_rays(&defaults),
            })
        })
        .collect()
}

/// A loaded scene's content hash (`scene_hash`, [`Scene::content_hash`], which a caller that
/// keeps it passes), statistics, bounds and cameras: `manylights info --json`.
pub fn scene_info_json((spec, scene_hash): (&str, &str), scene: &Scene) -> serde_json::Value {
    serde_json::json!({
        "scene": spec,
        "scene_hash": scene_hash,
        "stats": scene.stats,
        "bounds": [scene.bounds.0.to_array(), scene.bounds.1.to_array()],
        "cameras": scene.cameras.iter().map(|c| &c.name).collect::<Vec<_>>(),
    })
}
