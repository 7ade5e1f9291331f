//! The pbrt loader against small scenes written by the tests.
use super::*;
use crate::scratch::Scratch;
use glam::{Vec2, Vec3};
use render_core::bsdf::Specular;
use render_core::light::LightShape;
use render_core::material::Model;
use std::path::PathBuf;

fn dir(test: &str) -> Scratch {
    Scratch::new(&format!("pbrt-{test}"))
}

fn write(d: &Path, name: &str, text: &str) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A binary little-endian PLY triangle with normals, and an ASCII PLY quad without.
fn write_plys(d: &Path) {
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]] {
        for x in v.iter().chain(&[0.0, 1.0, 0.0]) {
            bin.extend(x.to_le_bytes());
        }
    }
    bin.push(3);
    for i in [0i32, 1, 2] {
        bin.extend(i.to_le_bytes());
    }
    std::fs::write(d.join("tri.ply"), bin).unwrap();
    write(
        d,
        "quad.ply",
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n",
    );
}

const SCENE: &str = r#"# every directive the loader maps
LookAt 0 1 5   0 1 0   0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 64 ] "integer yresolution" [ 32 ] "string filename" "x.exr"
Sampler "halton" "integer pixelsamples" 16
Integrator "path" "integer maxdepth" [ 5 ]
PixelFilter "triangle"
WorldBegin
Texture "grey" "spectrum" "constant" "rgb value" [ 0.2 0.4 0.6 ]
Texture "checks" "spectrum" "checkerboard" "float uscale" 4
MakeNamedMaterial "walls" "string type" "matte" "rgb Kd" [ .725 .71 .68 ]
MakeNamedMaterial "bunny" "string type" [ "plastic" ] "rgb Kd" [ .3 .1 .2 ] "rgb Ks" [ .7 .7 .7 ]
    "float roughness" [ 0.008 ] "bool remaproughness" [ "false" ]
MakeNamedMaterial "gold" "string type" "conductor" "rgb reflectance" [ 1 0.8 0.3 ] "float roughness" 0.1
    "bool remaproughness" false
MakeNamedMaterial "coat" "string type" "coateddiffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
MakeNamedMaterial "glass" "string type" "dielectric" "float eta" 1.5
MakeNamedMaterial "checked" "string type" "diffuse" "texture reflectance" "checks"
Material "diffuse" "texture reflectance" "grey"
AttributeBegin
  Translate 10 0 0
  Rotate 90 0 0 1
  Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 1 0 ] "integer indices" [ 0 1 2 ]
AttributeEnd
TransformBegin
  Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  0 20 0 1 ]
  ConcatTransform [ 2 0 0 0  0 2 0 0  0 0 2 0  0 0 0 1 ]
  NamedMaterial "walls"
  Shape "bilinearmesh" "point3 P" [ 0 0 0  1 0 0  0 0 1  1 0 1 ]
TransformEnd
AttributeBegin
  NamedMaterial "bunny"
  Translate 0 -10 0
  Shape "plymesh" "string filename" "tri.ply"
  Scale 1 1 -1
  Shape "plymesh" "string filename" "quad.ply"
AttributeEnd
AttributeBegin
  CoordSysTransform "camera"
  Translate 0 0 1
  CoordinateSystem "in front"
  Shape "trianglemesh" "point3 P" [ 0 0 0  0.01 0 0  0 0.01 0 ]
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 300 180 225 ] "float scale" 2
  NamedMaterial "walls"
  Translate 0.999 0.5 -0.5
  Shape "sphere" "float radius" [ 0.01 ]
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 4 4 4 ] "bool twosided" true
  Translate 0 1.9 0
  Rotate 90 1 0 0
  Shape "disk" "float radius" 0.5
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 1 2 3 ]
  ReverseOrientation
  Shape "trianglemesh" "point3 P" [ 0 3 0  1 3 0  0 3 1 ] "integer indices" [ 0 1 2 ]
AttributeEnd
AttributeBegin
  NamedMaterial "gold"
  Translate 0 -5 0
  Shape "sphere" "float radius" 0.5
