//! I_BO of four nodes at once, in f32 lanes, for the four-wide descent below the BO cut
//! (issue 22): the nodes whose terms take their point form (a cap wholly above the horizon,
//! half-angle below 0.25 rad, narrower than the lobe or far from its peak: most nodes below
//! a cut) are evaluated together; the other lanes come back empty and the caller takes the
//! scalar [`BoRecord::terms`] for them.
//!
//! A lane repeats `terms`' point form operation for operation, except the lobe density in f32
//! instead of f64, so a lane agrees with `terms` to f32 rounding (tested below), and the
//! exceptional cases (the receiver inside a node's sphere, zero solid angle, the clipped caps)
//! all go to the scalar path. Sampling and the pmf replay read the same lanes (memoised per
//! quad), so the descent's pmf is exact whatever the rounding.
use super::importance::{BoRecord, LobeDensity};
use brdf_integrals::LobeIntegral;
use glam::{BVec4A, Vec4};
use light_tree::{MIN_DIST_SQ, MIN_EMIT_COS, Node};
use std::f32::consts::PI;

/// Largest sin² of a cap's half-angle that takes the point form (`point_estimate`).
const POINT_SIN2: f32 = 0.0606;

/// Four nodes' fields, one lane each.
struct Gathered {
    lo: [Vec4; 3],
    hi: [Vec4; 3],
    axis: [Vec4; 3],
    radius: Vec4,
    power: Vec4,
    cos_o: Vec4,
    cos_e: Vec4,
    two_sided: BVec4A,
    half_space: BVec4A,
}

fn gather(nodes: [&Node; 4]) -> Gathered {
    let lane = |f: &dyn Fn(&Node) -> f32| Vec4::from_array(nodes.map(f));
    let flag = |f: &dyn Fn(&Node) -> bool| {
        let b = nodes.map(f);
        BVec4A::new(b[0], b[1], b[2], b[3])
    };
    Gathered {
        lo: [0, 1, 2].map(|k| lane(&|n| n.aabb().0[k])),
        hi: [0, 1, 2].map(|k| lane(&|n| n.aabb().1[k])),
        axis: [0, 1, 2].map(|k| lane(&|n| n.axis()[k])),
        radius: lane(&|n| n.radius()),
        power: lane(&|n| n.power()),
        cos_o: lane(&|n| n.cos_theta_o()),
        cos_e: lane(&|n| n.cos_theta_e()),
        two_sided: flag(&|n| n.two_sided()),
        half_space: flag(&|n| n.half_space()),
    }
}

fn dot3(a: &[Vec4; 3], b: &[Vec4; 3]) -> Vec4 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sqrt0(v: Vec4) -> Vec4 {
    v.max(Vec4::ZERO).sqrt()
}

/// cos and sin of max(θa − θb, 0), lane by lane (`light_tree`'s `cos_sub_clamped`).
fn sub_clamped(cos_a: Vec4, sin_a: Vec4, cos_b: Vec4, sin_b: Vec4) -> (Vec4, Vec4) {
    let wide = cos_a.cmpge(cos_b);
    let cos = Vec4::select(wide, Vec4::ONE, cos_a * cos_b + sin_a * sin_b);
    let sin = Vec4::select(wide, Vec4::ZERO, sin_a * cos_b - cos_a * sin_b);
    (cos, sin)
}

impl<L: LobeIntegral + LobeDensity> BoRecord<L> {
    /// I_BO of four nodes: `Some` in each lane that takes the point form (equal to
    /// `terms(node).importance` up to f32 rounding), `None` where the caller must use
    /// [`BoRecord::terms`]. All `None` when the record has no point form.
    pub fn point_importances(&self, nodes: [&Node; 4]) -> [Option<f32>; 4] {
        // Checked before the gather, which is the costly part here.
        if self.point_peak().is_none() {
            return [None; 4];
        }
        let g = gather(nodes);
        let x = [self.x.x, self.x.y, self.x.z].map(Vec4::splat);
        let half = |k: usize| (g.hi[k] - g.lo[k]) * 0.5;
        let to_c: [Vec4; 3] = std::array::from_fn(|k| (g.lo[k] + g.hi[k]) * 0.5 - x[k]);

        // The emitter bound Φ·cos θ′/d² of `Node::importance` without a receiver normal.
        let abs_axis = g.axis.map(Vec4::abs);
        let behind = (-dot3(&g.axis, &to_c) + dot3(&abs_axis, &[half(0), half(1), half(2)]))
            .cmple(Vec4::ZERO)
            & g.half_space;
        let d2 = dot3(&to_c, &to_c);
        let r2 = g.radius * g.radius;
        let d2c = d2.max(0.25 * r2).max(Vec4::splat(MIN_DIST_SQ));
        let inv_d = d2.sqrt().recip();
        let w = to_c.map(|c| c * inv_d);
        let sin_u = (g.radius * inv_d).min(Vec4::ONE);
        let cos_u = sqrt0(Vec4::ONE - sin_u * sin_u);
        let cos_t = -dot3(&g.axis, &w);
        let cos_t = Vec4::select(g.two_sided, cos_t.abs(), cos_t);
        let sin_t = sqrt0(Vec4::ONE - cos_t * cos_t);
        let sin_o = sqrt0(Vec4::ONE - g.cos_o * g.cos_o);
        let (cos_x, sin_x) = sub_clamped(cos_t, sin_t, g.cos_o, sin_o);
        let (cos_p, _) = sub_clamped(cos_x, sin_x, cos_u, sin_u);
        let lit = cos_p.cmpgt(g.cos_e) & !behind;
        let emit = Vec4::select(
            lit,
            g.power * cos_p.max(Vec4::splat(MIN_EMIT_COS)) / d2c,
            Vec4::ZERO,
        );
        self.point_lanes(to_c, r2, emit)
    }

