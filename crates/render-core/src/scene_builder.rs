//! Building a [`Scene`]: [`SceneBuilder`] collects geometry, materials, lights and cameras
//! from the loaders and the built-in generators, refuses what no render could use (non-finite
//! or out-of-range geometry, negative emission, bad material parameters) and builds the
//! acceleration structure.
use crate::accel::{Accel, Primitive};
use crate::camera::Camera;
use crate::error::SceneError;
use crate::light::{DistantLight, Light, LightShape, SpotCone, TriangleRecord};
use crate::material::Material;
use crate::scene::{NO_LIGHT, Scene, SceneStats, Triangle};
use glam::{Mat4, Vec2, Vec3};
use std::f32::consts::PI;

/// A vector as `[x, y, z]` for messages.
fn fmt3(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// Collects geometry, materials and lights, validates them and builds a [`Scene`].
pub struct SceneBuilder {
    name: String,
    triangles: Vec<Triangle>,
    materials: Vec<Material>,
    lights: Vec<Light>,
    spheres: Vec<u32>,
    distant: Vec<DistantLight>,
    cameras: Vec<Camera>,
    stats: SceneStats,
    render_hints: crate::scene_hints::RenderHints,
}

/// The largest coordinate (and sphere radius) a scene may have: squares and areas of larger
/// ones overflow f32, and the BVH builder fails on them.
pub const MAX_COORDINATE: f32 = 1e18;

fn within_range(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
}

/// A material's factors must be finite and non-negative (NaN there makes NaN pixels).
fn check_material(m: &Material) -> Result<(), SceneError> {
    if let crate::material::Model::Dielectric { ior, alpha } = m.model {
        let alpha_ok = alpha.is_finite() && alpha >= 0.0;
        crate::bsdf::dielectric::check_ior(ior)
            .and_then(|()| {
                alpha_ok
                    .then_some(())
                    .ok_or(format!("alpha {alpha} must be finite and non-negative"))
            })
            .map_err(|message| SceneError::BadMaterial {
                name: m.name.clone(),
                message,
            })?;
    }
    let model_ok = match m.model {
        crate::material::Model::PbrtPlastic { ks, alpha } => {
            ks.is_finite() && ks.min_element() >= 0.0 && alpha.is_finite() && alpha >= 0.0
        }
        _ => true,
    };
    let ok = m.base_color.is_finite()
        && m.base_color.min_element() >= 0.0
        && [m.metallic, m.roughness, m.specular]
            .iter()
            .all(|x| x.is_finite() && *x >= 0.0)
        && model_ok;
    if ok {
        Ok(())
    } else {
        Err(SceneError::BadMaterial {
            name: m.name.clone(),
            message: format!(
                "base colour {:?}, metallic {}, roughness {}, specular {} must be finite and non-negative",
                m.base_color.to_array(),
                m.metallic,
                m.roughness,
                m.specular
            ),
        })
    }
}

fn check_emission(what: &str, e: Vec3) -> Result<(), SceneError> {
    if !e.is_finite() || e.min_element() < 0.0 {
        return Err(SceneError::BadEmission {
            what: what.into(),
            value: format!("{:?}", e.to_array()),
        });
    }
    Ok(())
}

/// A light's power must be finite, in luminance and in its brightest channel: the strategies
/// weigh lights by it and a light sample's value is of its size, so an infinite one makes NaN
/// pixels or a light tree that cannot be built. `what` names the light for the message.
fn check_power(light: &Light, what: impl FnOnce() -> String) -> Result<(), SceneError> {
    let factor = match &light.shape {
        LightShape::Triangle { area, .. } => area * if light.two_sided { 2.0 } else { 1.0 } * PI,
        LightShape::Sphere { radius, .. } => 4.0 * PI * PI * radius * radius,
        LightShape::Point { .. } => 4.0 * PI,
    };
    let brightest = light.mean_emission.max_element() * factor;
    if light.power().is_finite() && brightest.is_finite() {
        return Ok(());
    }
    Err(SceneError::InfinitePower {
        what: what(),
        emission: format!("{:?}", light.mean_emission.to_array()),
        size: match &light.shape {
            LightShape::Triangle { area, .. } => format!("area {area}"),
            LightShape::Sphere { radius, .. } => format!("radius {radius}"),
            LightShape::Point { .. } => "a point".into(),
        },
    })
}

/// Mean of an emission texture over a triangle, by a stratified barycentric grid whose
/// density follows the triangle's footprint in texels.
fn mean_over_triangle(tex: &crate::texture::Texture, uv: [Vec2; 3]) -> Vec3 {
    let texels =
        0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs() * (tex.width * tex.height) as f32;
    let n = (texels.sqrt() * 2.0).clamp(4.0, 64.0) as usize;
    let mut sum = Vec3::ZERO;
    let mut count = 0usize;
    for i in 0..n {
        for j in 0..n {
            let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let b = crate::sampling::uniform_triangle(u);
            let t = uv[0] * (1.0 - b.x - b.y) + uv[1] * b.x + uv[2] * b.y;
            sum += tex.sample(t).truncate();
            count += 1;
        }
    }
    sum / count as f32
}

impl SceneBuilder {
    pub fn new(name: &str) -> SceneBuilder {
        SceneBuilder {
            name: name.into(),
            triangles: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            spheres: Vec::new(),
            distant: Vec::new(),
            cameras: Vec::new(),
            stats: SceneStats::default(),
            render_hints: Default::default(),
        }
    }

    /// The sampler and filter the scene file asks for, to fill in as the file is read.
    pub fn render_hints_mut(&mut self) -> &mut crate::scene_hints::RenderHints {
        &mut self.render_hints
    }

    pub fn add_material(&mut self, m: Material) -> Result<u32, SceneError> {
        check_emission(&format!("material `{}`", m.name), m.emission)?;
        self.materials.push(m);
        Ok(self.materials.len() as u32 - 1)
    }

    pub fn material(&self, index: u32) -> &Material {
        &self.materials[index as usize]
    }

    /// Adds an indexed triangle mesh under `transform`. Degenerate triangles are skipped and
    /// counted; non-finite positions are an error. Triangles of an emissive material become
    /// area lights unless their emission averages to zero.
    #[allow(clippy::too_many_arguments)]
    pub fn add_mesh(
        &mut self,
        mesh_name: &str,
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        uvs: Option<&[Vec2]>,
        indices: &[u32],
        transform: Mat4,
        material: u32,
    ) -> Result<(), SceneError> {
        if positions.iter().any(|p| !p.is_finite()) || !transform.is_finite() {
            return Err(SceneError::NonFiniteVertex {
                mesh: mesh_name.into(),
            });
        }
        let normal_matrix = transform.inverse().transpose();
        let flips = transform.determinant() < 0.0;
        let wp: Vec<Vec3> = positions
            .iter()
            .map(|p| transform.transform_point3(*p))
            .collect();
        if !wp.iter().all(|p| within_range(*p)) {
            return Err(SceneError::NonFiniteVertex {
                mesh: mesh_name.into(),
            });
        }
        let wn: Option<Vec<Vec3>> = normals.map(|ns| {
            ns.iter()
                .map(|n| normal_matrix.transform_vector3(*n).normalize_or_zero())
                .collect()
        });
        let mat = self.materials[material as usize].clone();
        for (k, idx) in indices.chunks_exact(3).enumerate() {
            let (mut i0, i1, mut i2) = (idx[0] as usize, idx[1] as usize, idx[2] as usize);
            if [i0, i1, i2].iter().any(|&i| i >= wp.len()) {
                return Err(SceneError::Gltf {
                    path: mesh_name.into(),
                    message: format!("triangle {k} indexes past the vertex array"),
                });
            }
            if flips {
                std::mem::swap(&mut i0, &mut i2); // keep counter-clockwise = front
            }
            let p = [wp[i0], wp[i1], wp[i2]];
            let cross = (p[1] - p[0]).cross(p[2] - p[0]);
            let area = 0.5 * cross.length();
            if !(area > 1e-12 * (1.0 + p[0].abs().max_element()).powi(2)) || !cross.is_finite() {
                self.stats.degenerate_triangles_skipped += 1;
                continue;
            }
            let ng = cross.normalize();
            let n = match &wn {
                Some(wn) => [i0, i1, i2].map(|i| {
                    if wn[i] == Vec3::ZERO || !wn[i].is_finite() {
                        ng
                    } else {
                        wn[i]
                    }
                }),
                None => [ng; 3],
            };
            let uv = match uvs {
                Some(uv) if uv.len() == positions.len() => [uv[i0], uv[i1], uv[i2]],
                _ => [Vec2::ZERO; 3],
            };
            let mut light = NO_LIGHT;
            if mat.is_emissive() {
                let mean = match &mat.emission_texture {
                    Some(t) => mat.emission * mean_over_triangle(t, uv),
                    None => mat.emission,
                };
                if mean.max_element() > 0.0 {
                    light = self.lights.len() as u32;
                    let l = Light {
                        shape: LightShape::Triangle {
                            p,
                            normal: ng,
                            area,
                            uv,
                        },
                        emission: mat.emission,
                        texture: mat.emission_texture.clone(),
                        mean_emission: mean,
                        two_sided: mat.double_sided,
                        spot: None,
                    };
                    check_power(&l, || {
                        format!(
                            "triangle {k} of mesh `{mesh_name}` (emissive material `{}`)",
                            mat.name
                        )
                    })?;
                    self.lights.push(l);
                    self.stats.triangle_lights += 1;
                } else {
                    self.stats.black_emissive_triangles += 1;
                }
            }
            self.triangles.push(Triangle {
                p,
                n,
                uv,
                material,
                light,
            });
        }
        Ok(())
    }

    /// A sphere light of radius `radius` > 0 and uniform radiance.
    pub fn add_sphere_light(
        &mut self,
        center: Vec3,
        radius: f32,
        radiance: Vec3,
        spot: Option<SpotCone>,
    ) -> Result<(), SceneError> {
        check_emission("sphere light", radiance)?;
        if !within_range(center) || !(radius > 0.0) || !(radius <= MAX_COORDINATE) {
            return Err(SceneError::BadLight {
                what: "sphere".into(),
                message: format!("center {center:?}, radius {radius}"),
            });
        }
        let l = Light {
            shape: LightShape::Sphere { center, radius },
            emission: radiance,
            texture: None,
            mean_emission: radiance,
            two_sided: false,
            spot,
        };
        check_power(&l, || format!("sphere light at {}", fmt3(center)))?;
        self.spheres.push(self.lights.len() as u32);
        self.lights.push(l);
        self.stats.sphere_lights += 1;
        Ok(())
    }

    pub fn add_point_light(
        &mut self,
        position: Vec3,
        intensity: Vec3,
        spot: Option<SpotCone>,
    ) -> Result<(), SceneError> {
        check_emission("point light", intensity)?;
        if !within_range(position) {
            return Err(SceneError::BadLight {
                what: "point".into(),
                message: format!("position {position:?}"),
            });
        }
        let l = Light {
            shape: LightShape::Point { position },
            emission: intensity,
            texture: None,
            mean_emission: intensity,
            two_sided: false,
            spot,
        };
        check_power(&l, || format!("point light at {}", fmt3(position)))?;
        if spot.is_some() {
            self.stats.spot_lights += 1;
        } else {
            self.stats.point_lights += 1;
        }
        self.lights.push(l);
        Ok(())
    }

    pub fn add_distant_light(
        &mut self,
        direction_to_light: Vec3,
        irradiance: Vec3,
    ) -> Result<(), SceneError> {
        check_emission("directional light", irradiance)?;
        let d = direction_to_light.normalize_or_zero();
        if d == Vec3::ZERO || !d.is_finite() {
            return Err(SceneError::BadLight {
                what: "directional".into(),
                message: "zero direction".into(),
            });
        }
        self.distant.push(DistantLight {
            direction: d,
            irradiance,
        });
        self.stats.distant_lights += 1;
        Ok(())
    }

    /// Counts input primitives that were not loaded (points, lines, no positions).
    pub fn count_skipped_primitives(&mut self, n: usize) {
        self.stats.non_triangle_primitives_skipped += n;
    }

    /// Materials added so far, for composition files that override them after loading a glTF.
    pub fn materials_mut(&mut self) -> &mut [Material] {
        &mut self.materials
    }

    /// Number of materials added so far.
    pub fn material_count(&self) -> usize {
        self.materials.len()
    }

    /// Bounds of the triangles and lights added so far (`None` when empty).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in &self.triangles {
            for p in t.p {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        for l in &self.lights {
            let (a, b) = l.bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        (lo.x <= hi.x).then_some((lo, hi))
    }

    /// Forgets the cameras added so far (a composition places its own).
    pub fn clear_cameras(&mut self) {
        self.cameras.clear();
    }

    pub fn add_camera(&mut self, camera: Camera) {
        self.cameras.push(camera);
    }

    pub fn build(mut self) -> Result<Scene, SceneError> {
        if self.triangles.is_empty() && self.lights.is_empty() {
            return Err(SceneError::Empty);
        }
        // Checked here, not in add_material: compositions override factors after adding.
        for m in &self.materials {
            check_material(m)?;
        }
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut prims: Vec<Primitive> =
            Vec::with_capacity(self.triangles.len() + self.spheres.len());
        for t in &self.triangles {
            for p in t.p {
                lo = lo.min(p);
                hi = hi.max(p);
            }
            prims.push(Primitive::Triangle {
                v0: t.p[0],
                v1: t.p[1],
                v2: t.p[2],
            });
        }
        for &l in &self.spheres {
            if let LightShape::Sphere { center, radius } = self.lights[l as usize].shape {
                prims.push(Primitive::Sphere { center, radius });
            }
        }
        for l in &self.lights {
            let (a, b) = l.bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        self.stats.triangles = self.triangles.len();
        self.stats.total_power_w = self.lights.iter().map(|l| l.power() as f64).sum::<f64>() + 0.0; // + 0.0: an empty sum is −0.0
        let accel = Accel::build(&prims);
        Ok(Scene {
            name: self.name,
            triangles: self.triangles,
            materials: self.materials,
            triangle_records: self.lights.iter().map(TriangleRecord::of).collect(),
            lights: self.lights,
            sphere_prims: self.spheres,
            distant_lights: self.distant,
            cameras: self.cameras,
            bounds: (lo, hi),
            stats: self.stats,
            render_hints: self.render_hints,
            accel,
            light_points: Default::default(),
            derived: Default::default(),
        })
    }
}

#[cfg(test)]
#[path = "scene_builder_tests.rs"]
mod tests;
