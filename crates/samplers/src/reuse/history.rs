//! Reuse across passes (`--restir-history CAP`): each pixel's final reservoir of the previous
//! pass, with the shading point it was made for, resampled with the pixel's new first
//! reservoir before the spatial rounds. This is the paper's temporal reuse for a still camera:
//! the pixel's camera sample moves within its footprint from pass to pass, so the previous
//! pass's shading point is another domain in GRIS's sense, combined by the same pairwise MIS
//! weights as a neighbour (with its shadow ray), and only where it passes the neighbours' test
//! (normal within 25°, depth within 10%).
//!
//! The previous reservoir's confidence is capped at CAP times the new reservoir's (the paper
//! caps at 20), so that an old sample cannot outweigh fresh candidates forever. A pass is then
//! unbiased but no longer independent of the passes before it: the render says so
//! (`ImageSpaceLighting::correlates_passes`), and its per-pixel variance understates the error.
use super::reservoir::Reservoir;
use super::spatial::{alike, biased_resample, pairwise_resample};
use render_core::estimator::ShadingPoint;
use render_core::image_space::{ImagePass, PassCarry};
use render_core::rng::SampleStream;
use render_core::stats::Counters;

/// The phase number of the reuse across passes (apart from the spatial rounds' 1..=8).
pub const HISTORY_PHASE: u32 = 16;

/// What a pass hands to the next: every pixel's final reservoir and its shading point.
pub struct History {
    reservoirs: Vec<Reservoir>,
    points: Vec<Option<ShadingPoint>>,
}

impl History {
    /// The pass's final reservoirs, for the next pass.
    pub fn keep(pass: &ImagePass, reservoirs: Vec<Reservoir>, carry: &mut PassCarry) {
        *carry = Some(Box::new(History {
            reservoirs,
            points: pass.points.to_vec(),
        }));
    }

    /// What the previous pass left, if it was a pass of the same image.
    pub fn of<'a>(pass: &ImagePass, carry: &'a PassCarry) -> Option<&'a History> {
        let h = carry.as_ref()?.downcast_ref::<History>()?;
        (h.points.len() == pass.points.len()).then_some(h)
    }

    /// Pixel `i`'s new reservoir `cur[i]` resampled with its previous one (confidence capped at
    /// `cap` × the new one's), unbiased (`pairwise`) or by the 1/M form.
    pub fn reuse(
        &self,
        pass: &ImagePass,
        (cur, i): (&[Reservoir], usize),
        (cap, pairwise): (f32, bool),
        rng: &mut SampleStream,
        c: &mut Counters,
    ) -> Reservoir {
        let r0 = cur[i];
        let (Some(sp0), Some(sp1)) = (&pass.points[i], &self.points[i]) else {
            return r0;
        };
        if !alike(sp0, sp1, pass.camera_position) {
            return r0;
        }
        let r1 = Reservoir {
            c: self.reservoirs[i].c.min(cap * r0.c),
            ..self.reservoirs[i]
        };
        if pairwise {
            pairwise_resample(pass.scene, (r0, sp0), std::iter::once((r1, sp1)), rng, c)
        } else {
            biased_resample(pass.scene, (r0, sp0), std::iter::once(r1), rng)
        }
    }
}
