//! Rays in streams: a batch of shading points hands its rays to the accelerator together
//! ([`crate::accel::Accel::intersect_stream`], [`crate::accel::Accel::occluded_stream`]), which
//! may interleave their traversals; each answer is the one the single-ray call gives.
use crate::accel::{Accel, Hit, StreamRay};
use crate::scene::{Scene, SurfaceHit, ray_epsilon};
use glam::Vec3;

impl Scene {
    /// The segment [`Scene::occluded`] tests, as a ray of a stream.
    #[inline]
    pub fn shadow_ray(&self, origin: Vec3, dir: Vec3, dist: f32) -> StreamRay {
        StreamRay {
            origin,
            dir,
            tmin: 0.0,
            tmax: dist * (1.0 - 1e-4) - ray_epsilon(origin + dir * dist),
        }
    }

    /// Closest surfaces along a stream of rays ([`Scene::intersect`] of each, in order).
    pub fn intersect_stream(
        &self,
        rays: &[StreamRay],
        hits: &mut Vec<Option<Hit>>,
        out: &mut Vec<Option<SurfaceHit>>,
    ) {
        self.surfaces_along(rays, hits, out, Accel::intersect_stream);
    }

    /// [`Scene::intersect_stream`] for rays that travel together (a tile's camera rays):
    /// eight consecutive rays share a traversal ([`Accel::intersect_packets`]).
    pub fn intersect_packets(
        &self,
        rays: &[StreamRay],
        hits: &mut Vec<Option<Hit>>,
        out: &mut Vec<Option<SurfaceHit>>,
    ) {
        self.surfaces_along(rays, hits, out, Accel::intersect_packets);
    }

    /// The hits of `rays` by `trace`, then their surfaces.
    #[inline]
    fn surfaces_along(
        &self,
        rays: &[StreamRay],
        hits: &mut Vec<Option<Hit>>,
        out: &mut Vec<Option<SurfaceHit>>,
        trace: fn(&Accel, &[StreamRay], &mut [Option<Hit>]),
    ) {
        hits.clear();
        hits.resize(rays.len(), None);
        trace(&self.accel, rays, hits);
        // Every hit triangle's record starts loading before the first is read.
        for h in hits.iter().flatten() {
            if let Some(tri) = self.triangles.get(h.prim as usize) {
                crate::accel::prefetch(tri);
            }
        }
        out.clear();
        out.extend(
            rays.iter()
                .zip(hits.iter())
                .map(|(r, h)| h.as_ref().map(|h| self.surface(r.origin, r.dir, h))),
        );
    }

    /// Whether each shadow ray of `rays` is blocked ([`Scene::occluded`] of each, in order).
    pub fn occluded_stream(&self, rays: &[StreamRay], blocked: &mut Vec<bool>) {
        blocked.clear();
        blocked.resize(rays.len(), false);
        self.accel.occluded_stream(rays, blocked);
    }
}
