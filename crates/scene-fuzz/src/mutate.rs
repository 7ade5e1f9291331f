//! Mutations of a valid input, chosen by a seeded generator so that a case is reproduced from
//! (run seed, case index) alone. glTF inputs are mutated with their structure in view (numbers,
//! indices, accessor counts and strides, buffer lengths, NaN/Inf in the binary data, camera and
//! emission parameters, removed members) and then, sometimes, as raw bytes (flips, truncation,
//! GLB header and chunk lengths). Composition TOMLs get their numbers, words and paths replaced,
//! lines dropped or duplicated, and the same raw-byte mutations.
use crate::corpus::{GltfSeed, Kind, Seed, encode};
use rand::{Rng, RngExt};
use serde_json::Value;

/// Numbers at the edges: zero, negatives, powers of two around integer widths, huge, f32
/// overflow (1e39 reads as infinity), denormals.
const NUMBERS: [f64; 24] = [
    0.0,
    -1.0,
    1.0,
    2.0,
    3.0,
    7.0,
    255.0,
    65535.0,
    65536.0,
    2147483647.0,
    2147483648.0,
    4294967295.0,
    4294967296.0,
    9007199254740991.0,
    1e30,
    -1e30,
    1e39,
    -1e39,
    1e-40,
    0.5,
    -0.5,
    1e308,
    -3.0,
    100000.0,
];

/// Members whose value indexes another array of the document.
const INDEX_KEYS: [&str; 14] = [
    "buffer",
    "bufferView",
    "accessor",
    "indices",
    "material",
    "mesh",
    "camera",
    "node",
    "source",
    "sampler",
    "index",
    "light",
    "scene",
    "POSITION",
];

/// TOML literals to put where a number was.
const TOML_NUMBERS: [&str; 18] = [
    "nan",
    "inf",
    "-inf",
    "+nan",
    "0",
    "0.0",
    "-1",
    "-1.0",
    "1e30",
    "-1e30",
    "1e-45",
    "65536",
    "4294967296",
    "9223372036854775807",
    "99999999999999999999",
    "1e39",
    "[]",
    "\"x\"",
];

/// Paths a composition may point at instead of its glTF file.
const TOML_PATHS: [&str; 8] = [
    "missing.glb",
    ".",
    "..",
    "/dev/zero",
    "/dev/null",
    "case.toml",
    "",
    "placed.glb/../placed.glb",
];

/// A mutated input: its bytes and the mutations that made it.
pub struct Mutant {
    pub bytes: Vec<u8>,
    pub ops: Vec<String>,
}

pub fn mutate(seed: &Seed, rng: &mut impl Rng) -> Mutant {
    let mut ops = Vec::new();
    let mut bytes = match seed {
        Seed::Gltf { gltf, .. } | Seed::Glb { gltf, .. } => {
            let mut g = gltf.clone();
            for _ in 0..rng.random_range(1..=3) {
                ops.push(mutate_gltf(&mut g, rng));
            }
            encode(&g, seed.kind())
        }
        Seed::Toml { text, .. } => {
            let mut t = text.clone();
            for _ in 0..rng.random_range(1..=3) {
                ops.push(mutate_toml(&mut t, rng));
            }
            t.into_bytes()
        }
    };
    if rng.random_bool(0.3) {
        ops.push(mutate_bytes(&mut bytes, seed.kind(), rng));
    }
    Mutant { bytes, ops }
}

/// JSON pointers to every scalar of `v` (numbers, strings, booleans, nulls).
fn scalars(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                scalars(
                    x,
                    format!("{at}/{}", k.replace('~', "~0").replace('/', "~1")),
                    out,
                );
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                scalars(x, format!("{at}/{i}"), out);
            }
        }
        _ => out.push(at),
    }
}

fn pick<'a, T>(v: &'a [T], rng: &mut impl Rng) -> Option<&'a T> {
    (!v.is_empty()).then(|| &v[rng.random_range(0..v.len())])
}

fn number(x: f64) -> Value {
    if x.fract() == 0.0 && x.abs() < 9.3e18 {
        if x >= 0.0 {
            Value::from(x as u64)
        } else {
            Value::from(x as i64)
        }
    } else {
        serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
    }
}

