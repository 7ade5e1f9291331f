//! The scene: triangles, materials, lights, cameras and the acceleration structure,
//! assembled through [`SceneBuilder`] (`scene_builder.rs`) by the loaders and the built-in
//! generators, and the queries a render makes of it.
use crate::accel::Accel;
use crate::camera::Camera;
use crate::error::SceneError;
use crate::light::{DistantLight, Light, LightSample, LightShape, TriangleRecord};
use crate::material::Material;
use glam::{Vec2, Vec3};
use serde::Serialize;

pub use crate::scene_builder::{MAX_COORDINATE, SceneBuilder};

pub const NO_LIGHT: u32 = u32::MAX;

/// One triangle with its shading attributes.
#[derive(Clone, Debug)]
pub struct Triangle {
    pub p: [Vec3; 3],
    /// Shading normals (the geometric normal repeated when the mesh has none).
    pub n: [Vec3; 3],
    pub uv: [Vec2; 3],
    pub material: u32,
    /// The area light this triangle is, or [`NO_LIGHT`].
    pub light: u32,
}

/// Counts that `manylights info` prints.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SceneStats {
    pub triangles: usize,
    pub degenerate_triangles_skipped: usize,
    /// Input primitives not loaded: points, lines, or no positions.
    pub non_triangle_primitives_skipped: usize,
    pub triangle_lights: usize,
    pub sphere_lights: usize,
    pub point_lights: usize,
    pub spot_lights: usize,
    pub distant_lights: usize,
    /// Emissive triangles whose emission averages to zero (not lights).
    pub black_emissive_triangles: usize,
    pub total_power_w: f64,
    /// Input features that were ignored or approximated (e.g. glTF extensions not modelled).
    pub warnings: Vec<String>,
}

/// Where a ray met the scene.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub point: Vec3,
    pub t: f32,
    /// Geometric normal (unit, not flipped).
    pub ng: Vec3,
    /// Interpolated shading normal (unit, not flipped).
    pub ns: Vec3,
    pub uv: Vec2,
    /// Material index, or `None` for a sphere light (black surface).
    pub material: Option<u32>,
    /// The light this surface belongs to, or [`NO_LIGHT`].
    pub light: u32,
}

pub struct Scene {
    pub name: String,
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    /// One cache line per light for sampling plain triangle lights (see [`TriangleRecord`]).
    pub triangle_records: Vec<TriangleRecord>,
    /// Light index of each sphere light, in primitive order after the triangles.
    pub sphere_prims: Vec<u32>,
    pub distant_lights: Vec<DistantLight>,
    pub cameras: Vec<Camera>,
    pub bounds: (Vec3, Vec3),
    pub stats: SceneStats,
    /// The sampler and filter the scene file asks for, if any.
    pub render_hints: crate::scene_hints::RenderHints,
    pub accel: Accel,
    /// How points on triangle lights are drawn ([`Scene::sample_light`]): a render's choice,
    /// set before it starts.
    pub light_points: crate::light_points::LightPoints,
    /// What strategies derived from this scene, kept for its next renders.
    pub derived: crate::derived::Derived,
}

impl Scene {
    /// Geometry at a hit returned by the accelerator.
    pub fn surface(&self, origin: Vec3, dir: Vec3, hit: &crate::accel::Hit) -> SurfaceHit {
        let point = origin + dir * hit.t;
        let ntri = self.triangles.len() as u32;
        if hit.prim < ntri {
            let tri = &self.triangles[hit.prim as usize];
            let b0 = 1.0 - hit.b1 - hit.b2;
            let ng = (tri.p[1] - tri.p[0]).cross(tri.p[2] - tri.p[0]).normalize();
            let ns = (tri.n[0] * b0 + tri.n[1] * hit.b1 + tri.n[2] * hit.b2).normalize_or(ng);
            let uv = tri.uv[0] * b0 + tri.uv[1] * hit.b1 + tri.uv[2] * hit.b2;
            SurfaceHit {
                point,
                t: hit.t,
                ng,
                ns,
                uv,
                material: Some(tri.material),
                light: tri.light,
            }
        } else {
            let light = self.sphere_prims[(hit.prim - ntri) as usize];
            let LightShape::Sphere { center, .. } = self.lights[light as usize].shape else {
                unreachable!("sphere primitives map to sphere lights")
            };
            let n = (point - center).normalize_or(-dir);
            SurfaceHit {
                point,
                t: hit.t,
                ng: n,
                ns: n,
                uv: Vec2::ZERO,
                material: None,
                light,
            }
        }
    }

