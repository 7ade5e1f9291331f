//! Spherical-Gaussian (SG) light of every node, after Tokuyoshi, Ikeda, Kulkarni & Harada,
//! "Hierarchical Light Sampling with Accurate Spherical Gaussian Lighting" (SIGGRAPH Asia
//! 2024): a node's lights are seen as one Gaussian cloud in space (power-weighted mean and
//! variance of the emitting points) whose radiant intensity is a von Mises–Fisher (normalised
//! SG) lobe over directions (axis and sharpness fitted to the power-weighted mean emission
//! direction). At a shading point the cloud becomes an SG light of sharpness d²/σ² around the
//! direction to its mean; the lighting integral with a BRDF is the caller's (`samplers::sg`).
//!
//! The fit runs bottom-up over the built tree ([`SgNodes::build`]): children merge by the
//! parallel-axis rule, so a node's moments are exactly those of its lights, and its power is
//! the tree's node power, so the lobe's intensity integrates to the node's power over the
//! sphere (see [`SgNode::intensity`]). Nothing here knows about rendering: the input is one
//! [`SgEmitter`] per light, in the order the tree was built from.

use crate::{BuildError, LightTree, NodeId};
use glam::{DVec3, Vec3};
use std::f32::consts::PI;

/// Mean resultant lengths are capped here before the vMF fit, so that the sharpness stays
/// finite (about 10⁶) for clusters of identically oriented emitters.
const MAX_MEAN_LENGTH: f64 = 1.0 - 1e-6;

/// What the SG fit needs of one light: where its emission comes from and where it goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SgEmitter {
    /// Mean of the emitting points (the centroid of a uniformly emitting surface).
    pub mean: Vec3,
    /// Spatial variance E|p − mean|² over the emitting points (the trace of their covariance),
    /// ≥ 0: 0 for a point light.
    pub variance: f32,
    /// Mean emission direction ∫ ω I(ω) dω / Φ of the light's radiant intensity I, of length
    /// in [0, 1]: 2/3 of the normal for a one-sided Lambertian emitter, 0 for isotropic or
    /// two-sided ones.
    pub direction: Vec3,
}

impl SgEmitter {
    /// A uniformly emitting triangle with unit `normal` (one-sided Lambertian: direction
    /// 2n/3; two-sided: 0). Its variance is Σ|pᵢ − pⱼ|²/36 over the three edges.
    pub fn triangle(p: [Vec3; 3], normal: Vec3, two_sided: bool) -> SgEmitter {
        let edges = (p[0] - p[1]).length_squared()
            + (p[1] - p[2]).length_squared()
            + (p[2] - p[0]).length_squared();
        SgEmitter {
            mean: (p[0] + p[1] + p[2]) / 3.0,
            variance: edges / 36.0,
            direction: if two_sided {
                Vec3::ZERO
            } else {
                normal * (2.0 / 3.0)
            },
        }
    }

    /// A sphere of radius `r` emitting uniformly outwards (isotropic in total; the points lie
    /// at distance r from the centre, so the variance is r²).
    pub fn sphere(center: Vec3, r: f32) -> SgEmitter {
        SgEmitter {
            mean: center,
            variance: r * r,
            direction: Vec3::ZERO,
        }
    }

    /// An isotropic point light.
    pub fn point(p: Vec3) -> SgEmitter {
        SgEmitter {
            mean: p,
            variance: 0.0,
            direction: Vec3::ZERO,
        }
    }

    /// A point light emitting into the cone of half-angle acos(`cos_outer`) around the unit
    /// `axis`, taken as uniform inside it: mean direction (1 + cos_outer)/2 · axis.
    pub fn spot(p: Vec3, axis: Vec3, cos_outer: f32) -> SgEmitter {
        SgEmitter {
            mean: p,
            variance: 0.0,
            direction: axis * (0.5 * (1.0 + cos_outer.clamp(-1.0, 1.0))),
        }
    }
}

/// The SG light of one node, 32 bytes, indexed by the node's [`NodeId`]; the power is the
/// node's ([`crate::Node::power`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct SgNode {
    mean: Vec3,
    variance: f32,
    axis: Vec3,
    sharpness: f32,
}

impl SgNode {
    /// Power-weighted mean of the node's emitting points.
    #[inline]
    pub fn mean(&self) -> Vec3 {
        self.mean
    }
    /// Power-weighted spatial variance E|p − mean|² of the node's emitting points (their own
    /// spread plus the spread of their means).
    #[inline]
    pub fn variance(&self) -> f32 {
        self.variance
    }
    /// Axis of the intensity lobe (unit; +z when the lights emit isotropically in total).
    #[inline]
    pub fn axis(&self) -> Vec3 {
        self.axis
    }
    /// Sharpness λ ≥ 0 of the intensity lobe exp(λ(ω·axis − 1)).
    #[inline]
    pub fn sharpness(&self) -> f32 {
        self.sharpness
    }
    /// The SG amplitude of the intensity lobe for a node of power `power`: Φ · λ/(2π(1 − e^{−2λ}))
    /// (Φ/4π at λ = 0), so that the lobe integrates to Φ over the sphere.
    #[inline]
    pub fn amplitude(&self, power: f32) -> f32 {
        power * vmf_normalization(self.sharpness)
    }
    /// Radiant intensity the lobe gives in the unit direction `w` (from the cluster outwards),
    /// for a node of power `power`.
    #[inline]
    pub fn intensity(&self, power: f32, w: Vec3) -> f32 {
        self.amplitude(power) * (self.sharpness * (self.axis.dot(w) - 1.0)).exp()
    }
}

