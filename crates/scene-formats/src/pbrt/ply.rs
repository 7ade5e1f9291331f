//! PLY meshes (`Shape "plymesh"`), ASCII and binary, through the `ply-rs-bw` crate: vertex
//! positions, optional normals (`nx ny nz`) and texture coordinates (`u v`, `s t` or
//! `texture_u texture_v`), and faces (`vertex_indices` or `vertex_index`) of three or more
//! vertices, fanned into triangles (pbrt reads triangles and quads).
use super::shapes::MeshData;
use glam::{Vec2, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};
use std::io::BufReader;
use std::path::Path;

/// One PLY element of any kind; each property lands where its name says.
#[derive(Debug, Default)]
struct Element {
    p: [f32; 3],
    n: [f32; 3],
    uv: [f32; 2],
    has_n: bool,
    has_uv: bool,
    list: Vec<u32>,
    bad_index: bool,
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(x) => x as f64,
        Property::UChar(x) => x as f64,
        Property::Short(x) => x as f64,
        Property::UShort(x) => x as f64,
        Property::Int(x) => x as f64,
        Property::UInt(x) => x as f64,
        Property::Float(x) => x as f64,
        Property::Double(x) => x,
        _ => return None,
    })
}

fn list(p: Property) -> Option<(Vec<u32>, bool)> {
    fn conv<T: TryInto<u32>>(v: Vec<T>) -> (Vec<u32>, bool) {
        let mut bad = false;
        let out = v
            .into_iter()
            .map(|x| {
                x.try_into().unwrap_or_else(|_| {
                    bad = true;
                    0
                })
            })
            .collect();
        (out, bad)
    }
    Some(match p {
        Property::ListChar(v) => conv(v),
        Property::ListUChar(v) => conv(v),
        Property::ListShort(v) => conv(v),
        Property::ListUShort(v) => conv(v),
        Property::ListInt(v) => conv(v),
        Property::ListUInt(v) => conv(v),
        _ => return None,
    })
}

impl PropertyAccess for Element {
    fn new() -> Self {
        Element::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if let Some(x) = scalar(&property) {
            let x = x as f32;
            match name {
                "x" => self.p[0] = x,
                "y" => self.p[1] = x,
                "z" => self.p[2] = x,
                "nx" | "ny" | "nz" => {
                    self.n[(name.as_bytes()[1] - b'x') as usize] = x;
                    self.has_n = true;
                }
                "u" | "s" | "texture_u" | "texture_s" => {
                    self.uv[0] = x;
                    self.has_uv = true;
                }
                "v" | "t" | "texture_v" | "texture_t" => {
                    self.uv[1] = x;
                    self.has_uv = true;
                }
                _ => return PropertyAccessResult::Ignored,
            }
            return PropertyAccessResult::Set;
        }
        if name == "vertex_indices" || name == "vertex_index" {
            if let Some((l, bad)) = list(property) {
                self.list = l;
                self.bad_index |= bad;
                return PropertyAccessResult::Set;
            }
        }
        PropertyAccessResult::Ignored
    }
}

/// The PLY reader's message on one line. It nests its errors ("Couldn't read element line.
/// String: '…' Error: Couldn't parse element line. String: '…' Error: error at 1:1: expected
/// one of …"), each part on lines of its own and the quoted line with its newline: kept are
/// the outer part and the innermost error, without the grammar's list of the characters it
/// expected, whitespace collapsed.
fn one_line(e: &impl std::fmt::Display) -> String {
    let text = e.to_string().replace("\r\n'", "'").replace("\n'", "'");
    let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
    let text = match text.find(": expected one of") {
        Some(i) => &text[..i],
        None => &text,
    };
    match (text.find(" Error: "), text.rfind(" Error: ")) {
        (Some(first), Some(last)) if first != last => {
            format!("{}{}", &text[..first], &text[last..])
        }
        _ => text.to_string(),
    }
}

/// Reads a PLY file into an object-space mesh.
pub fn read(path: &Path) -> Result<MeshData, String> {
    let file =
        std::fs::File::open(path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    let mut reader = Reader::new(BufReader::with_capacity(1 << 18, file));
    let parser = Parser::<Element>::new();
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| format!("{}: malformed PLY header: {}", path.display(), one_line(&e)))?;
    let mut mesh = MeshData::default();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let (mut all_n, mut all_uv) = (true, true);
    for (name, def) in &header.elements {
        let elements = parser
            .read_payload_for_element(&mut reader, def, &header)
            .map_err(|e| {
                let e = one_line(&e);
                format!("{}: malformed PLY element `{name}`: {e}", path.display())
            })?;
        match name.as_str() {
            "vertex" => {
                mesh.positions.reserve(elements.len());
                for e in &elements {
                    mesh.positions.push(Vec3::from(e.p));
                    normals.push(Vec3::from(e.n));
                    uvs.push(Vec2::from(e.uv));
                    all_n &= e.has_n;
                    all_uv &= e.has_uv;
                }
            }
            "face" => {
                for e in &elements {
                    if e.bad_index {
                        return Err(format!("{}: negative face index", path.display()));
                    }
                    // fan: (0, k, k + 1)
                    for k in 1..e.list.len().saturating_sub(1) {
                        mesh.indices.extend([e.list[0], e.list[k], e.list[k + 1]]);
                    }
                }
            }
            _ => {}
        }
    }
    if mesh.positions.is_empty() {
        return Err(format!("{}: no vertices", path.display()));
    }
    if let Some(i) = mesh
        .indices
        .iter()
        .find(|&&i| i as usize >= mesh.positions.len())
    {
        return Err(format!(
            "{}: face index {i} is past its {} vertices",
            path.display(),
            mesh.positions.len()
        ));
    }
    if all_n {
        mesh.normals = Some(normals);
    }
    if all_uv {
        mesh.uvs = Some(uvs);
    }
    Ok(mesh)
}
