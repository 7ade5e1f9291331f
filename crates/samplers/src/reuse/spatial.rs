//! One round of spatial reuse at a pixel: its reservoir and its neighbours' of the previous
//! round, resampled into a new one.
//!
//! **Unbiased form** (GRIS, Lin et al. 2022, with pairwise MIS weights). Domain 0 is the pixel's
//! own reservoir (canonical), domains 1..k the neighbours'; each one's sample comes with a
//! contribution weight W_j unbiased for its pixel's target p̂_j·V_j (visibility included: the
//! first phase shadow-tests its kept sample and every round keeps only samples the pixel sees).
//! The weights pair the canonical domain, split in k parts of confidence c₀/k, with each
//! neighbour: pair j has share (c_j + c₀/k)/C of the whole (C = c₀ + Σ c_j), split between its
//! two members by the balance heuristic of their confidence-weighted targets. They sum to one
//! over the domains whose target is non-zero at any y the pixel sees, which is what GRIS needs;
//! each evaluation of p̂_j·V_j at a sample from another pixel costs a shadow ray.
//!
//! **Biased form** (Bitterli et al. 2020, their "1/M"): weights c_j/C whatever the neighbours'
//! targets, unshadowed targets in the resampling and a shadow ray at the end. It darkens where a
//! neighbour cannot see or reflect what the pixel sees; kept as a named variant only.
use super::config::MAX_NEIGHBOURS;
use super::light_point::{occluded, target};
use super::reservoir::{Reservoir, Stream};
use render_core::Vec3;
use render_core::estimator::ShadingPoint;
use render_core::image_space::ImagePass;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::stats::Counters;

/// Index of the neighbours' samples the pixel sees (and reflects) in the technique counters.
pub const TECHNIQUE_SEEN: usize = 3;

/// Normals further apart than this (cos 25°) make a neighbour unlike the pixel (the paper's test).
const MIN_NORMAL_COS: f32 = 0.906;
/// Depths further apart than this fraction make a neighbour unlike the pixel (the paper's test).
const MAX_DEPTH_RATIO: f32 = 0.1;

/// The neighbours of pixel `i`: `n` pixels drawn uniformly in a disk of `radius` pixels, kept
/// when they have a shading point like the pixel's (normal within 25°, depth within 10%).
pub fn neighbours(
    pass: &ImagePass,
    i: usize,
    (n, radius): (u32, f32),
    rng: &mut SampleStream,
    out: &mut Vec<usize>,
) {
    out.clear();
    let Some(sp) = &pass.points[i] else { return };
    let (x, y) = ((i % pass.width) as f32, (i / pass.width) as f32);
    for _ in 0..n.min(MAX_NEIGHBOURS as u32) {
        let u = rng.next_2d();
        let r = radius * u.x.sqrt();
        let phi = std::f32::consts::TAU * u.y;
        let (qx, qy) = ((x + r * phi.cos()).round(), (y + r * phi.sin()).round());
        if qx < 0.0 || qy < 0.0 || qx >= pass.width as f32 || qy >= pass.height as f32 {
            continue;
        }
        let q = pass.index(qx as usize, qy as usize);
        if q == i {
            continue;
        }
        let Some(sq) = &pass.points[q] else { continue };
        if alike(sp, sq, pass.camera_position) {
            out.push(q);
        }
    }
}

/// Whether shading point `sq` is like `sp` seen from `camera` (normal within 25°, depth within
/// 10%): the paper's test for a neighbour worth reusing.
pub fn alike(sp: &ShadingPoint, sq: &ShadingPoint, camera: Vec3) -> bool {
    let depth = (sp.point() - camera).length();
    let dq = (sq.point() - camera).length();
    sq.hit.ns.dot(sp.hit.ns) >= MIN_NORMAL_COS && (dq - depth).abs() <= MAX_DEPTH_RATIO * depth
}

/// p̂·V of `sp` at `r`'s sample: 0 where the target is 0 or the point is hidden (one shadow ray
/// where the target is not 0).
fn seen_target(scene: &Scene, sp: &ShadingPoint, r: &Reservoir, c: &mut Counters) -> f32 {
    match target(scene, sp, &r.y) {
        Some((p, _, seen)) if !occluded(scene, sp, &r.y, &seen, c) => p,
        _ => 0.0,
    }
}

/// Pair j's MIS weights at a sample y: (neighbour j's, the canonical part's), for a pair of
/// share `pair` of the whole, neighbour j's confidence and target at y `(c_j, p̂_j·V_j)` and the
/// canonical part's `(c₀/k, p̂₀·V₀)`. Both 0 where both targets are.
pub fn pair_weights(pair: f32, (cj, pj): (f32, f32), (c0k, p0): (f32, f32)) -> (f32, f32) {
    let den = cj * pj + c0k * p0;
    if !(den > 0.0) {
        return (0.0, 0.0);
    }
    (pair * cj * pj / den, pair * c0k * p0 / den)
}

/// The unbiased round at pixel `i` over neighbours `nbrs` of reservoirs `prev`.
pub fn pairwise_round(
    pass: &ImagePass,
    prev: &[Reservoir],
    i: usize,
    nbrs: &[usize],
    rng: &mut SampleStream,
    c: &mut Counters,
) -> Reservoir {
    let Some(sp0) = &pass.points[i] else {
        return prev[i];
    };
    let others = nbrs.iter().map(|&j| {
        let spj = pass.points[j].as_ref();
        (prev[j], spj.expect("neighbours have shading points"))
    });
    pairwise_resample(pass.scene, (prev[i], sp0), others, rng, c)
}