AttributeEnd
ObjectBegin "leaf"
  NamedMaterial "coat"
  Shape "trianglemesh" "point3 P" [ 0 0 0  0.1 0 0  0 0.1 0 ]
ObjectEnd
AttributeBegin
  Translate 0 0 -30
  ObjectInstance "leaf"
  Translate 1 0 0
  ObjectInstance "leaf"
AttributeEnd
LightSource "point" "rgb I" [ 5 5 5 ] "point3 from" [ 0 1.5 0 ]
LightSource "spot" "rgb I" [ 1 1 1 ] "point3 from" [ 0 2 0 ] "point3 to" [ 0 0 0 ] "float coneangle" 30 "float conedelta" 10
LightSource "distant" "rgb L" [ 2 2 2 ] "point3 from" [ 0 1 0 ] "point3 to" [ 0 0 0 ]
LightSource "infinite" "rgb L" [ 1 1 1 ]
NamedMaterial "glass"
Include "more.pbrt"
Import "more2.pbrt"
MakeNamedMedium "fog" "string type" "homogeneous"
Shape "curve" "point3 P" [ 0 0 0 1 1 1 2 2 2 3 3 3 ]
WorldEnd
"#;

fn load_test_scene() -> (render_core::scene::Scene, PbrtReport, PathBuf, Scratch) {
    let d = dir("every");
    write_plys(&d);
    write(
        &d,
        "more.pbrt",
        "NamedMaterial \"checked\"\nShape \"trianglemesh\" \"point3 P\" [ 5 5 5  6 5 5  5 6 5 ]\n",
    );
    write(
        &d,
        "more2.pbrt",
        "NamedMaterial \"glass\"\nShape \"trianglemesh\" \"point3 P\" [ 7 7 7  8 7 7  7 8 7 ]\n",
    );
    let path = write(&d, "scene.pbrt", SCENE);
    let (scene, report) = load_pbrt_with_report(&path, None).unwrap();
    (scene, report, path, d)
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-4
}

