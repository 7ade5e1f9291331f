//! Mesh primitives: triangles, strips and fans (indexed or not) with their positions, normals
//! and uvs (under the material's texture transform); points and lines are counted and skipped.
use super::Loader;
use glam::{Mat4, Vec2, Vec3};
use render_core::error::SceneError;

impl Loader<'_> {
    /// Adds every triangle primitive of `mesh` under the node's world transform.
    pub(super) fn add_mesh(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: Mat4,
    ) -> Result<(), SceneError> {
        let mesh_name = mesh
            .name()
            .or(node.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("mesh {}", mesh.index()));
        for prim in mesh.primitives() {
            use gltf::mesh::Mode;
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.report.skipped_primitives += 1;
                self.builder.count_skipped_primitives(1);
                continue;
            }
            if prim.get(&gltf::Semantic::Positions).is_none() {
                self.report.skipped_primitives += 1;
                self.builder.count_skipped_primitives(1);
                continue;
            }
            let (material, uv_spec) = self.material(prim.material())?;
            if prim.get(&gltf::Semantic::Colors(0)).is_some() {
                self.report.warn("vertex colours (COLOR_0) ignored".into());
            }
            check_accessor_types(&prim)
                .map_err(|e| self.err(format!("mesh `{mesh_name}`: {e}")))?;
            let buffers = self.buffers;
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let positions: Vec<Vec3> = match reader.read_positions() {
                Some(it) => it.map(Vec3::from).collect(),
                None => {
                    return Err(self.err(format!(
                        "mesh `{mesh_name}`: POSITION accessor lies outside its buffer"
                    )));
                }
            };
            let normals: Option<Vec<Vec3>> = reader
                .read_normals()
                .map(|it| it.map(Vec3::from).collect::<Vec<_>>())
                .filter(|n| n.len() == positions.len());
            let mut uvs: Option<Vec<Vec2>> = reader
                .read_tex_coords(uv_spec.set)
                .map(|t| t.into_f32().map(Vec2::from).collect::<Vec<_>>())
                .filter(|t| t.len() == positions.len());
            if let (Some(uvs), Some((offset, rotation, scale))) = (uvs.as_mut(), uv_spec.transform)
            {
                let (s, c) = rotation.sin_cos();
                for uv in uvs.iter_mut() {
                    let (x, y) = (uv.x * scale[0], uv.y * scale[1]);
                    *uv = Vec2::new(c * x + s * y + offset[0], -s * x + c * y + offset[1]);
                }
            }
            let raw: Vec<u32> = match prim.indices() {
                Some(_) => match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => {
                        return Err(self.err(format!(
                            "mesh `{mesh_name}`: index accessor lies outside its buffer"
                        )));
                    }
                },
                None => (0..positions.len() as u32).collect(),
            };
            let indices = triangle_list(mode, &raw);
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(self.err(format!(
                    "mesh `{mesh_name}`: index {bad} is past its {} vertices",
                    positions.len()
                )));
            }
            self.report.primitives += 1;
            self.report.triangles += indices.len() / 3;
            self.builder.add_mesh(
                &mesh_name,
                &positions,
                normals.as_deref(),
                uvs.as_deref(),
                &indices,
                world,
                material,
            )?;
        }
        Ok(())
    }
}

/// Triangle-list indices from a primitive's indices in its drawing mode.
pub(super) fn triangle_list(mode: gltf::mesh::Mode, idx: &[u32]) -> Vec<u32> {
    use gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
            .flat_map(|i| {
                if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i + 1], idx[i], idx[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..idx.len().saturating_sub(1))
            .flat_map(|i| [idx[i], idx[i + 1], idx[0]])
            .collect(),
        _ => idx[..idx.len() / 3 * 3].to_vec(),
    }
}

/// The component types and shapes the gltf crate's readers assume of the accessors read here
/// (it panics on others): float VEC3 positions and normals, float or normalised-integer VEC2
/// uvs, unsigned-integer scalar indices.
pub(super) fn check_accessor_types(prim: &gltf::Primitive) -> Result<(), String> {
    use gltf::Semantic;
    use gltf::accessor::{DataType, Dimensions};
    let check = |what: &str, a: gltf::Accessor, types: &[DataType], dims: Dimensions| {
        let element = a.data_type().size() * a.dimensions().multiplicity();
        let stride = a.view().and_then(|v| v.stride()).unwrap_or(element);
        if stride < element {
            return Err(format!(
                "{what} accessor {}: byteStride {stride} is less than its {element}-byte elements",
                a.index()
            ));
        }
        if types.contains(&a.data_type()) && a.dimensions() == dims {
            Ok(())
        } else {
            Err(format!(
                "{what} accessor {} is {:?} {:?}, not {:?} of {types:?}",
                a.index(),
                a.data_type(),
                a.dimensions(),
                dims
            ))
        }
    };
    for (semantic, a) in prim.attributes() {
        match semantic {
            Semantic::Positions => check("POSITION", a, &[DataType::F32], Dimensions::Vec3)?,
            Semantic::Normals => check("NORMAL", a, &[DataType::F32], Dimensions::Vec3)?,
            Semantic::TexCoords(_) => check(
                "TEXCOORD",
                a,
                &[DataType::F32, DataType::U8, DataType::U16],
                Dimensions::Vec2,
            )?,
            _ => {}
        }
    }
    if let Some(a) = prim.indices() {
        let unsigned = [DataType::U8, DataType::U16, DataType::U32];
        check("index", a, &unsigned, Dimensions::Scalar)?;
    }
    Ok(())
}
