//! pbrt shapes as object-space triangle meshes: `trianglemesh`, `bilinearmesh` (each patch as
//! two triangles), `disk` and non-emitting `sphere`s (tessellated; an emitting sphere becomes
//! a sphere light instead, see the parser), `plymesh` (see [`super::ply`]).
use super::params::ParamList;
use crate::builtin::mesh::Mesh;
use glam::{Vec2, Vec3};
use std::f32::consts::TAU;

/// Segments around a tessellated disk or sphere (and half as many rings on a sphere).
pub const SEGMENTS: usize = 64;

#[derive(Clone, Debug, Default)]
pub struct MeshData {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<u32>,
}

impl MeshData {
    fn from_mesh(m: Mesh) -> MeshData {
        MeshData {
            positions: m.positions,
            normals: Some(m.normals),
            uvs: Some(m.uvs),
            indices: m.indices,
        }
    }

    /// Winds each triangle counter-clockwise around its vertices' shading normals when the
    /// mesh has them (pbrt turns the geometric normal towards them, which decides the side an
    /// area light emits on), else reverses every triangle under `ReverseOrientation`.
    pub fn orient(&mut self, reverse: bool) {
        let p = &self.positions;
        for t in self.indices.chunks_exact_mut(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
            let flip = match &self.normals {
                Some(n) => {
                    let ng = (p[b] - p[a]).cross(p[c] - p[a]);
                    ng.dot(n[a] + n[b] + n[c]) < 0.0
                }
                None => reverse,
            };
            if flip {
                t.swap(1, 2);
            }
        }
    }
}

/// `Shape "trianglemesh"`: `point3 P`, `integer indices` (optional for a single triangle),
/// `normal N`, `point2 uv` (pbrt-v3: `float uv` or `float st`).
pub fn triangle_mesh(params: &ParamList) -> Result<MeshData, String> {
    let positions = params
        .points("P")?
        .ok_or("trianglemesh without \"point3 P\"")?;
    let indices = match params.indices("indices")? {
        Some(i) => i,
        None if positions.len() == 3 => vec![0, 1, 2],
        None => return Err("trianglemesh without \"integer indices\"".into()),
    };
    if indices.len() % 3 != 0 {
        return Err(format!(
            "trianglemesh: {} indices is not a multiple of 3",
            indices.len()
        ));
    }
    if let Some(i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
        return Err(format!(
            "trianglemesh: index {i} is past its {} vertices",
            positions.len()
        ));
    }
    let normals = per_vertex(params.points("N")?, positions.len(), "N")?;
    let uv = match params.uvs("uv")? {
        Some(uv) => Some(uv),
        None => params.uvs("st")?,
    };
    let uvs = per_vertex(uv, positions.len(), "uv")?;
    Ok(MeshData {
        positions,
        normals,
        uvs,
        indices,
    })
}

fn per_vertex<T>(v: Option<Vec<T>>, n: usize, name: &str) -> Result<Option<Vec<T>>, String> {
    match v {
        Some(v) if v.len() != n => Err(format!(
            "\"{name}\" has {} values for {n} vertices",
            v.len()
        )),
        v => Ok(v),
    }
}

/// `Shape "bilinearmesh"`: `point3 P`, `integer indices` (4 per patch: p00 p10 p01 p11; optional
/// for one patch), `normal N`, `point2 uv`. Each patch becomes the triangles (p00, p10, p11)
/// and (p00, p11, p01); a non-planar patch is approximated by them.
pub fn bilinear_mesh(params: &ParamList) -> Result<MeshData, String> {
    let positions = params
        .points("P")?
        .ok_or("bilinearmesh without \"point3 P\"")?;
    let quads = match params.indices("indices")? {
        Some(i) => i,
        None if positions.len() == 4 => vec![0, 1, 2, 3],
        None => return Err("bilinearmesh without \"integer indices\"".into()),
    };
    if quads.len() % 4 != 0 {
        return Err(format!(
            "bilinearmesh: {} indices is not a multiple of 4",
            quads.len()
        ));
    }
    if let Some(i) = quads.iter().find(|&&i| i as usize >= positions.len()) {
        return Err(format!(
            "bilinearmesh: index {i} is past its {} vertices",
            positions.len()
        ));
    }
    let indices = quads
        .chunks_exact(4)
        .flat_map(|q| [q[0], q[1], q[3], q[0], q[3], q[2]])
        .collect();
    let normals = per_vertex(params.points("N")?, positions.len(), "N")?;
    let uvs = per_vertex(params.uvs("uv")?, positions.len(), "uv")?;
    Ok(MeshData {
        positions,
        normals,
        uvs,
        indices,
    })
}

/// A full sphere of `radius` about the origin.
pub fn sphere(radius: f32) -> MeshData {
    MeshData::from_mesh(Mesh::uv_sphere(Vec3::ZERO, radius, SEGMENTS, SEGMENTS / 2))
}

/// `Shape "disk"`: radius `radius` at z = `height`, facing +z, as a fan of `SEGMENTS` triangles.
pub fn disk(radius: f32, height: f32) -> MeshData {
    let mut positions = vec![Vec3::new(0.0, 0.0, height)];
    let mut uvs = vec![Vec2::new(0.0, 0.0)];
    for k in 0..SEGMENTS {
        let phi = TAU * k as f32 / SEGMENTS as f32;
        positions.push(Vec3::new(radius * phi.cos(), radius * phi.sin(), height));
        uvs.push(Vec2::new(k as f32 / SEGMENTS as f32, 1.0));
    }
    let indices = (0..SEGMENTS as u32)
        .flat_map(|k| [0, 1 + k, 1 + (k + 1) % SEGMENTS as u32])
        .collect();
    MeshData {
        normals: Some(vec![Vec3::Z; positions.len()]),
        positions,
        uvs: Some(uvs),
        indices,
    }
}