#[test]
fn every_directive_loads_to_the_expected_scene() {
    let (scene, report, _, _tmp) = load_test_scene();
    let sphere_tris = shapes::sphere(0.5).indices.len() / 3;
    // 1 + 2 (bilinear) + 1 + 2 (plys) + 1 (camera space) + 64 (disk) + 1 (reversed)
    // + sphere + 2 (instances) + 1 + 1 (includes)
    let want = 1 + 2 + 3 + 1 + shapes::SEGMENTS + 1 + sphere_tris + 2 + 2;
    assert_eq!(
        (
            scene.triangles.len(),
            scene.stats.degenerate_triangles_skipped
        ),
        (want, 0),
        "{:#?}",
        report.warnings
    );
    let s = &scene.stats;
    assert_eq!(
        (
            s.sphere_lights,
            s.point_lights,
            s.spot_lights,
            s.distant_lights
        ),
        (1, 1, 1, 1)
    );
    assert_eq!(s.triangle_lights, shapes::SEGMENTS + 1);
    assert_eq!(report.instances, 2);

    // transforms: Translate 10 then Rotate 90° about z maps (1, 0, 0) to (10, 1, 0)
    assert!(
        scene
            .triangles
            .iter()
            .any(|t| close(t.p[1], Vec3::new(10.0, 1.0, 0.0)))
    );
    // Transform then ConcatTransform: (1, 0, 1) → 2 × (1, 0, 1) + (0, 20, 0)
    assert!(
        scene
            .triangles
            .iter()
            .any(|t| t.p.iter().any(|&p| close(p, Vec3::new(2.0, 20.0, 2.0))))
    );
    // the mirrored PLY quad lies at z ≤ 0 with y from −10 to −9
    let quad: Vec<_> = scene
        .triangles
        .iter()
        .filter(|t| {
            t.p.iter()
                .all(|p| p.y <= -9.0 + 1e-4 && p.y >= -10.0 - 1e-4 && p.z.abs() < 1e-6)
        })
        .collect();
    assert_eq!(quad.len(), 2);
    // instances at z = −30, x = 0 and 1
    for x in [0.0, 1.0] {
        assert!(
            scene
                .triangles
                .iter()
                .any(|t| close(t.p[0], Vec3::new(x, 0.0, -30.0)))
        );
    }

    // camera: LookAt from (0, 1, 5) towards (0, 1, 0); pbrt's LookAt frame is mirrored for a
    // right-handed scene, fov 40° on the shorter (vertical) axis of 64 × 32
    let cam = scene.camera(None).unwrap();
    assert!(close(cam.position, Vec3::new(0.0, 1.0, 5.0)));
    assert!(close(cam.forward, Vec3::NEG_Z) && close(cam.up, Vec3::Y));
    assert!(cam.mirrored);
    assert!(
        close(cam.right(), Vec3::NEG_X),
        "pbrt's LookAt puts world −x on the image's right here"
    );
    assert_eq!((cam.width, cam.height), (64, 32));
    assert!((cam.yfov - 40f32.to_radians()).abs() < 1e-6);
    // CoordSysTransform "camera" + Translate 0 0 1: one unit in front of the eye
    assert!(
        scene
            .triangles
            .iter()
            .any(|t| t.p.iter().any(|&p| close(p, Vec3::new(0.0, 1.0, 4.0))))
    );

    // materials
    let m = |name: &str| {
        scene
            .materials
            .iter()
            .find(|m| m.name == name)
            .unwrap_or_else(|| panic!("{name}"))
    };
    assert_eq!(m("walls").params_at(Vec2::ZERO).specular, Specular::None);
    assert_eq!(
        m("bunny").model,
        Model::PbrtPlastic {
            ks: Vec3::splat(0.7),
            alpha: 0.008
        }
    );
    assert_eq!(m("bunny").base_color, Vec3::new(0.3, 0.1, 0.2));
    assert_eq!(
        (m("gold").metallic, m("gold").base_color),
        (1.0, Vec3::new(1.0, 0.8, 0.3))
    );
    assert!((m("gold").roughness - 0.1f32.sqrt()).abs() < 1e-6);
    // pbrt-v4's default roughness 0: a smooth pane, at our least α
    assert_eq!(
        m("glass").model,
        Model::Dielectric {
            ior: 1.5,
            alpha: render_core::bsdf::microfacet::MIN_ALPHA
        }
    );
    assert_eq!(m("glass").base_color, Vec3::ONE);
    assert_eq!(
        m("checked").base_color,
        Vec3::splat(0.5),
        "a non-constant texture takes the default"
    );
    let textured = scene
        .triangles
        .iter()
        .find(|t| close(t.p[0], Vec3::new(10.0, 0.0, 0.0)))
        .unwrap();
    assert_eq!(
        scene.materials[textured.material as usize].base_color,
        Vec3::new(0.2, 0.4, 0.6)
    );

    // lights
    let sphere = scene
        .lights
        .iter()
        .find(|l| matches!(l.shape, LightShape::Sphere { .. }))
        .unwrap();
    let LightShape::Sphere { center, radius } = sphere.shape else {
        unreachable!()
    };
    assert!(close(center, Vec3::new(0.999, 0.5, -0.5)) && (radius - 0.01).abs() < 1e-7);
    assert_eq!(sphere.emission, Vec3::new(600.0, 360.0, 450.0));
    // the disk (rotated +90° about x: its +z normal points to −y) emits on both sides
    let disk: Vec<_> = scene
        .lights
        .iter()
        .filter(|l| l.emission == Vec3::splat(4.0))
        .collect();
    assert_eq!(disk.len(), shapes::SEGMENTS);
    assert!(disk.iter().all(|l| l.two_sided
        && matches!(l.shape, LightShape::Triangle { normal, .. } if close(normal, Vec3::NEG_Y))));
    // ReverseOrientation turns the emitting side from −y (counter-clockwise) to +y
    let rev = scene
        .lights
        .iter()
        .find(|l| l.emission == Vec3::new(1.0, 2.0, 3.0))
        .unwrap();
    assert!(matches!(rev.shape, LightShape::Triangle { normal, .. } if close(normal, Vec3::Y)));
    assert!(!rev.two_sided);
    let spot = scene.lights.iter().find_map(|l| l.spot).unwrap();
    assert!(close(spot.direction, Vec3::NEG_Y));
    assert!((spot.cos_outer - 30f32.to_radians().cos()).abs() < 1e-6);
    assert!((spot.cos_inner - 20f32.to_radians().cos()).abs() < 1e-6);
    assert!(close(scene.distant_lights[0].direction, Vec3::Y));

    // what is not supported is a warning with its file and line
    for (what, line) in [
        ("LightSource \"infinite\"", 79),
        ("MakeNamedMedium", 83),
        ("Shape \"curve\"", 84),
        ("checkerboard", 10),
        ("Integrator", 6),
        (
            "Sampler \"halton\" is not implemented: the sobol sampler",
            5,
        ),
    ] {
        assert!(
            report
                .warnings
                .iter()
                .any(|w| w.contains(what) && w.contains(&format!("scene.pbrt:{line}:"))),
            "{what} at line {line}: {:#?}",
            report.warnings
        );
    }
    assert_eq!(scene.stats.warnings, report.warnings);
    // Sampler and PixelFilter become render hints (pbrt's default triangle radius is 2).
    let hints = &scene.render_hints;
    assert_eq!(
        (hints.sampler, hints.spp),
        (Some(render_core::sampler::Sampler::Sobol), Some(16))
    );
    assert_eq!(
        hints.filter,
        Some(render_core::filter::PixelFilter::Triangle { radius: 2.0 })
    );
}

