//! table.md's figures: per scene a convergence plot and a comparison strip, with the strip's
//! per-pixel relMSE and HDR-ꟻLIP maps.
use super::layout::{Layout, clock_words};
use crate::experiments::cell::CellResult;
use crate::experiments::charts::{self, Series};
use crate::experiments::compositing::{self, StripColumn};
use crate::experiments::config::Experiment;
use crate::experiments::flip;
use crate::experiments::paths::reference_path;
use crate::experiments::plan::{Budget, slug};
use crate::experiments::report::{self, Pixels};
use std::fmt::Write;
use std::path::Path;

/// The curves of one scene's convergence plot: per strategy, relMSE against spp (spp
/// budgets only) and against seconds (every budget).
fn convergence_series(
    layout: &Layout,
    cells: &[CellResult],
    scene: &str,
) -> (Vec<Series>, Vec<Series>) {
    let mut vs_spp = Vec::new();
    let mut vs_sec = Vec::new();
    for col in &layout.cols {
        let mut a = Vec::new();
        let mut b = Vec::new();
        for budget in &layout.budgets {
            let sel: Vec<&CellResult> = cells
                .iter()
                .filter(|c| c.scene == scene && &c.strategy == col && &c.budget == budget)
                .collect();
            if sel.is_empty() {
                continue;
            }
            let e = report::entry(&sel, Pixels::Unlit, layout.clock());
            if let Budget::Spp(n) = budget {
                a.push((*n as f64, e.error.mean, e.error.std));
            }
            b.push((e.seconds, e.error.mean, e.error.std));
        }
        b.sort_by(|x, y| x.0.total_cmp(&y.0));
        if !a.is_empty() {
            vs_spp.push(Series {
                label: col.clone(),
                points: a,
            });
        }
        if !b.is_empty() {
            vs_sec.push(Series {
                label: col.clone(),
                points: b,
            });
        }
    }
    (vs_spp, vs_sec)
}

/// Per scene a convergence plot (plots/) and a comparison strip (strips/, where the renders
/// and the reference are on this machine), and the section that shows them.
pub fn write_figures(
    md: &mut String,
    layout: &Layout,
    cells: &[CellResult],
    out: &Path,
    refs_dir: &Path,
) -> Result<(), String> {
    let plots_dir = out.join("plots");
    let strips_dir = out.join("strips");
    for d in [&plots_dir, &strips_dir] {
        std::fs::create_dir_all(d).map_err(|e| e.to_string())?;
    }
    let mut figures = String::new();
    for scene in &layout.rows {
        let (vs_spp, vs_sec) = convergence_series(layout, cells, scene);
        let file = format!("{}.png", slug(scene));
        let floor = layout
            .ref_noise
            .get(scene)
            .map(|n| report::reference_own(*n));
        charts::convergence_plot(
            &plots_dir.join(&file),
            &format!("{scene}: relMSE (unlit pixels), mean ± std over seeds"),
            &vs_spp,
            &vs_sec,
            &clock_words(layout.clock()).to_lowercase(),
            floor,
        )?;
        let _ = writeln!(figures, "![{scene}: convergence](plots/{file})\n");
        match strip(layout.exp, out, refs_dir, scene, &layout.cols, cells) {
            Ok(Some(f)) => {
                let _ = writeln!(figures, "![{scene}: comparison](strips/{f})\n");
            }
            Ok(None) => {
                if strips_dir.join(&file).is_file() {
                    let _ = writeln!(figures, "![{scene}: comparison](strips/{file})\n");
                }
            }
            Err(e) => eprintln!("warning: no comparison strip for {scene}: {e}"),
        }
    }
    if !figures.is_empty() {
        md.push_str("## Plots and comparison strips\n\n");
        md.push_str(
            "Plots: relMSE (unlit pixels) vs spp and vs seconds (as above), log-log; the dashed line is the \
             reference's own estimated error. Strips: the reference with the insets marked; per strategy \
             the insets at the highest spp (seed of the first listed), the per-pixel relMSE map \
             (log scale 1e-4 dark → 10 yellow, grey = the camera sees a light) and the relMSE; they are \
             in index.html beside this file (written by every run, not committed).\n\n",
        );
        md.push_str(&figures);
    }
    Ok(())
}

