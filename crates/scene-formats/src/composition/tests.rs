//! Composition files: what loads, and what is refused with the file and field named.
use super::*;
use crate::scratch::Scratch;

fn write(tmp: &Scratch, name: &str, text: &str) -> std::path::PathBuf {
    let p = tmp.path(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn layouts_carry_their_power() {
    let tmp = Scratch::new("composition");
    let p = write(
        &tmp,
        "studio.toml",
        r#"
        [ground]
        size = 10.0
        [[lights]]
        layout = "grid"
        shape = "sphere"
        count = 100
        center = [0.0, 3.0, 0.0]
        extent = [5.0, 0.0, 5.0]
        size = 0.01
        power = 500.0
        [[lights]]
        layout = "ring"
        shape = "quad"
        count = 10
        center = [0.0, 2.0, 0.0]
        extent = [3.0, 0.0, 0.0]
        size = 0.05
        power = 100.0
        [camera]
        eye = [0.0, 3.0, 8.0]
        target = [0.0, 0.0, 0.0]
        "#,
    );
    let s = load_composition(&p).unwrap();
    assert_eq!(s.stats.sphere_lights, 100);
    assert_eq!(s.stats.triangle_lights, 20);
    assert!(
        (s.stats.total_power_w - 600.0).abs() < 0.5,
        "{}",
        s.stats.total_power_w
    );
    assert_eq!(s.cameras.len(), 1);
}

#[test]
fn bad_files_name_the_problem() {
    let tmp = Scratch::new("composition");
    let p = write(&tmp, "bad.toml", "[[lights]]\nlayout = \"spiral\"\n");
    let e = load_composition(&p).err().expect("must fail").to_string();
    assert!(e.contains("bad.toml") && e.contains("spiral"), "{e}");
    let p = write(
        &tmp,
        "missing.toml",
        "[[gltf]]\npath = \"no-such-file.glb\"\n",
    );
    let e = load_composition(&p).err().expect("must fail").to_string();
    assert!(e.contains("no-such-file.glb"), "{e}");
    let p = write(
        &tmp,
        "zero.toml",
        "[[lights]]\nlayout = \"grid\"\nshape = \"sphere\"\ncount = 0\ncenter = [0.0,0.0,0.0]\nextent = [1.0,0.0,1.0]\nsize = 0.1\npower = 1.0\n",
    );
    let e = load_composition(&p).err().expect("must fail").to_string();
    assert!(e.contains("lights[0]"), "{e}");
    // a count beyond any machine is refused at once (scene-fuzz found it loading for minutes)
    let p = write(
        &tmp,
        "huge.toml",
        "[[lights]]\nlayout = \"random\"\nshape = \"quad\"\ncount = 9223372036854775807\ncenter = [0.0,0.0,0.0]\nextent = [1.0,0.0,1.0]\nsize = 0.1\npower = 1.0\n",
    );
    let e = load_composition(&p).err().expect("must fail").to_string();
    assert!(e.contains("more than the 4194304 lights"), "{e}");
}

/// A studio of one light over a ground, with `camera` as its `[camera]` table.
fn studio(camera: &str) -> String {
    format!(
        "[ground]\nsize = 10.0\n[[lights]]\nlayout = \"grid\"\nshape = \"sphere\"\ncount = 1\n\
         center = [0.0, 3.0, 0.0]\nextent = [1.0, 0.0, 1.0]\nsize = 0.1\npower = 10.0\n\
         [camera]\n{camera}\n"
    )
}

/// A camera that sees nothing is an error naming the file and the camera (each rendered
/// black, or not at all, with exit status 0).
#[test]
fn degenerate_cameras_are_refused() {
    let tmp = Scratch::new("composition");
    let ok = write(
        &tmp,
        "ok.toml",
        &studio("eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]"),
    );
    assert_eq!(load_composition(&ok).unwrap().cameras.len(), 1);
    let cases = [
        (
            "eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 1.0, 5.0]",
            "the same point",
        ),
        (
            "eye = [0.0, 5.0, 0.0]\ntarget = [0.0, 0.0, 0.0]",
            "parallel to the view direction",
        ),
        (
            "eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nyfov_deg = 0.0",
            "yfov 0°",
        ),
        (
            "eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nyfov_deg = 180.0",
            "yfov 180°",
        ),
        (
            "eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nyfov_deg = nan",
            "yfov NaN°",
        ),
        (
            "eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, inf]",
            "must be finite",
        ),
        (
            "eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 0",
            "0 × 240",
        ),
    ];
    for (k, (camera, want)) in cases.iter().enumerate() {
        let p = write(&tmp, &format!("cam{k}.toml"), &studio(camera));
        let e = load_composition(&p).err().expect("must fail").to_string();
        assert!(
            e.contains(&format!("cam{k}.toml: [camera]: camera `main`: "))
                && e.contains(want)
                && !e.contains('\n'),
            "case {k}: {e}"
        );
    }
}

/// Each number out of its range is an error naming the file and the field: a `fit_size` of 0
/// collapsed the asset to a point (every triangle skipped as degenerate), a roughness of 5
/// was used as it was.
#[test]
fn numbers_out_of_range_name_their_field() {
    let tmp = Scratch::new("composition");
    let asset = write(
        &tmp,
        "asset.pbrt",
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n",
    );
    let part = |fields: &str| {
        format!(
            "[[gltf]]\npath = \"{}\"\n{fields}\n{}",
            asset.file_name().unwrap().to_string_lossy(),
            studio("eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]")
        )
    };
    let ok = write(&tmp, "ok.toml", &part("fit_size = 2.0"));
    assert_eq!(load_composition(&ok).unwrap().triangles.len(), 3);
    let cases = [
        (
            part("fit_size = 0.0"),
            "gltf[0].fit_size 0 must be positive and finite",
        ),
        (
            part("fit_size = -1.0"),
            "gltf[0].fit_size -1 must be positive",
        ),
        (
            part("fit_size = inf"),
            "gltf[0].fit_size inf must be positive and finite",
        ),
        (part("scale = 0.0"), "gltf[0].scale 0 must be positive"),
        (
            part("translate = [0.0, nan, 0.0]"),
            "gltf[0].translate [0.0, NaN, 0.0] must be finite",
        ),
        (
            part("rotate_y_deg = inf"),
            "gltf[0].rotate_y_deg inf must be finite",
        ),
        (
            part("[[gltf.override]]\nroughness = 5.0"),
            "gltf[0].override[0].roughness 5 must be in [0, 1]",
        ),
        (
            part("[[gltf.override]]\nmetallic = -0.5"),
            "gltf[0].override[0].metallic -0.5 must be in [0, 1]",
        ),
        (
            part("[[gltf.override]]\nbase_color = [5.0, 5.0, 5.0]"),
            "gltf[0].override[0].base_color [5.0, 5.0, 5.0] must be in [0, 1]",
        ),
        (
            "[ground]\nsize = 0.0\n".into(),
            "ground.size 0 must be positive and finite",
        ),
        (
            "[ground]\nsize = 10.0\nroughness = 2.0\n".into(),
            "ground.roughness 2 must be in [0, 1]",
        ),
        (
            studio("eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 100000"),
            "camera: image size 100000 × 240 is larger than 65536 × 65536",
        ),
        (
            studio("eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]")
                .replace("size = 0.1", "size = inf"),
            "lights[0]: count 1, size inf, power 10 must be positive (and size and power finite)",
        ),
        (
            studio("eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]")
                .replace("center = [0.0, 3.0, 0.0]", "center = [0.0, inf, 0.0]"),
            "lights[0].center [0.0, inf, 0.0] must be finite",
        ),
        (
            studio("eye = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.0, 0.0]")
                .replace("power = 10.0", "power = 10.0\ncolor = [0.0, 0.0, 0.0]"),
            "lights[0].color [0.0, 0.0, 0.0] must be finite and non-negative",
        ),
    ];
    for (k, (text, want)) in cases.iter().enumerate() {
        let p = write(&tmp, &format!("range{k}.toml"), text);
        let e = load_composition(&p).err().expect("must fail").to_string();
        assert!(
            e.contains(&format!("range{k}.toml: {want}")) && !e.contains('\n'),
            "case {k}: want `{want}`, got `{e}`"
        );
    }
}

/// A placed asset's format follows its extension in any case (`ASSET.PBRT` was read as
/// glTF); an unknown extension is refused by name.
#[test]
fn placed_assets_follow_their_extension_in_any_case() {
    let tmp = Scratch::new("composition");
    write(
        &tmp,
        "ASSET.PBRT",
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n",
    );
    let upper = write(&tmp, "upper.toml", "[[gltf]]\npath = \"ASSET.PBRT\"\n");
    assert_eq!(load_composition(&upper).unwrap().triangles.len(), 1);
    let ply = write(&tmp, "ply.toml", "[[gltf]]\npath = \"bunny.ply\"\n");
    let e = load_composition(&ply).err().expect("must fail").to_string();
    assert!(
        e.contains("bunny.ply: unsupported scene format `.ply` (supported: "),
        "{e}"
    );
}