/// pbrt-v3's and pbrt-v4's filter parameters, and filters or samplers we lack.
#[test]
fn sampler_and_pixel_filter_become_hints() {
    use render_core::filter::PixelFilter;
    use render_core::sampler::Sampler;
    let hints = |header: &str| {
        let d = dir(&format!("hints-{}", header.len()));
        let world = "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0 ]\n";
        let path = write(&d, "s.pbrt", &format!("{header}\n{world}"));
        load_pbrt_with_report(&path, None).map(|(s, r)| (s.render_hints, r.warnings))
    };
    let (h, _) = hints("Sampler \"lowdiscrepancy\" \"integer pixelsamples\" [ 4 ]\nPixelFilter \"triangle\" \"float xwidth\" [ 1 ] \"float ywidth\" [ 1 ]").unwrap();
    assert_eq!(h.sampler, Some(Sampler::LowDiscrepancy));
    assert_eq!(h.spp, Some(4));
    assert_eq!(h.filter, Some(PixelFilter::Triangle { radius: 1.0 }));
    let (h, _) = hints("PixelFilter \"gaussian\" \"float alpha\" 8").unwrap();
    assert_eq!(h.filter, Some(PixelFilter::gaussian(2.0, 0.25)));
    let (h, _) = hints(
        "PixelFilter \"gaussian\" \"float sigma\" 0.7 \"float xradius\" 3 \"float yradius\" 3",
    )
    .unwrap();
    assert_eq!(h.filter, Some(PixelFilter::gaussian(3.0, 0.7)));
    let (h, _) = hints("PixelFilter \"mitchell\" \"float B\" 0.5 \"float C\" 0.25").unwrap();
    assert_eq!(h.filter, Some(PixelFilter::mitchell(2.0, 0.5, 0.25)));
    let (h, w) = hints("PixelFilter \"lanczos\"\nSampler \"fancy\"").unwrap();
    assert_eq!((h.filter, h.sampler), (Some(PixelFilter::default()), None));
    assert!(
        w.iter().any(|w| w.contains("lanczos")) && w.iter().any(|w| w.contains("fancy")),
        "{w:?}"
    );
    let e = hints("PixelFilter \"box\" \"float xwidth\" -1")
        .unwrap_err()
        .to_string();
    assert!(e.contains("filter radius"), "{e}");
}

