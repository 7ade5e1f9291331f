//! The SG tree's light selection: one descent from the root by the SG importance, with one
//! rescaled random number (as `tree`), and its pmf replayed along the light's bit trail. The
//! importances of a shading point are memoised, so the pick and every pmf replay read the same
//! numbers bit for bit.
use super::importance::SgShading;
use crate::memo::NodeMemo;
use crate::scratch::Pooled;
use crate::selection::LightSelection;
use crate::shared_tree::SharedTree;
use crate::shared_tree::shared_tree;
use crate::tree_selection::{PowerUnits, light_bounds};
use light_tree::{LightTree, NodeId, Rescaled, SgEmitter, SgNodes};
use render_core::estimator::ShadingPoint;
use render_core::light::LightShape;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use std::cell::RefCell;

/// One SG emitter per scene light, in scene order: triangles uniform over their surface,
/// spheres isotropic, spot lights uniform in their outer cone.
pub fn sg_emitters(scene: &Scene) -> Vec<SgEmitter> {
    scene
        .lights
        .iter()
        .map(|l| match (&l.shape, &l.spot) {
            (LightShape::Triangle { p, normal, .. }, _) => {
                SgEmitter::triangle(*p, *normal, l.two_sided)
            }
            (LightShape::Sphere { center, radius }, _) => SgEmitter::sphere(*center, *radius),
            (LightShape::Point { position }, Some(s)) => {
                SgEmitter::spot(*position, s.direction, s.cos_outer)
            }
            (LightShape::Point { position }, None) => SgEmitter::point(*position),
        })
        .collect()
}

/// The light tree with its SG lights (none without lights).
pub struct SgTreeSelection {
    tree: Option<(SharedTree, SgNodes)>,
}

impl SgTreeSelection {
    /// Builds the tree over `scene`'s lights (power in `units`) and fits its SG lights.
    pub fn new(scene: &Scene, units: PowerUnits) -> Result<SgTreeSelection, String> {
        let bounds = light_bounds(scene, units);
        if bounds.is_empty() {
            return Ok(SgTreeSelection { tree: None });
        }
        let tree = shared_tree(scene, bounds)?;
        let sg = SgNodes::build(&tree, &sg_emitters(scene)).map_err(|e| format!("SG tree: {e}"))?;
        Ok(SgTreeSelection {
            tree: Some((tree, sg)),
        })
    }

    /// The tree and its SG lights, if the scene has lights.
    pub fn tree(&self) -> Option<(&LightTree, &SgNodes)> {
        self.tree.as_ref().map(|(t, s)| (&**t, s))
    }
}

/// Per-thread memo of one shading point's SG importances.
#[derive(Default)]
pub struct SgScratch {
    memo: RefCell<NodeMemo>,
}

crate::scratch_pool!(SgScratch, |s| s.memo.get_mut().invalidate());

/// One shading point's SG record and memoised importances.
pub struct SgState {
    scratch: Pooled<SgScratch>,
    shading: SgShading,
}

impl SgState {
    /// The SG importance of `node` at this shading point (memoised).
    #[inline]
    pub fn importance(&self, tree: &LightTree, sg: &SgNodes, node: NodeId) -> f32 {
        let shading = &self.shading;
        self.scratch
            .memo
            .borrow_mut()
            .get_or(node, |id| shading.importance(tree.node(id), sg.node(id)))
    }
}

impl LightSelection for SgTreeSelection {
    type State = SgState;

    fn prepare(&self, _: &Scene, sp: &ShadingPoint) -> SgState {
        SgState {
            scratch: Pooled::take(),
            shading: SgShading::new(sp),
        }
    }

    fn pick(
        &self,
        state: &SgState,
        _: &ShadingPoint,
        rng: &mut SampleStream,
        picks: &mut Vec<(u32, f32)>,
    ) {
        let Some((tree, sg)) = &self.tree else { return };
        let imp = |id| state.importance(tree, sg, id);
        if let Some((light, pmf)) =
            tree.sample_subtree(tree.root(), imp, &mut Rescaled(rng.next_u64()))
        {
            picks.push((light as u32, pmf));
        }
    }

    fn pmf(&self, state: &SgState, _: &ShadingPoint, light: u32) -> f32 {
        let Some((tree, sg)) = &self.tree else {
            return 0.0;
        };
        tree.pmf_subtree(
            tree.root(),
            |id| state.importance(tree, sg, id),
            light as usize,
        )
    }
}
