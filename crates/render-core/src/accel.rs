//! Ray casting through one obvhs CWBVH over triangles and sphere lights.
//! Closest hit uses `ray_traverse`; shadow rays use `ray_traverse_miss`, which stops at the
//! first hit (`ray_traverse_anyhit` visits every hit and is not an occlusion query).
use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::{BvhBuildParams, cwbvh::builder::build_cwbvh};
use std::time::Duration;

/// A primitive as the BVH sees it.
#[derive(Clone, Copy, Debug)]
pub enum Primitive {
    Triangle { v0: Vec3, v1: Vec3, v2: Vec3 },
    Sphere { center: Vec3, radius: f32 },
}

#[derive(Clone, Copy, Debug)]
enum Packed {
    Triangle { v0: Vec3A, e1: Vec3A, e2: Vec3A },
    Sphere { center: Vec3A, radius: f32 },
}

/// Closest intersection: the primitive's index in the order given to [`Accel::build`],
/// the distance and the barycentrics (b1, b2) of a triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub prim: u32,
    pub t: f32,
    pub b1: f32,
    pub b2: f32,
}

pub struct Accel {
    bvh: CwBvh,
    /// Primitives in BVH order, so the traversal closure indexes them directly.
    packed: Vec<Packed>,
    /// BVH slot → index in the caller's primitive list.
    ids: Vec<u32>,
}

/// Möller–Trumbore with (t, b1, b2); t = ∞ on a miss.
#[inline(always)]
fn intersect_triangle(v0: Vec3A, e1: Vec3A, e2: Vec3A, ray: &Ray) -> (f32, f32, f32) {
    let p = ray.direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let inv = 1.0 / det;
    let s = ray.origin - v0;
    let b1 = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&b1) {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let q = s.cross(e1);
    let b2 = ray.direction.dot(q) * inv;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return (f32::INFINITY, 0.0, 0.0);
    }
    let t = e2.dot(q) * inv;
    if t >= ray.tmin && t <= ray.tmax {
        (t, b1, b2)
    } else {
        (f32::INFINITY, 0.0, 0.0)
    }
}

/// Ray–sphere test in the numerically careful form (Haines et al., Ray Tracing Gems ch. 7):
/// the discriminant is r² − |perpendicular offset|², exact enough for radius 0.001 at distance 10.
#[inline(always)]
fn intersect_sphere(center: Vec3A, radius: f32, ray: &Ray) -> f32 {
    let f = ray.origin - center;
    let tca = -f.dot(ray.direction);
    let perp = f + ray.direction * tca;
    let h2 = radius * radius - perp.length_squared();
    if h2 < 0.0 {
        return f32::INFINITY;
    }
    let h = h2.sqrt();
    let t0 = tca - h;
    if t0 >= ray.tmin && t0 <= ray.tmax {
        return t0;
    }
    let t1 = tca + h;
    if t1 >= ray.tmin && t1 <= ray.tmax {
        t1
    } else {
        f32::INFINITY
    }
}

impl Packed {
    #[inline(always)]
    fn intersect(&self, ray: &Ray) -> f32 {
        match *self {
            Packed::Triangle { v0, e1, e2 } => intersect_triangle(v0, e1, e2, ray).0,
            Packed::Sphere { center, radius } => intersect_sphere(center, radius, ray),
        }
    }
}

/// obvhs picks the traversal order from the direction's sign bits but its inverse from
/// `1/x`: a −0.0 component makes them disagree and the ray misses. Adding +0.0 turns −0.0 into +0.0.
#[inline(always)]
fn positive_zeros(d: Vec3) -> Vec3 {
    d + Vec3::ZERO
}

impl Accel {
    pub fn build(prims: &[Primitive]) -> Accel {
        if prims.is_empty() {
            return Accel {
                bvh: CwBvh::default(),
                packed: Vec::new(),
                ids: Vec::new(),
            };
        }
        // obvhs finds nothing in a BVH of a single primitive: give it the same primitive twice.
        let doubled;
        let prims = if prims.len() == 1 {
            doubled = [prims[0], prims[0]];
            &doubled[..]
        } else {
            prims
        };
        let aabbs: Vec<Aabb> = prims
            .iter()
            .map(|p| match *p {
                Primitive::Triangle { v0, v1, v2 } => {
                    Aabb::from_points(&[v0.into(), v1.into(), v2.into()])
                }
                Primitive::Sphere { center, radius } => Aabb::new(
                    (center - Vec3::splat(radius)).into(),
                    (center + Vec3::splat(radius)).into(),
                ),
            })
            .collect();
        let bvh = build_cwbvh(
            &aabbs,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let ids: Vec<u32> = bvh.primitive_indices.clone();
        let packed = ids
            .iter()
            .map(|&i| match prims[i as usize] {
                Primitive::Triangle { v0, v1, v2 } => Packed::Triangle {
                    v0: v0.into(),
                    e1: (v1 - v0).into(),
                    e2: (v2 - v0).into(),
                },
                Primitive::Sphere { center, radius } => Packed::Sphere {
                    center: center.into(),
                    radius,
                },
            })
            .collect();
        Accel { bvh, packed, ids }
    }

    /// Closest hit with t in [tmin, tmax].
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        let dir = positive_zeros(dir);
        if self.packed.is_empty() {
            return None;
        }
        let ray = Ray::new(origin.into(), dir.into(), tmin, tmax);
        let mut hit = RayHit::none();
        let packed = &self.packed;
        if !self
            .bvh
            .ray_traverse(ray, &mut hit, |r, i| packed[i].intersect(r))
        {
            return None;
        }
        let slot = hit.primitive_id as usize;
        let (b1, b2) = match packed[slot] {
            Packed::Triangle { v0, e1, e2 } => {
                let r = Ray::new(origin.into(), dir.into(), tmin, f32::INFINITY);
                let (_, b1, b2) = intersect_triangle(v0, e1, e2, &r);
                (b1, b2)
            }
            Packed::Sphere { .. } => (0.0, 0.0),
        };
        Some(Hit {
            prim: self.ids[slot],
            t: hit.t,
            b1,
            b2,
        })
    }

