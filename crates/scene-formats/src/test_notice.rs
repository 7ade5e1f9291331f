//! For the unit tests that need the shared scenes (../shared/scenes beside the repository).

/// Says on the terminal that a test checked nothing: what `eprintln!` prints in a passing test
/// is captured and never shown, a direct write to stderr is not.
pub(crate) fn skipped(what: &str) {
    use std::io::Write;
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED: {what} (../shared/scenes not found)"
    );
}
