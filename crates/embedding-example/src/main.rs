//! BRDF-oriented light selection (Liu, Xu & Yan 2019) driven from raw inputs, as another
//! renderer would embed it: a list of light bounds (`light-tree`), a shading point given as a
//! position, a frame and GGX lobe parameters (`brdf-integrals`), and any source of random
//! numbers (here a PCG generator). No scene, camera or BSDF of ours is involved; only
//! `render_core`'s `Frame` and `Vec3` (glam) name the geometry, see the crate's docs.
//!
//! It draws lights by BO, compares their frequencies with the probabilities
//! `BoState::selection_pmf` gives (chi-square), and prints the test. `cargo run --release -p
//! embedding-example`; `cargo test -p embedding-example` runs it too, with a check.
use brdf_integrals::CapIntegral;
use light_tree::{LightBounds, LightTree};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg32;
use render_core::Vec3;
use render_core::frame::Frame;
use samplers::brdf_oriented::importance::BoRecord;
use samplers::brdf_oriented::technique::BoState;

/// What one run found: the chi-square outcome, the sum of the pmf over the lights, and how
/// many lights the BO cut has as clusters.
struct Outcome {
    chi2: chi2_test::Chi2Outcome,
    pmf_sum: f64,
    clusters: usize,
}

/// `n_lights` small spherical lights spread over a ceiling, `samples` BO selections at one
/// glossy shading point.
fn run(n_lights: usize, samples: usize, seed: u64) -> Outcome {
    let mut rng = Pcg32::seed_from_u64(seed);
    // The host's lights, as bounds: a sphere of radius r is a box, every normal (θo = π).
    let r = 0.02;
    let lights: Vec<LightBounds> = (0..n_lights)
        .map(|_| {
            let c = Vec3::new(
                rng.random::<f32>() * 4.0 - 2.0,
                2.0 + rng.random::<f32>() * 0.5,
                rng.random::<f32>() * 4.0 - 2.0,
            );
            LightBounds {
                aabb_min: c - Vec3::splat(r),
                aabb_max: c + Vec3::splat(r),
                axis: Vec3::Y,
                theta_o: std::f32::consts::PI,
                theta_e: std::f32::consts::FRAC_PI_2,
                power: 1.0 + rng.random::<f32>(),
                two_sided: false,
            }
        })
        .collect();
    let tree = LightTree::build(&lights).expect("valid bounds");

    // The host's shading point: position, normal, view direction, GGX α and lobe weights.
    let x = Vec3::ZERO;
    let n = Vec3::Y;
    let wo = Vec3::new(0.6, 0.8, 0.0).normalize();
    let alpha = 0.05;
    let frame = Frame::from_normal_and_direction(n, wo);
    let lobe = brdf_integrals::Sptd::default().lobe(frame.to_local(wo), alpha);
    let (ks, kd) = (0.8, 0.2); // luminances of the glossy weight and of the diffuse albedo
    let rec = BoRecord::from_parts(x, frame, lobe, ks, kd, true, false);
    let state = BoState::new(&tree, rec, 0.5, 64, None);

    let mut counts = vec![0.0f64; n_lights];
    for _ in 0..samples {
        let u = rng.random::<f32>();
        if let Some((light, p)) = state.select_from(&tree, u, || rng.random::<u64>()) {
            // the probability reported at sampling is the one the pmf gives later (MIS needs it)
            let q = state.selection_pmf(&tree, light);
            assert!((p - q).abs() <= 1e-5 * q.max(1e-30), "{p} vs {q}");
            counts[light] += 1.0;
        }
    }
    let pmf: Vec<f64> = (0..n_lights)
        .map(|l| state.selection_pmf(&tree, l) as f64)
        .collect();
    let expected: Vec<f64> = pmf.iter().map(|p| p * samples as f64).collect();
    Outcome {
        chi2: chi2_test::chi2_test(&counts, &expected),
        pmf_sum: pmf.iter().sum(),
        clusters: state.cut().cut.nodes.len(),
    }
}

fn main() {
    let o = run(500, 200_000, 7);
    println!(
        "BO cut: {} clusters; Σ pmf = {:.6}; chi-square {:.1} on {} dof, p = {:.3}",
        o.clusters, o.pmf_sum, o.chi2.statistic, o.chi2.dof, o.chi2.p_value
    );
}

#[cfg(test)]
mod tests {
    /// Its BO samples pass the chi-square test against their own pmf, as our renderer's do.
    #[test]
    fn bo_from_raw_inputs_matches_its_pmf() {
        let o = super::run(300, 100_000, 11);
        assert!((o.pmf_sum - 1.0).abs() < 1e-4, "Σ pmf = {}", o.pmf_sum);
        assert!(o.clusters > 1, "a glossy point splits the cut");
        assert!(o.chi2.dof > 20, "{:?}", o.chi2);
        assert!(o.chi2.p_value > 1e-4, "{:?}", o.chi2);
    }
}
