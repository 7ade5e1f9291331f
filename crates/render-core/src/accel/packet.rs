//! Leaf primitives four at a time: a packet holds four triangles (v0, e1 = v1 − v0,
//! e2 = v2 − v0) or four spheres in structure-of-arrays rows, tested together in four lanes.
//! Unused lanes hold NaN, which fails every comparison. Each lane repeats, operation for
//! operation, the scalar Möller–Trumbore and ray–sphere tests the obvhs-based traversal used,
//! so a hit's distance and barycentrics are those it reported.
use super::lanes::{F4, V4};
use glam::Vec3;

/// Four primitives of one kind, 160 bytes.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct Packet {
    /// Triangles: v0, e1, e2 (rows 0–2, 3–5, 6–8). Spheres: centre (rows 0–2) and radius (row 3).
    rows: [[f32; 4]; 9],
    /// The primitive of each lane, in the caller's numbering (unused lanes: u32::MAX).
    pub ids: [u32; 4],
}

/// A ray as the lanes read it: origin and direction splatted, the segment's start.
pub struct LaneRay {
    pub o: V4,
    pub d: V4,
    pub tmin: F4,
}

impl LaneRay {
    pub fn new(o: Vec3, d: Vec3, tmin: f32) -> LaneRay {
        LaneRay {
            o: V4::splat(o),
            d: V4::splat(d),
            tmin: F4::splat(tmin),
        }
    }
}

impl Packet {
    /// Up to four triangles (id, v0, v1, v2).
    pub fn triangles(tris: &[(u32, Vec3, Vec3, Vec3)]) -> Packet {
        debug_assert!(tris.len() <= 4);
        let mut p = Packet::empty();
        for (lane, &(id, v0, v1, v2)) in tris.iter().enumerate() {
            let (e1, e2) = (v1 - v0, v2 - v0);
            for (row, v) in [v0, e1, e2].iter().enumerate() {
                p.rows[3 * row][lane] = v.x;
                p.rows[3 * row + 1][lane] = v.y;
                p.rows[3 * row + 2][lane] = v.z;
            }
            p.ids[lane] = id;
        }
        p
    }

    /// Up to four spheres (id, centre, radius).
    pub fn spheres(spheres: &[(u32, Vec3, f32)]) -> Packet {
        debug_assert!(spheres.len() <= 4);
        let mut p = Packet::empty();
        for (lane, &(id, c, r)) in spheres.iter().enumerate() {
            p.rows[0][lane] = c.x;
            p.rows[1][lane] = c.y;
            p.rows[2][lane] = c.z;
            p.rows[3][lane] = r;
            p.ids[lane] = id;
        }
        p
    }

    fn empty() -> Packet {
        Packet {
            rows: [[f32::NAN; 4]; 9],
            ids: [u32::MAX; 4],
        }
    }

    #[inline(always)]
    fn v(&self, first_row: usize) -> V4 {
        V4 {
            x: F4::load(&self.rows[first_row]),
            y: F4::load(&self.rows[first_row + 1]),
            z: F4::load(&self.rows[first_row + 2]),
        }
    }

    /// Triangle lanes hit in [tmin, tmax] (bits 0–3), their distances and barycentrics.
    #[inline(always)]
    pub fn intersect_triangles(&self, r: &LaneRay, tmax: f32) -> (u32, F4, F4, F4) {
        let (v0, e1, e2) = (self.v(0), self.v(3), self.v(6));
        let p = r.d.cross(e2);
        let det = e1.dot(p);
        let zero = F4::splat(0.0);
        let one = F4::splat(1.0);
        let mut ok = det.ne(zero);
        let inv = one.div(det);
        let s = r.o.sub(v0);
        let b1 = s.dot(p).mul(inv);
        ok &= zero.le(b1) & b1.le(one);
        let q = s.cross(e1);
        let b2 = r.d.dot(q).mul(inv);
        // Not (b2 < 0 or b1 + b2 > 1): the scalar test's own form, NaN included.
        ok &= !(b2.lt(zero) | one.lt(b1.add(b2))) & 0xF;
        let t = e2.dot(q).mul(inv);
        ok &= r.tmin.le(t) & t.le(F4::splat(tmax));
        (ok, t, b1, b2)
    }

    /// Sphere lanes hit in [tmin, tmax] (bits 0–3) and their distances: the near root when it
    /// lies in the segment, else the far one.
    #[inline(always)]
    pub fn intersect_spheres(&self, r: &LaneRay, tmax: f32) -> (u32, F4) {
        let c = self.v(0);
        let radius = F4::load(&self.rows[3]);
        let f = r.o.sub(c);
        let tca = f.dot(r.d).neg();
        let perp = V4 {
            x: f.x.add(r.d.x.mul(tca)),
            y: f.y.add(r.d.y.mul(tca)),
            z: f.z.add(r.d.z.mul(tca)),
        };
        let h2 = radius.mul(radius).sub(perp.dot(perp));
        let real = F4::splat(0.0).le(h2);
        let h = h2.sqrt();
        let tmax = F4::splat(tmax);
        let t0 = tca.sub(h);
        let t1 = tca.add(h);
        let near = real & r.tmin.le(t0) & t0.le(tmax);
        let far = real & !near & r.tmin.le(t1) & t1.le(tmax);
        (near | far, t1.select(near, t0))
    }
}
