//! The method's LS technique (light-tree sampling at every shading point, the first of its three
//! techniques) behind one trait, so that the three-technique MIS never names an implementation:
//! the tree's E&K cut or one descent ([`crate::tree_selection::TreeSelection`], the paper's) and
//! the learned cluster selection ([`crate::learned::selection::LearnedSelection`],
//! `mis3-adaptive-learned`) live with their own code.
use crate::selection::LightSelection;
use light_tree::LightTree;
use render_core::Vec3;
use render_core::estimator::{PIXEL_MEMORY, SampleContext, ShadingPoint};
use render_core::light::LightSample;
use render_core::rng::SampleStream;
use render_core::scene::Scene;

/// A light selection as the method's LS technique.
pub trait LsTechnique: LightSelection + Send + Sync {
    /// The light tree that BO's cut is of.
    fn tree(&self) -> Option<&LightTree>;
    /// Its state at `sp`; `one_descent`: one descent instead of a cut (our default at the
    /// glossy points, where BO runs).
    fn prepare_ls(&self, scene: &Scene, sp: &ShadingPoint, one_descent: bool) -> Self::State;
    /// Samples a point on the picked `light` (selection probability `pmf`) and shades it:
    /// `(sample, pmf × point pdf, f·L with visibility, the BSDF's density of its direction)`.
    #[allow(clippy::too_many_arguments)]
    fn sample_ls(
        &self,
        state: &Self::State,
        scene: &Scene,
        sp: &ShadingPoint,
        light: u32,
        pmf: f32,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) -> Option<(LightSample, f32, Vec3, f32)>;
    /// Whether its `sample_ls` is [`crate::light_strategy::sample_pick`] (a point on the light
    /// from two numbers, shaded, nothing learnt from the value), so that the method may draw
    /// the same sample before visibility and trace its shadow ray later with the others.
    fn defers_visibility(&self) -> bool {
        false
    }
    /// Forgets what an earlier render taught it.
    fn begin_render(&self) {}
    /// Learns from a finished pass's pixel memories, in pixel order.
    fn end_pass(&self, _pixels: &[&[f32; PIXEL_MEMORY]]) {}
    /// What the render's JSON records of it under `parameters()["learned"]`, if anything.
    fn describe(&self) -> Option<serde_json::Value> {
        None
    }
}
