//! The light tree over a scene's lights, built once per scene and set of bounds and shared by
//! every strategy of every render of that scene ([`render_core::derived`]): the build is a pure
//! function of the bounds (deterministic for any thread count), so a tree found again is the
//! tree a new build would give, bit for bit. Rendering one scene again (from Python, say)
//! skips the build, a quarter of a second on 80,000 lights.
use light_tree::{LightBounds, LightTree};
use render_core::scene::Scene;
use std::ops::Deref;
use std::sync::Arc;

/// A tree and the bounds it was built over, as the scene keeps it.
struct Kept {
    bounds: Vec<LightBounds>,
    tree: LightTree,
}

/// A shared light tree: reads as a [`LightTree`].
#[derive(Clone)]
pub struct SharedTree(Arc<Kept>);

impl Deref for SharedTree {
    type Target = LightTree;

    fn deref(&self) -> &LightTree {
        &self.0.tree
    }
}

impl SharedTree {
    /// Whether `self` and `other` are one tree (not two equal builds).
    pub fn same_build(&self, other: &SharedTree) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The tree over `bounds` (non-empty) for `scene`: the scene's kept one for equal bounds, else
/// a new build, then kept.
pub fn shared_tree(scene: &Scene, bounds: Vec<LightBounds>) -> Result<SharedTree, String> {
    scene
        .derived
        .get_or_make(
            |k: &Kept| k.bounds == bounds,
            || {
                // (the build error's message starts with "light tree: ")
                let tree = LightTree::build(&bounds).map_err(|e| e.to_string())?;
                Ok(Kept {
                    bounds: bounds.clone(),
                    tree,
                })
            },
        )
        .map(SharedTree)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::baselines::tree_selection::{PowerUnits, light_bounds};

    /// Equal bounds find the scene's tree again; other bounds (the authors' power units) and
    /// another scene build their own; a tree found again is the tree a new build gives.
    #[test]
    fn equal_bounds_share_one_build() {
        let load = || scene_formats::load_scene("builtin:glossy-spheres?lights=64", None).unwrap();
        let scene = load();
        let watts = || light_bounds(&scene, PowerUnits::Watts);
        let a = shared_tree(&scene, watts()).unwrap();
        let b = shared_tree(&scene, watts()).unwrap();
        assert!(a.same_build(&b));
        let authors = shared_tree(&scene, light_bounds(&scene, PowerUnits::Authors)).unwrap();
        assert!(!a.same_build(&authors));
        let other = load();
        let fresh = shared_tree(&other, light_bounds(&other, PowerUnits::Watts)).unwrap();
        assert!(!a.same_build(&fresh));
        let (x, n) = (render_core::Vec3::new(0.1, 0.5, 0.2), render_core::Vec3::Y);
        for light in 0..64 {
            let (p, q) = (
                a.pmf_from(a.root(), x, n, light),
                fresh.pmf_from(fresh.root(), x, n, light),
            );
            assert_eq!(p.to_bits(), q.to_bits(), "light {light}");
        }
    }

    /// Two selections created on one scene hold one tree (the golden images, rendered with
    /// strategies created one after another on each scene, check that they render the same).
    #[test]
    fn strategies_of_one_scene_share_its_tree() {
        let scene = scene_formats::load_scene("builtin:glossy-spheres?lights=64", None).unwrap();
        let opts = crate::StrategyOptions::default();
        let tree_of = |s: &crate::baselines::tree_selection::TreeSelection| s.tree.clone().unwrap();
        let units = opts.power_units();
        let mode = crate::baselines::tree_selection::TreeMode::Single;
        let one =
            crate::baselines::tree_selection::TreeSelection::new(&scene, mode, units).unwrap();
        let two =
            crate::baselines::tree_selection::TreeSelection::new(&scene, mode, units).unwrap();
        assert!(tree_of(&one).same_build(&tree_of(&two)));
    }

    /// A tree that cannot be built says so once ("light tree: light tree: ..." before).
    #[test]
    fn a_failed_build_is_named_once() {
        let scene = scene_formats::load_scene("builtin:glossy-spheres?lights=4", None).unwrap();
        let mut bounds = light_bounds(&scene, PowerUnits::Watts);
        bounds[0].power = f32::INFINITY;
        let e = shared_tree(&scene, bounds).err().expect("must fail");
        assert_eq!(e.matches("light tree:").count(), 1, "{e}");
        assert!(e.starts_with("light tree: light 0 has"), "{e}");
    }

    /// Every strategy built on the light tree reports lights that make none as the scene's
    /// fault (`StrategyError::Scene`), not as a bad option.
    #[test]
    fn strategies_on_a_tree_blame_the_scene_for_a_failed_build() {
        let mut scene = scene_formats::load_scene("builtin:glossy-spheres?lights=4", None).unwrap();
        scene.lights[0].emission = render_core::Vec3::INFINITY;
        scene.lights[0].mean_emission = render_core::Vec3::INFINITY;
        let opts = crate::StrategyOptions::default();
        let names = [
            "tree",
            "tree+bsdf",
            "sg-tree",
            "slc",
            "rht",
            "varl",
            "mis3-adaptive",
            "ris",
            "restir-bo",
        ];
        for name in names {
            let e = crate::create(name, &scene, &opts)
                .err()
                .unwrap_or_else(|| panic!("{name} must fail"));
            assert!(matches!(e, crate::StrategyError::Scene(_)), "{name}: {e}");
        }
    }
}