fn mutate_gltf(g: &mut GltfSeed, rng: &mut impl Rng) -> String {
    let mut all = Vec::new();
    scalars(&g.doc, String::new(), &mut all);
    let numeric: Vec<&String> = all
        .iter()
        .filter(|p| g.doc.pointer(p).is_some_and(Value::is_number))
        .collect();
    let last_key = |p: &str| p.rsplit('/').next().unwrap_or("").to_string();
    match rng.random_range(0..9) {
        // any number → an edge value
        0 => {
            let Some(p) = pick(&numeric, rng) else {
                return "nothing".into();
            };
            let x = NUMBERS[rng.random_range(0..NUMBERS.len())];
            *g.doc.pointer_mut(p).expect("pointer") = number(x);
            format!("{p} = {x}")
        }
        // an index → out of range
        1 => {
            let idx: Vec<&&String> = numeric
                .iter()
                .filter(|p| {
                    let k = last_key(p);
                    INDEX_KEYS.contains(&k.as_str())
                        || p.contains("/children/")
                        || p.contains("/nodes/")
                        || k.starts_with("TEXCOORD")
                        || k == "NORMAL"
                })
                .collect();
            let Some(p) = pick(&idx, rng) else {
                return "nothing".into();
            };
            let x = *pick(&[7.0, 64.0, 65535.0, 4294967295.0, -1.0], rng).expect("non-empty");
            *g.doc.pointer_mut(p).expect("pointer") = number(x);
            format!("index {p} = {x}")
        }
        // accessor and buffer sizes that overrun
        2 => {
            let sizes: Vec<&&String> = numeric
                .iter()
                .filter(|p| {
                    matches!(
                        last_key(p).as_str(),
                        "count" | "byteOffset" | "byteStride" | "byteLength" | "componentType"
                    )
                })
                .collect();
            let Some(p) = pick(&sizes, rng) else {
                return "nothing".into();
            };
            let x = *pick(
                &[
                    0.0,
                    1.0,
                    4.0,
                    5.0,
                    13.0,
                    252.0,
                    256.0,
                    5120.0,
                    5125.0,
                    5126.0,
                    1e6,
                    2147483647.0,
                    4294967295.0,
                    9007199254740991.0,
                ],
                rng,
            )
            .expect("non-empty");
            *g.doc.pointer_mut(p).expect("pointer") = number(x);
            format!("size {p} = {x}")
        }
        // NaN / Inf / huge floats in the binary data
        3 | 4 => {
            if g.bin.len() < 4 {
                return "nothing".into();
            }
            let at = rng.random_range(0..g.bin.len() / 4) * 4;
            let x = *pick(
                &[
                    f32::NAN,
                    f32::INFINITY,
                    f32::NEG_INFINITY,
                    3e38,
                    -3e38,
                    1e-42,
                ],
                rng,
            )
            .expect("non-empty");
            g.bin[at..at + 4].copy_from_slice(&x.to_le_bytes());
            format!("bin[{at}] = {x}")
        }
        // camera, emission, light and transform parameters → edge values
        5 => {
            let params: Vec<&&String> = numeric
                .iter()
                .filter(|p| {
                    p.contains("/cameras/")
                        || p.contains("emissive")
                        || p.contains("/lights/")
                        || p.contains("/translation/")
                        || p.contains("/rotation/")
                        || p.contains("/scale/")
                        || p.contains("/matrix/")
                        || p.contains("extras")
                        || p.contains("Factor")
                })
                .collect();
            let Some(p) = pick(&params, rng) else {
                return "nothing".into();
            };
            let x =
                *pick(&[0.0, -1.0, 1e39, -1e39, 1e30, 1e-40, 1e6, -0.0], rng).expect("non-empty");
            *g.doc.pointer_mut(p).expect("pointer") = number(x);
            format!("param {p} = {x}")
        }
        // a member removed
        6 => {
            let Some(p) = pick(&all, rng) else {
                return "nothing".into();
            };
            let (parent, key) = p.rsplit_once('/').expect("pointers start with /");
            match g.doc.pointer_mut(parent) {
                Some(Value::Object(m)) => {
                    m.remove(key);
                }
                Some(Value::Array(a)) => {
                    if let Ok(i) = key.parse::<usize>()
                        && i < a.len()
                    {
                        a.remove(i);
                    }
                }
                _ => {}
            }
            format!("removed {p}")
        }
        // a value of the wrong type
        7 => {
            let Some(p) = pick(&all, rng) else {
                return "nothing".into();
            };
            let v = pick(
                &[
                    Value::Null,
                    Value::from("x"),
                    Value::from(true),
                    serde_json::json!([]),
                    serde_json::json!({}),
                ],
                rng,
            )
            .expect("non-empty")
            .clone();
            *g.doc.pointer_mut(p).expect("pointer") = v;
            format!("wrong type at {p}")
        }
        // node cycles and shared children
        _ => {
            let n = g.doc["nodes"].as_array().map_or(0, Vec::len);
            if n == 0 {
                return "nothing".into();
            }
            let a = rng.random_range(0..n);
            let b = rng.random_range(0..n);
            let node = &mut g.doc["nodes"][a];
            if !node["children"].is_array() {
                node["children"] = serde_json::json!([]);
            }
            node["children"]
                .as_array_mut()
                .expect("just made")
                .push(b.into());
            format!("node {a} gets child {b}")
        }
    }
}