/// The scene converted to glTF and loaded back: same triangles, lights and materials.
#[test]
fn convert_round_trips_through_gltf() {
    let (scene, _, path, _tmp) = load_test_scene();
    let glb = path.with_extension("glb");
    crate::gltf_writer::write_glb(&scene, &glb).unwrap();
    let back = crate::gltf_reader::load_gltf(&glb, None).unwrap();
    assert_eq!(back.triangles.len(), scene.triangles.len());
    let (a, b) = (&scene.stats, &back.stats);
    assert_eq!(
        (
            a.sphere_lights,
            a.point_lights,
            a.spot_lights,
            a.distant_lights,
            a.triangle_lights
        ),
        (
            b.sphere_lights,
            b.point_lights,
            b.spot_lights,
            b.distant_lights,
            b.triangle_lights
        )
    );
    assert!((a.total_power_w - b.total_power_w).abs() < 1e-4 * a.total_power_w);
    let bunny = back.materials.iter().find(|m| m.name == "bunny").unwrap();
    assert_eq!(
        bunny.model,
        Model::PbrtPlastic {
            ks: Vec3::splat(0.7),
            alpha: 0.008
        }
    );
    let walls = back.materials.iter().find(|m| m.name == "walls").unwrap();
    assert_eq!(walls.params_at(Vec2::ZERO).specular, Specular::None);
    // the dielectric as KHR_materials_transmission + ior: α through glTF's √α and back
    let glass = |s: &render_core::scene::Scene| {
        let m = s.materials.iter().find(|m| m.name == "glass").unwrap();
        let Model::Dielectric { ior, alpha } = m.model else {
            panic!("{:?}", m.model)
        };
        (ior, alpha, m.base_color)
    };
    let (a, b) = (glass(&scene), glass(&back));
    assert!(
        a.0 == b.0 && a.2 == b.2 && (a.1 - b.1).abs() < 1e-6 * a.1,
        "{a:?} vs {b:?}"
    );
    let (c0, c1) = (scene.camera(None).unwrap(), back.camera(None).unwrap());
    assert!(
        close(c0.position, c1.position) && close(c0.forward, c1.forward) && close(c0.up, c1.up)
    );
    // the sampler and filter hints survive the glTF (as extras.pbrt)
    assert_eq!(back.render_hints, scene.render_hints);
    assert!(scene.render_hints.filter.is_some());
}

/// The start of a PLY file, and its elements: three vertices (x, y, z) and one face.
const PLY_HEADER: &str = "ply\n";
const PLY_ELEMENTS: &str = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

fn error_of(files: &[(&str, &str)]) -> String {
    let d = dir(&format!("err-{}", files[0].1.len() + files.len()));
    for (name, text) in files {
        write(&d, name, text);
    }
    match load_pbrt(&d.join(files[0].0), None) {
        Ok(_) => panic!("{files:?} loaded"),
        Err(e) => e.to_string(),
    }
}

