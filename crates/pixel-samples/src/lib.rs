//! `pixel-samples`: the numbers of one pixel sample and where on the film it lands, knowing
//! nothing of scenes or rendering. [`rng::SampleStream`] hands out a sample's numbers one
//! dimension at a time, each a function of (seed, pixel, sample index, dimension) alone, so
//! images do not depend on the thread count; [`sampler::Sampler`] decides what those values
//! are; [`filter::PixelFilter`] turns the first pair into an offset from the pixel centre and a
//! weight. `render-core` re-exports the three modules under the same names.

pub mod filter;
mod hash;
pub mod rng;
pub mod sampler;
pub mod zsobol;
