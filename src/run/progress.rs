//! Progress of a running sweep on stderr: a bar (done, failed, running, ETA) on a terminal,
//! plain periodic lines otherwise, nothing with `--quiet`.
//!
//! Not responsible for counting (the driver's reporter owns the counts and hands them in).

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Time between plain progress lines when stderr is not a terminal.
pub const LINE_EVERY: Duration = Duration::from_secs(10);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProgressMode {
    Bar,
    Lines,
    Quiet,
}

impl ProgressMode {
    /// A bar when stderr is a terminal, lines otherwise; nothing when `quiet`.
    pub fn detect(quiet: bool) -> ProgressMode {
        if quiet {
            ProgressMode::Quiet
        } else if std::io::stderr().is_terminal() {
            ProgressMode::Bar
        } else {
            ProgressMode::Lines
        }
    }
}

/// Counts of design points.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    pub total: usize,
    pub done: usize,
    pub failed: usize,
    pub running: usize,
    /// Finished before this session started (reused).
    pub reused: usize,
    /// Skipped by a verified screen (MFR = 0 without a run).
    pub screened: usize,
}

impl Counts {
    fn finished(&self) -> usize {
        self.done + self.failed + self.screened
    }
}

pub struct Progress {
    mode: ProgressMode,
    bar: Option<ProgressBar>,
    start: Instant,
    last_line: Instant,
    /// Runs other processes hold, and who holds them.
    held: Option<String>,
}

impl Progress {
    pub fn new(mode: ProgressMode, total: usize) -> Progress {
        let bar = (mode == ProgressMode::Bar).then(|| {
            let b = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
            b.set_style(
                ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} finished: {msg}")
                    .expect("valid template")
                    .progress_chars("=> "),
            );
            b.enable_steady_tick(Duration::from_millis(500));
            b
        });
        Progress { mode, bar, start: Instant::now(), last_line: Instant::now(), held: None }
    }

    /// Runs held by other processes, named in the progress line (`1 held by node7 pid 42 ...`).
    pub fn set_held(&mut self, held: Option<String>) {
        self.held = held;
    }

    /// Redraw (bar) or print a line if [`LINE_EVERY`] has passed (lines).
    pub fn update(&mut self, c: &Counts) {
        match self.mode {
            ProgressMode::Quiet => {}
            ProgressMode::Bar => {
                let b = self.bar.as_ref().expect("bar mode has a bar");
                b.set_position(c.finished() as u64);
                b.set_message(self.message(c));
            }
            ProgressMode::Lines => {
                if self.last_line.elapsed() >= LINE_EVERY {
                    self.last_line = Instant::now();
                    eprintln!("sweep: {}/{} finished: {}", c.finished(), c.total, self.message(c));
                }
            }
        }
    }

    /// A line that must be seen (the screen refuted), above the bar, whatever the mode.
    pub fn warn(&self, line: &str) {
        match &self.bar {
            Some(b) => b.suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        }
    }

    /// The final line.
    pub fn finish(&mut self, c: &Counts) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
        if self.mode != ProgressMode::Quiet {
            let screened = if c.screened > 0 { format!(", {} screened", c.screened) } else { String::new() };
            eprintln!(
                "sweep: {}/{} finished ({} done, {} failed{screened}, {} reused) in {}",
                c.finished(),
                c.total,
                c.done,
                c.failed,
                c.reused,
                human(self.start.elapsed())
            );
        }
    }

    fn message(&self, c: &Counts) -> String {
        let m = message(c, eta(c, self.start.elapsed()));
        match &self.held {
            Some(h) => format!("{m} · {h}"),
            None => m,
        }
    }
}

/// What follows "9/12 finished: ": `9 done, 0 failed · 1 running · ETA 35 s`.
fn message(c: &Counts, eta: Option<Duration>) -> String {
    let screened = if c.screened > 0 { format!(", {} screened", c.screened) } else { String::new() };
    let eta = eta.map_or("?".to_string(), human);
    format!("{} done, {} failed{screened} · {} running · ETA {eta}", c.done, c.failed, c.running)
}

/// Remaining time at this session's rate: elapsed / finished-here × left. Runs reused from an
/// earlier session finish instantly and are left out of the rate.
pub fn eta(c: &Counts, elapsed: Duration) -> Option<Duration> {
    // Screened points cost nothing: they are no part of the rate.
    let here = c.finished().checked_sub(c.reused + c.screened)?;
    if here == 0 {
        return None;
    }
    let left = c.total.saturating_sub(c.finished());
    Some(elapsed.mul_f64(left as f64 / here as f64))
}

/// A duration as people say it: `35 s`, `2 min 05 s`, `1 h 02 min`.
fn human(d: Duration) -> String {
    let s = d.as_secs_f64().round() as u64;
    if s >= 3600 {
        format!("{} h {:02} min", s / 3600, s % 3600 / 60)
    } else if s >= 60 {
        format!("{} min {:02} s", s / 60, s % 60)
    } else {
        format!("{s} s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eta_uses_only_this_sessions_rate() {
        // 10 reused + 10 run here in 100 s; 20 left → 200 s.
        let c = Counts { total: 40, done: 18, failed: 2, running: 2, reused: 10, screened: 0 };
        assert_eq!(eta(&c, Duration::from_secs(100)), Some(Duration::from_secs(200)));
        let fresh = Counts { reused: 20, ..c };
        assert_eq!(eta(&fresh, Duration::from_secs(100)), None);
    }

    #[test]
    fn the_line_says_what_each_count_is() {
        let c = Counts { total: 12, done: 9, failed: 0, running: 1, reused: 0, screened: 0 };
        assert_eq!(
            message(&c, Some(Duration::from_millis(34_600))),
            "9 done, 0 failed · 1 running · ETA 35 s"
        );
        let c = Counts { total: 4, done: 0, failed: 1, running: 1, reused: 0, screened: 2 };
        assert_eq!(message(&c, None), "0 done, 1 failed, 2 screened · 1 running · ETA ?");
        assert_eq!(human(Duration::from_secs(125)), "2 min 05 s");
        assert_eq!(human(Duration::from_secs(3720)), "1 h 02 min");
    }
}