/// Malformed input: one message naming the file and line, never a panic.
#[test]
fn malformed_input_is_one_error_with_file_and_line() {
    let shape = "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n";
    let cases: Vec<(Vec<(&str, String)>, &str)> = vec![
        (vec![("a.pbrt", format!("{shape}Shape \"sphere\" \"float radius\" \"big\n"))], "a.pbrt:2: unterminated string"),
        (vec![("b.pbrt", format!("{shape}\nShape \"sphere\" \"float radius\" \"big\"\n"))], "b.pbrt:3: parameter \"float radius\": a `float` cannot hold strings"),
        (vec![("c.pbrt", format!("{shape}Material \"matte\" \"rgb Kd\" [ 0.1 0.2 ]\n"))], "c.pbrt:2: parameter `Kd`: want 3 values, got 2"),
        (vec![("d.pbrt", format!("{shape}\n\nInclude \"nowhere.pbrt\"\n"))], "d.pbrt:4: cannot open"),
        (vec![("e.pbrt", format!("{shape}Include \"f.pbrt\"\n")), ("f.pbrt", "\nInclude \"e.pbrt\"\n".into())], "f.pbrt:2: Include cycle"),
        (vec![("g.pbrt", format!("{shape}Translate 1 2\nWorldEnd\n"))], "g.pbrt:3: Translate expects 3 numbers"),
        (vec![("h.pbrt", format!("{shape}AttributeEnd\n"))], "h.pbrt:2: AttributeEnd without a matching begin"),
        (vec![("i.pbrt", format!("{shape}Frobnicate 3\n"))], "i.pbrt:2: unknown directive `Frobnicate`"),
        (vec![("j.pbrt", "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 7]\n".into())], "j.pbrt:1: Shape \"trianglemesh\": trianglemesh: index 7 is past its 3 vertices"),
        (vec![("k.pbrt", format!("{shape}NamedMaterial \"nothing\"\n"))], "k.pbrt:2: NamedMaterial \"nothing\" is not defined"),
        (vec![("l.pbrt", format!("{shape}Shape \"plymesh\" \"string filename\" \"missing.ply\"\n"))], "l.pbrt:2: Shape \"plymesh\": cannot open"),
        (vec![("m.pbrt", format!("{shape}AreaLightSource \"diffuse\" \"rgb L\" [ -1 0 0 ]\n"))], "m.pbrt:2: AreaLightSource: L × scale"),
        (vec![("n.pbrt", format!("{shape}Shape \"sphere\" \"float radius\" [ 1 \n"))], "n.pbrt:2: parameter \"float radius\": `[` without `]`"),
        (vec![("o.pbrt", format!("{shape}LookAt 0 0 0  0 0 1  0 0 1\n"))], "o.pbrt:2: LookAt: the up vector"),
        (vec![("p.pbrt", format!("Camera \"perspective\" \"float fov\" 0\n{shape}"))], "p.pbrt:1: Camera: fov 0° is not in (0°, 180°)"),
        (vec![("q.pbrt", format!("Scale 1 0 1\nCamera \"perspective\"\n{shape}"))], "q.pbrt:2: the camera transform is degenerate: camera `pbrt camera`: "),
        (vec![("r.pbrt", format!("Include \"s.pbrt\"\n{shape}")), ("s.pbrt", "\nScale 0 0 0\nCamera \"perspective\"\n".into())], "s.pbrt:3: the camera transform is degenerate"),
        (vec![("t.pbrt", "Shape \"plymesh\" \"string filename\" \"nan.ply\"\n".into()), ("nan.ply", format!("{PLY_HEADER}format ascii 1.0\n{PLY_ELEMENTS}nan 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"))], "nan.ply: malformed PLY element `vertex`: Line 10: Couldn't read element line. String: 'nan 0 0' Error: error at 1:1"),
        (vec![("u.pbrt", "\nShape \"plymesh\" \"string filename\" \"cut.ply\"\n".into()), ("cut.ply", format!("{PLY_HEADER}format binary_little_endian 1.0\n{PLY_ELEMENTS}abcd"))], "cut.ply: malformed PLY element `vertex`: Line 10: Unexpected end of file while reading binary element 'vertex' (expected 3, got 0)."),
    ];
    for (files, want) in &cases {
        let files: Vec<(&str, &str)> = files.iter().map(|(n, t)| (*n, t.as_str())).collect();
        let e = error_of(&files);
        assert!(e.contains(want), "want `{want}`, got `{e}`");
        assert!(!e.contains('\n'), "one line: {e}");
    }
}

/// The authors' Cornell box from its own pbrt-v3 files (skipped without ../shared).
#[test]
fn bisml_cornell_pbrt_loads_like_its_gltf() {
    let dir = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/bisml_cornell"
    ));
    if !dir.exists() {
        crate::test_notice::skipped("bisml_cornell_pbrt_loads_like_its_gltf");
        return;
    }
    let (scene, report) = load_pbrt_with_report(&dir.join("pbrt/scene.pbrt"), None).unwrap();
    let glb = crate::gltf_reader::load_gltf(&dir.join("bisml_cornell.glb"), None).unwrap();
    assert_eq!(
        (scene.render_hints.sampler, scene.render_hints.spp),
        (Some(render_core::sampler::Sampler::LowDiscrepancy), Some(4))
    );
    assert_eq!(
        scene.render_hints.filter,
        Some(render_core::filter::PixelFilter::Triangle { radius: 1.0 })
    );
    assert_eq!(
        glb.render_hints, scene.render_hints,
        "the glb's extras.pbrt"
    );
    assert_eq!(scene.stats.sphere_lights, 1494);
    assert_eq!(scene.triangles.len(), glb.triangles.len());
    assert!(
        (scene.stats.total_power_w - glb.stats.total_power_w).abs()
            < 1e-3 * glb.stats.total_power_w
    );
    for (a, b) in scene.lights.iter().zip(&glb.lights) {
        let (
            LightShape::Sphere {
                center: ca,
                radius: ra,
            },
            LightShape::Sphere {
                center: cb,
                radius: rb,
            },
        ) = (&a.shape, &b.shape)
        else {
            panic!("sphere lights")
        };
        assert!((*ca - *cb).length() < 1e-5 && (ra - rb).abs() < 1e-9);
        assert!((a.emission - b.emission).abs().max_element() < 1e-3 * b.emission.max_element());
    }
    let cam = scene.camera(None).unwrap();
    let gcam = glb.camera(None).unwrap();
    assert!(
        close(cam.position, gcam.position)
            && close(cam.forward, gcam.forward)
            && close(cam.up, gcam.up)
    );
    assert!(!cam.mirrored && (cam.yfov - gcam.yfov).abs() < 1e-6);
    assert_eq!((cam.width, cam.height), (1024, 1024));
    let bunny = scene.materials.iter().find(|m| m.name == "Bunny").unwrap();
    assert_eq!(
        bunny.model,
        Model::PbrtPlastic {
            ks: Vec3::splat(0.7),
            alpha: 0.008
        }
    );
    eprintln!("{:#?}", report.warnings);
}