/// Byte ranges of the TOML's numbers (outside strings and comments, roughly: enough here).
fn toml_numbers(t: &str) -> Vec<(usize, usize)> {
    let b = t.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let mut in_string = false;
    while i < b.len() {
        let c = b[i];
        if c == b'"' {
            in_string = !in_string;
        }
        let starts = !in_string
            && (c.is_ascii_digit() || c == b'-')
            && (i == 0 || matches!(b[i - 1], b' ' | b'[' | b'=' | b','));
        if starts {
            let j = i
                + 1
                + b[i + 1..]
                    .iter()
                    .take_while(|c| c.is_ascii_digit() || matches!(c, b'.' | b'e' | b'-' | b'+'))
                    .count();
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

fn mutate_toml(t: &mut String, rng: &mut impl Rng) -> String {
    match rng.random_range(0..6) {
        0 | 1 => {
            let nums = toml_numbers(t);
            let Some(&(a, b)) = pick(&nums, rng) else {
                return "nothing".into();
            };
            let lit = TOML_NUMBERS[rng.random_range(0..TOML_NUMBERS.len())];
            let old = t[a..b].to_string();
            t.replace_range(a..b, lit);
            format!("number {old} at {a} = {lit}")
        }
        2 => {
            let lines: Vec<&str> = t.lines().collect();
            let Some(k) = (!lines.is_empty()).then(|| rng.random_range(0..lines.len())) else {
                return "nothing".into();
            };
            let dup = rng.random_bool(0.5);
            let mut out: Vec<&str> = Vec::with_capacity(lines.len() + 1);
            for (i, l) in lines.iter().enumerate() {
                if i != k || dup {
                    out.push(l);
                }
                if i == k && dup {
                    out.push(l);
                }
            }
            *t = out.join("\n");
            format!("{} line {k}", if dup { "duplicated" } else { "dropped" })
        }
        3 => {
            let p = TOML_PATHS[rng.random_range(0..TOML_PATHS.len())];
            *t = t.replace("\"placed.glb\"", &format!("\"{p}\""));
            format!("path = {p:?}")
        }
        4 => {
            let words = [
                ("\"grid\"", "\"spiral\""),
                ("\"random\"", "\"ring\""),
                ("\"sphere\"", "\"quad\""),
                ("\"quad\"", "\"disk\""),
                ("[camera]", "[[camera]]"),
                ("[ground]", "[ground.x]"),
                ("eye = ", "eye_pos = "),
            ];
            let (from, to) = *pick(&words, rng).expect("non-empty");
            *t = t.replacen(from, to, 1);
            format!("{from} → {to}")
        }
        _ => {
            // an array with too few or too many values
            let Some(start) = t.find('[').filter(|&i| {
                t[i..].starts_with("[0")
                    || t[i..].starts_with("[1")
                    || t[i..].starts_with("[-")
                    || t[i..].starts_with("[2")
                    || t[i..].starts_with("[3")
                    || t[i..].starts_with("[4")
            }) else {
                return "nothing".into();
            };
            let end = t[start..].find(']').map(|e| start + e).unwrap_or(t.len());
            let lit = *pick(
                &["[1.0]", "[1.0, 2.0, 3.0, 4.0]", "[]", "[nan, nan, nan]"],
                rng,
            )
            .expect("non-empty");
            t.replace_range(start..(end + 1).min(t.len()), lit);
            format!("array at {start} = {lit}")
        }
    }
}

fn mutate_bytes(bytes: &mut Vec<u8>, kind: Kind, rng: &mut impl Rng) -> String {
    if bytes.is_empty() {
        return "nothing".into();
    }
    match rng.random_range(0..4) {
        0 => {
            let n = rng.random_range(1..=16);
            for _ in 0..n {
                let i = rng.random_range(0..bytes.len());
                bytes[i] ^= 1 << rng.random_range(0..8);
            }
            format!("{n} bit flips")
        }
        1 => {
            let n = rng.random_range(0..bytes.len());
            bytes.truncate(n);
            format!("truncated to {n}")
        }
        2 => {
            let i = rng.random_range(0..bytes.len());
            let junk: Vec<u8> = (0..rng.random_range(1..64)).map(|_| rng.random()).collect();
            let n = junk.len();
            bytes.splice(i..i, junk);
            format!("{n} random bytes at {i}")
        }
        _ if kind == Kind::Glb && bytes.len() >= 28 => {
            // header length (8), JSON chunk length (12), or BIN chunk length (after JSON)
            let json_len = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes")) as usize;
            let fields = [8usize, 12, 20 + json_len];
            let at = *pick(&fields, rng).expect("non-empty");
            let v = *pick(&[0u32, 1, 7, 0x7fff_ffff, u32::MAX, 1 << 30], rng).expect("non-empty");
            if at + 4 <= bytes.len() {
                bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
            format!("GLB length at {at} = {v}")
        }
        _ => {
            let i = rng.random_range(0..bytes.len());
            bytes[i] = *pick(&[0u8, 0xff, b'"', b'{', b'[', b'\n', b'\\'], rng).expect("non-empty");
            format!("byte {i} replaced")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_numbers_are_found_outside_strings() {
        let t = "a = 1.5\nb = [0.0, -2, 3e4]\nc = \"x1\"\n";
        let found: Vec<&str> = toml_numbers(t).iter().map(|&(a, b)| &t[a..b]).collect();
        assert_eq!(found, ["1.5", "0.0", "-2", "3e4"]);
    }
}
