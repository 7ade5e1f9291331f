//! What a run prints while it works: lines above the progress bars, one per finished cell
//! with the count and an estimate of the time left.
use indicatif::MultiProgress;
use std::time::Instant;

/// A line above the progress bars, or on stderr when they are hidden (no terminal).
pub fn say(multi: &MultiProgress, msg: String) -> std::io::Result<()> {
    if multi.is_hidden() {
        eprintln!("{msg}");
        Ok(())
    } else {
        multi.println(msg)
    }
}

/// Counts a run's cells as they finish and estimates the time left from the mean so far.
pub struct Eta {
    total: usize,
    finished: usize,
    start: Instant,
}

impl Eta {
    pub fn new(total: usize) -> Self {
        Eta {
            total,
            finished: 0,
            start: Instant::now(),
        }
    }

    /// A cell passed over without rendering.
    pub fn pass(&mut self) {
        self.finished += 1;
    }

    /// The line of a finished cell: `[3/40] what — 0:42 elapsed, about 8:24 left`.
    pub fn line(&mut self, what: &str) -> String {
        self.finished += 1;
        eta_line(
            self.finished,
            self.total,
            self.start.elapsed().as_secs_f64(),
            what,
        )
    }
}

/// [`Eta::line`] after `finished` of `total` cells in `elapsed` seconds.
pub fn eta_line(finished: usize, total: usize, elapsed: f64, what: &str) -> String {
    let left = if finished >= total {
        "done".to_string()
    } else {
        let per_cell = elapsed / finished.max(1) as f64;
        format!("about {} left", clock((total - finished) as f64 * per_cell))
    };
    format!(
        "[{finished}/{total}] {what} — {} elapsed, {left}",
        clock(elapsed)
    )
}

/// Seconds as `m:ss`, or `h:mm:ss` from an hour on.
pub fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}:{:02}", s / 60, s % 60)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_estimate_is_the_mean_so_far_times_the_cells_left() {
        assert_eq!(clock(0.4), "0:00");
        assert_eq!(clock(62.0), "1:02");
        assert_eq!(clock(3723.0), "1:02:03");
        // 3 of 10 cells in 30 s: 10 s each, 7 left
        assert_eq!(
            eta_line(3, 10, 30.0, "c: relMSE 1e-2"),
            "[3/10] c: relMSE 1e-2 — 0:30 elapsed, about 1:10 left"
        );
        assert_eq!(
            eta_line(10, 10, 95.0, "c"),
            "[10/10] c — 1:35 elapsed, done"
        );
        let mut eta = Eta::new(2);
        eta.pass();
        assert!(
            eta.line("c").starts_with("[2/2] c — "),
            "passed cells count"
        );
    }
}
