//! The embedding example (examples/bo_from_raw.rs) runs, and its BO samples pass the
//! chi-square test against their own pmf, as our renderer's do.
#[path = "../examples/bo_from_raw.rs"]
mod example;

#[test]
fn bo_from_raw_inputs_matches_its_pmf() {
    let o = example::run(300, 100_000, 11);
    assert!((o.pmf_sum - 1.0).abs() < 1e-4, "Σ pmf = {}", o.pmf_sum);
    assert!(o.clusters > 1, "a glossy point splits the cut");
    assert!(o.chi2.dof > 20, "{:?}", o.chi2);
    assert!(o.chi2.p_value > 1e-4, "{:?}", o.chi2);
}
