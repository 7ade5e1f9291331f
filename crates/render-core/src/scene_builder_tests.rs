//! What the builder refuses: lights whose power overflows f32.
use super::*;

fn emissive(b: &mut SceneBuilder, emission: Vec3) -> u32 {
    b.add_material(Material {
        emission,
        ..Material::diffuse("lamp", Vec3::ZERO)
    })
    .unwrap()
}

/// Area 2, as the audit's glTF triangle.
const TRIANGLE: [Vec3; 3] = [
    Vec3::ZERO,
    Vec3::new(2.0, 0.0, 0.0),
    Vec3::new(0.0, 2.0, 0.0),
];

/// An emission that is finite but whose power (radiance × area × π) is not is refused where
/// the light is added, naming the triangle, its mesh and its material. It loaded with a total
/// power of `inf W`, and the light tree then failed with a message about a strategy option.
#[test]
fn lights_of_infinite_power_are_refused() {
    let mut b = SceneBuilder::new("t");
    let m = emissive(&mut b, Vec3::splat(1e38));
    let e = b
        .add_mesh(
            "panel",
            &TRIANGLE,
            None,
            None,
            &[0, 1, 2],
            Mat4::IDENTITY,
            m,
        )
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("triangle 0 of mesh `panel` (emissive material `lamp`): emission [1e38")
            && e.contains("area 2")
            && e.contains("infinite power"),
        "{e}"
    );
    // one bright channel is enough
    let mut b = SceneBuilder::new("t");
    let m = emissive(&mut b, Vec3::new(3e38, 0.0, 0.0));
    let big = TRIANGLE.map(|p| p * 4.0);
    assert!(matches!(
        b.add_mesh("panel", &big, None, None, &[0, 1, 2], Mat4::IDENTITY, m),
        Err(SceneError::InfinitePower { .. })
    ));
    let e = SceneBuilder::new("t")
        .add_sphere_light(Vec3::ZERO, 1e17, Vec3::splat(1e5), None)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("sphere light at [0, 0, 0]: ") && e.contains("radius 100000000000000000"),
        "{e}"
    );
    let e = SceneBuilder::new("t")
        .add_point_light(Vec3::ZERO, Vec3::splat(1e38), None)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("point light at [0, 0, 0]: "), "{e}");
    // a bright but finite light is a light
    let mut b = SceneBuilder::new("t");
    let m = emissive(&mut b, Vec3::splat(1e30));
    b.add_mesh(
        "panel",
        &TRIANGLE,
        None,
        None,
        &[0, 1, 2],
        Mat4::IDENTITY,
        m,
    )
    .unwrap();
    let scene = b.build().unwrap();
    assert!(scene.stats.total_power_w.is_finite() && scene.lights.len() == 1);
}
