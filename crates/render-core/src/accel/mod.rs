//! Ray casting through our own eight-wide BVH over triangles and sphere lights, collapsed
//! from obvhs's binary build: children's float bounds side by side (`node`), primitives four
//! to a packet (`packet`), closest hit nearest child first and occlusion with an any-hit exit
//! (`traverse`), and streams of rays several at a time (`stream`). The node test runs on
//! AVX-512 or AVX2 when the CPU has it, on SSE2 otherwise; all give the same hits bit for bit
//! (see [`Simd`]).
mod coherent;
mod collapse;
mod isa;
mod lanes;
mod node;
mod node16;
pub use node::prefetch;
mod packet;
mod stream;
mod traverse;

#[cfg(test)]
mod coherent_tests;
#[cfg(test)]
mod simd_paths_tests;
#[cfg(test)]
mod stream_tests;

use collapse::Wide;
use glam::Vec3;
use obvhs::aabb::Aabb;
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2};
use std::time::Duration;

/// Most primitives in a leaf of obvhs's build.
const LEAF_PRIMS: u32 = 4;

/// A primitive as the BVH sees it.
#[derive(Clone, Copy, Debug)]
pub enum Primitive {
    Triangle { v0: Vec3, v1: Vec3, v2: Vec3 },
    Sphere { center: Vec3, radius: f32 },
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

/// The instruction set the node test runs on. All do the same float operations per lane in
/// the same order (none fused), so they return the same hits bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// Eight children's near and far slabs in one 16-lane pass (AVX-512F).
    Avx512,
    /// Eight children in one 8-lane pass.
    Avx2,
    /// Eight children in two 4-lane passes (SSE2 on x86-64, plain arrays elsewhere).
    Sse2,
}

impl Simd {
    /// Every path, the widest first.
    pub const ALL: [Simd; 3] = [Simd::Avx512, Simd::Avx2, Simd::Sse2];

    /// The best this CPU runs, as `is_x86_feature_detected!` finds it.
    pub fn detect() -> Simd {
        Simd::ALL
            .into_iter()
            .find(|s| s.available())
            .unwrap_or(Simd::Sse2)
    }

    /// Whether this CPU (and its OS) runs the path.
    pub fn available(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            match self {
                Simd::Avx512 => has!("avx512f") && has!("avx2"),
                Simd::Avx2 => has!("avx2"),
                Simd::Sse2 => true,
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self == Simd::Sse2
        }
    }

    /// The instruction set's usual name.
    pub fn name(self) -> &'static str {
        match self {
            Simd::Avx512 => "AVX-512",
            Simd::Avx2 => "AVX2",
            Simd::Sse2 => "SSE2",
        }
    }
}

/// The acceleration structure: a wide BVH over the scene's primitives.
pub struct Accel {
    /// `None` for a scene without primitives.
    wide: Option<Wide>,
    /// Stack entries a traversal needs.
    stack_need: usize,
    simd: Simd,
}

impl Accel {
    /// The BVH over `prims` (obvhs's binary build, collapsed to eight-wide nodes), traversed
    /// with [`Simd::detect`]'s instruction set.
    pub fn build(prims: &[Primitive]) -> Accel {
        let simd = Simd::detect();
        if prims.is_empty() {
            return Accel {
                wide: None,
                stack_need: 0,
                simd,
            };
        }
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
        let bvh2 = build_bvh2(
            &aabbs,
            BvhBuildParams {
                // One packet of four: a leaf costs one 4-lane test.
                max_prims_per_leaf: LEAF_PRIMS,
                ..BvhBuildParams::medium_build()
            },
            &mut Duration::default(),
        );
        let wide = collapse::collapse(&bvh2, prims);
        Accel {
            stack_need: traverse::stack_need(wide.depth),
            wide: Some(wide),
            simd,
        }
    }

    /// The instruction set traversals use.
    pub fn simd(&self) -> Simd {
        self.simd
    }

    /// Traverse with `simd` from now on; a path the CPU lacks is an error.
    pub fn set_simd(&mut self, simd: Simd) -> Result<(), String> {
        if !simd.available() {
            return Err(format!("this CPU has no {}", simd.name()));
        }
        self.simd = simd;
        Ok(())
    }

