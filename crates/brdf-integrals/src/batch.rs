//! Batch evaluation: CSV rows `alpha,theta_o,cap_x,cap_y,cap_z,cap_cos` in, one value per row out
//! (∫_{C∩H} f·cos dω, θo in radians, ωo = (sin θo, 0, cos θo), the cap axis in the local frame
//! with z the normal, GGX α directly). Blank lines and lines starting with `#` are skipped, and so
//! is a first line that starts with `alpha` (a header). The cap axis is normalised.

use crate::{Cap, CapIntegral, Ltc, Reference, Sptd, ggx, reference};
use glam::Vec3;
use std::fmt;
use std::io::{BufRead, Write};
use std::str::FromStr;

/// Which integrator [`run_batch`] uses. Parsed case-insensitively from `sptd`, `ltc` or
/// `reference` (also `ref`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// [`Sptd::default`]: the committed SPTD table, default options.
    Sptd,
    /// [`Ltc::default`]: the committed LTC table, default options.
    Ltc,
    /// The reference integrator with [`Reference::default`] samples (2¹⁶ per row).
    Reference,
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "sptd" => Ok(Method::Sptd),
            "ltc" => Ok(Method::Ltc),
            "reference" | "ref" => Ok(Method::Reference),
            _ => Err(format!(
                "unknown method `{s}` (expected sptd, ltc or reference)"
            )),
        }
    }
}

/// Why [`run_batch`] stopped.
#[derive(Debug)]
pub enum BatchError {
    /// Reading the input or writing the output failed.
    Io(std::io::Error),
    /// A malformed row; `line` is 1-based.
    Parse {
        /// 1-based line number in the input (blank and comment lines count).
        line: usize,
        /// What is wrong with the row, naming the field.
        message: String,
    },
}

impl fmt::Display for BatchError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BatchError::Io(e) => write!(f, "I/O error: {e}"),
            BatchError::Parse { line, message } => write!(f, "line {line}: {message}"),
        }
    }
}

impl std::error::Error for BatchError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            BatchError::Io(e) => Some(e),
            BatchError::Parse { .. } => None,
        }
    }
}

impl From<std::io::Error> for BatchError {
    fn from(e: std::io::Error) -> Self {
        BatchError::Io(e)
    }
}

/// One parsed row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// GGX roughness α, in (0, 1].
    pub alpha: f32,
    /// View angle θo from the normal in radians, in [0, π/2]; ωo = (sin θo, 0, cos θo).
    pub theta_o: f32,
    /// The cap, in the local frame, with its axis normalised.
    pub cap: Cap,
}

const FIELDS: [&str; 6] = ["alpha", "theta_o", "cap_x", "cap_y", "cap_z", "cap_cos"];

/// Parses one data line `alpha,theta_o,cap_x,cap_y,cap_z,cap_cos` (1-based `line` for
/// messages). Checks ranges: α ∈ (0, 1], θo ∈ [0, π/2], a non-zero axis, cap_cos ∈ [−1, 1].
pub fn parse_row(text: &str, line: usize) -> Result<Row, BatchError> {
    let err = |message: String| BatchError::Parse { line, message };
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 6 {
        return Err(err(format!(
            "expected 6 comma-separated fields ({}), found {}",
            FIELDS.join(","),
            parts.len()
        )));
    }
    let mut v = [0f32; 6];
    for (k, p) in parts.iter().enumerate() {
        v[k] = p.parse::<f32>().map_err(|_| {
            err(format!(
                "field {} `{}`: `{p}` is not a number",
                k + 1,
                FIELDS[k]
            ))
        })?;
        if !v[k].is_finite() {
            return Err(err(format!(
                "field {} `{}` is not finite",
                k + 1,
                FIELDS[k]
            )));
        }
    }
    let [alpha, theta_o, x, y, z, c] = v;
    if !(alpha > 0.0 && alpha <= 1.0) {
        return Err(err(format!("alpha = {alpha} is outside (0, 1]")));
    }
    if !(0.0..=std::f32::consts::FRAC_PI_2).contains(&theta_o) {
        return Err(err(format!("theta_o = {theta_o} rad is outside [0, π/2]")));
    }
    let axis = Vec3::new(x, y, z);
    if axis.length_squared() < 1e-12 {
        return Err(err("the cap axis is zero".into()));
    }
    if !(-1.0..=1.0).contains(&c) {
        return Err(err(format!("cap_cos = {c} is outside [-1, 1]")));
    }
    Ok(Row {
        alpha,
        theta_o,
        cap: Cap::new(axis.normalize(), c),
    })
}

