//! What a run prints while it works: lines above the progress bars.
use indicatif::MultiProgress;

/// A line above the progress bars, or on stderr when they are hidden (no terminal).
pub fn say(multi: &MultiProgress, msg: String) -> std::io::Result<()> {
    if multi.is_hidden() {
        eprintln!("{msg}");
        Ok(())
    } else {
        multi.println(msg)
    }
}
