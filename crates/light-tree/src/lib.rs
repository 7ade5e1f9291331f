//! A light BVH with orientation bounds (Conty Estevez & Kulla 2018, "Importance Sampling of
//! Many Lights with Adaptive Tree Splitting"), the tree underneath Liu, Xu & Yan 2019.
//!
//! This crate knows nothing of rendering: the input is one [`LightBounds`] per light, queries
//! take a shading point `x`, a receiver normal `n` and random numbers.
//!
//! * [`LightTree::build`]: SAOH over 12 centroid buckets on all three axes, one light per
//!   leaf, depth-first layout (left child = node + 1), depth ≤ 64 so each light's bit trail
//!   fits a `u64` (median-split fallback).
//! * [`LightTree::importance`]: E&K's conservative Φ·cos θ′·cos θ′ᵢ/d².
//! * [`LightTree::sample`] / [`LightTree::pmf`]: single stochastic descent and its exact
//!   replay; [`LightTree::sample_subtree`] / [`LightTree::pmf_subtree`] do the same from any
//!   node with any node importance.
//! * [`LightTree::cut`] / [`LightTree::adaptive_cut`]: cuts for adaptive tree splitting, with
//!   the authors' E&K criterion in scene units or our unit-free one ([`SplitCriterion`]).
//! * [`SgNodes::build`]: the spherical-Gaussian light of every node (Tokuyoshi et al. 2024),
//!   fitted bottom-up from one [`SgEmitter`] per light, beside the nodes.
//!
//! A descent that reaches a node whose two children both have zero importance returns `None`
//! (with conservative bounds, every light below is dark at `x`), so Σ pmf over all lights is
//! 1 − P(None): exactly 1 without such dead ends, 0 when everything is dark.
//!
//! All positions, directions and boxes are in one space of the caller's choosing (usually world
//! space); the tree never transforms them. Angles are in radians. Powers only need a common unit:
//! the pmfs are ratios of importances, so scaling every power leaves them unchanged.
//!
//! See `README.md` for units, conventions and measured performance.
//!
//! # Example
//!
//! Build a tree over three lights and pick one of them for a shading point, with the
//! probability it was picked:
//!
//! ```
//! use glam::Vec3;
//! use light_tree::{LightBounds, LightTree};
//! use std::f32::consts::FRAC_PI_2;
//!
//! let lights = [
//!     // Two isotropic point lights (intensity in W/sr).
//!     LightBounds::point(Vec3::new(0.0, 0.0, 2.0), 1.0),
//!     LightBounds::point(Vec3::new(3.0, 0.0, 1.0), 5.0),
//!     // A one-sided 2 × 2 Lambertian quad at height 3, facing down.
//!     LightBounds {
//!         aabb_min: Vec3::new(-1.0, -1.0, 3.0),
//!         aabb_max: Vec3::new(1.0, 1.0, 3.0),
//!         axis: -Vec3::Z,
//!         theta_o: 0.0,
//!         theta_e: FRAC_PI_2,
//!         power: 10.0,
//!         two_sided: false,
//!     },
//! ];
//! let tree = LightTree::build(&lights).expect("valid bounds");
//! assert_eq!(tree.num_lights(), 3);
//!
//! // Shading point at the origin on a floor facing +z; `u` is 64 uniform random bits.
//! let (x, n, u) = (Vec3::ZERO, Vec3::Z, 0x5eb8_51eb_851e_b851);
//! let (light, pmf) = tree.sample(x, n, u).expect("every light can reach x");
//! assert!(light < lights.len() && pmf > 0.0 && pmf <= 1.0);
//! // The pmf can be recomputed for any light (e.g. for MIS), bit for bit.
//! assert_eq!(tree.pmf(x, n, light), pmf);
//! // No light is dark here, so the pmf sums to one over the lights.
//! let total: f32 = (0..lights.len()).map(|i| tree.pmf(x, n, i)).sum();
//! assert!((total - 1.0).abs() < 1e-5);
//! ```

#![warn(missing_docs)]

mod build;
mod codes;
mod compact;
#[cfg(test)]
mod compact_tests;
mod cone;
mod descent_step;
mod lane_slots;
mod lanes;
mod oct;
mod oct_descent;
mod quad;
mod quad_descent;
mod query;
mod sg;
#[cfg(test)]
mod sg_tests;
#[cfg(test)]
mod split_tests;
#[cfg(test)]
mod tests;

