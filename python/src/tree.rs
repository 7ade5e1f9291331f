//! `light-tree`'s light BVH and the BRDF-oriented selection of `samplers` on the caller's own
//! lights, vectorised: one call answers every query of the arrays given (over threads, the GIL
//! released), as `crates/embedding-example` drives them from raw inputs.
use crate::{f32_bytes, read_buffer, value_error};
use brdf_integrals::{CapIntegral, Sptd};
use glam::Vec3;
use light_tree::LightBounds;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use rayon::prelude::*;
use render_core::frame::Frame;
use samplers::brdf_oriented::importance::BoRecord;
use samplers::brdf_oriented::technique::BoState;

/// A light tree over the caller's light bounds.
#[pyclass(frozen, module = "manylights._native")]
pub struct LightTree {
    tree: light_tree::LightTree,
    lights: usize,
}

/// `m` points of three floats from a buffer.
fn points(obj: &Bound<'_, PyAny>, m: usize, what: &str) -> PyResult<Vec<Vec3>> {
    Ok(read_buffer::<f32>(obj, Some(3 * m), what)?
        .chunks_exact(3)
        .map(Vec3::from_slice)
        .collect())
}

/// Shading points: positions, unit normals and, for the BO selection, GGX lobes.
struct Points {
    x: Vec<Vec3>,
    n: Vec<Vec3>,
}

impl Points {
    fn read(x: &Bound<'_, PyAny>, n: &Bound<'_, PyAny>, m: usize) -> PyResult<Points> {
        let (x, n) = (points(x, m, "x")?, points(n, m, "n")?);
        let bad = |i: usize| !x[i].is_finite() || !(n[i].is_finite() && n[i].length() > 0.0);
        if let Some(i) = (0..m).find(|&i| bad(i)) {
            return Err(value_error(format!(
                "point {i}: x must be finite and n a finite non-zero vector"
            )));
        }
        let n = n.into_iter().map(Vec3::normalize).collect();
        Ok(Points { x, n })
    }
}

/// A BO query's shading: view direction, GGX α, glossy and diffuse weights per point.
struct Lobes {
    wo: Vec<Vec3>,
    alpha: Vec<f32>,
    ks: Vec<f32>,
    kd: Vec<f32>,
}

/// 64 random bits after `state` (SplitMix64): the numbers of one BO selection, from one seed.
fn split_mix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl LightTree {
    fn check_lights(&self, lights: &[i64]) -> PyResult<()> {
        match lights.iter().find(|&&l| l < 0 || l as usize >= self.lights) {
            Some(l) => Err(value_error(format!(
                "light {l} is not one of the tree's {} lights",
                self.lights
            ))),
            None => Ok(()),
        }
    }

    /// The BO state of point `i`: its record and cut.
    fn bo_state(
        &self,
        p: &Points,
        l: &Lobes,
        i: usize,
        cut: (f32, usize),
    ) -> BoState<'static, <Sptd as CapIntegral>::Lobe> {
        let frame = Frame::from_normal_and_direction(p.n[i], l.wo[i]);
        let lobe = Sptd::default().lobe(frame.to_local(l.wo[i]), l.alpha[i]);
        let rec = BoRecord::from_parts(p.x[i], frame, lobe, l.ks[i], l.kd[i], true, false);
        BoState::new(&self.tree, rec, cut.0, cut.1, None)
    }
}

#[allow(clippy::too_many_arguments)]
#[pymethods]
impl LightTree {
    /// Builds the tree (SAOH) from per-light arrays: box corners and cone axes (`n` × 3),
    /// θo, θe and power (`n`), two-sidedness (`n` bytes); see `light_tree::LightBounds`.
    #[new]
    fn new(
        py: Python<'_>,
        aabb_min: &Bound<'_, PyAny>,
        aabb_max: &Bound<'_, PyAny>,
        axis: &Bound<'_, PyAny>,
        theta_o: &Bound<'_, PyAny>,
        theta_e: &Bound<'_, PyAny>,
        power: &Bound<'_, PyAny>,
        two_sided: &Bound<'_, PyAny>,
    ) -> PyResult<LightTree> {
        let n = read_buffer::<f32>(power, None, "power")?.len();
        let (lo, hi, ax) = (
            points(aabb_min, n, "aabb_min")?,
            points(aabb_max, n, "aabb_max")?,
            points(axis, n, "axis")?,
        );
        let (to, te) = (
            read_buffer::<f32>(theta_o, Some(n), "theta_o")?,
            read_buffer::<f32>(theta_e, Some(n), "theta_e")?,
        );
        let (pw, ts) = (
            read_buffer::<f32>(power, Some(n), "power")?,
            read_buffer::<u8>(two_sided, Some(n), "two_sided")?,
        );
        let bounds: Vec<LightBounds> = (0..n)
            .map(|i| LightBounds {
                aabb_min: lo[i],
                aabb_max: hi[i],
                axis: ax[i],
                theta_o: to[i],
                theta_e: te[i],
                power: pw[i],
                two_sided: ts[i] != 0,
            })
            .collect();
        let tree = py
            .detach(|| light_tree::LightTree::build(&bounds))
            .map_err(value_error)?;
        Ok(LightTree { tree, lights: n })
    }

    fn __len__(&self) -> usize {
        self.lights
    }

