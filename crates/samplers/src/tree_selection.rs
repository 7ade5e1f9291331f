//! Light-tree selection (Conty Estevez & Kulla 2018): a single stochastic descent, or
//! adaptive splitting into a cut with one light drawn per cluster.
use crate::selection::LightSelection;
use light_tree::{Cut, LightBounds, LightTree, Rescaled};
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::Scene;

/// The bounds the tree is built over, one per scene light, in scene order.
pub fn light_bounds(scene: &Scene) -> Vec<LightBounds> {
    scene
        .lights
        .iter()
        .map(|l| {
            let (lo, hi) = l.bounds();
            let (axis, theta_o, theta_e) = l.orientation();
            LightBounds {
                aabb_min: lo,
                aabb_max: hi,
                axis,
                theta_o,
                theta_e,
                power: l.power(),
                two_sided: l.two_sided,
            }
        })
        .collect()
}

/// How the tree is used at a shading point.
#[derive(Clone, Copy, Debug)]
pub enum TreeMode {
    /// One descent from the root.
    Single,
    /// Split nodes whose importance estimate is unreliable (E&K's normalised variance below
    /// `tau`, or the point inside the node's bounds), up to `max_cut` clusters.
    Split { tau: f32, max_cut: usize },
}

pub struct TreeSelection {
    pub tree: Option<LightTree>,
    pub mode: TreeMode,
}

impl TreeSelection {
    pub fn new(scene: &Scene, mode: TreeMode) -> Result<TreeSelection, String> {
        let bounds = light_bounds(scene);
        let tree = if bounds.is_empty() {
            None
        } else {
            Some(LightTree::build(&bounds).map_err(|e| format!("light tree: {e}"))?)
        };
        Ok(TreeSelection { tree, mode })
    }
}

impl LightSelection for TreeSelection {
    /// The cut for splitting; unused for a single descent.
    type State = Option<Cut>;

    fn prepare(&self, _: &Scene, sp: &ShadingPoint) -> Option<Cut> {
        match (&self.tree, self.mode) {
            (Some(t), TreeMode::Split { tau, max_cut }) => {
                Some(t.adaptive_cut(sp.point(), sp.bsdf.ng, tau, max_cut))
            }
            _ => None,
        }
    }

    fn pick(
        &self,
        cut: &Option<Cut>,
        sp: &ShadingPoint,
        rng: &mut SampleStream,
        picks: &mut Vec<(u32, f32)>,
    ) {
        let Some(tree) = &self.tree else { return };
        let (x, n) = (sp.point(), sp.bsdf.ng);
        match cut {
            None => {
                if let Some((light, pmf)) = tree.sample(x, n, rng.next_f32()) {
                    picks.push((light as u32, pmf));
                }
            }
            Some(cut) => {
                for &node in &cut.nodes {
                    let mut u = Rescaled(rng.next_f32());
                    if let Some((light, pmf)) =
                        tree.sample_subtree(node, |c| tree.importance(c, x, n), &mut u)
                    {
                        picks.push((light as u32, pmf));
                    }
                }
            }
        }
    }

    fn pmf(&self, cut: &Option<Cut>, sp: &ShadingPoint, light: u32) -> f32 {
        let Some(tree) = &self.tree else { return 0.0 };
        let (x, n) = (sp.point(), sp.bsdf.ng);
        match cut {
            None => tree.pmf(x, n, light as usize),
            Some(cut) => match cut.cluster_of(tree, light as usize) {
                Some(k) => {
                    tree.pmf_subtree(cut.nodes[k], |c| tree.importance(c, x, n), light as usize)
                }
                None => 0.0,
            },
        }
    }
}