    /// Closest hit with t in [tmin, tmax).
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        let w = self.wide.as_ref()?;
        if !(origin.is_finite() && dir.is_finite()) {
            return None; // NaN distances would pass every box test and find nothing.
        }
        let dir = positive_zeros(dir);
        traverse::with_stack(self.stack_need, |stack| match self.simd {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `simd` names only a path the CPU has (`build`, `set_simd`).
            Simd::Avx512 => unsafe { isa::avx512::closest(w, origin, dir, tmin, tmax, stack) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Simd::Avx2 => unsafe { isa::avx2::closest(w, origin, dir, tmin, tmax, stack) },
            _ => traverse::closest::<node::Lanes4>(w, origin, dir, tmin, tmax, stack),
        })
    }

    /// True when something lies on the segment t in [tmin, tmax).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let Some(w) = self.wide.as_ref() else {
            return false;
        };
        if !(origin.is_finite() && dir.is_finite()) {
            return false;
        }
        let dir = positive_zeros(dir);
        traverse::with_stack(self.stack_need, |stack| match self.simd {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as in `intersect`.
            Simd::Avx512 => unsafe { isa::avx512::occluded(w, origin, dir, tmin, tmax, stack) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as in `intersect`.
            Simd::Avx2 => unsafe { isa::avx2::occluded(w, origin, dir, tmin, tmax, stack) },
            _ => traverse::occluded::<node::Lanes4>(w, origin, dir, tmin, tmax, stack),
        })
    }
}

/// A ray of a stream: the segment t in [tmin, tmax) of origin + t·dir.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamRay {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmin: f32,
    pub tmax: f32,
}

/// The batch traversal `$name` of `isa` on `$accel`'s path (its AVX-512 or AVX2 build), else
/// `$portable`: `$rays` answered into `$out`, which is filled with `$empty` for a scene without
/// primitives.
macro_rules! batch_on_path {
    ($accel:ident, ($rays:ident, $out:ident), $empty:expr, $name:ident, $portable:expr) => {{
        assert_eq!($rays.len(), $out.len(), "one answer per ray");
        let Some(w) = $accel.wide.as_ref() else {
            $out.fill($empty);
            return;
        };
        let need = $accel.stack_need;
        match $accel.simd {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `simd` names only a path the CPU has (`build`, `set_simd`).
            Simd::Avx512 => unsafe { isa::avx512::$name(w, need, $rays, $out) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Simd::Avx2 => unsafe { isa::avx2::$name(w, need, $rays, $out) },
            _ => $portable(w, need, $rays, $out),
        }
    }};
}

impl Accel {
    /// [`Accel::intersect`] of every ray of `rays`, into `hits` in the same order: the same
    /// hits bit for bit, whatever the stream's length. The rays' traversals are interleaved
    /// so that one ray's memory loads overlap the others' tests.
    pub fn intersect_stream(&self, rays: &[StreamRay], hits: &mut [Option<Hit>]) {
        batch_on_path!(self, (rays, hits), None, closest_stream, |w, need, r, h| {
            stream::closest_stream::<node::Lanes4>(w, need, stream::HOT_NODES, r, h)
        })
    }

    /// [`Accel::intersect`] of every ray of `rays`, into `hits` in the same order, for rays
    /// that travel together (a tile's camera rays): each run of eight consecutive rays shares
    /// one traversal (`coherent.rs`). The same hits bit for bit as one at a time, but at a
    /// tie whose box entry rounds beyond the hit (`traverse::leaf_closest`).
    pub fn intersect_packets(&self, rays: &[StreamRay], hits: &mut [Option<Hit>]) {
        batch_on_path!(
            self,
            (rays, hits),
            None,
            closest_packets,
            coherent::closest_packets::<node::Lanes4>
        )
    }

    /// [`Accel::occluded`] of every ray of `rays`, into `blocked` in the same order, the
    /// traversals interleaved as in [`Accel::intersect_stream`].
    pub fn occluded_stream(&self, rays: &[StreamRay], blocked: &mut [bool]) {
        batch_on_path!(
            self,
            (rays, blocked),
            false,
            occluded_stream,
            |w, need, r, b| {
                stream::occluded_stream::<node::Lanes4>(w, need, stream::HOT_NODES, r, b)
            }
        )
    }
}

/// The node test picks a box's near slab by the sign of 1/d: a −0.0 component would give −∞
/// and the far slab. Adding +0.0 turns −0.0 into +0.0.
#[inline(always)]
pub(crate) fn positive_zeros(d: Vec3) -> Vec3 {
    d + Vec3::ZERO
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