/// pbrt-v4's `dielectric` and pbrt-v3's `glass` load as the rough dielectric: η, roughness
/// remapped as each version does (√r in v4, v3's polynomial), v3's `Kt` as the tint; η = 1
/// (an index-matched interface) is an error naming the material's line.
#[test]
fn dielectric_and_glass_load_as_the_rough_dielectric() {
    let d = dir("dielectric");
    let text = r#"Camera "perspective"
WorldBegin
LightSource "point" "point3 from" [ 0 0 -2 ] "rgb I" [ 1 1 1 ]
MakeNamedMaterial "v4" "string type" "dielectric" "float eta" 1.33 "float roughness" 0.09
MakeNamedMaterial "v4u" "string type" "dielectric" "float uroughness" 0.2 "float vroughness" 0.2 "bool remaproughness" false
Material "glass" "float index" 1.7 "float uroughness" 0.1 "float vroughness" 0.1 "rgb Kt" [ 0.9 0.8 0.7 ]
Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 1 0 ]
NamedMaterial "v4"
Shape "trianglemesh" "point3 P" [ 0 0 1  1 0 1  0 1 1 ]
NamedMaterial "v4u"
Shape "trianglemesh" "point3 P" [ 0 0 2  1 0 2  0 1 2 ]
"#;
    let (scene, _) = load_pbrt_with_report(&write(&d, "glass.pbrt", text), None).unwrap();
    let model = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap();
    let Model::Dielectric { ior, alpha } = model("v4").model else {
        panic!("{:?}", model("v4").model)
    };
    assert!((ior - 1.33).abs() < 1e-6 && (alpha - 0.3).abs() < 1e-6);
    assert_eq!(
        model("v4u").model,
        Model::Dielectric {
            ior: 1.5,
            alpha: 0.2
        }
    );
    let v3 = scene
        .materials
        .iter()
        .find(|m| matches!(m.model, Model::Dielectric { ior, .. } if ior == 1.7))
        .unwrap();
    let want = render_core::bsdf::plastic::roughness_to_alpha(0.1);
    assert!(matches!(v3.model, Model::Dielectric { alpha, .. } if (alpha - want).abs() < 1e-6));
    assert_eq!(v3.base_color, Vec3::new(0.9, 0.8, 0.7));
    assert!(v3.params_at(Vec2::ZERO).specular != Specular::None);
    let e = error_of(&[(
        "one.pbrt",
        "WorldBegin\nMaterial \"dielectric\" \"float eta\" 1\nShape \"sphere\"\n",
    )]);
    assert!(e.contains("one.pbrt:2") && e.contains("ior"), "{e}");
}

