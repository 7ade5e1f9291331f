//! `<results>/index.html`: the experiment as a page to look at. Per scene the
//! reference and each strategy at each budget (first seed), flipped or swiped, zoomed and
//! panned with sharp pixels, re-exposed from linear values, with per-pixel relMSE maps; then
//! table.md (tables, plots, strips) as HTML. Self-contained: the page, `viewer/<scene>.js`
//! (the images as data URIs, see [`encode`]) and the PNGs beside it open from the file system
//! with nothing fetched. Written from the cell files, the renders and the references found on
//! this machine; without renders (a merge of shards that kept none) it shows the reference, the
//! harness's error maps, the tables and the plots.
pub mod encode;
pub mod markdown;

use super::cell::CellResult;
use super::config::Experiment;
use super::flip_cells;
use super::plan::{Budget, slug};
use crate::experiments::paths::reference_path;
use glam::Vec3;
use serde_json::{Value, json};
use std::fmt::Write;
use std::path::Path;

const CSS: &str = include_str!("../../../assets/viewer.css");
const JS: &str = include_str!("../../../assets/viewer.js");

/// Short form of a budget for the page's buttons: "16 spp", "1 s".
fn budget_label(b: &Budget) -> String {
    match b {
        Budget::Spp(n) => format!("{n} spp"),
        Budget::Time(t) => format!("{t} s"),
    }
}

/// An image as the page's data URI (RGBE split PNG).
fn image_uri(px: &[Vec3], w: u32, h: u32) -> Result<String, String> {
    let buf = encode::split_rgbe(px, w, h);
    Ok(encode::data_uri(&encode::png_bytes(&buf, w, 2 * h, 3)?))
}

/// A mask as the page's data URI: a grey PNG, 255 where the camera sees no light.
fn unlit_uri(unlit: &[bool], w: u32, h: u32) -> Result<String, String> {
    let buf: Vec<u8> = unlit.iter().map(|&u| if u { 255 } else { 0 }).collect();
    Ok(encode::data_uri(&encode::png_bytes(&buf, w, h, 1)?))
}

/// A ꟻLIP map (magma PNG bytes) as the page's data URI: its palette indices as a grey PNG,
/// a third of the magma PNG's size (the page applies `flip_palette`).
fn flip_map_uri(png: &[u8], w: u32, h: u32) -> Option<String> {
    let img = image::load_from_memory(png).ok()?.to_rgb8();
    if img.dimensions() != (w, h) {
        return None;
    }
    let idx = super::flip::magma_indices(img.as_raw())?;
    Some(encode::data_uri(&encode::png_bytes(&idx, w, h, 1).ok()?))
}

/// The render of `cell` (and its own light mask) when renders/ has it at the cell's size.
fn cell_render(out: &Path, cell: &CellResult) -> Option<(Vec<Vec3>, Option<Vec<bool>>)> {
    let renders = out.join("renders");
    let (w, h, px) =
        render_core::output::read_exr(&renders.join(format!("{}.exr", cell.id))).ok()?;
    if (w, h) != (cell.width, cell.height) {
        return None;
    }
    let mask =
        render_core::output::read_mask_png(&renders.join(format!("{}.mask.png", cell.id)), w, h)
            .ok();
    Some((px, mask))
}

/// The cells of an existing `viewer/<scene>.js` by id (none if it is absent or unreadable).
fn previous_cells(path: &Path) -> std::collections::HashMap<String, Value> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Default::default();
    };
    let json = text
        .trim_end()
        .strip_prefix("MLV.scene(")
        .and_then(|t| t.strip_suffix(");"))
        .and_then(|t| serde_json::from_str::<Value>(t).ok());
    let Some(Value::Array(cells)) = json.map(|mut j| j["cells"].take()) else {
        return Default::default();
    };
    cells
        .into_iter()
        .filter_map(|c| Some((c["id"].as_str()?.to_string(), c)))
        .collect()
}

/// Whether a viewer entry shows this cell's result (same spp and error, to parse precision),
/// not an earlier render under the same id.
fn same_cell(old: &Value, c: &CellResult) -> bool {
    let close = |a: Option<f64>, b: f64| a.is_some_and(|a| (a - b).abs() <= 1e-12 * b.abs());
    old["spp"].as_u64() == Some(c.spp) && close(old["rel_mse"].as_f64(), c.unlit.rel_mse)
}