pub use codes::{MIN_DIST_SQ, MIN_EMIT_COS};
pub use cone::Cone;
pub use descent_step::{DescentRandom, Fresh, Rescaled};
pub use oct_descent::{DescentSimd, LaneCache};
pub use quad_descent::{NO_NODE, QuadView, QuadWeights};
pub use query::{Cut, SplitCriterion, SplitParams};
pub use sg::{
    SgEmitter, SgNode, SgNodes, sg_integral, sharpness_from_mean_length, vmf_normalization,
};

use glam::Vec3;
use std::fmt;

/// Index of a node in [`LightTree::nodes`] (depth-first order).
pub type NodeId = u32;

/// Maximum depth of a leaf (root has depth 0): bit `k` of a light's trail records the choice
/// made at depth `k`, so 64 levels fit a `u64`.
pub const MAX_DEPTH: u32 = 64;

/// Spatial, directional and power bounds of one light: the input of [`LightTree::build`].
///
/// Units and conventions are the caller's responsibility; the tree only needs them to be
/// consistent across lights:
/// * `power` in watts (any one unit): one-sided Lambertian emitter π·L·A, two-sided 2π·L·A,
///   sphere of radiance L and radius r π·L·4πr², isotropic point light 4π·I.
/// * `axis` (unit; normalised by `build`), `theta_o` = spread of the emitting normals around
///   `axis` (0 for a planar emitter, π for spheres and points), `theta_e` = how far beyond a
///   normal light leaves (π/2 for Lambertian). Both in [0, π].
/// * `two_sided`: the emitter also emits around `-axis` (e.g. a two-sided quad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// Lower corner of an axis-aligned box enclosing the emitter (`aabb_min <= aabb_max` on
    /// every axis; equal to `aabb_max` for a point light).
    pub aabb_min: Vec3,
    /// Upper corner of the enclosing box.
    pub aabb_max: Vec3,
    /// Central direction of the emitting normals. Any non-zero length (`build` normalises
    /// it); may be zero only when `theta_o` is π.
    pub axis: Vec3,
    /// Half-angle, in radians in [0, π], of the cone around `axis` that holds every emitting
    /// normal.
    pub theta_o: f32,
    /// How far, in radians in [0, π], emitted light can stray from its normal (π/2 for a
    /// Lambertian emitter).
    pub theta_e: f32,
    /// Emitted power Φ, finite and ≥ 0, in the unit shared by all lights. Zero-power lights
    /// are kept but never sampled.
    pub power: f32,
    /// Whether the emitter also radiates around `-axis`.
    pub two_sided: bool,
}

impl LightBounds {
    /// Bounds of an isotropic point light at `p` with radiant intensity `intensity` (power
    /// 4π·I; θo = π, θe = π/2, not two-sided).
    pub fn point(p: Vec3, intensity: f32) -> Self {
        Self {
            aabb_min: p,
            aabb_max: p,
            axis: Vec3::Z,
            theta_o: std::f32::consts::PI,
            theta_e: std::f32::consts::FRAC_PI_2,
            power: 4.0 * std::f32::consts::PI * intensity,
            two_sided: false,
        }
    }
}

