//! The method's three techniques at one shading point: light-tree sampling (LS), BRDF-oriented
//! light sampling (BO) and BRDF sampling. Each sample drawn is kept with the densities of all
//! three techniques at its light point, so that the strategy can weight it by MIS.
use super::importance::LobeDensity;
use super::ls_technique::LsTechnique;
use super::technique::BoState;
use crate::bsdf_sampling::{sample_bsdf, sample_bsdf_at};
use crate::light_strategy::sample_pick_unshadowed;
use crate::scratch::Pooled;
use brdf_integrals::LobeIntegral;
use light_tree::LightTree;
use render_core::accel::StreamRay;
use render_core::estimator::{SampleContext, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::{Vec2, Vec3};
use std::cell::RefCell;

/// Index of tree-splitting light sampling in [`Taken::p`] and the technique counters.
pub const TECHNIQUE_LS: usize = 0;
/// Index of BRDF-oriented light sampling.
pub const TECHNIQUE_BO: usize = 1;
/// Index of BRDF sampling.
pub const TECHNIQUE_BSDF: usize = 2;

/// A sample with a non-zero unweighted contribution: technique, f·L (shadowed), and the densities
/// of the three techniques at its light point.
#[derive(Clone, Copy, Debug)]
pub struct Taken {
    /// The technique that drew it ([`TECHNIQUE_LS`], [`TECHNIQUE_BO`], [`TECHNIQUE_BSDF`]).
    pub tech: usize,
    /// The sample's index among its technique's samples at this shading point.
    pub index: u32,
    /// f·L·G with visibility, unweighted.
    pub f: Vec3,
    /// The three techniques' densities at its light point (solid angle × selection).
    pub p: [f32; 3],
    /// Its shadow ray in the point's queue ([`PointTechniques::shadows`]) when its visibility
    /// is still to be decided, else [`NO_RAY`].
    pub ray: u32,
}

/// [`Taken::ray`] of a sample whose visibility is already in `f`.
pub const NO_RAY: u32 = u32::MAX;

/// Per-thread buffers of one shading point's queued shadow rays and their answers.
#[derive(Default)]
pub struct ShadowQueue {
    rays: Vec<StreamRay>,
    blocked: Vec<bool>,
}
crate::scratch_pool!(ShadowQueue, |q| {
    q.rays.clear();
    q.blocked.clear();
});

/// One shading point with both cuts made: the LS state (E&K cut or one descent) and, at a
/// glossy point, the BO state (BO cut and its record).
pub struct PointTechniques<'a, L, S: LsTechnique> {
    /// The scene (lights and occlusion).
    pub scene: &'a Scene,
    /// The shading point.
    pub sp: &'a ShadingPoint,
    /// The light tree both cuts are of.
    pub tree: &'a LightTree,
    /// The LS technique.
    pub ls: &'a S,
    /// Its state at this point.
    pub ls_state: S::State,
    /// The BO state, at glossy points.
    pub bo: Option<BoState<'a, L>>,
    /// BO's descent takes a fresh random number per tree level (off: the authors' rescaled one).
    pub fresh: bool,
    /// Where the LS and BO samples' shadow rays wait to be traced together as one stream
    /// ([`PointTechniques::resolve_shadows`]); `None`: each is traced when its sample is drawn.
    /// Only for allocations that never look at a sample's value before all are drawn.
    pub shadows: Option<RefCell<Pooled<ShadowQueue>>>,
}

