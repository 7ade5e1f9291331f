//! The body of the wide descent nodes: N compact slots side by side, structure of arrays, so
//! that one N-lane pass evaluates them all (`QuadNode`: a node's four grandchildren; `OctNode`:
//! its eight great-grandchildren).

use crate::codes::{LEAF_BIT, Slot, Slots};

/// N slots, structure of arrays.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub(crate) struct LaneSlots<const N: usize> {
    qbox: [[u16; N]; 6],
    axis: [[i16; N]; 3],
    cos_o: [i16; N],
    cos_e: [i16; N],
    power: [f32; N],
    /// Interior slot: index of its own wide node. Leaf: `LEAF_BIT | light`. Empty: `LEAF_BIT`
    /// with zero power, never chosen.
    pub(crate) child: [u32; N],
    flags: [u8; N],
}

impl<const N: usize> Default for LaneSlots<N> {
    fn default() -> Self {
        LaneSlots {
            qbox: [[0; N]; 6],
            axis: [[0; N]; 3],
            cos_o: [0; N],
            cos_e: [0; N],
            power: [0.0; N],
            child: [0; N],
            flags: [0; N],
        }
    }
}

impl<const N: usize> LaneSlots<N> {
    /// Lane `lane` holds slot `s`, whose code (wide node or light) is `child`.
    pub(crate) fn set(&mut self, lane: usize, s: &Slot, child: u32) {
        for k in 0..6 {
            self.qbox[k][lane] = s.qbox[k];
        }
        for k in 0..3 {
            self.axis[k][lane] = s.axis[k];
        }
        self.cos_o[lane] = s.cos_o;
        self.cos_e[lane] = s.cos_e;
        self.power[lane] = s.power;
        self.flags[lane] = s.flags;
        self.child[lane] = child;
    }

    /// A lane of zero power (importance 0; a valid axis keeps NaN out of it).
    pub(crate) fn set_empty(&mut self, lane: usize) {
        self.axis[2][lane] = i16::MAX;
        self.child[lane] = LEAF_BIT;
    }
}

impl<const N: usize> Slots<N> for LaneSlots<N> {
    #[inline(always)]
    fn qbox(&self, k: usize) -> [u16; N] {
        self.qbox[k]
    }
    #[inline(always)]
    fn axis(&self, k: usize) -> [i16; N] {
        self.axis[k]
    }
    #[inline(always)]
    fn cos_o(&self) -> [i16; N] {
        self.cos_o
    }
    #[inline(always)]
    fn cos_e(&self) -> [i16; N] {
        self.cos_e
    }
    #[inline(always)]
    fn power(&self) -> [f32; N] {
        self.power
    }
    #[inline(always)]
    fn flags(&self) -> [u8; N] {
        self.flags
    }
}
