//! The report page from a small synthetic experiment: well formed, self-contained, every file
//! it names present, every image decoding to its render.
use super::encode;
use crate::experiments::cell::CellResult;
use crate::experiments::cell::cell_key;
use crate::experiments::config::parse;
use crate::experiments::plan::{self, Budget};
use crate::experiments::reference::Metric;
use crate::experiments::summary;
use glam::Vec3;
use std::path::Path;

const VOID: [&str; 6] = ["meta", "img", "br", "input", "hr", "link"];

/// Checks that the tags of `html` nest (void elements apart; script and style bodies skipped)
/// and returns the values of its src and href attributes.
fn check_well_formed(html: &str) -> Result<Vec<String>, String> {
    if !html.starts_with("<!DOCTYPE html>") {
        return Err("no doctype".into());
    }
    let mut stack: Vec<String> = Vec::new();
    let mut refs = Vec::new();
    let mut rest = &html["<!DOCTYPE html>".len()..];
    while let Some(start) = rest.find('<') {
        rest = &rest[start + 1..];
        let end = rest.find('>').ok_or("unterminated tag")?;
        let tag = &rest[..end];
        rest = &rest[end + 1..];
        if let Some(name) = tag.strip_prefix('/') {
            let open = stack.pop().ok_or(format!("</{name}> closes nothing"))?;
            if open != name {
                return Err(format!("<{open}> closed by </{name}>"));
            }
            continue;
        }
        let name: String = tag
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric())
            .collect::<String>()
            .to_lowercase();
        if name.is_empty() {
            return Err(format!("odd tag <{tag}>"));
        }
        for attr in ["src=\"", "href=\""] {
            let mut t = tag;
            while let Some(i) = t.find(attr) {
                t = &t[i + attr.len()..];
                let j = t.find('"').ok_or("unterminated attribute")?;
                refs.push(t[..j].to_string());
                t = &t[j..];
            }
        }
        if name == "script" || name == "style" {
            let close = format!("</{name}>");
            let j = rest.find(&close).ok_or(format!("<{name}> not closed"))?;
            rest = &rest[j + close.len()..];
            continue;
        }
        if !VOID.contains(&name.as_str()) {
            stack.push(name);
        }
    }
    if !stack.is_empty() {
        return Err(format!("unclosed: {stack:?}"));
    }
    Ok(refs)
}

fn base64_decode(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let mut out = Vec::new();
    for chunk in s.as_bytes().chunks(4) {
        let n = chunk.iter().filter(|&&c| c != b'=').count();
        let mut v = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            v |= if c == b'=' { 0 } else { val(c) as u32 } << (18 - 6 * k);
        }
        out.extend_from_slice(&v.to_be_bytes()[1..n]);
    }
    out
}

fn png_of(uri: &str) -> image::DynamicImage {
    let b64 = uri
        .strip_prefix("data:image/png;base64,")
        .expect("a PNG data URI");
    image::load_from_memory(&base64_decode(b64)).expect("a PNG")
}

#[test]
fn base64_round_trip() {
    let bytes: Vec<u8> = (0..=255u8).chain([0, 1]).collect();
    assert_eq!(base64_decode(&encode::base64(&bytes)), bytes);
}

#[test]
fn the_checker_finds_broken_pages() {
    assert!(check_well_formed("<!DOCTYPE html><html><body><p>a</p></body></html>").is_ok());
    assert!(check_well_formed("<!DOCTYPE html><html><body><p>a</body></html>").is_err());
    assert!(check_well_formed("<!DOCTYPE html><html><div></html>").is_err());
    assert!(check_well_formed("<html></html>").is_err());
    let r = check_well_formed("<!DOCTYPE html><p><img src=\"a.png\"><a href=\"b\">x</a></p>");
    assert_eq!(r.unwrap(), vec!["a.png".to_string(), "b".to_string()]);
}