    /// One light per point `(x, n)` by the tree's stochastic descent with the 64 random bits
    /// `u`: `(lights as int64 bytes, −1 where none can reach x; pmfs as float32 bytes)`.
    fn sample<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        n: &Bound<'py, PyAny>,
        u: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyBytes>)> {
        let u = read_buffer::<u64>(u, None, "u")?;
        let p = Points::read(x, n, u.len())?;
        let picks: Vec<(i64, f32)> = py.detach(|| {
            (0..u.len())
                .into_par_iter()
                .map(|i| match self.tree.sample(p.x[i], p.n[i], u[i]) {
                    Some((l, pmf)) => (l as i64, pmf),
                    None => (-1, 0.0),
                })
                .collect()
        });
        Ok(picks_bytes(py, &picks))
    }

    /// The probability that `sample` at `(x, n)` returns `light`, per point: float32 bytes.
    fn pmf<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        n: &Bound<'py, PyAny>,
        light: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let lights = read_buffer::<i64>(light, None, "light")?;
        self.check_lights(&lights)?;
        let p = Points::read(x, n, lights.len())?;
        let pmf: Vec<f32> = py.detach(|| {
            (0..lights.len())
                .into_par_iter()
                .map(|i| self.tree.pmf(p.x[i], p.n[i], lights[i] as usize))
                .collect()
        });
        Ok(f32_bytes(py, pmf.into_iter()))
    }

    /// BRDF-oriented selection (Liu et al. 2019) at shading points given by position, normal,
    /// view direction `wo`, GGX `alpha` and the luminances of the glossy (`ks`) and diffuse (`kd`)
    /// weights; the BO cut splits while the cap integral exceeds `delta`, to at most `max_cut`
    /// clusters. `seed`: 64 bits per point, the start of that point's random numbers.
    fn bo_sample<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        n: &Bound<'py, PyAny>,
        shading: Shading<'py>,
        seed: &Bound<'py, PyAny>,
        delta: f32,
        max_cut: usize,
    ) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyBytes>)> {
        let seeds = read_buffer::<u64>(seed, None, "seed")?;
        let m = seeds.len();
        let (p, l) = (Points::read(x, n, m)?, read_lobes(&shading, m)?);
        check_cut(delta, max_cut)?;
        let picks: Vec<(i64, f32)> = py.detach(|| {
            (0..m)
                .into_par_iter()
                .map(|i| {
                    let state = self.bo_state(&p, &l, i, (delta, max_cut));
                    let mut s = seeds[i];
                    let u_cluster = (split_mix(&mut s) >> 40) as f32 / (1u64 << 24) as f32;
                    match state.select_from(&self.tree, u_cluster, || split_mix(&mut s)) {
                        Some((light, pmf)) => (light as i64, pmf),
                        None => (-1, 0.0),
                    }
                })
                .collect()
        });
        Ok(picks_bytes(py, &picks))
    }

    /// The probability that `bo_sample` with the same shading returns `light`: float32 bytes.
    fn bo_pmf<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        n: &Bound<'py, PyAny>,
        shading: Shading<'py>,
        light: &Bound<'py, PyAny>,
        delta: f32,
        max_cut: usize,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let lights = read_buffer::<i64>(light, None, "light")?;
        self.check_lights(&lights)?;
        let m = lights.len();
        let (p, l) = (Points::read(x, n, m)?, read_lobes(&shading, m)?);
        check_cut(delta, max_cut)?;
        let pmf: Vec<f32> = py.detach(|| {
            (0..m)
                .into_par_iter()
                .map(|i| {
                    let state = self.bo_state(&p, &l, i, (delta, max_cut));
                    state.selection_pmf(&self.tree, lights[i] as usize)
                })
                .collect()
        });
        Ok(f32_bytes(py, pmf.into_iter()))
    }
}

type Shading<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
);

fn read_lobes(s: &Shading<'_>, m: usize) -> PyResult<Lobes> {
    let wo: Vec<Vec3> = points(&s.0, m, "wo")?;
    let alpha = read_buffer::<f32>(&s.1, Some(m), "alpha")?;
    let ks = read_buffer::<f32>(&s.2, Some(m), "ks")?;
    let kd = read_buffer::<f32>(&s.3, Some(m), "kd")?;
    if let Some(i) = (0..m).find(|&i| {
        !(wo[i].length() > 0.0 && wo[i].is_finite())
            || !(alpha[i] > 0.0 && alpha[i] <= 1.0)
            || !(ks[i] >= 0.0 && ks[i].is_finite() && kd[i] >= 0.0 && kd[i].is_finite())
    }) {
        return Err(value_error(format!(
            "point {i}: wo must be a finite non-zero vector, alpha in (0, 1], ks and kd finite and ≥ 0"
        )));
    }
    let wo = wo.into_iter().map(Vec3::normalize).collect();
    Ok(Lobes { wo, alpha, ks, kd })
}

fn check_cut(delta: f32, max_cut: usize) -> PyResult<()> {
    if !(delta >= 0.0 && delta.is_finite()) || max_cut == 0 {
        return Err(value_error(
            "delta must be finite and ≥ 0, max_cut at least 1",
        ));
    }
    Ok(())
}

fn picks_bytes<'py>(
    py: Python<'py>,
    picks: &[(i64, f32)],
) -> (Bound<'py, PyBytes>, Bound<'py, PyBytes>) {
    let lights: Vec<u8> = picks.iter().flat_map(|p| p.0.to_ne_bytes()).collect();
    (
        PyBytes::new(py, &lights),
        f32_bytes(py, picks.iter().map(|p| p.1)),
    )
}
