//! The content hash of a loaded scene: geometry, materials as the renderer understands them,
//! lights and cameras, in their canonical loaded form. Whatever files a loader read to build
//! the scene (glTF buffers and images, pbrt includes and PLY meshes, composition assets), two
//! scenes with one hash render the same image for the same settings, and a file change that
//! alters nothing loaded leaves the hash as it was. The experiment harness keys its cached
//! references and cells by it.
//!
//! Derived data (the BVH, triangle records, bounds, statistics) is left out: it follows from
//! what is hashed. Names are left out except the cameras' (`--camera` selects by name).
use crate::bsdf::Bsdf;
use crate::camera::Camera;
use crate::light::{Light, LightShape};
use crate::material::{Material, Model};
use crate::scene::Scene;
use crate::texture::Texture;
use glam::{Vec2, Vec3, Vec4};

/// A streaming 128-bit hash (two 64-bit multiply–xorshift lanes over 32-bit words): stable
/// across toolchains and machines, fast enough for millions of triangles. Not cryptographic.
#[derive(Clone, Debug)]
pub struct ContentHasher {
    a: u64,
    b: u64,
    words: u64,
}

impl Default for ContentHasher {
    fn default() -> Self {
        ContentHasher {
            a: 0x9e37_79b9_7f4a_7c15,
            b: 0xc2b2_ae3d_27d4_eb4f,
            words: 0,
        }
    }
}

impl ContentHasher {
    pub fn write_u32(&mut self, w: u32) {
        self.a = (self.a ^ w as u64)
            .wrapping_mul(0x0100_0000_01b3)
            .rotate_left(29);
        self.b = (self.b ^ (w as u64).wrapping_add(self.words)).wrapping_mul(0xff51_afd7_ed55_8ccd);
        self.b ^= self.b >> 31;
        self.words += 1;
    }

    pub fn write_u64(&mut self, w: u64) {
        self.write_u32(w as u32);
        self.write_u32((w >> 32) as u32);
    }

    /// The exact bits: a value that changes in its last bit changes the hash.
    pub fn write_f32(&mut self, x: f32) {
        self.write_u32(x.to_bits());
    }

    pub fn write_vec2(&mut self, v: Vec2) {
        v.to_array().iter().for_each(|&x| self.write_f32(x));
    }

    pub fn write_vec3(&mut self, v: Vec3) {
        v.to_array().iter().for_each(|&x| self.write_f32(x));
    }

    pub fn write_vec4(&mut self, v: Vec4) {
        v.to_array().iter().for_each(|&x| self.write_f32(x));
    }

    /// Length-prefixed, so that ("ab", "c") and ("a", "bc") differ.
    pub fn write_str(&mut self, s: &str) {
        self.write_u64(s.len() as u64);
        for chunk in s.as_bytes().chunks(4) {
            let mut w = [0u8; 4];
            w[..chunk.len()].copy_from_slice(chunk);
            self.write_u32(u32::from_le_bytes(w));
        }
    }

    /// A section tag, so that the same numbers in different places hash differently.
    pub fn tag(&mut self, t: &str) {
        self.write_str(t);
    }

    /// 32 hex digits.
    pub fn finish(&self) -> String {
        let [a, b] = self.finish_words();
        format!("{a:016x}{b:016x}")
    }

    /// The hash as two 64-bit words (the digits of [`ContentHasher::finish`]).
    pub fn finish_words(&self) -> [u64; 2] {
        let mix = |mut h: u64| {
            h ^= h >> 33;
            h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
            h ^= h >> 33;
            h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
            h ^ (h >> 33)
        };
        [
            mix(self.a ^ self.words),
            mix(self.b.wrapping_add(self.words)),
        ]
    }
}

/// The texel digests of the textures met so far, keyed by allocation: a texture shared by
/// many materials or lights (an emissive texture is shared by every triangle light cut from
/// it: 2,720 on the ToyCar) is hashed once and then stands in the scene's hash by its
/// 128-bit digest. The digest is of the content, so two copies of one texture hash alike.
#[derive(Default)]
struct TextureDigests(std::collections::HashMap<*const Texture, [u64; 2]>);

impl TextureDigests {
    fn of(&mut self, t: &Texture) -> [u64; 2] {
        *self.0.entry(t as *const Texture).or_insert_with(|| {
            let mut h = ContentHasher::default();
            t.texels.iter().for_each(|&v| h.write_vec4(v));
            h.finish_words()
        })
    }
}

/// Directions (local frame, z = the normal) at which each material's BSDF is probed.
const PROBE_DIRECTIONS: [[f32; 3]; 3] = [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [-0.3, 0.8, 0.52]];
/// Texture coordinates at which each material is probed (besides its texels, hashed whole).
const PROBE_UVS: [[f32; 2]; 2] = [[0.25, 0.25], [0.7, 0.4]];

