//! What a long run says while it runs: a bar on a terminal, otherwise (a log file, a Slurm
//! job, a pipe) a line every few seconds with how far it is and an estimate of how long is
//! left, so that a batch user can see progress without a terminal.

use std::time::{Duration, Instant};

/// Seconds between progress lines when stderr is not a terminal.
pub const LINE_EVERY: Duration = Duration::from_secs(10);

/// "12.3 s elapsed, about 45 s left" for `done` of `total` steps after `elapsed`.
pub fn eta(elapsed: Duration, done: u64, total: u64) -> String {
    let s = elapsed.as_secs_f64();
    if done == 0 || total <= done {
        return format!("{} elapsed", human(s));
    }
    let left = s / done as f64 * (total - done) as f64;
    format!("{} elapsed, about {} left", human(s), human(left))
}

fn human(s: f64) -> String {
    if s < 90.0 {
        format!("{s:.0} s")
    } else if s < 5400.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

/// Decides when a line is due: at the first step, then every `LINE_EVERY`, and at the last.
pub struct Lines {
    last: Option<Instant>,
}

impl Lines {
    pub fn new() -> Self {
        Lines { last: None }
    }
    pub fn due(&mut self, done: u64, total: u64) -> bool {
        let now = Instant::now();
        let due = match self.last {
            None => true,
            Some(t) => now.duration_since(t) >= LINE_EVERY || done >= total,
        };
        if due {
            self.last = Some(now);
        }
        due
    }
}

impl Default for Lines {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eta_scales_the_elapsed_time_to_the_steps_left() {
        assert_eq!(eta(Duration::from_secs(10), 10, 40), "10 s elapsed, about 30 s left");
        assert_eq!(eta(Duration::from_secs(120), 1, 2), "2.0 min elapsed, about 2.0 min left");
        assert_eq!(eta(Duration::from_secs(5), 0, 40), "5 s elapsed");
        assert_eq!(eta(Duration::from_secs(5), 40, 40), "5 s elapsed");
    }

    #[test]
    fn a_line_is_due_at_the_start_and_the_end() {
        let mut l = Lines::new();
        assert!(l.due(1, 100));
        assert!(!l.due(2, 100));
        assert!(l.due(100, 100));
    }
}