impl<L: LobeIntegral + LobeDensity, S: LsTechnique> PointTechniques<'_, L, S> {
    /// Densities of the three techniques at a light point (solid angle; delta lights use the
    /// discrete selection probabilities and no BRDF density). `own` is the sampling technique,
    /// whose density the caller already has (left at 0, or computed for a debug check).
    fn densities(
        &self,
        light: usize,
        point: Vec3,
        normal: Vec3,
        wi: Vec3,
        delta: bool,
        own: usize,
        bsdf_pdf: Option<f32>,
    ) -> [f32; 3] {
        let (scene, sp) = (self.scene, self.sp);
        let l = &scene.lights[light];
        let p_ls = if own == TECHNIQUE_LS {
            0.0
        } else {
            let p_pt = if delta {
                1.0
            } else {
                scene.light_pdf(light as u32, sp.point(), sp.normal(), point, normal)
            };
            self.ls.pmf(&self.ls_state, sp, light as u32) * p_pt
        };
        let p_bo = match &self.bo {
            Some(b) if own != TECHNIQUE_BO || cfg!(debug_assertions) => {
                b.selection_pmf(self.tree, light) * b.point_pdf(l, point, normal, wi)
            }
            _ => 0.0,
        };
        let p_bsdf = if delta || own == TECHNIQUE_BSDF {
            0.0
        } else {
            bsdf_pdf.unwrap_or_else(|| sp.bsdf.pdf(sp.wo, wi))
        };
        [p_ls, p_bo, p_bsdf]
    }

    /// LS: one light per cluster of the LS cut (a splitting technique counts as one sample).
    pub fn ls_samples(
        &self,
        taken: &mut Vec<Taken>,
        picks: &mut Vec<(u32, f32)>,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
    ) {
        let (scene, sp) = (self.scene, self.sp);
        self.ls.pick(&self.ls_state, sp, rng, picks);
        let defer = self.shadows.is_some() && self.ls.defers_visibility();
        for &(light, pmf) in picks.iter() {
            ctx.counters.technique_samples[TECHNIQUE_LS] += 1;
            let (sampled, ray) = if defer {
                let s =
                    sample_pick_unshadowed(scene, sp, (light, pmf), rng.next_2d(), ctx.counters);
                match s {
                    Some((s, p, f, p_bsdf, ray)) => (Some((s, p, f, p_bsdf)), self.queue(ray)),
                    None => (None, NO_RAY),
                }
            } else {
                let s = self
                    .ls
                    .sample_ls(&self.ls_state, scene, sp, light, pmf, rng, ctx);
                (s, NO_RAY)
            };
            let Some((s, p_ls, f, p_bsdf)) = sampled else {
                continue;
            };
            let p_bsdf = Some(p_bsdf);
            let mut p = self.densities(
                light as usize,
                s.point,
                s.normal,
                s.wi,
                s.is_delta,
                TECHNIQUE_LS,
                p_bsdf,
            );
            debug_assert!(
                {
                    let replay = self.ls.pmf(&self.ls_state, sp, light)
                        * scene.light_pdf(light, sp.point(), sp.normal(), s.point, s.normal);
                    s.is_delta || (replay - p_ls).abs() <= 1e-3 * p_ls
                },
                "LS pdf at sampling vs replay"
            );
            p[TECHNIQUE_LS] = p_ls;
            taken.push(Taken {
                tech: TECHNIQUE_LS,
                index: 0,
                f,
                p,
                ray,
            });
        }
    }

    /// One BO sample, the `index`-th of this point. `u_cluster`: the cluster choice's number
    /// when the caller stratifies them.
    pub fn bo_sample(
        &self,
        taken: &mut Vec<Taken>,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
        index: u32,
        u_cluster: Option<f32>,
    ) {
        let Some(b) = self.bo.as_ref() else { return };
        let (scene, sp, tree) = (self.scene, self.sp, self.tree);
        ctx.counters.technique_samples[TECHNIQUE_BO] += 1;
        let picked = match u_cluster {
            Some(u) => b.select_with(tree, u, rng, self.fresh),
            None => b.select(tree, rng, self.fresh),
        };
        let Some((light, p_sel)) = picked else {
            return;
        };
        let Some(s) = b.sample_point(&scene.lights[light], rng) else {
            return;
        };
        let p_bo = p_sel * s.pdf;
        if !(p_bo > 0.0) {
            return;
        }
        let (f, p_bsdf, ray) = match &self.shadows {
            None => {
                let (f, p_bsdf) = sp.shade_with_pdf(scene, &s, ctx.counters);
                (f, p_bsdf, NO_RAY)
            }
            Some(_) => {
                let (f, p_bsdf) = sp.unshadowed_with_pdf(&s);
                if f == Vec3::ZERO {
                    return;
                }
                ctx.counters.shadow_rays += 1;
                (f, p_bsdf, self.queue(sp.shadow_ray(scene, &s)))
            }
        };
        if f == Vec3::ZERO {
            return;
        }
        let mut p = self.densities(
            light,
            s.point,
            s.normal,
            s.wi,
            s.is_delta,
            TECHNIQUE_BO,
            Some(p_bsdf),
        );
        debug_assert!(
            (p[TECHNIQUE_BO] - p_bo).abs() <= 1e-3 * p_bo,
            "BO pdf at sampling {p_bo} vs replay {}",
            p[TECHNIQUE_BO]
        );
        p[TECHNIQUE_BO] = p_bo;
        taken.push(Taken {
            tech: TECHNIQUE_BO,
            index,
            f,
            p,
            ray,
        });
    }

    /// One BRDF sample; returns whether it reached an emitter. `u`: the lobe choice's and the
    /// direction's numbers when the caller stratifies them.
    pub fn bsdf_sample(
        &self,
        taken: &mut Vec<Taken>,
        rng: &mut SampleStream,
        ctx: &mut SampleContext,
        u: Option<(f32, Vec2)>,
    ) -> bool {
        let (scene, sp) = (self.scene, self.sp);
        ctx.counters.technique_samples[TECHNIQUE_BSDF] += 1;
        let drawn = match u {
            Some((u_lobe, u_dir)) => sample_bsdf_at(scene, sp, u_lobe, u_dir, ctx.counters),
            None => sample_bsdf(scene, sp, rng, ctx.counters),
        };
        let Some(b) = drawn else {
            return false;
        };
        if !b.found_light() {
            return false;
        }
        let mut p = self.densities(
            b.light as usize,
            b.point,
            b.normal,
            b.wi,
            false,
            TECHNIQUE_BSDF,
            None,
        );
        p[TECHNIQUE_BSDF] = b.pdf;
        taken.push(Taken {
            tech: TECHNIQUE_BSDF,
            index: 0,
            f: b.f_cos * b.radiance,
            p,
            ray: NO_RAY,
        });
        true
    }

    /// Queues a shadow ray; its index in the queue.
    fn queue(&self, ray: StreamRay) -> u32 {
        let mut q = self
            .shadows
            .as_ref()
            .expect("a queue to defer to")
            .borrow_mut();
        q.rays.push(ray);
        (q.rays.len() - 1) as u32
    }

    /// Traces the queued shadow rays as one stream and drops the samples whose ray is
    /// blocked: `taken` is then what tracing each ray at once leaves, in the same order.
    pub fn resolve_shadows(&self, taken: &mut Vec<Taken>) {
        let Some(q) = &self.shadows else { return };
        let mut q = q.borrow_mut();
        if q.rays.is_empty() {
            return;
        }
        let ShadowQueue { rays, blocked } = &mut **q;
        self.scene.occluded_stream(rays, blocked);
        taken.retain(|t| t.ray == NO_RAY || !blocked[t.ray as usize]);
    }

    /// Clusters of the LS cut and of the BO cut (0 without BO).
    pub fn cluster_counts(&self) -> (usize, usize) {
        (
            self.ls.clusters(&self.ls_state),
            self.bo.as_ref().map_or(0, |b| b.cut().cut.len()),
        )
    }
}