/// The probe's values with their last 8 mantissa bits cleared: a libm that rounds one `powf`
/// differently on another machine leaves the hash unchanged, a real change of a material's
/// reflectance does not.
fn coarse(x: f32) -> u32 {
    if x.is_finite() {
        x.to_bits() & !0xff
    } else {
        0x7fc0_0000
    }
}

impl Scene {
    /// The content hash of the scene as loaded (see the module documentation), 32 hex digits.
    pub fn content_hash(&self) -> String {
        let mut h = ContentHasher::default();
        let mut digests = TextureDigests::default();
        h.tag("triangles");
        h.write_u64(self.triangles.len() as u64);
        for t in &self.triangles {
            t.p.iter().for_each(|&p| h.write_vec3(p));
            t.n.iter().for_each(|&n| h.write_vec3(n));
            t.uv.iter().for_each(|&uv| h.write_vec2(uv));
            h.write_u32(t.material);
            h.write_u32(t.light);
        }
        h.tag("materials");
        h.write_u64(self.materials.len() as u64);
        for m in &self.materials {
            hash_material(&mut h, m, &mut digests);
        }
        h.tag("lights");
        h.write_u64(self.lights.len() as u64);
        for l in &self.lights {
            hash_light(&mut h, l, &mut digests);
        }
        h.tag("distant lights");
        h.write_u64(self.distant_lights.len() as u64);
        for d in &self.distant_lights {
            h.write_vec3(d.direction);
            h.write_vec3(d.irradiance);
        }
        h.tag("cameras");
        h.write_u64(self.cameras.len() as u64);
        for c in &self.cameras {
            hash_camera(&mut h, c);
        }
        // The file's sampler and filter choose the render's when no flag does.
        let hints = &self.render_hints;
        h.tag("render hints");
        h.write_str(hints.sampler.map_or("-", |s| s.name()));
        h.write_str(hints.filter.as_ref().map_or("-", |f| f.name()));
        for (k, v) in hints.filter.iter().flat_map(|f| f.parameters()) {
            h.write_str(k);
            h.write_f32(v);
        }
        h.finish()
    }
}

fn hash_texture(
    h: &mut ContentHasher,
    t: &Option<std::sync::Arc<Texture>>,
    d: &mut TextureDigests,
) {
    match t {
        None => h.write_u32(0),
        Some(t) => {
            h.write_u32(1);
            h.write_u32(t.width);
            h.write_u32(t.height);
            d.of(t).iter().for_each(|&w| h.write_u64(w));
        }
    }
}

/// Its fields, and its BSDF evaluated at fixed directions and texture coordinates: how the
/// renderer understands the material, so that a change of the material → BSDF step changes it.
fn hash_material(h: &mut ContentHasher, m: &Material, d: &mut TextureDigests) {
    h.write_vec3(m.base_color);
    hash_texture(h, &m.base_color_texture, d);
    h.write_f32(m.metallic);
    h.write_f32(m.roughness);
    hash_texture(h, &m.metallic_roughness_texture, d);
    h.write_f32(m.specular);
    h.write_u32(m.double_sided as u32);
    h.write_vec3(m.emission);
    hash_texture(h, &m.emission_texture, d);
    match m.model {
        Model::MetallicRoughness => h.write_u32(0),
        Model::PbrtPlastic { ks, alpha } => {
            h.write_u32(1);
            h.write_vec3(ks);
            h.write_f32(alpha);
        }
        Model::Dielectric { ior, alpha } => {
            h.write_u32(2);
            h.write_f32(ior);
            h.write_f32(alpha);
        }
    }
    let n = Vec3::Z;
    for uv in PROBE_UVS {
        let params = m.params_at(Vec2::from(uv));
        for wo in PROBE_DIRECTIONS {
            let wo = Vec3::from(wo).normalize();
            let bsdf = Bsdf::new(n, n, wo, params);
            for wi in PROBE_DIRECTIONS {
                let wi = Vec3::from(wi).normalize();
                let f = bsdf.eval_cos(wo, wi);
                f.to_array().iter().for_each(|&x| h.write_u32(coarse(x)));
                h.write_u32(coarse(bsdf.pdf(wo, wi)));
                if bsdf.transmits() {
                    // and the transmitted direction below it, for the materials that have one
                    let wt = wi * Vec3::new(1.0, 1.0, -1.0);
                    let f = bsdf.eval_cos(wo, wt);
                    f.to_array().iter().for_each(|&x| h.write_u32(coarse(x)));
                    h.write_u32(coarse(bsdf.pdf(wo, wt)));
                }
            }
        }
    }
}