/// The data of one scene: what `viewer/<scene>.js` hands to the page.
fn scene_data(
    exp: &Experiment,
    out: &Path,
    refs_dir: &Path,
    scene: &str,
    cols: &[String],
    cells: &[CellResult],
    flips: &mut flip_cells::Sources,
) -> Result<Value, String> {
    let seed = exp.seeds.first().copied().unwrap_or(0);
    let mine: Vec<&CellResult> = cells
        .iter()
        .filter(|c| c.scene == scene && c.seed == seed)
        .collect();
    let (mut w, mut h) = mine.first().map(|c| (c.width, c.height)).unwrap_or((0, 0));
    let mut reference = Value::Null;
    let mut exposure = 1.0f32;
    if let Some(first) = mine.first() {
        let dir = reference_path(refs_dir, &first.reference_dir);
        if let Ok((rw, rh, px)) = render_core::output::read_exr(&dir.join("ref.exr"))
            && (rw, rh) == (w, h)
        {
            let unlit = render_core::output::read_mask_png(&dir.join("mask.png"), w, h)
                .unwrap_or_else(|_| vec![true; px.len()]);
            exposure = super::compositing::auto_exposure(&px, &unlit);
            reference = json!({
                "image": image_uri(&px, w, h)?,
                "unlit": unlit_uri(&unlit, w, h)?,
                "caption": format!("{} at {} spp", exp.reference.strategy, exp.reference.spp),
            });
        }
    } else {
        (w, h) = (1, 1);
    }
    let previous = previous_cells(&out.join("viewer").join(format!("{}.js", slug(scene))));
    let mut budgets = Vec::new();
    let mut items = Vec::new();
    for budget in super::plan::budgets(exp) {
        let label = budget_label(&budget);
        for col in cols {
            let Some(c) = mine
                .iter()
                .find(|c| &c.strategy == col && c.budget == budget)
            else {
                continue;
            };
            if !budgets.contains(&label) {
                budgets.push(label.clone());
            }
            let (image, unlit) = match cell_render(out, c) {
                Some((px, mask)) => (
                    Value::String(image_uri(&px, w, h)?),
                    match mask {
                        Some(m) => Value::String(unlit_uri(&m, w, h)?),
                        None => Value::Null,
                    },
                ),
                None => (Value::Null, Value::Null),
            };
            // the harness's HDR-ꟻLIP map of this render (ꟻLIP is not computed in the page)
            let mut flip_map = match image {
                Value::Null => Value::Null,
                _ => flips
                    .map_png(c)
                    .and_then(|b| flip_map_uri(&b, w, h))
                    .map_or(Value::Null, Value::String),
            };
            let (mut image, mut unlit) = (image, unlit);
            if image.is_null()
                && let Some(old) = previous.get(&c.id).filter(|o| same_cell(o, c))
            {
                // a results directory without `renders/` (shards merged without them) keeps
                // the images its viewer already has for this very cell
                image = old["image"].clone();
                unlit = old["unlit"].clone();
                flip_map = old["flip_map"].clone();
            }
            items.push(json!({
                "strategy": col,
                "budget": label,
                "id": c.id,
                "seed": c.seed,
                "rel_mse": c.unlit.rel_mse,
                "flip": c.flip_unlit,
                "flip_map": flip_map,
                "spp": c.spp,
                "seconds": c.seconds(exp.budget_clock),
                "image": image,
                "unlit": unlit,
            }));
        }
    }
    let maps_in = |dir: &str| -> Vec<Value> {
        cols.iter()
            .filter_map(|col| {
                let src = format!("{dir}/{}__{}.png", slug(scene), slug(col));
                out.join(&src)
                    .is_file()
                    .then(|| json!({ "strategy": col, "src": src }))
            })
            .collect()
    };
    let error_maps = maps_in("error-maps");
    let flip_maps = maps_in("flip-maps");
    let strip_budget = exp
        .spp
        .iter()
        .max()
        .map(|&n| format!("{n} spp"))
        .or_else(|| {
            exp.time_budgets
                .iter()
                .copied()
                .max_by(f64::total_cmp)
                .map(|t| format!("{t} s"))
        })
        .unwrap_or_default();
    Ok(json!({
        "label": scene,
        "width": w,
        "height": h,
        "exposure": exposure,
        "strategies": cols,
        "baseline": exp.baseline(),
        "budgets": budgets,
        "reference": reference,
        "cells": items,
        "error_maps": error_maps,
        "flip_maps": flip_maps,
        "flip_palette": super::flip::magma_palette(),
        "error_maps_budget": format!("{strip_budget}, seed {seed}"),
    }))
}

