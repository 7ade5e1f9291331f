//! A few thousand mutated glTF, GLB and composition files: each ends in a scene or a one-line
//! error, never a panic, a non-finite pixel, a hang or an outsized allocation. Deterministic
//! (seed 1); `SCENE_FUZZ_CASES=N` changes the count, `cargo xtask fuzz --minutes N` runs longer.
use scene_fuzz::{ALLOCATION_LIMIT, CountingAllocator, Fuzzer};

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

#[test]
fn mutated_scene_files_end_in_a_scene_or_one_error_line() {
    let cases: u64 = std::env::var("SCENE_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3000);
    let dir = std::env::temp_dir().join(format!("scene-fuzz-test-{}", std::process::id()));
    let shared = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    let fuzzer = Fuzzer::new(&dir, 1, shared.is_dir().then_some(shared.as_path())).unwrap();
    let first: u64 = std::env::var("SCENE_FUZZ_FIRST")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let report = fuzzer.run(first, cases, None);
    for n in &report.notices {
        match n.strip_prefix("skipped ") {
            // Written past the test harness's capture, so that a passing run shows it.
            Some(what) => {
                use std::io::Write;
                let _ = writeln!(std::io::stderr(), "SKIPPED: fuzzing from {what}");
            }
            None => eprintln!("{n}"),
        }
    }
    eprintln!(
        "{} cases in {:.1} s over {} seeds: {:?}; largest single allocation {} bytes (limit {ALLOCATION_LIMIT})",
        report.cases,
        report.seconds,
        fuzzer.seeds().len(),
        report.outcomes,
        report.largest_allocation,
    );
    let failures: Vec<String> = report.failures.iter().map(|f| f.to_string()).collect();
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
    assert!(scene_fuzz::allocations_tracked());
    assert_eq!(report.cases, cases);
    // The mutations are neither all fatal nor all harmless.
    for kind in ["Rendered", "Refused"] {
        let n = report.outcomes.get(kind).copied().unwrap_or(0);
        assert!(n * 20 > cases, "{:?}", report.outcomes);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