/// pbrt-v4's `conductor` and `coateddiffuse` remap roughness as v4 does (α = √r), pbrt-v3's
/// `metal` as v3 does (its polynomial in ln r); `remaproughness false` takes r as α. The
/// glTF-style material keeps √α as its roughness.
#[test]
fn conductor_and_coateddiffuse_remap_roughness_as_v4_metal_as_v3() {
    let d = dir("remap");
    let text = r#"Camera "perspective"
WorldBegin
LightSource "point" "point3 from" [ 0 0 -2 ] "rgb I" [ 1 1 1 ]
MakeNamedMaterial "cond" "string type" "conductor" "rgb reflectance" [ 1 1 1 ] "float roughness" 0.09
MakeNamedMaterial "condraw" "string type" "conductor" "float roughness" 0.09 "bool remaproughness" false
MakeNamedMaterial "coat" "string type" "coateddiffuse" "float roughness" 0.16
MakeNamedMaterial "v3" "string type" "metal" "float roughness" 0.1
NamedMaterial "cond"
Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 1 0 ]
NamedMaterial "condraw"
Shape "trianglemesh" "point3 P" [ 0 0 1  1 0 1  0 1 1 ]
NamedMaterial "coat"
Shape "trianglemesh" "point3 P" [ 0 0 2  1 0 2  0 1 2 ]
NamedMaterial "v3"
Shape "trianglemesh" "point3 P" [ 0 0 3  1 0 3  0 1 3 ]
"#;
    let (scene, _) = load_pbrt_with_report(&write(&d, "remap.pbrt", text), None).unwrap();
    let alpha = |name: &str| {
        let m = scene.materials.iter().find(|m| m.name == name).unwrap();
        assert_eq!(m.model, Model::MetallicRoughness, "{name}");
        m.roughness * m.roughness
    };
    let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
    assert!(close(alpha("cond"), 0.3), "{}", alpha("cond"));
    assert!(close(alpha("condraw"), 0.09), "{}", alpha("condraw"));
    assert!(close(alpha("coat"), 0.4), "{}", alpha("coat"));
    let v3 = render_core::bsdf::plastic::roughness_to_alpha(0.1);
    assert!(
        close(alpha("v3"), v3) && !close(v3, 0.1f32.sqrt()),
        "{}",
        alpha("v3")
    );
}

/// A diffuse reflectance out of range is clamped as the version of its material evaluates it
/// (pbrt-v4's `diffuse` to [0, 1], pbrt-v3's `matte` below 0 only), with a warning naming the
/// material; reflectance 5 was used as given.
#[test]
fn diffuse_reflectance_is_clamped_as_its_pbrt_version_does() {
    let d = dir("clamp");
    let text = r#"WorldBegin
MakeNamedMaterial "v4" "string type" "diffuse" "rgb reflectance" [ 5 0.5 -1 ]
MakeNamedMaterial "v3" "string type" "matte" "rgb Kd" [ 5 0.5 -1 ]
MakeNamedMaterial "fine" "string type" "diffuse" "rgb reflectance" [ 1 0.5 0 ]
NamedMaterial "v4"
Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 1 0 ]
NamedMaterial "v3"
Shape "trianglemesh" "point3 P" [ 0 0 1  1 0 1  0 1 1 ]
NamedMaterial "fine"
Shape "trianglemesh" "point3 P" [ 0 0 2  1 0 2  0 1 2 ]
"#;
    let (scene, report) = load_pbrt_with_report(&write(&d, "clamp.pbrt", text), None).unwrap();
    let base = |name: &str| {
        scene
            .materials
            .iter()
            .find(|m| m.name == name)
            .unwrap()
            .base_color
    };
    assert_eq!(base("v4"), Vec3::new(1.0, 0.5, 0.0));
    assert_eq!(base("v3"), Vec3::new(5.0, 0.5, 0.0));
    assert_eq!(base("fine"), Vec3::new(1.0, 0.5, 0.0));
    let warned = |name: &str| {
        report
            .warnings
            .iter()
            .filter(|w| w.contains(&format!("material `{name}`")) && w.contains("clamped"))
            .count()
    };
    assert_eq!(
        (warned("v4"), warned("v3"), warned("fine")),
        (1, 1, 0),
        "{:?}",
        report.warnings
    );
    let v4 = report.warnings.iter().find(|w| w.contains("`v4`")).unwrap();
    assert!(
        v4.contains("clamp.pbrt:2: ") && v4.contains("[0, 1]"),
        "{v4}"
    );
}