/// Writes `out/index.html` and `out/viewer/<scene>.js` for the scenes `rows` and the strategy
/// columns `cols`; `md` is table.md, shown below the viewer; `flips` gives the cells' ꟻLIP maps.
#[allow(clippy::too_many_arguments)]
pub fn write(
    exp: &Experiment,
    out: &Path,
    refs_dir: &Path,
    rows: &[String],
    cols: &[String],
    cells: &[CellResult],
    md: &str,
    flips: &mut flip_cells::Sources,
) -> Result<(), String> {
    let dir = out.join("viewer");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let mut scripts = Vec::new();
    for scene in rows {
        let data = scene_data(exp, out, refs_dir, scene, cols, cells, flips)?;
        let file = format!("{}.js", slug(scene));
        // `</` cannot end a script that is a file of its own, but keep the data inert anyway
        let text = format!(
            "MLV.scene({});\n",
            serde_json::to_string(&data).map_err(|e| e.to_string())?
        )
        .replace("</", "<\\/");
        render_core::output::write_atomically(&dir.join(&file), |tmp| {
            std::fs::write(tmp, &text).map_err(|e| e.to_string())
        })?;
        scripts.push(format!("viewer/{file}"));
    }
    // data of scenes no longer in the report
    if let Ok(entries) = std::fs::read_dir(&dir) {
        for e in entries.flatten() {
            let name = format!("viewer/{}", e.file_name().to_string_lossy());
            if name.ends_with(".js") && !scripts.contains(&name) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    let html = page(exp, &scripts, md);
    render_core::output::write_atomically(&out.join("index.html"), |tmp| {
        std::fs::write(tmp, &html).map_err(|e| e.to_string())
    })
}

/// The page: controls, the stage, the harness's error maps, table.md, the scripts.
fn page(exp: &Experiment, scripts: &[String], md: &str) -> String {
    let esc = markdown::escape;
    let mut h = String::new();
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>Experiment {} — manylights</title>\n<style>\n{CSS}</style>\n</head>\n<body>",
        esc(&exp.name)
    );
    let _ = writeln!(
        h,
        "<h1>Experiment <code>{}</code></h1>\n\
         <p><a href=\"#viewer\">viewer</a> · <a href=\"#tables\">tables and plots</a> · \
         <a href=\"table.md\">table.md</a> · <a href=\"cells.csv\">cells.csv</a></p>",
        esc(&exp.name)
    );
    h.push_str(
        "<section id=\"viewer\">\n<div id=\"bars\"></div>\n<p id=\"note\"></p>\n\
         <div id=\"stage\"><div id=\"layer\"><canvas id=\"canvasA\"></canvas><canvas id=\"canvasB\"></canvas></div>\
         <div id=\"split\"></div><span class=\"tag\" id=\"tagA\"></span><span class=\"tag\" id=\"tagB\"></span></div>\n\
         <p id=\"info\"></p>\n\
         <p class=\"keys\">Wheel: zoom at the cursor; drag: pan; double-click or f: fit. 0–9: A, shift+0–9: B; \
         space: flip A/B; s: swipe (the split follows the mouse); e: relMSE map; l: ꟻLIP map; −/+: exposure. \
         relMSE maps: per-pixel (x − r)² / (r² + 0.01), log scale 1e-4<span id=\"legend\"></span>10, \
         grey where the camera sees a light. ꟻLIP maps: the harness's per-pixel HDR-ꟻLIP from the full-precision \
         render, magma 0 (black) to 1 (yellow-white), every pixel.</p>\n\
         <h3 id=\"mapsTitle\"></h3>\n<div id=\"maps\"></div>\n\
         <h3 id=\"flipMapsTitle\"></h3>\n<div id=\"flipMaps\"></div>\n</section>\n",
    );
    h.push_str("<section id=\"tables\">\n");
    // table.md's own title is the page's
    let body: Vec<&str> = md.lines().skip_while(|l| l.starts_with("# ")).collect();
    h.push_str(&markdown::to_html(&body.join("\n"), "px"));
    h.push_str("</section>\n");
    let _ = writeln!(h, "<script>\n{JS}</script>");
    for s in scripts {
        let _ = writeln!(h, "<script src=\"{}\"></script>", esc(s));
    }
    h.push_str("<script>MLV.start();</script>\n</body>\n</html>\n");
    h
}

#[cfg(test)]
mod tests;