    /// I_BO of a quad's four nodes from its compact view ([`light_tree::QuadView`]: decoded
    /// centres and radii and the compact emitter bound), without reading the nodes: `Some`
    /// where the point form applies to those bounds, `None` where the caller must use
    /// [`BoRecord::terms`] (on the exact node). The compact bounds contain the exact ones, so
    /// a lane is close to, not equal to, `terms`.
    pub fn point_importances_view(&self, view: &light_tree::QuadView) -> [Option<f32>; 4] {
        let to_c = view.to_centre.map(Vec4::from_array);
        let r2 = Vec4::from_array(view.radius_sq);
        self.point_lanes(to_c, r2, Vec4::from_array(view.emit))
    }

    fn point_peak(&self) -> Option<super::importance::PeakBound> {
        self.peak.filter(|_| self.point_approx && self.ks > 0.0)
    }

    /// The point form of `terms` in four lanes, from each node's centre − x, radius² and
    /// emitter bound.
    #[inline(always)]
    fn point_lanes(&self, to_c: [Vec4; 3], r2: Vec4, emit: Vec4) -> [Option<f32>; 4] {
        let Some(pk) = self.point_peak() else {
            return [None; 4];
        };
        let d2 = dot3(&to_c, &to_c);
        let outside = d2.cmpgt(r2);

        // The cap in the shading frame, as `terms` computes it.
        let d = d2.sqrt();
        let f = &self.frame;
        let frame_row = |v: glam::Vec3| [v.x, v.y, v.z].map(Vec4::splat);
        let dir = to_c.map(|c| c / d);
        let local = [f.x, f.y, f.z].map(|row| dot3(&dir, &frame_row(row)));
        let inv_len = dot3(&local, &local).sqrt().recip();
        let axis = local.map(|c| c * inv_len);
        let sin2 = (r2 / d2).min(Vec4::ONE);
        let cos = sqrt0(Vec4::ONE - sin2);
        let sin = sin2.sqrt();
        let sin_axis = sqrt0(Vec4::ONE - axis[2] * axis[2]);
        let lowest = axis[2] * cos - sin_axis * sin;
        let highest = axis[2] * cos + sin_axis * sin;
        let omega = Vec4::splat(2.0 * PI) * sin2 / (Vec4::ONE + cos);

        // Where `point_estimate` applies: small, wholly above the horizon, narrow or far.
        let narrow = sin2.cmplt(Vec4::splat((0.25 * pk.width) * (0.25 * pk.width)));
        let below_pi = pk.cos3w >= 0.0;
        let far_bound = cos * Vec4::splat(pk.cos3w) - sin * Vec4::splat(pk.sin3w);
        let peak_dot = dot3(&axis, &frame_row(pk.dir));
        let far = peak_dot.cmplt(far_bound)
            & (sin.cmplt(Vec4::splat(pk.sin3w)) | BVec4A::splat(below_pi));
        let point = sin2.cmple(Vec4::splat(POINT_SIN2))
            & (axis[2] * axis[2]).cmpgt(sin2)
            & axis[2].cmpgt(Vec4::ZERO)
            & (narrow | far)
            & lowest.cmpge(Vec4::ZERO)
            & highest.cmpgt(Vec4::ZERO)
            & omega.cmpgt(Vec4::ZERO)
            & outside;
        let Some(density) = self.lobe.density4(axis) else {
            return [None; 4];
        };
        let glossy = density * omega;
        let diffuse = if self.diffuse_term && self.kd > 0.0 {
            Vec4::splat(self.kd / PI) * (Vec4::splat(PI) * sin2 * axis[2])
        } else {
            Vec4::ZERO
        };
        let value = emit * (Vec4::splat(self.ks) * glossy + diffuse) / omega;
        let (value, point) = (value.to_array(), point.bitmask());
        std::array::from_fn(|k| (point & (1 << k) != 0).then_some(value[k]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_integrals::{CapIntegral, Sptd};
    use light_tree::{LightBounds, LightTree};
    use rand::{RngExt, SeedableRng};
    use render_core::Vec3;
    use render_core::frame::Frame;

    /// Every lane that takes the point form equals the scalar `terms` within 2e-3 relative,
    /// is positive wherever the scalar value is, and most lanes below a tree's top levels take
    /// it (else the lanes buy nothing).
    #[test]
    fn lanes_match_the_scalar_terms() {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(7);
        let lights: Vec<LightBounds> = (0..4000)
            .map(|_| {
                let c = Vec3::new(
                    rng.random_range(-20.0..20.0),
                    rng.random_range(-20.0..20.0),
                    rng.random_range(2.0..12.0),
                );
                let e = Vec3::splat(rng.random_range(0.01..0.2));
                LightBounds {
                    aabb_min: c - e,
                    aabb_max: c + e,
                    axis: Vec3::new(rng.random_range(-1.0..1.0), 0.3, -1.0).normalize(),
                    theta_o: rng.random_range(0.0..1.5),
                    theta_e: std::f32::consts::FRAC_PI_2,
                    power: rng.random_range(0.1..10.0),
                    two_sided: rng.random_range(0..4) == 0,
                }
            })
            .collect();
        let tree = LightTree::build(&lights).unwrap();
        let sptd = Sptd::default();
        let (mut taken, mut lanes) = (0usize, 0usize);
        for case in 0..40 {
            let n = Vec3::new(
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
                1.0,
            )
            .normalize();
            let wo = (n + Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                0.0,
            ))
            .normalize();
            let frame = Frame::from_normal_and_direction(n, wo);
            let alpha = [0.05, 0.1, 0.2, 0.4][case % 4];
            let lobe = sptd.lobe(frame.to_local(wo), alpha);
            let x = Vec3::new(
                rng.random_range(-20.0..20.0),
                rng.random_range(-20.0..20.0),
                0.0,
            );
            let rec =
                BoRecord::from_parts(x, frame, lobe, 0.6, 0.3 * (case % 2) as f32, true, false);
            for q in 0..tree.nodes().len() as u32 / 8 {
                let ids: [u32; 4] =
                    std::array::from_fn(|k| (q * 4 + k as u32) % tree.nodes().len() as u32);
                let nodes = ids.map(|id| tree.node(id));
                for (k, lane) in rec.point_importances(nodes).into_iter().enumerate() {
                    lanes += 1;
                    let Some(v) = lane else { continue };
                    taken += 1;
                    let s = rec.terms(nodes[k]).importance;
                    assert!(
                        (v - s).abs() <= 2e-3 * s.abs().max(1e-30),
                        "node {}: lanes {v}, scalar {s}",
                        ids[k]
                    );
                    assert_eq!(v > 0.0, s > 0.0, "node {}", ids[k]);
                }
            }
        }
        assert!(
            taken * 2 > lanes,
            "only {taken} of {lanes} lanes took the point form"
        );

        // From the quads' compact view: positive wherever `terms` is, and close to it (the
        // compact boxes are the exact ones rounded outward to 16 bits).
        let mut rel = Vec::new();
        for case in 0..20 {
            let n = Vec3::Z;
            let wo = Vec3::new(rng.random_range(-1.0..1.0), 0.2, 0.8).normalize();
            let frame = Frame::from_normal_and_direction(n, wo);
            let lobe = sptd.lobe(frame.to_local(wo), [0.05, 0.2][case % 2]);
            let x = Vec3::new(
                rng.random_range(-20.0..20.0),
                rng.random_range(-20.0..20.0),
                0.0,
            );
            let rec = BoRecord::from_parts(x, frame, lobe, 0.6, 0.3, true, false);
            for q in 0..tree.num_quads() {
                let ids = *tree.quad_nodes(q);
                let lanes = rec.point_importances_view(&tree.quad_view(q, x));
                for k in 0..4 {
                    let (id, Some(v)) = (ids[k], lanes[k]) else {
                        continue;
                    };
                    assert_ne!(id, light_tree::NO_NODE, "an empty lane takes no point form");
                    let s = rec.terms(tree.node(id)).importance;
                    if s > 0.0 {
                        assert!(v > 0.0, "quad {q} lane {k}: view {v}, scalar {s}");
                        rel.push(((v - s) / s).abs());
                    }
                }
            }
        }
        rel.sort_by(f32::total_cmp);
        assert!(rel.len() > 1000, "{} lanes compared", rel.len());
        let median = rel[rel.len() / 2];
        assert!(median < 1e-2, "median relative difference {median}");
    }
}
