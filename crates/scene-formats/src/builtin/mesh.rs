//! Triangle-mesh helpers shared by the built-in scenes: quads, boxes (sharp and rounded),
//! UV spheres, cylinders, tori and tubes along curves. Every mesh has per-vertex normals and
//! counter-clockwise winding around its outward normal (the front face), and no degenerate
//! triangles.
use glam::{Mat4, Vec2, Vec3};
use render_core::error::SceneError;
use render_core::scene::SceneBuilder;
use std::f32::consts::{FRAC_PI_4, PI, TAU};

#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Appends `other` (as a separate part of the same mesh).
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.uvs.extend_from_slice(&other.uvs);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// The mesh under an affine transform (normals by the inverse transpose; winding kept
    /// counter-clockwise around the outward side when the transform mirrors).
    pub fn transformed(mut self, m: Mat4) -> Mesh {
        let nm = m.inverse().transpose();
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        for n in &mut self.normals {
            *n = nm.transform_vector3(*n).normalize_or_zero();
        }
        if m.determinant() < 0.0 {
            for t in self.indices.chunks_exact_mut(3) {
                t.swap(1, 2);
            }
        }
        self
    }

    /// Adds the mesh to a scene (world-space coordinates) with one material.
    pub fn add_to(
        &self,
        builder: &mut SceneBuilder,
        name: &str,
        material: u32,
    ) -> Result<(), SceneError> {
        builder.add_mesh(
            name,
            &self.positions,
            Some(&self.normals),
            Some(&self.uvs),
            &self.indices,
            Mat4::IDENTITY,
            material,
        )
    }

    /// A grid surface over (u, v) ∈ [0, 1]² with `nu` × `nv` cells; `f(u, v)` gives the point
    /// and its outward normal. Each triangle is wound counter-clockwise around the normals of
    /// its corners; zero-area triangles (at poles) are dropped.
    pub fn parametric(nu: usize, nv: usize, f: impl Fn(f32, f32) -> (Vec3, Vec3)) -> Mesh {
        let mut m = Mesh::default();
        for j in 0..=nv {
            for i in 0..=nu {
                let (u, v) = (i as f32 / nu as f32, j as f32 / nv as f32);
                let (p, n) = f(u, v);
                m.positions.push(p);
                m.normals.push(n.normalize_or_zero());
                m.uvs.push(Vec2::new(u, v));
            }
        }
        let id = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
        for j in 0..nv {
            for i in 0..nu {
                m.push_oriented([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                m.push_oriented([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        m
    }

    /// Pushes a triangle wound counter-clockwise around its vertex normals; drops it when it
    /// has no area.
    fn push_oriented(&mut self, t: [u32; 3]) {
        let p = t.map(|i| self.positions[i as usize]);
        let cross = (p[1] - p[0]).cross(p[2] - p[0]);
        let scale = p[0].abs().max_element().max(1.0);
        let area2 = cross.length();
        if area2.is_nan() || area2 <= 1e-9 * scale * scale {
            return;
        }
        let n: Vec3 = t.iter().map(|&i| self.normals[i as usize]).sum();
        if cross.dot(n) < 0.0 {
            self.indices.extend_from_slice(&[t[0], t[2], t[1]]);
        } else {
            self.indices.extend_from_slice(&t);
        }
    }

    /// A parallelogram centred at `center` spanning ±`u_half` and ±`v_half`; its front face
    /// (normal) is `u_half × v_half`.
    pub fn quad(center: Vec3, u_half: Vec3, v_half: Vec3) -> Mesh {
        let n = u_half.cross(v_half).normalize();
        let positions = vec![
            center - u_half - v_half,
            center + u_half - v_half,
            center + u_half + v_half,
            center - u_half + v_half,
        ];
        Mesh {
            positions,
            normals: vec![n; 4],
            uvs: vec![
                Vec2::new(0.0, 1.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(0.0, 0.0),
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
        }
    }

    /// A horizontal rectangle facing +y, `size_x` × `size_z`, centred at `center`.
    pub fn plane(center: Vec3, size_x: f32, size_z: f32) -> Mesh {
        Mesh::quad(
            center,
            Vec3::new(0.0, 0.0, 0.5 * size_z),
            Vec3::new(0.5 * size_x, 0.0, 0.0),
        )
    }

    /// An axis-aligned box with sharp edges (flat normals), faces outward.
    pub fn cuboid(min: Vec3, max: Vec3) -> Mesh {
        let c = 0.5 * (min + max);
        let h = 0.5 * (max - min);
        let mut m = Mesh::default();
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let mut n = Vec3::ZERO;
                n[axis] = sign;
                let mut a = Vec3::ZERO;
                a[(axis + 1) % 3] = h[(axis + 1) % 3];
                let mut b = Vec3::ZERO;
                b[(axis + 2) % 3] = h[(axis + 2) % 3];
                // a × b points along +axis; swap for the negative face.
                let q = if sign > 0.0 {
                    Mesh::quad(c + n * h[axis], a, b)
                } else {
                    Mesh::quad(c + n * h[axis], b, a)
                };
                m.append(&q);
            }
        }
        m
    }

    /// A box of half-extents `half` with edges and corners rounded to `radius`
    /// (`steps` segments per 45° of rounding), smooth normals.
    pub fn rounded_box(center: Vec3, half: Vec3, radius: f32, steps: usize) -> Mesh {
        let r = radius.clamp(1e-4, half.min_element());
        let inner = half - Vec3::splat(r);
        let steps = steps.max(1);
        // Face coordinates along one axis: the rounded band at each end is sampled so that the
        // projected points are evenly spaced in angle; the flat middle gets two cells.
        let coords = |h_in: f32| -> Vec<f32> {
            let mut v: Vec<f32> = (1..=steps)
                .rev()
                .map(|i| -h_in - r * (FRAC_PI_4 * i as f32 / steps as f32).tan())
                .collect();
            if h_in > 1e-6 {
                v.extend_from_slice(&[-h_in, 0.0, h_in]);
            } else {
                v.push(0.0);
            }
            v.extend((1..=steps).map(|i| h_in + r * (FRAC_PI_4 * i as f32 / steps as f32).tan()));
            v
        };
        let mut m = Mesh::default();
        for axis in 0..3 {
            let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
            let (c1, c2) = (coords(inner[a1]), coords(inner[a2]));
            for sign in [-1.0f32, 1.0] {
                let face = Mesh::parametric(c1.len() - 1, c2.len() - 1, |u, v| {
                    let i = (u * (c1.len() - 1) as f32).round() as usize;
                    let j = (v * (c2.len() - 1) as f32).round() as usize;
                    let mut q = Vec3::ZERO;
                    q[axis] = sign * half[axis];
                    q[a1] = c1[i];
                    q[a2] = c2[j];
                    let clamped = q.clamp(-inner, inner);
                    let n = (q - clamped).normalize();
                    (center + clamped + n * r, n)
                });
                m.append(&face);
            }
        }
        m
    }

    /// A UV sphere with `segments` around and `rings` from pole to pole.
    pub fn uv_sphere(center: Vec3, radius: f32, segments: usize, rings: usize) -> Mesh {
        Mesh::parametric(segments, rings, |u, v| {
            let (phi, theta) = (u * TAU, v * PI);
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            (center + n * radius, n)
        })
    }

    /// An icosphere: the regular icosahedron with each face split into 4^`subdivisions`
    /// triangles, vertices pushed onto the sphere (20·4^s triangles, flat normals so every
    /// triangle is a planar emitter that faces outward).
    pub fn icosphere(center: Vec3, radius: f32, subdivisions: u32) -> Mesh {
        let t = (1.0 + 5f32.sqrt()) / 2.0;
        let mut corners: Vec<Vec3> = [
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ]
        .iter()
        .map(|c| Vec3::from(*c).normalize())
        .collect();
        let mut faces: Vec<[usize; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..subdivisions {
            // Midpoints are shared by the two faces of an edge, keyed by the sorted edge.
            let mut midpoints = std::collections::HashMap::new();
            let mut mid = |a: usize, b: usize, corners: &mut Vec<Vec3>| -> usize {
                *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    corners.push((corners[a] + corners[b]).normalize());
                    corners.len() - 1
                })
            };
            let mut next = Vec::with_capacity(faces.len() * 4);
            for [a, b, c] in faces {
                let ab = mid(a, b, &mut corners);
                let bc = mid(b, c, &mut corners);
                let ca = mid(c, a, &mut corners);
                next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            faces = next;
        }
        // Flat shading: three vertices of its own per face, normal = the face's direction.
        let mut m = Mesh::default();
        for f in faces {
            let p = f.map(|i| center + corners[i] * radius);
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
            let base = m.positions.len() as u32;
            m.positions.extend_from_slice(&p);
            m.normals.extend_from_slice(&[n; 3]);
            m.uvs.extend_from_slice(&[Vec2::ZERO; 3]);
            m.indices.extend_from_slice(&[base, base + 1, base + 2]);
        }
        m
    }

    /// A cylinder of `radius` from `base` along the unit `axis` for `height`, with flat caps
    /// when `caps` is set.
    pub fn cylinder(
        base: Vec3,
        axis: Vec3,
        radius: f32,
        height: f32,
        segments: usize,
        caps: bool,
    ) -> Mesh {
        let axis = axis.normalize();
        let (t, b) = axis.any_orthonormal_pair();
        let mut m = Mesh::parametric(segments, 1, |u, v| {
            let phi = u * TAU;
            let n = t * phi.cos() + b * phi.sin();
            (base + n * radius + axis * (v * height), n)
        });
        if caps {
            for (c, n) in [(base, -axis), (base + axis * height, axis)] {
                let cap = Mesh::parametric(segments, 1, |u, v| {
                    let phi = u * TAU;
                    (c + (t * phi.cos() + b * phi.sin()) * (radius * v), n)
                });
                m.append(&cap);
            }
        }
        m
    }

    /// A torus around the y axis through `center`: ring radius `major`, tube radius `minor`.
    pub fn torus(center: Vec3, major: f32, minor: f32, segments: usize, sides: usize) -> Mesh {
        Mesh::parametric(segments, sides, |u, v| {
            let (phi, psi) = (u * TAU, v * TAU);
            let radial = Vec3::new(phi.cos(), 0.0, phi.sin());
            let n = radial * psi.cos() + Vec3::Y * psi.sin();
            (center + radial * major + n * minor, n)
        })
    }

    /// A closed tube around the closed curve `curve(s)`, s ∈ [0, 1], with radius
    /// `radius(s, angle)`. Normals are computed from the surface by finite differences, so a
    /// varying radius (bumps, ridges) shades correctly. The frame around the curve uses the
    /// direction away from the y axis, so the curve must keep away from that axis.
    pub fn tube(
        curve: impl Fn(f32) -> Vec3,
        radius: impl Fn(f32, f32) -> f32,
        along: usize,
        around: usize,
    ) -> Mesh {
        let surface = |s: f32, a: f32| -> Vec3 {
            let p = curve(s);
            let e = 1e-3;
            let tangent = (curve(s + e) - curve(s - e)).normalize();
            let out = Vec3::new(p.x, 0.0, p.z).normalize_or(Vec3::X);
            let n1 = (out - tangent * out.dot(tangent)).normalize();
            let n2 = tangent.cross(n1);
            let angle = a * TAU;
            p + (n1 * angle.cos() + n2 * angle.sin()) * radius(s, angle)
        };
        Mesh::parametric(along, around, |u, v| {
            let p = surface(u, v);
            let (du, dv) = (0.5 / along as f32, 0.5 / around as f32);
            let tu = surface(u + du, v) - surface(u - du, v);
            let tv = surface(u, v + dv) - surface(u, v - dv);
            let mut n = tu.cross(tv).normalize_or_zero();
            // Outward: away from the curve.
            if n.dot(p - curve(u)) < 0.0 {
                n = -n;
            }
            (p, n)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sum of signed volumes: positive when every face winds counter-clockwise outward.
    fn signed_volume(m: &Mesh) -> f32 {
        m.indices
            .chunks_exact(3)
            .map(|t| {
                m.positions[t[0] as usize]
                    .dot(m.positions[t[1] as usize].cross(m.positions[t[2] as usize]))
                    / 6.0
            })
            .sum()
    }

    fn normals_agree(m: &Mesh) -> bool {
        m.indices.chunks_exact(3).all(|t| {
            let p = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
            let ng = (p[1] - p[0]).cross(p[2] - p[0]);
            let n: Vec3 = t.iter().map(|&i| m.normals[i as usize]).sum();
            ng.dot(n) > 0.0
        })
    }

    #[test]
    fn closed_meshes_enclose_their_volume_outward() {
        let cube = Mesh::cuboid(Vec3::splat(-1.0), Vec3::splat(1.0));
        assert!((signed_volume(&cube) - 8.0).abs() < 1e-4);
        let sphere = Mesh::uv_sphere(Vec3::ZERO, 1.0, 64, 32);
        let v = signed_volume(&sphere);
        assert!((v - 4.0 / 3.0 * PI).abs() < 0.02 * v, "{v}");
        let rb = Mesh::rounded_box(Vec3::ZERO, Vec3::new(1.0, 0.5, 0.75), 0.2, 4);
        // Minkowski sum of the inner box (x, y, z) and a ball of radius r.
        let (x, y, z, r) = (1.6f32, 0.6f32, 1.1f32, 0.2f32);
        let exact = x * y * z
            + 2.0 * (x * y + y * z + z * x) * r
            + PI * (x + y + z) * r * r
            + 4.0 / 3.0 * PI * r * r * r;
        assert!(
            (signed_volume(&rb) - exact).abs() < 0.01,
            "{} vs {exact}",
            signed_volume(&rb)
        );
        let cyl = Mesh::cylinder(Vec3::ZERO, Vec3::Y, 0.5, 2.0, 64, true);
        assert!((signed_volume(&cyl) - PI * 0.25 * 2.0).abs() < 0.01);
        let torus = Mesh::torus(Vec3::ZERO, 1.0, 0.25, 64, 32);
        assert!((signed_volume(&torus) - 2.0 * PI * PI * 0.0625).abs() < 0.02);
        for m in [&cube, &sphere, &rb, &cyl, &torus] {
            assert!(normals_agree(m));
        }
        let mirrored = sphere
            .clone()
            .transformed(Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)));
        assert!(signed_volume(&mirrored) > 0.0 && normals_agree(&mirrored));
    }

    #[test]
    fn icosphere_is_closed_outward_and_round() {
        for s in 0..3u32 {
            let m = Mesh::icosphere(Vec3::new(1.0, 2.0, 3.0), 0.5, s);
            assert_eq!(m.triangle_count(), 20 * 4usize.pow(s));
            assert!(normals_agree(&m));
            let moved = m
                .clone()
                .transformed(Mat4::from_translation(-Vec3::new(1.0, 2.0, 3.0)));
            let v = signed_volume(&moved);
            let ball = 4.0 / 3.0 * PI * 0.125;
            // Inscribed polyhedra: 61 % of the ball at s = 0, closer with each subdivision.
            assert!(v > 0.6 * ball && v < ball, "s = {s}: {v} vs {ball}");
            for p in &moved.positions {
                assert!((p.length() - 0.5).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn tube_around_a_circle_is_a_torus() {
        let m = Mesh::tube(
            |s| Vec3::new((s * TAU).cos(), 0.0, (s * TAU).sin()) * 2.0,
            |_, _| 0.25,
            128,
            24,
        );
        let v = signed_volume(&m);
        let exact = 2.0 * PI * PI * 2.0 * 0.0625;
        assert!((v - exact).abs() < 0.02 * exact, "{v} vs {exact}");
        assert!(normals_agree(&m));
    }

    #[test]
    fn quad_faces_along_u_cross_v() {
        let q = Mesh::quad(Vec3::ZERO, Vec3::X, Vec3::Z);
        let p = &q.positions;
        let ng = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        assert!((ng - Vec3::X.cross(Vec3::Z)).length() < 1e-6);
        let pl = Mesh::plane(Vec3::ZERO, 2.0, 3.0);
        let p = &pl.positions;
        assert!(((p[1] - p[0]).cross(p[2] - p[0]).normalize() - Vec3::Y).length() < 1e-6);
    }
}