    /// True when something lies on the segment t in [tmin, tmax].
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let dir = positive_zeros(dir);
        if self.packed.is_empty() {
            return false;
        }
        let ray = Ray::new(origin.into(), dir.into(), tmin, tmax);
        let packed = &self.packed;
        !self
            .bvh
            .ray_traverse_miss(ray, |r, i| packed[i].intersect(r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_hit_and_occlusion_agree_with_brute_force() {
        // A stack of parallel triangles and spheres along z; rays from below.
        let mut prims = Vec::new();
        for k in 0..20 {
            let z = k as f32;
            prims.push(Primitive::Triangle {
                v0: Vec3::new(-1.0, -1.0, z),
                v1: Vec3::new(3.0, -1.0, z),
                v2: Vec3::new(-1.0, 3.0, z),
            });
            prims.push(Primitive::Sphere {
                center: Vec3::new(5.0, 0.0, z),
                radius: 0.001,
            });
        }
        let accel = Accel::build(&prims);
        let h = accel
            .intersect(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, 0.0, f32::INFINITY)
            .unwrap();
        assert_eq!(h.prim, 0);
        assert!((h.t - 1.0).abs() < 1e-6);
        let h = accel
            .intersect(Vec3::new(0.0, 0.0, 2.5), Vec3::Z, 0.0, f32::INFINITY)
            .unwrap();
        assert_eq!(h.prim, 6, "triangle at z = 3");
        let s = accel
            .intersect(Vec3::new(5.0, 0.0005, 7.5), Vec3::Z, 0.0, f32::INFINITY)
            .unwrap();
        assert_eq!(s.prim, 17, "tiny sphere at z = 8");
        assert!((s.t - (0.5 - (1e-6f32 - 0.0005f32 * 0.0005).sqrt())).abs() < 1e-5);
        assert!(
            accel
                .intersect(Vec3::new(5.0, 0.0011, 7.5), Vec3::Z, 0.0, f32::INFINITY)
                .is_none()
        );
        assert!(accel.occluded(Vec3::new(0.0, 0.0, 2.5), Vec3::Z, 0.0, 1.0));
        assert!(!accel.occluded(Vec3::new(0.0, 0.0, 2.5), Vec3::Z, 0.0, 0.4));
        assert!(!accel.occluded(Vec3::new(0.0, 0.0, 30.0), Vec3::Z, 0.0, f32::INFINITY));
    }
}

#[cfg(test)]
mod edge_cases {
    use super::*;

    #[test]
    fn single_primitive_and_axis_aligned_rays_hit() {
        let h = 50.0;
        let p = [
            Vec3::new(-h, -h, 0.0),
            Vec3::new(h, -h, 0.0),
            Vec3::new(h, h, 0.0),
            Vec3::new(-h, h, 0.0),
        ];
        let two = [
            Primitive::Triangle {
                v0: p[0],
                v1: p[1],
                v2: p[2],
            },
            Primitive::Triangle {
                v0: p[0],
                v1: p[2],
                v2: p[3],
            },
        ];
        for prims in [&two[..1], &two[..]] {
            let a = Accel::build(prims);
            for dir in [
                -Vec3::Z,
                Vec3::new(-0.0, 0.0, -1.0),
                Vec3::new(0.01, 0.02, -1.0).normalize(),
            ] {
                let hit = a.intersect(Vec3::new(10.0, -20.0, 0.5), dir, 0.0, f32::INFINITY);
                assert!(
                    hit.is_some_and(|h| (h.t - 0.5).abs() < 1e-3),
                    "{} prims, {dir:?}",
                    prims.len()
                );
                assert!(a.occluded(Vec3::new(10.0, -20.0, 0.5), dir, 0.0, 1.0));
            }
        }
    }
}
