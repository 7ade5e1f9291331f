//! A rendered cell against its reference: the checks that it is the render planned, and its
//! relMSE, MSE and HDR-ꟻLIP over all pixels and over the unlit ones.
use super::cell::{CellInputs, CellResult, cell_key};
use super::flip;
use super::plan::Cell;
use super::reference::Reference;
use std::path::Path;

/// That the render used the scene and strategy the cell is keyed by (a file edited during
/// the run, or a binary that resolves differently from `manylights strategy`, is an error).
pub fn check_render(render: &serde_json::Value, inputs: &CellInputs) -> Result<(), String> {
    if render["scene_hash"].as_str() != Some(inputs.scene_hash.as_str()) {
        return Err(format!(
            "the render loaded scene {}, not the one planned ({}): did a scene file change during the run?",
            render["scene_hash"], inputs.scene_hash
        ));
    }
    if render["resolved_strategy"] != inputs.strategy {
        return Err(format!(
            "the render resolved the strategy to {}, `manylights strategy` to {}",
            render["resolved_strategy"], inputs.strategy
        ));
    }
    Ok(())
}

/// The cell's errors against its reference, over all pixels and over the unlit ones.
pub fn measure(
    cell: &Cell,
    exr: &Path,
    reference: &Reference,
    render: serde_json::Value,
    experiment: &str,
) -> Result<CellResult, String> {
    let (w, h, px) = render_core::output::read_exr(exr)?;
    if (w, h)
        != (
            reference.manifest.identity.width,
            reference.manifest.identity.height,
        )
    {
        return Err(format!("render is {w}x{h}, its reference is not"));
    }
    let all = render_core::metrics::error_metrics(&px, &reference.pixels, None).into();
    // Unlit = neither the reference's camera rays nor this render's saw a light. The reference
    // alone misses lights that cover a tiny part of a pixel; one camera sample of this render
    // landing on one adds light-seen-directly noise that no light-sampling strategy changes
    // (at equal spp and seed every strategy shoots the same camera rays, so the same pixels).
    let own = render_core::output::read_mask_png(&exr.with_extension("mask.png"), w, h)?;
    let unlit_pixels: Vec<bool> = reference
        .unlit
        .iter()
        .zip(&own)
        .map(|(&r, &c)| r && c)
        .collect();
    let unlit =
        render_core::metrics::error_metrics(&px, &reference.pixels, Some(&unlit_pixels)).into();
    // HDR-ꟻLIP beside relMSE; its map is kept beside the render for the report.
    let flip = flip::score(&px, &reference.pixels, &unlit_pixels, w, h)?;
    flip::save_map(&exr.with_extension("flip.png"), &flip.map, w, h)?;
    Ok(CellResult {
        id: cell.id(),
        key: cell_key(cell),
        experiment: experiment.to_string(),
        scene: cell.scene_label.clone(),
        scene_spec: cell.scene.spec.clone(),
        strategy: cell.strategy.label.clone(),
        strategy_name: cell.strategy.name.clone(),
        strategy_args: cell.strategy.cli_args()?,
        budget: cell.budget,
        seed: cell.seed,
        width: w,
        height: h,
        reference: reference.manifest.content_id(),
        reference_dir: reference
            .dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        reference_noise_unlit: reference.manifest.noise_unlit.rel_mse,
        all,
        unlit,
        flip_all: Some(flip.all),
        flip_unlit: Some(flip.unlit),
        spp: render["spp"].as_u64().unwrap_or(0),
        wall_seconds: render["wall_seconds"].as_f64().unwrap_or(0.0),
        cpu_seconds: render["cpu_seconds"].as_f64().unwrap_or(0.0),
        render,
        code: None,
        inputs: None,
    })
}
