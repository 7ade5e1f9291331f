//! Cost of one cap integral (per-lobe) and of the per-shading-point `lobe()` setup.
//! Run: cargo bench -p brdf-integrals --bench cap_integral

use brdf_integrals::{CapIntegral, Intersection, LobeIntegral, Ltc, Sptd, ggx};
use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use std::hint::black_box;

/// A fixed set of caps around and away from the lobe, of many sizes.
fn caps() -> Vec<(Vec3, f32)> {
    let mut v = Vec::new();
    let mut s = 0x1234_5678u32;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s as f32 / u32::MAX as f32
    };
    for _ in 0..256 {
        let z = next() * 1.3 - 0.3;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = next() * std::f32::consts::TAU;
        let ang = (0.005f32.ln() + next() * (1.0f32.ln() - 0.005f32.ln())).exp();
        v.push((Vec3::new(r * phi.cos(), r * phi.sin(), z), ang.cos()));
    }
    v
}

fn bench(c: &mut Criterion) {
    let caps = caps();
    let wo = ggx::wo_from_theta(0.8);
    let alpha = 0.1;
    let sptd = Sptd::default();
    let sptd_oat = Sptd::default().intersection(Intersection::OatSander);
    let ltc = Ltc::default();
    let n = caps.len() as u64;
    let mut g = c.benchmark_group("lobe_integral_per_cap");
    g.throughput(criterion::Throughput::Elements(n));
    let lobe = sptd.lobe(wo, alpha);
    g.bench_function("sptd_exact", |b| {
        b.iter(|| {
            caps.iter()
                .map(|&(a, cs)| lobe.integral(black_box(a), black_box(cs)))
                .sum::<f32>()
        })
    });
    let lobe = sptd_oat.lobe(wo, alpha);
    g.bench_function("sptd_oat_sander", |b| {
        b.iter(|| {
            caps.iter()
                .map(|&(a, cs)| lobe.integral(black_box(a), black_box(cs)))
                .sum::<f32>()
        })
    });
    let lobe = ltc.lobe(wo, alpha);
    g.bench_function("ltc", |b| {
        b.iter(|| {
            caps.iter()
                .map(|&(a, cs)| lobe.integral(black_box(a), black_box(cs)))
                .sum::<f32>()
        })
    });
    g.finish();
    let mut g = c.benchmark_group("lobe_setup");
    g.bench_function("sptd_lobe", |b| {
        b.iter(|| sptd.lobe(black_box(wo), black_box(alpha)))
    });
    g.bench_function("ltc_lobe", |b| {
        b.iter(|| ltc.lobe(black_box(wo), black_box(alpha)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