/// The comparison strip of `scene` (None when its renders or reference are not on this machine).
fn strip(
    exp: &Experiment,
    out: &Path,
    refs_dir: &Path,
    scene: &str,
    cols: &[String],
    cells: &[CellResult],
) -> Result<Option<String>, String> {
    let mine: Vec<&CellResult> = cells
        .iter()
        .filter(|c| c.scene == scene && c.seed == exp.seeds[0])
        .collect();
    let budget = exp.spp.iter().max().map(|&n| Budget::Spp(n)).or_else(|| {
        exp.time_budgets
            .iter()
            .copied()
            .max_by(f64::total_cmp)
            .map(Budget::Time)
    });
    let Some(budget) = budget else {
        return Ok(None);
    };
    let Some(first) = mine.first() else {
        return Ok(None);
    };
    let ref_dir = reference_path(refs_dir, &first.reference_dir);
    if !ref_dir.join("ref.exr").is_file() {
        return Ok(None);
    }
    let (w, h, reference) = render_core::output::read_exr(&ref_dir.join("ref.exr"))?;
    let unlit = render_core::output::read_mask_png(&ref_dir.join("mask.png"), w, h)?;
    let mut columns = Vec::new();
    let mut baseline_err = None;
    for col in cols {
        let Some(c) = mine
            .iter()
            .find(|c| &c.strategy == col && c.budget == budget)
        else {
            continue;
        };
        let exr = out.join("renders").join(format!("{}.exr", c.id));
        if !exr.is_file() {
            return Ok(None);
        }
        let (iw, ih, px) = render_core::output::read_exr(&exr)?;
        if (iw, ih) != (w, h) {
            return Err(format!("{} is not {w}x{h}", exr.display()));
        }
        let err = render_core::metrics::rel_mse_map(&px, &reference);
        let maps = out.join("error-maps");
        std::fs::create_dir_all(&maps).map_err(|e| e.to_string())?;
        let rgb: Vec<u8> = err
            .iter()
            .zip(&unlit)
            .flat_map(|(v, u)| compositing::error_colour(*v, *u))
            .collect();
        compositing::save_png(
            &maps.join(format!("{}__{}.png", slug(scene), slug(col))),
            w,
            h,
            &rgb,
        )?;
        // and its HDR-ꟻLIP map (magma), beside it
        let flip_maps = out.join("flip-maps");
        std::fs::create_dir_all(&flip_maps).map_err(|e| e.to_string())?;
        flip::save_map(
            &flip_maps.join(format!("{}__{}.png", slug(scene), slug(col))),
            &flip::hdr_flip_map(&px, &reference, w, h)?,
            w,
            h,
        )?;
        if col == exp.baseline() || baseline_err.is_none() {
            baseline_err = Some(err.clone());
        }
        columns.push(StripColumn {
            label: col.clone(),
            caption: format!(
                "relMSE {}\n{:.2} s, {} spp",
                report::sci(c.unlit.rel_mse),
                c.seconds(exp.budget_clock),
                c.spp
            ),
            image: px,
            error: Some(err),
        });
    }
    if columns.is_empty() {
        return Ok(None);
    }
    columns.push(StripColumn {
        label: "reference".into(),
        caption: format!("ref. noise\n{}", report::sci(first.reference_noise_unlit)),
        image: reference.clone(),
        error: None,
    });
    let entry = exp.scenes.iter().find(|s| s.label() == scene);
    let insets = match entry.filter(|s| !s.insets.is_empty()) {
        Some(s) => s.insets.clone(),
        None => {
            let score: Vec<f32> = baseline_err
                .unwrap_or_default()
                .iter()
                .zip(&unlit)
                .map(|(e, u)| if *u { e.min(100.0) } else { 0.0 })
                .collect();
            compositing::pick_insets(&score, w, h, 2)
        }
    };
    let file = format!("{}.png", slug(scene));
    let desc = match budget {
        Budget::Spp(n) => format!("{n} spp"),
        Budget::Time(t) => format!("{t} s"),
    };
    compositing::comparison_strip(
        &out.join("strips").join(&file),
        &format!("{scene} — {desc}, seed {}", exp.seeds[0]),
        w,
        h,
        &reference,
        &unlit,
        &insets,
        &columns,
    )?;
    Ok(Some(file))
}