/// 1/∫ exp(λ(ω·μ − 1)) dω = λ / (2π(1 − e^{−2λ})), the factor that makes an SG of sharpness λ
/// a density on the sphere (1/4π at λ = 0).
#[inline]
pub fn vmf_normalization(sharpness: f32) -> f32 {
    1.0 / sg_integral(sharpness)
}

/// ∫ exp(λ(ω·μ − 1)) dω over the sphere = 2π(1 − e^{−2λ})/λ (4π at λ = 0), without
/// cancellation for small λ.
#[inline]
pub fn sg_integral(sharpness: f32) -> f32 {
    let two_l = 2.0 * sharpness;
    let ratio = if two_l < 1e-4 {
        1.0 - 0.5 * two_l
    } else {
        -(-two_l).exp_m1() / two_l
    };
    4.0 * PI * ratio
}

/// The vMF sharpness whose mean resultant length is `r` (Banerjee et al.'s approximation
/// r(3 − r²)/(1 − r²)); exact at r = 0, within a few per cent elsewhere.
pub fn sharpness_from_mean_length(r: f64) -> f64 {
    let r = r.clamp(0.0, MAX_MEAN_LENGTH);
    r * (3.0 - r * r) / (1.0 - r * r)
}

/// The SG lights of every node of one [`LightTree`], in its node order.
#[derive(Clone, Debug)]
pub struct SgNodes {
    nodes: Vec<SgNode>,
}

/// A node's moments during the fit, in f64: weight, mean, variance, mean direction vector.
#[derive(Clone, Copy)]
struct Moments {
    weight: f64,
    count: f64,
    mean: DVec3,
    variance: f64,
    direction: DVec3,
}

impl Moments {
    /// Parallel-axis merge: means and mean directions average by weight, the variance adds
    /// each side's spread about the merged mean. Weights are powers, or light counts when
    /// both sides are dark (the lobe of a dark node is never used, but stays well defined).
    fn merge(a: &Moments, b: &Moments) -> Moments {
        let (wa, wb) = if a.weight + b.weight > 0.0 {
            (a.weight, b.weight)
        } else {
            (a.count, b.count)
        };
        let w = wa + wb;
        let mean = (a.mean * wa + b.mean * wb) / w;
        let variance = (wa * (a.variance + (a.mean - mean).length_squared())
            + wb * (b.variance + (b.mean - mean).length_squared()))
            / w;
        Moments {
            weight: a.weight + b.weight,
            count: a.count + b.count,
            mean,
            variance,
            direction: (a.direction * wa + b.direction * wb) / w,
        }
    }

    fn node(&self) -> SgNode {
        let r = self.direction.length();
        let axis = if r > 1e-12 {
            (self.direction / r).as_vec3()
        } else {
            Vec3::Z
        };
        SgNode {
            mean: self.mean.as_vec3(),
            variance: self.variance.max(0.0) as f32,
            axis,
            sharpness: sharpness_from_mean_length(r) as f32,
        }
    }
}

impl SgNodes {
    /// Fits the SG light of every node of `tree` from one emitter per light (`emitters[i]` is
    /// light `i` of the slice the tree was built from); the weights are the leaves' powers.
    /// Fails on a count mismatch, a non-finite field, a negative variance or a direction
    /// longer than 1.
    pub fn build(tree: &LightTree, emitters: &[SgEmitter]) -> Result<SgNodes, BuildError> {
        if emitters.len() != tree.num_lights() {
            return Err(BuildError::EmitterCount {
                lights: tree.num_lights(),
                emitters: emitters.len(),
            });
        }
        for (i, e) in emitters.iter().enumerate() {
            if !(e.mean.is_finite() && e.variance.is_finite() && e.direction.is_finite()) {
                return Err(BuildError::NonFinite { light: i });
            }
            if e.variance < 0.0 || e.direction.length() > 1.0 + 1e-5 {
                return Err(BuildError::BadEmitter { light: i });
            }
        }
        let n = tree.nodes().len();
        let mut moments = vec![
            Moments {
                weight: 0.0,
                count: 0.0,
                mean: DVec3::ZERO,
                variance: 0.0,
                direction: DVec3::ZERO,
            };
            n
        ];
        // Children have larger DFS ids than their parent: one pass from the back.
        for id in (0..n).rev() {
            let node = &tree.nodes()[id];
            moments[id] = match node.children(id as NodeId) {
                None => {
                    let light = node.light().expect("a leaf holds a light");
                    let e = &emitters[light];
                    Moments {
                        weight: node.power() as f64,
                        count: 1.0,
                        mean: e.mean.as_dvec3(),
                        variance: e.variance as f64,
                        direction: e.direction.as_dvec3(),
                    }
                }
                Some((l, r)) => Moments::merge(&moments[l as usize], &moments[r as usize]),
            };
        }
        Ok(SgNodes {
            nodes: moments.iter().map(Moments::node).collect(),
        })
    }

    /// The SG light of node `id`. Panics if `id` is out of range.
    #[inline]
    pub fn node(&self, id: NodeId) -> &SgNode {
        &self.nodes[id as usize]
    }

    /// Every node's SG light, in the tree's node order.
    #[inline]
    pub fn nodes(&self) -> &[SgNode] {
        &self.nodes
    }
}
