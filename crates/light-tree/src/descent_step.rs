//! The random decisions of a descent ([`DescentRandom`], with the two ready-made sources
//! [`Rescaled`] and [`Fresh`]) and one binary step between two children ([`choose`]), with the
//! probability its pmf replay multiplies in ([`chosen`]): what every descent of the tree shares.

/// Source of the random decisions in a descent.
///
/// Implement it to drive [`LightTree::sample_subtree`] with your own sampler; [`Rescaled`]
/// and [`Fresh`] are the two ready-made choices, both from 64 random bits.
pub trait DescentRandom {
    /// Returns `true` (go left) with probability `p_left`, `0 < p_left ≤ 1`.
    fn go_left(&mut self, p_left: f32) -> bool;
    /// A uniform 64-bit number for a choice among several children (the eight-wide
    /// descent's step, `oct_descent.rs`, which uses its top 63 bits).
    fn draw(&mut self) -> u64;
    /// After such a choice took the range [lo, lo + `width`) of [0, 2⁶³) (0 < width ≤ 2⁶³),
    /// where the drawn number's top 63 bits were lo + `offset`: a rescaling source continues
    /// with ⌊2⁶⁴ · offset / width⌋.
    fn chose(&mut self, offset: u64, width: u64);
}

/// 2⁶⁴ · `p` as an integer: 64 uniform bits fall below it with probability `p` (to 2⁻⁶⁴).
/// Exact for p ≥ 2⁻⁴¹ (an f32 has 24 significant bits), truncated below; p = 1 saturates at
/// 2⁶⁴ − 1.
#[inline]
fn threshold(p: f32) -> u64 {
    (p as f64 * 18_446_744_073_709_551_616.0) as u64
}

/// One 64-bit uniform number rescaled at every level (E&K / pbrt-v4 style, in fixed point):
/// at a node with left probability p, go left when u < t = 2⁶⁴p and continue with
/// ⌊2⁶⁴u/t⌋, else with ⌊2⁶⁴(u − t)/(2⁶⁴ − t)⌋. A decision of probability p uses up log₂(1/p)
/// of the 64 bits, so a descent to a light of probability P keeps 64 − log₂(1/P) bits for
/// the levels below (an f32 kept 24 − log₂(1/P): none at 2²⁴ lights).
#[derive(Clone, Copy, Debug)]
pub struct Rescaled(
    /// The current uniform number in [0, 2⁶⁴), rescaled in place after every decision.
    pub u64,
);

impl DescentRandom for Rescaled {
    #[inline]
    fn go_left(&mut self, p_left: f32) -> bool {
        const ONE: u128 = 1 << 64;
        let (u, t) = (self.0 as u128, threshold(p_left) as u128);
        // Both quotients are below 2⁶⁴: u < t on the left, u − t < 2⁶⁴ − t on the right.
        if u < t {
            self.0 = ((u << 64) / t) as u64;
            true
        } else {
            self.0 = (((u - t) << 64) / (ONE - t)) as u64;
            false
        }
    }
    #[inline]
    fn draw(&mut self) -> u64 {
        self.0
    }
    #[inline]
    fn chose(&mut self, offset: u64, width: u64) {
        // The quotient is below 2⁶⁴ since offset < width.
        self.0 = (((offset as u128) << 64) / width as u128) as u64;
    }
}

/// 64 fresh random bits per level (Liu et al.'s improvement), drawn from the wrapped closure.
pub struct Fresh<F: FnMut() -> u64>(
    /// Called once per random decision (an interior node whose two children both have
    /// non-zero importance); must return independent uniform 64-bit numbers.
    pub F,
);

impl<F: FnMut() -> u64> DescentRandom for Fresh<F> {
    #[inline]
    fn go_left(&mut self, p_left: f32) -> bool {
        (self.0)() < threshold(p_left)
    }
    #[inline]
    fn draw(&mut self) -> u64 {
        (self.0)()
    }
    #[inline]
    fn chose(&mut self, _: u64, _: u64) {}
}

impl<R: DescentRandom + ?Sized> DescentRandom for &mut R {
    #[inline]
    fn go_left(&mut self, p_left: f32) -> bool {
        (**self).go_left(p_left)
    }
    #[inline]
    fn draw(&mut self) -> u64 {
        (**self).draw()
    }
    #[inline]
    fn chose(&mut self, offset: u64, width: u64) {
        (**self).chose(offset, width)
    }
}

/// Importance as used by the descent: NaN and negative values count as 0, and values are
/// capped at f32::MAX / 4 so that the sum of two stays finite.
#[inline]
pub(crate) fn sanitize(i: f32) -> f32 {
    if i > 0.0 { i.min(f32::MAX / 4.0) } else { 0.0 }
}

/// One step of a descent between children of importances `il`, `ir` (sanitised): `(go left,
/// the step's probability)`, or `None` when both are 0. A child of importance 0 is never taken
/// and consumes no random number. `pmf_subtree` and `pmf_from` replay the same quotients.
#[inline(always)]
pub(crate) fn choose<R: DescentRandom>(il: f32, ir: f32, rng: &mut R) -> Option<(bool, f32)> {
    let sum = il + ir;
    if sum == 0.0 {
        return None;
    }
    let pl = il / sum;
    let left = if ir == 0.0 {
        true
    } else if il == 0.0 {
        false
    } else {
        rng.go_left(pl)
    };
    Some(if left { (true, pl) } else { (false, ir / sum) })
}

/// The probability with which [`choose`] takes the right (`right`) or left child between
/// sanitised importances `il`, `ir`, by the same quotients; `None` when both are 0. What the
/// pmf replays multiply in.
#[inline(always)]
pub(crate) fn chosen(il: f32, ir: f32, right: bool) -> Option<f32> {
    let sum = il + ir;
    (sum != 0.0).then(|| if right { ir / sum } else { il / sum })
}