/// What `cargo xtask run-experiments` and `merge-results` write: index.html beside table.md.
#[test]
fn report_page_is_well_formed_and_complete() {
    let exp = parse(
        "t",
        r#"
        description = "a <test> & more"
        width = 6
        height = 4
        seeds = [3, 4]
        spp = [4, 16]
        time_budgets = [1.0]
        [reference]
        strategy = "power+bsdf"
        spp = 8
        [[scenes]]
        label = "s one"
        spec = "builtin:s"
        [[scenes]]
        label = "t"
        spec = "builtin:t"
        [[strategies]]
        label = "A&B"
        name = "tree"
        [[strategies]]
        label = "C"
        name = "power"
        "#,
    )
    .unwrap();
    let base = std::env::temp_dir().join(format!("xtask-viewer-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let (out, refs) = (base.join("results"), base.join("references"));
    for d in [out.join("cells"), out.join("renders"), refs.join("ref-s")] {
        std::fs::create_dir_all(d).unwrap();
    }
    let (w, h) = (6u32, 4u32);
    let n = (w * h) as usize;
    // scene "s one" has a reference and renders for its first seed; "t" has neither
    let reference: Vec<Vec3> = (0..n)
        .map(|i| Vec3::new(0.1, 0.2, 0.3) * i as f32)
        .collect();
    render_core::output::write_exr(&refs.join("ref-s/ref.exr"), w, h, &reference).unwrap();
    let mut light = vec![0.0f32; n];
    light[5] = 1.0;
    render_core::output::write_mask_png(&refs.join("ref-s/mask.png"), w, h, &light).unwrap();
    let mut rendered = Vec::new();
    for (k, cell) in plan::expand(&exp).iter().enumerate() {
        let s = cell.scene_label == "s one";
        let r = CellResult {
            id: cell.id(),
            key: cell_key(cell),
            experiment: "t".into(),
            scene: cell.scene_label.clone(),
            scene_spec: cell.scene.spec.clone(),
            strategy: cell.strategy.label.clone(),
            strategy_name: cell.strategy.name.clone(),
            strategy_args: vec![],
            budget: cell.budget,
            seed: cell.seed,
            width: w,
            height: h,
            reference: "r".into(),
            reference_dir: if s { "ref-s" } else { "absent" }.into(),
            reference_noise_unlit: 1e-4,
            all: Metric {
                rel_mse: 0.2,
                mse: 0.1,
                pixels: n,
            },
            unlit: Metric {
                rel_mse: 0.1 + k as f64,
                mse: 0.1,
                pixels: n - 1,
            },
            spp: 4,
            wall_seconds: 1.0,
            cpu_seconds: 1.0,
            render: serde_json::json!({ "git_commit": "abc" }),
            code: None,
            inputs: None,
            flip_all: None,
            flip_unlit: None,
        };
        render_core::output::write_json(
            &out.join("cells").join(format!("{}.json", r.id)),
            &serde_json::to_value(&r).unwrap(),
        )
        .unwrap();
        if s && cell.seed == 3 {
            let px: Vec<Vec3> = (0..n)
                .map(|i| Vec3::new(i as f32, 1e-3 * k as f32, 50.0))
                .collect();
            render_core::output::write_exr(
                &out.join("renders").join(format!("{}.exr", r.id)),
                w,
                h,
                &px,
            )
            .unwrap();
            // the ꟻLIP map measure() keeps beside a render
            let map: Vec<f32> = (0..n).map(|i| i as f32 / n as f32).collect();
            crate::experiments::flip::save_map(
                &out.join("renders").join(format!("{}.flip.png", r.id)),
                &map,
                w,
                h,
            )
            .unwrap();
            rendered.push((r.id.clone(), px));
        }
    }
    // Cells made up here record no code state: the page is what is tested, not provenance.
    let permissions = crate::experiments::provenance::Permissions {
        allow_dirty: true,
        allow_mixed: true,
        current: None,
    };
    summary::generate(&exp, &out, &refs, &[], &permissions).unwrap();

    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let names = check_well_formed(&html).unwrap_or_else(|e| panic!("{e}\n{html}"));
    // self-contained: nothing from the network
    assert!(!html.contains("http://") && !html.contains("https://"));
    assert!(html.contains("Experiment <code>t</code>"));
    assert!(
        html.contains("a &lt;test&gt; &amp; more"),
        "table.md is in the page"
    );
    assert!(html.contains("<th>A&amp;B (baseline)</th>"), "{html}");
    let mut scripts = 0;
    for name in &names {
        if name.starts_with('#') {
            continue;
        }
        assert!(!name.starts_with("data:"), "data URIs live in viewer/*.js");
        assert!(out.join(name).is_file(), "{name} is named but absent");
        scripts += name.starts_with("viewer/") as usize;
    }
    assert_eq!(scripts, 2, "one data file per scene");
    assert!(names.iter().any(|n| n == "plots/s_one.png"));

    // the data of "s one": the reference, each strategy at each budget (first seed), images
    // that decode to the renders
    let js = std::fs::read_to_string(out.join("viewer/s_one.js")).unwrap();
    assert!(!js.contains("http://") && !js.contains("https://"));
    let json = js
        .strip_prefix("MLV.scene(")
        .and_then(|s| s.trim_end().strip_suffix(");"))
        .unwrap();
    let data: serde_json::Value = serde_json::from_str(json).unwrap();
    assert_eq!(
        (data["width"].as_u64(), data["height"].as_u64()),
        (Some(6), Some(4))
    );
    assert_eq!(
        data["budgets"],
        serde_json::json!(["4 spp", "16 spp", "1 s"])
    );
    let cells = data["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 2 * 3, "2 strategies × 3 budgets, seed 3 only");
    assert_eq!(rendered.len(), 6);
    for c in cells {
        assert_eq!(c["seed"], 3);
        let (_, px) = rendered
            .iter()
            .find(|(id, _)| c["id"] == id.as_str())
            .unwrap();
        // its ꟻLIP map, as the harness wrote it: palette indices that colour to the magma PNG
        let f = png_of(c["flip_map"].as_str().unwrap()).to_luma8();
        assert_eq!(f.dimensions(), (w, h));
        let pal: Vec<u8> = serde_json::from_value(data["flip_palette"].clone()).unwrap();
        let coloured: Vec<u8> = f
            .as_raw()
            .iter()
            .flat_map(|&i| pal[3 * i as usize..3 * i as usize + 3].to_vec())
            .collect();
        let path = out
            .join("renders")
            .join(format!("{}.flip.png", c["id"].as_str().unwrap()));
        let magma = image::open(path).unwrap().to_rgb8().into_raw();
        assert_eq!(coloured, magma);
        let img = png_of(c["image"].as_str().unwrap()).to_rgb8();
        assert_eq!(img.dimensions(), (w, 2 * h));
        let back = encode::decode_split(&img.into_raw(), w, h);
        for (a, b) in back.iter().zip(px) {
            assert!(
                (*a - *b).abs().max_element() <= b.max_element() / 128.0,
                "{a} vs {b}"
            );
        }
    }
    let r = png_of(data["reference"]["image"].as_str().unwrap()).to_rgb8();
    let back = encode::decode_split(&r.into_raw(), w, h);
    assert!((back[7] - reference[7]).abs().max_element() <= reference[7].max_element() / 128.0);
    let unlit = png_of(data["reference"]["unlit"].as_str().unwrap()).to_luma8();
    let unlit: Vec<u8> = unlit.into_raw();
    assert_eq!((unlit[5], unlit[4]), (0, 255), "pixel 5 sees a light");
    // the exposure is the strips' (the reference's auto exposure)
    let unlit_ref: Vec<bool> = light.iter().map(|&f| f == 0.0).collect();
    let e = crate::experiments::compositing::auto_exposure(&reference, &unlit_ref);
    assert!((data["exposure"].as_f64().unwrap() - e as f64).abs() < 1e-6);
    // the harness's error maps (written by the strip at 16 spp) are named and present
    let maps = data["error_maps"].as_array().unwrap();
    assert_eq!(maps.len(), 2);
    for m in maps {
        assert!(out.join(m["src"].as_str().unwrap()).is_file());
    }
    // and its HDR-ꟻLIP maps beside them
    let maps = data["flip_maps"].as_array().unwrap();
    assert_eq!(maps.len(), 2);
    for m in maps {
        let src = m["src"].as_str().unwrap();
        assert!(
            src.starts_with("flip-maps/") && out.join(src).is_file(),
            "{src}"
        );
    }

    // "t": no reference and no renders on this machine, still listed, images null
    let js = std::fs::read_to_string(out.join("viewer/t.js")).unwrap();
    assert!(js.contains("\"reference\":null"), "{js}");
    assert!(!js.contains("data:image"), "{js}");
    assert!(js.contains("\"image\":null"));
    assert!(js.contains("\"flip_map\":null") && js.contains("\"flip_maps\":[]"));
    let _ = Budget::Spp(0);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn stale_scene_data_is_removed() {
    let dir = std::env::temp_dir().join(format!("xtask-viewer-stale-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("viewer")).unwrap();
    std::fs::write(dir.join("viewer/old.js"), "MLV.scene({});").unwrap();
    let exp = parse(
        "t",
        "width = 2\nheight = 2\nspp = [1]\n[reference]\nstrategy = \"power\"\nspp = 2\n\
         [[scenes]]\nspec = \"builtin:s\"\n[[strategies]]\nlabel = \"A\"\nname = \"tree\"\n",
    )
    .unwrap();
    super::write(
        &exp,
        &dir,
        Path::new("/nonexistent"),
        &[],
        &[],
        &[],
        "# x\n",
        &mut crate::experiments::flip_cells::Sources::new(&dir, Path::new("/nonexistent")),
    )
    .unwrap();
    assert!(!dir.join("viewer/old.js").exists());
    assert!(dir.join("index.html").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn images_of_the_committed_viewer_are_kept_only_for_the_same_cell() {
    let dir = std::env::temp_dir().join(format!("xtask-viewer-keep-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut c = crate::experiments::cell::testing::cell_result("s__A__spp4__seed0", "r", "c");
    c.unlit.rel_mse = 1.2345678901234567e-2;
    let js = dir.join("s.js");
    let entry = serde_json::json!({"cells": [{"id": c.id, "spp": c.spp, "rel_mse": c.unlit.rel_mse,
        "image": "data:image/png;base64,AA", "unlit": null, "flip_map": null}]});
    std::fs::write(&js, format!("MLV.scene({entry});\n")).unwrap();
    let previous = super::previous_cells(&js);
    let old = &previous[&c.id];
    assert_eq!(old["image"], "data:image/png;base64,AA");
    assert!(super::same_cell(old, &c));
    // a re-rendered cell under the same id (another error) does not get the old image
    c.unlit.rel_mse *= 1.001;
    assert!(!super::same_cell(old, &c));
    assert!(super::previous_cells(&dir.join("absent.js")).is_empty());
    std::fs::write(&js, "not a viewer file").unwrap();
    assert!(super::previous_cells(&js).is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}
