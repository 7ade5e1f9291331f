//! LTC placeholder (filled in below).
use crate::{CapIntegral, LobeIntegral};
use glam::Vec3;
#[derive(Clone, Debug, Default)]
pub struct Ltc;
#[derive(Clone, Copy, Debug)]
pub struct LtcLobe;
impl LobeIntegral for LtcLobe {
    fn integral(&self, _a: Vec3, _c: f32) -> f32 {
        0.0
    }
    fn hemisphere(&self) -> f32 {
        0.0
    }
}
impl CapIntegral for Ltc {
    type Lobe = LtcLobe;
    fn lobe(&self, _w: Vec3, _a: f32) -> LtcLobe {
        LtcLobe
    }
}
pub const MAGIC: &[u8; 8] = b"LTCGGX01";
pub fn fit_table(_s: usize, _a: usize, _p: impl Fn(usize) + Sync) -> crate::table::Table<6> {
    unimplemented!()
}