    /// Asks for light `light`'s sampling record ahead of [`Scene::sample_light`] (a hint:
    /// nothing changes but when its cache line arrives).
    #[inline]
    pub fn prefetch_light(&self, light: u32) {
        if let Some(rec) = self.triangle_records.get(light as usize) {
            crate::accel::prefetch(rec);
        }
    }

    /// Closest surface along a ray.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        self.accel
            .intersect(origin, dir, tmin, tmax)
            .map(|h| self.surface(origin, dir, &h))
    }

    /// True when the segment from `origin` (already offset off its surface) along `dir` up to
    /// `dist` is blocked. The far end is shortened so the light's own surface never occludes.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, dist: f32) -> bool {
        let r = self.shadow_ray(origin, dir, dist);
        self.accel.occluded(r.origin, r.dir, r.tmin, r.tmax)
    }

    /// Scene diagonal, a length scale for defaults.
    pub fn diagonal(&self) -> f32 {
        (self.bounds.1 - self.bounds.0).length()
    }

    /// The error for a camera name the scene lacks, with the names it has.
    fn camera_not_found(&self, name: &str) -> SceneError {
        let names: Vec<&str> = self.cameras.iter().map(|c| c.name.as_str()).collect();
        SceneError::CameraNotFound {
            name: name.into(),
            suggestion: crate::suggest::did_you_mean(name, names.iter().copied()),
            known: match names.len() {
                0 => "it has none: leave out --camera for a view framing the scene".into(),
                _ => format!("its cameras: {}", names.join(", ")),
            },
        }
    }

    /// Makes the camera called `name` the first one (the one [`Scene::camera`]`(None)`
    /// returns); `None` changes nothing, an unknown name is an error.
    pub fn select_camera(&mut self, name: Option<&str>) -> Result<(), SceneError> {
        if let Some(name) = name {
            let i = self
                .cameras
                .iter()
                .position(|c| c.name == name)
                .ok_or_else(|| self.camera_not_found(name))?;
            let c = self.cameras.remove(i);
            self.cameras.insert(0, c);
        }
        Ok(())
    }

    pub fn camera(&self, name: Option<&str>) -> Result<Camera, SceneError> {
        match name {
            Some(n) => self
                .cameras
                .iter()
                .find(|c| c.name == n)
                .cloned()
                .ok_or_else(|| self.camera_not_found(n)),
            None => match self.cameras.first() {
                Some(c) => Ok(c.clone()),
                None => Camera::framing(self.bounds.0, self.bounds.1, 512, 512).map_err(|error| {
                    SceneError::BadCamera {
                        scene: self.name.clone(),
                        error,
                    }
                }),
            },
        }
    }
}

/// Offset that moves a ray origin off the surface it starts on: scaled with the coordinates'
/// magnitude, as f32 rounding is.
pub fn ray_epsilon(p: Vec3) -> f32 {
    1e-6 * (1.0 + p.abs().max_element()) * 8.0
}

/// Moves `p` off its surface towards the side `w` leaves through.
pub fn offset_origin(p: Vec3, ng: Vec3, w: Vec3) -> Vec3 {
    let e = ray_epsilon(p);
    if ng.dot(w) >= 0.0 {
        p + ng * e
    } else {
        p - ng * e
    }
}

impl Scene {
    /// A point on light `light` for a receiver at `x` with unit normal `n` (zero if none), by
    /// the scene's [`crate::light_points::LightPoints`]; under `area` through the light's one-cache-line record when
    /// it is a plain triangle (the same result as [`Light::sample`], bit for bit).
    #[inline]
    pub fn sample_light(&self, light: u32, x: Vec3, n: Vec3, u: Vec2) -> Option<LightSample> {
        if self.light_points != crate::light_points::LightPoints::Area {
            return self
                .light_points
                .sample(&self.lights[light as usize], x, n, u);
        }
        let rec = &self.triangle_records[light as usize];
        if rec.is_plain_triangle() {
            rec.sample(x, u)
        } else {
            self.lights[light as usize].sample(x, u)
        }
    }

    /// The solid-angle density with which [`Scene::sample_light`] draws `point` (normal
    /// `normal`) of light `light`, for MIS.
    #[inline]
    pub fn light_pdf(&self, light: u32, x: Vec3, n: Vec3, point: Vec3, normal: Vec3) -> f32 {
        self.light_points
            .pdf(&self.lights[light as usize], x, n, point, normal)
    }
}