/// Why [`LightTree::build`] refused its input.
#[derive(Clone, Debug, PartialEq)]
pub enum BuildError {
    /// The light list is empty.
    NoLights,
    /// More lights than the 32-bit node indices can address (2³¹ − 1 at most).
    TooManyLights(usize),
    /// A field of light `light` is NaN or infinite.
    NonFinite {
        /// Index of the rejected light in the slice given to [`LightTree::build`].
        light: usize,
    },
    /// Light `light` has negative power.
    NegativePower {
        /// Index of the rejected light.
        light: usize,
        /// The negative power it was given.
        power: f32,
    },
    /// `aabb_min > aabb_max` on some axis.
    InvertedBounds {
        /// Index of the rejected light.
        light: usize,
    },
    /// `theta_o` or `theta_e` outside [0, π].
    AngleOutOfRange {
        /// Index of the rejected light.
        light: usize,
    },
    /// Zero-length `axis` while `theta_o < π`.
    ZeroAxis {
        /// Index of the rejected light.
        light: usize,
    },
    /// [`SgNodes::build`] got another number of emitters than the tree has lights.
    EmitterCount {
        /// Lights in the tree.
        lights: usize,
        /// Emitters given.
        emitters: usize,
    },
    /// The lights' bounding box is too large for f32 arithmetic (an extent overflows).
    BoundsTooLarge,
    /// An [`SgEmitter`] with a negative variance or a mean direction longer than 1.
    BadEmitter {
        /// Index of the rejected emitter.
        light: usize,
    },
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::NoLights => write!(f, "light tree: no lights to build from"),
            BuildError::TooManyLights(n) => {
                write!(f, "light tree: {n} lights exceed the limit of 2^31 - 1")
            }
            BuildError::NonFinite { light } => {
                write!(f, "light tree: light {light} has a NaN or infinite field")
            }
            BuildError::NegativePower { light, power } => {
                write!(f, "light tree: light {light} has negative power {power}")
            }
            BuildError::InvertedBounds { light } => {
                write!(f, "light tree: light {light} has aabb_min > aabb_max")
            }
            BuildError::AngleOutOfRange { light } => {
                write!(
                    f,
                    "light tree: light {light} has theta_o or theta_e outside [0, pi]"
                )
            }
            BuildError::ZeroAxis { light } => {
                write!(
                    f,
                    "light tree: light {light} has a zero axis but theta_o < pi"
                )
            }
            BuildError::BoundsTooLarge => {
                write!(f, "light tree: the lights' bounding box overflows f32")
            }
            BuildError::EmitterCount { lights, emitters } => {
                write!(
                    f,
                    "light tree: {emitters} SG emitters given for {lights} lights"
                )
            }
            BuildError::BadEmitter { light } => {
                write!(
                    f,
                    "light tree: SG emitter {light} has a negative variance or a mean direction longer than 1"
                )
            }
        }
    }
}

impl std::error::Error for BuildError {}

const FLAG_LEAF: u8 = 1;
const FLAG_TWO_SIDED: u8 = 2;
/// θo + θe ≤ π/2 and one-sided: all emission goes into the half-space in front of each
/// emitter, so a receiver behind the whole box gets nothing.
const FLAG_HALF_SPACE: u8 = 4;

/// One node of the flattened tree: exactly one cache line holding everything the importance
/// and the descent touch. Rarely used data (exact cone angles, Σ Φ²) lives in
/// [`LightTree::node_extra`].
///
/// A node bounds all the lights of its subtree: the box is the union of their boxes, the cone
/// (axis, θo, θe) contains all their cones, and the power is their sum. Nodes are read-only
/// views obtained from [`LightTree::nodes`] or [`LightTree::node`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node {
    aabb_min: Vec3,
    aabb_max: Vec3,
    radius: f32,
    axis: Vec3,
    power: f32,
    cos_theta_o: f32,
    cos_theta_e: f32,
    num_lights: u32,
    /// Interior: id of the right child. Leaf: index of the light.
    child_or_light: u32,
    depth: u8,
    flags: u8,
}

/// Per-node data that queries rarely need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeExtra {
    /// Normal-spread half-angle θo of the node's cone, radians in [0, π] (exact value of the
    /// union; `Node` only keeps its cosine).
    pub theta_o: f32,
    /// Emission half-angle θe of the node's cone, radians in [0, π] (the largest θe below).
    pub theta_e: f32,
    /// Σ Φᵢ² over the subtree's lights (for the E&K variance metric).
    pub power_sq_sum: f32,
    /// V\[Φ\]/E\[Φ\]² over the subtree's lights (sample variance, N − 1): the squared coefficient
    /// of variation of the lights' powers, unit-free; 0 for one light or zero power.
    pub power_cv2: f32,
}

