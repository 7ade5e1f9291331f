//! The cost of a pixel sample's numbers, one thread: for every sampler, the first eight
//! dimensions of one sample in each of 4,096 pixels of a 64 × 64 image, drawn one at a time
//! (`next_u64`) and as four 2D pairs (`next_2d`, as a camera sample, a light sample and a BSDF
//! sample draw them).
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pixel_samples::rng::SampleStream;
use pixel_samples::sampler::Sampler;
use std::hint::black_box;

const SIDE: u32 = 64;
const DIMS: u32 = 8;

/// Every pixel's stream of sample `index`, folded by `draw` into one number.
fn draw_image(sampler: Sampler, index: u64, draw: impl Fn(&mut SampleStream) -> u64) -> u64 {
    let mut acc = 0u64;
    for y in 0..SIDE {
        for x in 0..SIDE {
            let pixel = (y * SIDE + x) as u64;
            let mut s = SampleStream::with_sampler(sampler, 7, pixel, index)
                .with_pixel_samples(64)
                .in_image((x, y), (SIDE, SIDE));
            acc ^= draw(&mut s);
        }
    }
    acc
}

/// The eight dimensions one at a time.
fn one_by_one(s: &mut SampleStream) -> u64 {
    (0..DIMS).fold(0, |acc, _| acc ^ s.next_u64())
}

/// The eight dimensions as four pairs.
fn in_pairs(s: &mut SampleStream) -> u64 {
    (0..DIMS / 2).fold(0, |acc, _| {
        let u = s.next_2d();
        acc ^ (u.x.to_bits() as u64) << 32 ^ u.y.to_bits() as u64
    })
}

fn streams(c: &mut Criterion) {
    let groups: [(&str, fn(&mut SampleStream) -> u64); 2] = [
        ("sample streams", one_by_one),
        ("sample streams in 2D pairs", in_pairs),
    ];
    for (name, draw) in groups {
        let mut g = c.benchmark_group(name);
        g.throughput(Throughput::Elements((SIDE * SIDE * DIMS) as u64));
        for sampler in Sampler::ALL {
            let mut index = 0u64;
            g.bench_function(sampler.name(), |b| {
                b.iter(|| {
                    index = (index + 1) % 64;
                    black_box(draw_image(sampler, black_box(index), draw))
                })
            });
        }
        g.finish();
    }
}

criterion_group!(benches, streams);
criterion_main!(benches);
