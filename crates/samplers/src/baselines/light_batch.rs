//! [`LightStrategy`]'s batched form (`render_core::batch`), in phases over a work unit's
//! shading points: each point draws its numbers and picks its lights (the picked lights'
//! records prefetched); each samples its BSDF direction; each light sample is shaded before
//! visibility; the BSDF rays and the shadow rays are traced as two streams; each point's
//! estimate is summed.
//!
//! Every point gets [`DirectLighting::estimate`]'s value bit for bit: its numbers come from
//! its own stream in `estimate`'s order, the same operations run on them, and its terms are
//! added in the same order (the light picks in pick order, the BSDF sample's term last).
//!
//! [`DirectLighting::estimate`]: render_core::estimator::DirectLighting::estimate
use super::light_strategy::{
    LightStrategy, Picks, TECHNIQUE_BSDF, TECHNIQUE_LIGHT, sample_pick_unshadowed,
};
use crate::bsdf_sampling::{BsdfDirection, bsdf_direction};
use crate::mis::power2;
use crate::scratch::Pooled;
use crate::selection::LightSelection;
use render_core::accel::StreamRay;
use render_core::batch::{BatchLighting, ShadingBatch};
use render_core::estimator::ShadingPoint;
use render_core::rng::SampleStream;
use render_core::scene::Scene;
use render_core::stats::Counters;
use render_core::{Vec2, Vec3};
use std::ops::Range;

/// A shading point's share of the batch.
struct PointWork<'a, St> {
    sp: &'a ShadingPoint,
    /// Its index in the batch.
    point: usize,
    state: St,
    /// Its picks in the batch's list, in pick order.
    picks: Range<usize>,
    /// The BSDF sample's three numbers (lobe choice, direction), when the strategy has one.
    bsdf_numbers: Option<(f32, Vec2)>,
    /// The BSDF sample and its ray's index in the BSDF stream.
    bsdf: Option<(BsdfDirection, usize)>,
}

/// A light pick: the light, its selection probability and its point's two numbers.
struct Pick {
    light: u32,
    pmf: f32,
    u: Vec2,
}

/// A light sample's MIS-weighted term before visibility, and its ray's index in the shadow
/// stream.
struct Pending {
    term: Vec3,
    ray: usize,
}

impl<S: LightSelection> BatchLighting for LightStrategy<S> {
    fn estimate_batch(&self, scene: &Scene, b: ShadingBatch<'_>) {
        let g = self.selection.batch_group();
        let groups = b.points.chunks(g).zip(b.rngs.chunks_mut(g));
        for ((points, rngs), out) in groups.zip(b.out.chunks_mut(g)) {
            self.estimate_group(scene, (points, rngs), b.counters, out);
        }
    }
}

impl<S: LightSelection> LightStrategy<S> {
    /// The phases over one group of points.
    fn estimate_group(
        &self,
        scene: &Scene,
        (points, rngs): (&[Option<ShadingPoint>], &mut [SampleStream]),
        counters: &mut Counters,
        out: &mut [Vec3],
    ) {
        for (sp, rng) in points.iter().zip(rngs.iter()) {
            if sp.is_some() {
                self.selection.prefetch_pick(rng);
            }
        }
        let mut picks = Vec::new();
        let mut work: Vec<_> = (points.iter().zip(rngs.iter_mut()).enumerate())
            .filter_map(|(i, (sp, rng))| {
                let sp = sp.as_ref()?;
                Some(self.draw(scene, (sp, i), rng, counters, &mut picks))
            })
            .collect();
        let mut bsdf_rays = Vec::new();
        for w in &mut work {
            if let Some((u_lobe, u)) = w.bsdf_numbers {
                counters.technique_samples[TECHNIQUE_BSDF] += 1;
                if let Some(d) = bsdf_direction(w.sp, u_lobe, u, counters) {
                    w.bsdf = Some((d, bsdf_rays.len()));
                    bsdf_rays.push(d.ray(w.sp));
                }
            }
        }
        let mut shadow_rays = Vec::new();
        let mut pending = Vec::with_capacity(picks.len());
        for w in &work {
            for p in &picks[w.picks.clone()] {
                counters.technique_samples[TECHNIQUE_LIGHT] += 1;
                pending.push(self.light_term(scene, w.sp, p, &mut shadow_rays, counters));
            }
        }
        let (mut hits, mut surfaces, mut blocked) = (Vec::new(), Vec::new(), Vec::new());
        scene.intersect_stream(&bsdf_rays, &mut hits, &mut surfaces);
        scene.occluded_stream(&shadow_rays, &mut blocked);
        for w in &work {
            let mut l = Vec3::ZERO;
            for t in pending[w.picks.clone()].iter().flatten() {
                if !blocked[t.ray] {
                    l += t.term;
                }
            }
            if let Some((d, ray)) = w.bsdf {
                l += self.bsdf_term(scene, w, d.found(scene, surfaces[ray]));
            }
            out[w.point] = l;
        }
    }

    /// A point's numbers, in `estimate`'s order: its picks' (the selection's, then each
    /// pick's point), then its BSDF sample's.
    fn draw<'a>(
        &self,
        scene: &Scene,
        (sp, point): (&'a ShadingPoint, usize),
        rng: &mut SampleStream,
        counters: &mut Counters,
        picks: &mut Vec<Pick>,
    ) -> PointWork<'a, S::State> {
        let state = self.selection.prepare(scene, sp);
        let mut chosen = Pooled::<Picks>::take();
        self.selection.pick(&state, sp, rng, &mut chosen.0);
        crate::work_counters::record(
            counters,
            !sp.bsdf.is_pure_diffuse(),
            self.selection.clusters(&state),
            0,
            self.with_bsdf as usize,
        );
        let start = picks.len();
        for &(light, pmf) in &chosen.0 {
            picks.push(Pick {
                light,
                pmf,
                u: rng.next_2d(),
            });
        }
        let bsdf_numbers = self.with_bsdf.then(|| (rng.next_f32(), rng.next_2d()));
        for p in &picks[start..] {
            scene.prefetch_light(p.light);
        }
        PointWork {
            sp,
            point,
            state,
            picks: start..picks.len(),
            bsdf_numbers,
            bsdf: None,
        }
    }

    /// A light pick's point and weighted term, its shadow ray queued; `None` where the
    /// per-sample path adds nothing before visibility.
    fn light_term(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        p: &Pick,
        rays: &mut Vec<StreamRay>,
        counters: &mut Counters,
    ) -> Option<Pending> {
        let (s, p_light, f, p_bsdf, ray) =
            sample_pick_unshadowed(scene, sp, (p.light, p.pmf), p.u, counters)?;
        let w = if self.with_bsdf && !s.is_delta {
            power2(p_light, p_bsdf)
        } else {
            1.0
        };
        rays.push(ray);
        Some(Pending {
            term: f * (w / p_light),
            ray: rays.len() - 1,
        })
    }

    /// The BSDF sample's MIS-weighted term, once its ray has been traced.
    fn bsdf_term(
        &self,
        scene: &Scene,
        w: &PointWork<'_, S::State>,
        b: crate::bsdf_sampling::BsdfLightHit,
    ) -> Vec3 {
        if !b.found_light() {
            return Vec3::ZERO;
        }
        let sp = w.sp;
        let p_light = self.selection.pmf(&w.state, sp, b.light)
            * scene.light_pdf(b.light, sp.point(), sp.normal(), b.point, b.normal);
        b.f_cos * b.radiance * (power2(b.pdf, p_light) / b.pdf)
    }
}
