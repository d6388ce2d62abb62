//! Progress of one point run pass by pass (`sweep run` on a layers point): such a point runs for
//! minutes to hours, so a line on stderr says each pass as it ends — its CPU, the time so far,
//! and how many passes the point may still run — read from the pass records it writes.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use demsweep::point::passes::{finished_passes, read_record, PassRecord};
use demsweep::scenes::ByPass;

/// How often the run directory is looked at: a pass takes tens of seconds at the least.
const POLL: Duration = Duration::from_millis(500);

/// Says each pass of the point in `dir` as it ends, until dropped.
pub(super) struct PassWatch {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl PassWatch {
    /// Watch `dir`, where the point of run hash `hash` runs between `by.least` and `by.most`
    /// passes.
    pub(super) fn start(dir: &Path, hash: &str, by: ByPass) -> PassWatch {
        let stop = Arc::new(AtomicBool::new(false));
        let (dir, flag) = (dir.to_path_buf(), stop.clone());
        // The passes an earlier attempt left, that this one goes on from.
        let ran = finished_passes(&dir, hash).map(|d| d.len()).unwrap_or(0);
        let thread = std::thread::spawn(move || say_passes(&dir, ran, by, &flag));
        PassWatch { stop, thread: Some(thread) }
    }
}

impl Drop for PassWatch {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn say_passes(dir: &Path, ran: usize, by: ByPass, stop: &AtomicBool) {
    let ByPass { least, most } = by;
    if ran > 0 {
        eprintln!("going on from pass {ran} (the passes before it are kept)");
    } else {
        eprintln!("{least} to {most} passes: from pass {least} on, the point stops once its layer is steady");
    }
    let start = Instant::now();
    let mut k = ran + 1;
    while k <= most {
        // Read before the stop is looked at: the pass that ended as the point did is said too.
        let stopped = stop.load(Ordering::Relaxed);
        match read_record(dir, k) {
            Some(r) => {
                eprintln!("{}", pass_line(&r, most, start.elapsed()));
                k += 1;
            }
            None if stopped => break,
            None => std::thread::sleep(POLL),
        }
    }
}

/// "pass 3 of at most 14: 61 CPU s, 0:03:12 since the start".
fn pass_line(r: &PassRecord, most: usize, since: Duration) -> String {
    let cpu = r.cpu_time.map(|c| format!("{c:.0} CPU s")).unwrap_or_else(|| format!("{:.0} s", r.wall_time));
    let s = since.as_secs();
    format!(
        "pass {} of at most {most}: {cpu}, {}:{:02}:{:02} since the start",
        r.k,
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pass_line_names_the_pass_its_cpu_and_the_time_so_far() {
        let r = PassRecord { hash: "h".into(), k: 3, wall_time: 70.2, cpu_time: Some(61.4) };
        assert_eq!(
            pass_line(&r, 14, Duration::from_secs(3 * 3600 + 12 * 60 + 5)),
            "pass 3 of at most 14: 61 CPU s, 3:12:05 since the start"
        );
        let r = PassRecord { cpu_time: None, ..r };
        assert_eq!(
            pass_line(&r, 14, Duration::from_secs(59)),
            "pass 3 of at most 14: 70 s, 0:00:59 since the start"
        );
    }
}
