//! The cost of a pixel sample's numbers, one thread: for every sampler, the first eight
//! dimensions (four 2D pairs, as a camera sample, a light pick and a BSDF sample draw them) of
//! one sample in each of 4,096 pixels of a 64 × 64 image.
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pixel_samples::rng::SampleStream;
use pixel_samples::sampler::Sampler;
use std::hint::black_box;

const SIDE: u32 = 64;
const DIMS: u32 = 8;

fn draw_image(sampler: Sampler, index: u64) -> u64 {
    let mut acc = 0u64;
    for y in 0..SIDE {
        for x in 0..SIDE {
            let pixel = (y * SIDE + x) as u64;
            let mut s = SampleStream::with_sampler(sampler, 7, pixel, index)
                .with_pixel_samples(64)
                .in_image((x, y), (SIDE, SIDE));
            for _ in 0..DIMS {
                acc ^= s.next_u64();
            }
        }
    }
    acc
}

fn streams(c: &mut Criterion) {
    let mut g = c.benchmark_group("sample streams");
    g.throughput(Throughput::Elements((SIDE * SIDE * DIMS) as u64));
    for sampler in Sampler::ALL {
        let mut index = 0u64;
        g.bench_function(sampler.name(), |b| {
            b.iter(|| {
                index = (index + 1) % 64;
                black_box(draw_image(sampler, black_box(index)))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, streams);
criterion_main!(benches);
