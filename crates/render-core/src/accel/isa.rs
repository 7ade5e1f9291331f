//! The traversals compiled for each wide instruction set: `#[target_feature]` entry points
//! into which the generic loops and their node test are inlined. Callers check the CPU first
//! ([`super::Simd::available`]).
#![cfg(target_arch = "x86_64")]

/// Single-ray and stream traversals with node test `$test`, compiled with `$features`.
macro_rules! compiled_for {
    ($name:ident, $features:literal, $test:ty) => {
        pub mod $name {
            use super::super::collapse::Wide;
            use super::super::traverse::{self, Entry};
            use super::super::{Hit, StreamRay, coherent, stream};
            use glam::Vec3;
            use std::mem::MaybeUninit;

            #[target_feature(enable = $features)]
            pub unsafe fn closest(
                w: &Wide,
                o: Vec3,
                d: Vec3,
                tmin: f32,
                tmax: f32,
                stack: &mut [MaybeUninit<Entry>],
            ) -> Option<Hit> {
                traverse::closest::<$test>(w, o, d, tmin, tmax, stack)
            }

            #[target_feature(enable = $features)]
            pub unsafe fn occluded(
                w: &Wide,
                o: Vec3,
                d: Vec3,
                tmin: f32,
                tmax: f32,
                stack: &mut [MaybeUninit<Entry>],
            ) -> bool {
                traverse::occluded::<$test>(w, o, d, tmin, tmax, stack)
            }

            #[target_feature(enable = $features)]
            pub unsafe fn closest_stream(
                w: &Wide,
                need: usize,
                rays: &[StreamRay],
                hits: &mut [Option<Hit>],
            ) {
                stream::closest_stream::<$test>(w, need, stream::HOT_NODES, rays, hits)
            }

            #[target_feature(enable = $features)]
            pub unsafe fn closest_packets(
                w: &Wide,
                need: usize,
                rays: &[StreamRay],
                hits: &mut [Option<Hit>],
            ) {
                coherent::closest_packets::<$test>(w, need, rays, hits)
            }

            #[target_feature(enable = $features)]
            pub unsafe fn occluded_stream(
                w: &Wide,
                need: usize,
                rays: &[StreamRay],
                blocked: &mut [bool],
            ) {
                stream::occluded_stream::<$test>(w, need, stream::HOT_NODES, rays, blocked)
            }
        }
    };
}

compiled_for!(avx2, "avx2", super::super::node::Avx2);
compiled_for!(avx512, "avx512f,avx2", super::super::node16::Avx512);