/// GRIS with pairwise MIS weights: the canonical reservoir `r0` of shading point `sp0` and
/// the reservoirs `others` of other shading points (neighbours, or the pixel's own of the
/// previous pass), each with its confidence, resampled into one reservoir for `sp0`.
pub fn pairwise_resample<'a>(
    scene: &Scene,
    (r0, sp0): (Reservoir, &ShadingPoint),
    others: impl Iterator<Item = (Reservoir, &'a ShadingPoint)> + Clone,
    rng: &mut SampleStream,
    c: &mut Counters,
) -> Reservoir {
    let k = others.clone().count();
    if k == 0 {
        return r0;
    }
    let c0k = r0.c / k as f32;
    let total = r0.c + others.clone().map(|(r, _)| r.c).sum::<f32>();
    // The pixel's own sample is visible from it whenever W > 0 (every phase keeps only such).
    let p0_y0 = if r0.w > 0.0 {
        target(scene, sp0, &r0.y).map_or(0.0, |t| t.0)
    } else {
        0.0
    };
    let mut stream = Stream::default();
    let mut m0 = 0.0;
    for (rj, spj) in others {
        let pair = (rj.c + c0k) / total;
        if p0_y0 > 0.0 {
            let pj_y0 = seen_target(scene, spj, &r0, c);
            m0 += pair_weights(pair, (rj.c, pj_y0), (c0k, p0_y0)).1;
        }
        let u = rng.next_f32();
        if !(rj.w > 0.0) {
            continue;
        }
        let pj_yj = target(scene, spj, &rj.y).map_or(0.0, |t| t.0);
        let p0_yj = seen_target(scene, sp0, &rj, c);
        if pj_yj > 0.0 && p0_yj > 0.0 {
            c.technique_samples[TECHNIQUE_SEEN] += 1;
            let mj = pair_weights(pair, (rj.c, pj_yj), (c0k, p0_yj)).0;
            stream.offer(rj.y, mj * p0_yj * rj.w, p0_yj, u);
        }
    }
    let u = rng.next_f32();
    if p0_y0 > 0.0 {
        stream.offer(r0.y, m0 * p0_y0 * r0.w, p0_y0, u);
    }
    stream.finish(total)
}

/// The biased (1/M) round at pixel `i`: unshadowed targets, weights c_j / C.
pub fn biased_round(
    pass: &ImagePass,
    prev: &[Reservoir],
    i: usize,
    nbrs: &[usize],
    rng: &mut SampleStream,
) -> Reservoir {
    let Some(sp0) = &pass.points[i] else {
        return prev[i];
    };
    biased_resample(
        pass.scene,
        (prev[i], sp0),
        nbrs.iter().map(|&j| prev[j]),
        rng,
    )
}

/// The paper's 1/M combination of the canonical reservoir `r0` of `sp0` and reservoirs
/// `others`: unshadowed targets at `sp0`, weights c_j / C (biased where the others' shading
/// points see or reflect differently).
pub fn biased_resample(
    scene: &Scene,
    (r0, sp0): (Reservoir, &ShadingPoint),
    others: impl Iterator<Item = Reservoir>,
    rng: &mut SampleStream,
) -> Reservoir {
    let mut stream = Stream::default();
    let mut total = 0.0;
    for r in std::iter::once(r0).chain(others) {
        total += r.c;
        let u = rng.next_f32();
        if !(r.w > 0.0) {
            continue;
        }
        let p0 = target(scene, sp0, &r.y).map_or(0.0, |t| t.0);
        stream.offer(r.y, p0 * r.w * r.c, p0, u);
    }
    let mut r = stream.finish(total);
    r.w /= total.max(1.0);
    r
}

/// The pixel's estimate from its final reservoir: f·cos·L·G·W, with a shadow ray unless every
/// phase already kept only samples the pixel sees (`visible`).
pub fn shade(
    pass: &ImagePass,
    sp: &ShadingPoint,
    r: &Reservoir,
    visible: bool,
    c: &mut Counters,
) -> Vec3 {
    if !(r.w > 0.0) {
        return Vec3::ZERO;
    }
    match target(pass.scene, sp, &r.y) {
        Some((_, f, seen)) if visible || !occluded(pass.scene, sp, &r.y, &seen, c) => f * r.w,
        _ => Vec3::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::pair_weights;

    /// At any sample the pixel's target reaches, the weights of all domains sum to one, and a
    /// neighbour whose target is 0 there gets none of it.
    #[test]
    fn pairwise_weights_sum_to_one() {
        let mut x = 0.37f32;
        let mut next = || {
            x = (x * 3.7 + 0.13).fract();
            x
        };
        for k in 1..=8usize {
            let c0 = 1.0 + 40.0 * next();
            let p0 = 0.01 + 5.0 * next();
            let nbrs: Vec<(f32, f32)> = (0..k)
                .map(|j| (1.0 + 40.0 * next(), if j == 0 { 0.0 } else { 5.0 * next() }))
                .collect();
            let total = c0 + nbrs.iter().map(|n| n.0).sum::<f32>();
            let c0k = c0 / k as f32;
            let mut sum = 0.0;
            for &(cj, pj) in &nbrs {
                let (mj, m0) = pair_weights((cj + c0k) / total, (cj, pj), (c0k, p0));
                if pj == 0.0 {
                    assert_eq!(mj, 0.0);
                }
                sum += mj + m0;
            }
            assert!((sum - 1.0).abs() < 1e-5, "k = {k}: weights sum to {sum}");
        }
    }
}
