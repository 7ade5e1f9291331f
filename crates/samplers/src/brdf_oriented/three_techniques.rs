//! The method's three techniques at one shading point: light-tree sampling (LS), BRDF-oriented
//! light sampling (BO) and BRDF sampling. Each sample drawn is kept with the densities of all
//! three techniques at its light point, so that the strategy can weight it by MIS.
use super::importance::LobeDensity;
use super::ls_technique::LsTechnique;
use super::technique::BoState;
use crate::bsdf_sampling::{sample_bsdf, sample_bsdf_at};
use brdf_integrals::LobeIntegral;
use light_tree::LightTree;
use render_core::estimator::{SampleContext, ShadingPoint};
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::{Vec2, Vec3};

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
}

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
        for &(light, pmf) in picks.iter() {
            ctx.counters.technique_samples[TECHNIQUE_LS] += 1;
            let sampled = self
                .ls
                .sample_ls(&self.ls_state, scene, sp, light, pmf, rng, ctx)
                .map(|(s, p, f, p_bsdf)| (s, p, f, Some(p_bsdf)));
            let Some((s, p_ls, f, p_bsdf)) = sampled else {
                continue;
            };
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
        let (f, p_bsdf) = sp.shade_with_pdf(scene, &s, ctx.counters);
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
        });
        true
    }

    /// Clusters of the LS cut and of the BO cut (0 without BO).
    pub fn cluster_counts(&self) -> (usize, usize) {
        (
            self.ls.clusters(&self.ls_state),
            self.bo.as_ref().map_or(0, |b| b.cut().cut.len()),
        )
    }
}