fn hash_light(h: &mut ContentHasher, l: &Light, d: &mut TextureDigests) {
    match &l.shape {
        LightShape::Triangle {
            p,
            normal,
            area,
            uv,
        } => {
            h.write_u32(0);
            p.iter().for_each(|&p| h.write_vec3(p));
            h.write_vec3(*normal);
            h.write_f32(*area);
            uv.iter().for_each(|&uv| h.write_vec2(uv));
        }
        LightShape::Sphere { center, radius } => {
            h.write_u32(1);
            h.write_vec3(*center);
            h.write_f32(*radius);
        }
        LightShape::Point { position } => {
            h.write_u32(2);
            h.write_vec3(*position);
        }
    }
    h.write_vec3(l.emission);
    hash_texture(h, &l.texture, d);
    h.write_vec3(l.mean_emission);
    h.write_u32(l.two_sided as u32);
    match &l.spot {
        None => h.write_u32(0),
        Some(s) => {
            h.write_u32(1);
            h.write_vec3(s.direction);
            h.write_f32(s.cos_inner);
            h.write_f32(s.cos_outer);
        }
    }
}

fn hash_camera(h: &mut ContentHasher, c: &Camera) {
    h.write_str(&c.name);
    h.write_vec3(c.position);
    h.write_vec3(c.forward);
    h.write_vec3(c.up);
    h.write_f32(c.yfov);
    h.write_u32(c.width);
    h.write_u32(c.height);
    h.write_u32(c.mirrored as u32);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::scene::SceneBuilder;

    fn scene(edit: impl Fn(&mut SceneBuilder, &mut Material)) -> String {
        let mut b = SceneBuilder::new("t");
        let mut m = Material::simple("m", Vec3::splat(0.5), 0.0, 0.4);
        edit(&mut b, &mut m);
        let mi = b.add_material(m).unwrap();
        b.add_mesh(
            "tri",
            &[Vec3::ZERO, Vec3::X, Vec3::Y],
            None,
            None,
            &[0, 1, 2],
            glam::Mat4::IDENTITY,
            mi,
        )
        .unwrap();
        b.add_sphere_light(Vec3::new(0.0, 0.0, 2.0), 0.1, Vec3::splat(3.0), None)
            .unwrap();
        b.build().unwrap().content_hash()
    }

    #[test]
    fn equal_scenes_hash_equal_and_every_part_counts() {
        let base = scene(|_, _| {});
        assert_eq!(base, scene(|_, _| {}));
        assert_eq!(base.len(), 32);
        // a material's factor, and a light
        assert_ne!(base, scene(|_, m| m.roughness = 0.41));
        assert_ne!(
            base,
            scene(|b, _| {
                b.add_sphere_light(Vec3::new(1.0, 0.0, 2.0), 0.1, Vec3::ONE, None)
                    .unwrap();
            })
        );
        // the material's name does not change the image, so not the hash
        assert_eq!(base, scene(|_, m| m.name = "other".into()));
    }

    /// A texture enters by its content, wherever it is stored: shared or copied, one hash; one
    /// texel or the slot that holds it changes the hash.
    #[test]
    fn a_texture_counts_by_content_and_slot() {
        let tex = |v: f32| {
            let mut texels = vec![Vec4::splat(0.5); 4];
            texels[3] = Vec4::splat(v);
            Some(std::sync::Arc::new(Texture::new(2, 2, texels)))
        };
        let base = scene(|_, m| m.base_color_texture = tex(0.5));
        assert_eq!(base, scene(|_, m| m.base_color_texture = tex(0.5)));
        assert_ne!(base, scene(|_, _| {}));
        assert_ne!(base, scene(|_, m| m.base_color_texture = tex(0.6)));
        assert_ne!(base, scene(|_, m| m.metallic_roughness_texture = tex(0.5)));
        let shared = scene(|_, m| {
            let t = tex(0.5);
            m.base_color_texture = t.clone();
            m.metallic_roughness_texture = t;
        });
        let copies = scene(|_, m| {
            m.base_color_texture = tex(0.5);
            m.metallic_roughness_texture = tex(0.5);
        });
        assert_eq!(shared, copies);
        assert_ne!(shared, base);
        let other = scene(|_, m| {
            m.base_color_texture = tex(0.5);
            m.metallic_roughness_texture = tex(0.6);
        });
        assert_ne!(shared, other);
    }

    #[test]
    fn strings_are_length_prefixed() {
        let mut a = ContentHasher::default();
        a.write_str("ab");
        a.write_str("c");
        let mut b = ContentHasher::default();
        b.write_str("a");
        b.write_str("bc");
        assert_ne!(a.finish(), b.finish());
    }
}