impl Node {
    /// Centre of the bounding sphere (= centre of the node's AABB).
    #[inline]
    pub fn center(&self) -> Vec3 {
        (self.aabb_min + self.aabb_max) * 0.5
    }
    /// Radius of the bounding sphere (half the AABB diagonal).
    #[inline]
    pub fn radius(&self) -> f32 {
        self.radius
    }
    /// AABB `(min, max)` of the subtree's light bounds.
    #[inline]
    pub fn aabb(&self) -> (Vec3, Vec3) {
        (self.aabb_min, self.aabb_max)
    }
    /// Orientation cone axis (unit).
    #[inline]
    pub fn axis(&self) -> Vec3 {
        self.axis
    }
    /// cos θo: cosine of the half-angle around [`Node::axis`] that holds every emitting normal
    /// of the subtree (−1 when the normals may point anywhere).
    #[inline]
    pub fn cos_theta_o(&self) -> f32 {
        self.cos_theta_o
    }
    /// cos θe: cosine of the largest angle between emitted light and its normal in the
    /// subtree (0 for Lambertian emitters).
    #[inline]
    pub fn cos_theta_e(&self) -> f32 {
        self.cos_theta_e
    }
    /// Total power Φ of the subtree.
    #[inline]
    pub fn power(&self) -> f32 {
        self.power
    }
    /// Number of lights in the subtree (1 for a leaf).
    #[inline]
    pub fn num_lights(&self) -> usize {
        self.num_lights as usize
    }
    /// Number of nodes in the subtree (2·lights − 1).
    #[inline]
    pub fn subtree_size(&self) -> u32 {
        2 * self.num_lights - 1
    }
    /// Depth below the root (root = 0, leaves ≤ 64).
    #[inline]
    pub fn depth(&self) -> u32 {
        self.depth as u32
    }
    /// Whether the node is a leaf, i.e. holds exactly one light ([`Node::light`]).
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.flags & FLAG_LEAF != 0
    }
    /// Some light of the subtree is two-sided (cos θ is then taken as |cos θ|).
    #[inline]
    pub fn two_sided(&self) -> bool {
        self.flags & FLAG_TWO_SIDED != 0
    }
    /// The subtree's emission stays within π/2 of the axis even with θo + θe, so a receiver
    /// behind the whole box gets nothing.
    #[inline]
    pub fn half_space(&self) -> bool {
        self.flags & FLAG_HALF_SPACE != 0
    }
    /// Children `(left, right)` of an interior node, given the node's own id.
    #[inline]
    pub fn children(&self, id: NodeId) -> Option<(NodeId, NodeId)> {
        (!self.is_leaf()).then_some((id + 1, self.child_or_light))
    }
    /// Id of the right child (interior nodes only; the left child is `id + 1`).
    #[inline]
    pub fn right_child(&self) -> Option<NodeId> {
        (!self.is_leaf()).then_some(self.child_or_light)
    }
    /// The light stored in a leaf.
    #[inline]
    pub fn light(&self) -> Option<usize> {
        self.is_leaf().then_some(self.child_or_light as usize)
    }
}

/// A light BVH flattened depth-first; see the crate docs.
///
/// Lights are identified by their index in the slice given to [`LightTree::build`]; nodes by a
/// [`NodeId`]. The tree is immutable once built and can be shared between threads.
#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// Per node: exact cone angles and Σ Φ².
    extra: Vec<NodeExtra>,
    /// Per light: id of its leaf.
    leaf_of: Vec<NodeId>,
    /// Per light: bit k = 1 if the path from the root took the right child at depth k.
    trails: Vec<u64>,
    /// The quantised node pairs the descent reads.
    compact: compact::Compact,
}

impl LightTree {
    /// All nodes in depth-first order; the root is node 0.
    #[inline]
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }
    /// The node with id `id`. Panics if `id` is out of range.
    #[inline]
    pub fn node(&self, id: NodeId) -> &Node {
        &self.nodes[id as usize]
    }
    /// Id of the root node (always 0).
    #[inline]
    pub fn root(&self) -> NodeId {
        0
    }
    /// Number of lights the tree was built from (= number of leaves).
    #[inline]
    pub fn num_lights(&self) -> usize {
        self.leaf_of.len()
    }
    /// Leaf holding `light`.
    #[inline]
    pub fn leaf_of(&self, light: usize) -> NodeId {
        self.leaf_of[light]
    }
    /// Bit trail of `light`: bit k = 1 if its root-to-leaf path goes right at depth k.
    #[inline]
    pub fn bit_trail(&self, light: usize) -> u64 {
        self.trails[light]
    }
    /// Exact cone angles and Σ Φ² of a node.
    #[inline]
    pub fn node_extra(&self, id: NodeId) -> &NodeExtra {
        &self.extra[id as usize]
    }
    /// Orientation cone (axis, θo, θe) of a node.
    #[inline]
    pub fn node_cone(&self, id: NodeId) -> Cone {
        let e = &self.extra[id as usize];
        Cone {
            axis: self.nodes[id as usize].axis,
            theta_o: e.theta_o,
            theta_e: e.theta_e,
        }
    }
    /// DFS id range `[first, last]` of the subtree rooted at `id` (`first == id`).
    #[inline]
    pub fn subtree_range(&self, id: NodeId) -> (NodeId, NodeId) {
        (id, id + self.nodes[id as usize].subtree_size() - 1)
    }
    /// Largest leaf depth.
    pub fn max_depth(&self) -> u32 {
        self.nodes.iter().map(Node::depth).max().unwrap_or(0)
    }
}