fn eval<M: CapIntegral>(m: &M, r: &Row) -> f32 {
    m.integral(
        ggx::wo_from_theta(r.theta_o),
        r.alpha,
        r.cap.axis,
        r.cap.cos_theta,
    )
}

/// Reads rows from `input`, writes one value per row to `output`. Stops at the first malformed
/// row (values of earlier rows have been written).
pub fn run_batch(
    method: Method,
    input: impl BufRead,
    mut output: impl Write,
) -> Result<(), BatchError> {
    let sptd = matches!(method, Method::Sptd).then(Sptd::default);
    let ltc = matches!(method, Method::Ltc).then(Ltc::default);
    let refm = Reference::default();
    let mut first_data = true;
    for (k, line) in input.lines().enumerate() {
        let line = line?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        if first_data && t.to_ascii_lowercase().starts_with("alpha") {
            first_data = false;
            continue;
        }
        first_data = false;
        let row = parse_row(t, k + 1)?;
        let v = match method {
            Method::Sptd => eval(sptd.as_ref().unwrap(), &row),
            Method::Ltc => eval(ltc.as_ref().unwrap(), &row),
            Method::Reference => {
                reference::cap_integral(
                    ggx::wo_from_theta(row.theta_o),
                    row.alpha,
                    &row.cap,
                    refm.samples,
                )
                .0
            }
        };
        writeln!(output, "{v}")?;
    }
    output.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(method: Method, input: &str) -> Result<String, BatchError> {
        let mut out = Vec::new();
        run_batch(method, input.as_bytes(), &mut out)?;
        Ok(String::from_utf8(out).unwrap())
    }

    #[test]
    fn values_one_per_row() {
        let input = "alpha,theta_o,cap_x,cap_y,cap_z,cap_cos\n0.2,0.5,0,0,1,0\n# comment\n\n0.2, 0.5, -0.4, 0, 0.9, 0.95\n";
        for m in [Method::Sptd, Method::Ltc] {
            let out = run(m, input).unwrap();
            let vals: Vec<f32> = out.lines().map(|l| l.parse().unwrap()).collect();
            assert_eq!(vals.len(), 2);
            assert!(
                vals[0] > 0.5 && vals[0] <= 1.0 && vals[1] > 0.0 && vals[1] < vals[0],
                "{vals:?}"
            );
        }
    }

    #[test]
    fn malformed_rows_report_line_numbers() {
        let cases = [
            ("0.2,0.5,0,0,1\n", 1, "expected 6"),
            ("0.2,0.5,0,0,1,0\n0.2,x,0,0,1,0\n", 2, "theta_o"),
            ("\n# c\n0.2,0.5,0,0,1,2\n", 3, "cap_cos"),
            ("0,0.5,0,0,1,0\n", 1, "alpha"),
            ("0.2,0.5,0,0,0,0\n", 1, "axis is zero"),
            ("0.2,2.0,0,0,1,0\n", 1, "theta_o"),
            ("0.2,0.5,0,0,1,NaN\n", 1, "not finite"),
        ];
        for (input, line, needle) in cases {
            match run(Method::Sptd, input) {
                Err(BatchError::Parse { line: l, message }) => {
                    assert_eq!(l, line, "{input:?}: {message}");
                    assert!(message.contains(needle), "{input:?}: {message}");
                }
                other => panic!("{input:?}: expected a parse error, got {other:?}"),
            }
        }
    }

    #[test]
    fn method_names() {
        assert_eq!("SPTD".parse::<Method>().unwrap(), Method::Sptd);
        assert_eq!("reference".parse::<Method>().unwrap(), Method::Reference);
        assert!("foo".parse::<Method>().is_err());
    }
}
