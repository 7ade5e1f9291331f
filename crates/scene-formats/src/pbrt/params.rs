//! A directive's parameter list, `"type name" [values]` (or a single value without brackets),
//! with typed look-ups that report a wrong type or count as an error and remember which
//! parameters were used, so that the ones a directive ignores can be reported.
use glam::{Vec2, Vec3};
use std::cell::Cell;

#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    Nums(Vec<f64>),
    Strs(Vec<String>),
    Bools(Vec<bool>),
}

#[derive(Debug)]
pub struct Param {
    /// The declared type: `float`, `integer`, `rgb`, `point3`, `string`, `texture`, `bool`, …
    pub ty: String,
    pub name: String,
    pub values: Values,
    pub line: usize,
    used: Cell<bool>,
}

/// Types whose values are numbers.
const NUMERIC: &[&str] = &[
    "integer",
    "float",
    "point",
    "point2",
    "point3",
    "vector",
    "vector2",
    "vector3",
    "normal",
    "normal3",
    "rgb",
    "color",
    "xyz",
    "blackbody",
    "spectrum",
];
const TEXTUAL: &[&str] = &["string", "texture", "spectrum"];

impl Param {
    /// Checks the declared type against the values read.
    pub fn new(decl: &str, values: Values, line: usize) -> Result<Param, String> {
        let mut parts = decl.split_whitespace();
        let (Some(ty), Some(name), None) = (parts.next(), parts.next(), parts.next()) else {
            return Err(format!(
                "malformed parameter declaration \"{decl}\" (want \"type name\")"
            ));
        };
        let ok = match &values {
            Values::Nums(_) => NUMERIC.contains(&ty),
            Values::Strs(_) => TEXTUAL.contains(&ty) || ty == "bool",
            Values::Bools(_) => ty == "bool",
        };
        if !NUMERIC.contains(&ty) && !TEXTUAL.contains(&ty) && ty != "bool" {
            return Err(format!("parameter \"{decl}\": unknown type `{ty}`"));
        }
        if !ok {
            let got = match &values {
                Values::Nums(_) => "numbers",
                Values::Strs(_) => "strings",
                Values::Bools(_) => "booleans",
            };
            return Err(format!("parameter \"{decl}\": a `{ty}` cannot hold {got}"));
        }
        let values = match values {
            // pbrt-v3 writes booleans as strings
            Values::Strs(s) if ty == "bool" => Values::Bools(
                s.iter()
                    .map(|v| match v.as_str() {
                        "true" => Ok(true),
                        "false" => Ok(false),
                        _ => Err(format!("parameter \"{decl}\": `{v}` is not true or false")),
                    })
                    .collect::<Result<_, _>>()?,
            ),
            v => v,
        };
        if ty == "integer" {
            if let Values::Nums(n) = &values {
                if let Some(x) = n.iter().find(|x| x.fract() != 0.0) {
                    return Err(format!("parameter \"{decl}\": {x} is not an integer"));
                }
            }
        }
        Ok(Param {
            ty: ty.into(),
            name: name.into(),
            values,
            line,
            used: Cell::new(false),
        })
    }
}

#[derive(Debug, Default)]
pub struct ParamList {
    pub params: Vec<Param>,
}

impl ParamList {
    fn find(&self, name: &str) -> Option<&Param> {
        let p = self.params.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// Marks a parameter as consumed without reading it (e.g. one we deliberately skip).
    pub fn touch(&self, name: &str) -> bool {
        self.find(name).is_some()
    }

    /// The parameters no look-up asked for.
    pub fn unused(&self) -> impl Iterator<Item = &Param> {
        self.params.iter().filter(|p| !p.used.get())
    }

    pub fn has(&self, name: &str) -> bool {
        self.params.iter().any(|p| p.name == name)
    }

    /// The parameter's type, when present.
    pub fn type_of(&self, name: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.ty.as_str())
    }

    /// All numbers of a numeric parameter.
    pub fn nums(&self, name: &str) -> Result<Option<&[f64]>, String> {
        let Some(p) = self.find(name) else {
            return Ok(None);
        };
        match &p.values {
            Values::Nums(n) => Ok(Some(n)),
            _ => Err(format!(
                "parameter `{name}` must be numeric, not `{}`",
                p.ty
            )),
        }
    }

    pub fn float(&self, name: &str, default: f32) -> Result<f32, String> {
        match self.nums(name)? {
            None => Ok(default),
            Some([x]) => Ok(*x as f32),
            Some(v) => Err(format!(
                "parameter `{name}`: want one value, got {}",
                v.len()
            )),
        }
    }

    pub fn int(&self, name: &str, default: i64) -> Result<i64, String> {
        Ok(self.float(name, default as f32)? as i64)
    }

    pub fn bool(&self, name: &str, default: bool) -> Result<bool, String> {
        let Some(p) = self.find(name) else {
            return Ok(default);
        };
        match &p.values {
            Values::Bools(b) if b.len() == 1 => Ok(b[0]),
            _ => Err(format!("parameter `{name}`: want one bool")),
        }
    }

    pub fn string(&self, name: &str) -> Result<Option<&str>, String> {
        let Some(p) = self.find(name) else {
            return Ok(None);
        };
        match &p.values {
            Values::Strs(s) if s.len() == 1 => Ok(Some(&s[0])),
            _ => Err(format!("parameter `{name}`: want one string")),
        }
    }

    /// Groups of `n` numbers (points, normals, uvs).
    pub fn tuples<const N: usize>(&self, name: &str) -> Result<Option<Vec<[f32; N]>>, String> {
        let Some(v) = self.nums(name)? else {
            return Ok(None);
        };
        if v.len() % N != 0 {
            return Err(format!(
                "parameter `{name}`: {} values is not a multiple of {N}",
                v.len()
            ));
        }
        Ok(Some(
            v.chunks_exact(N)
                .map(|c| std::array::from_fn(|i| c[i] as f32))
                .collect(),
        ))
    }

    pub fn points(&self, name: &str) -> Result<Option<Vec<Vec3>>, String> {
        Ok(self
            .tuples::<3>(name)?
            .map(|v| v.into_iter().map(Vec3::from).collect()))
    }

    pub fn point(&self, name: &str, default: Vec3) -> Result<Vec3, String> {
        match self.points(name)?.as_deref() {
            None => Ok(default),
            Some([p]) => Ok(*p),
            Some(_) => Err(format!("parameter `{name}`: want one point")),
        }
    }

    pub fn uvs(&self, name: &str) -> Result<Option<Vec<Vec2>>, String> {
        Ok(self
            .tuples::<2>(name)?
            .map(|v| v.into_iter().map(Vec2::from).collect()))
    }

    pub fn indices(&self, name: &str) -> Result<Option<Vec<u32>>, String> {
        let Some(v) = self.nums(name)? else {
            return Ok(None);
        };
        v.iter()
            .map(|&i| {
                if i >= 0.0 && i <= u32::MAX as f64 && i.fract() == 0.0 {
                    Ok(i as u32)
                } else {
                    Err(format!("parameter `{name}`: {i} is not a vertex index"))
                }
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }
}
