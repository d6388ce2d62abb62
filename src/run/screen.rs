//! The screen: design points where nothing can pass under the blade are not run, and count as
//! MFR = 0 (real zeros, thesis Fig. 4.19) — but only once a seeded sample of them has run on the
//! engine and given MFR = 0.
//!
//! - **Closed points.** Whether a point is closed is the scene's geometric criterion
//!   ([`crate::scene::passage`]), decided when the design is planned (and again on a resume) and
//!   recorded per point in the manifest (`closed`). With `run.screen = false` no point is closed.
//! - **The verification sample**: each closed point draws a number in [0, 1) from a hash of
//!   `design.lds.seed` and its parameter values; the sample is the points whose number is below
//!   `run.screen_sample`, topped up with the lowest numbers to `run.screen_sample_min` (all the
//!   closed points when fewer). A pure function of the points and the settings: a resume or an
//!   extension draws the same numbers, and a point once run keeps its run.
//! - **The verdict**: *refuted* as soon as any closed point that ran gave MFR > 0 or failed;
//!   *verified* once the whole sample ran without that; *pending* before. Only a verified screen
//!   skips points; a refuted one runs every closed point for real.
//!
//! Not responsible for the criterion (the scene) or for running anything (the driver,
//! [`crate::run`], queues the sample first and the held-back points once refuted).

use std::collections::BTreeSet;

use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::store::{Manifest, PointRecord, PointStatus, RunState, Store};
use crate::sweep::Sweep;

/// The screen's settings, from `[run]` and `design.lds.seed` of a sweep file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Screen {
    pub enabled: bool,
    /// Fraction of the closed points in the verification sample.
    pub sample: f64,
    /// Least size of the verification sample.
    pub sample_min: usize,
    pub seed: u64,
}

/// The state of the screen in one sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// `run.screen = false`: every point runs.
    Off,
    /// No point is closed.
    NoneClosed,
    /// The sample has not run yet: the closed points are neither skipped nor run.
    Pending,
    /// The whole sample ran and gave MFR = 0: the other closed points are skipped.
    Verified,
    /// A closed point that ran gave MFR > 0 or failed: every closed point runs.
    Refuted,
}

impl Verdict {
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Off => "off",
            Verdict::NoneClosed => "none-closed",
            Verdict::Pending => "pending",
            Verdict::Verified => "verified",
            Verdict::Refuted => "refuted",
        }
    }
}

/// A closed point whose run contradicts the screen.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refutation {
    pub index: usize,
    /// `MFR 0.0123` or `failed (unsteady)`.
    pub outcome: String,
}

/// The screen of a sweep directory: `summary.json`'s `screen` and `sweep status`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScreenReport {
    pub verdict: Verdict,
    /// Points the criterion closes.
    pub closed: usize,
    /// Of them, the verification sample.
    pub sample: usize,
    /// Closed points not run: results.csv's `screened`, counted as MFR = 0.
    pub skipped: usize,
    /// Closed points that ran (the sample, and every one once refuted).
    pub ran: usize,
    pub refuted_by: Vec<Refutation>,
}

impl ScreenReport {
    /// One line for the terminal, `None` when the screen did nothing.
    pub fn sentence(&self) -> Option<String> {
        match self.verdict {
            Verdict::Off | Verdict::NoneClosed => None,
            Verdict::Pending => Some(format!(
                "screen pending: {} closed point(s) wait for the verification sample ({} of {} ran)",
                self.closed, self.ran, self.sample
            )),
            Verdict::Verified => Some(format!(
                "screen verified: {} of {} closed point(s) ran and gave MFR = 0; {} skipped as MFR = 0",
                self.ran, self.closed, self.skipped
            )),
            Verdict::Refuted => Some(format!(
                "SCREEN REFUTED: {}; every closed point runs for real ({} of {} ran)",
                refutation(&self.refuted_by),
                self.ran,
                self.closed
            )),
        }
    }
}

/// "point 4, which the screen closes, gave MFR 0.0779 (and 2 more closed point(s))", or
/// "... closes, failed (unsteady)".
pub fn refutation(by: &[Refutation]) -> String {
    let Some(first) = by.first() else { return "no closed point contradicts it".into() };
    let more = match by.len() {
        1 => String::new(),
        n => format!(" (and {} more closed point(s))", n - 1),
    };
    let verb = if first.outcome.starts_with("MFR") { "gave " } else { "" };
    format!("point {}, which the screen closes, {verb}{}{more}", first.index, first.outcome)
}

impl Screen {
    pub fn of(sweep: &Sweep) -> Screen {
        let r = &sweep.file.run;
        Screen {
            enabled: r.screen,
            sample: r.screen_sample,
            sample_min: r.screen_sample_min,
            seed: sweep.file.design.lds.seed,
        }
    }

    /// Indices of the closed points that form the verification sample.
    pub fn sample(&self, points: &[PointRecord]) -> BTreeSet<usize> {
        let mut keyed: Vec<(f64, usize)> =
            points.iter().filter(|p| p.closed).map(|p| (sample_key(self.seed, &p.values), p.index)).collect();
        keyed.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let drawn = keyed.iter().filter(|(k, _)| *k < self.sample).count();
        keyed.into_iter().take(drawn.max(self.sample_min)).map(|(_, i)| i).collect()
    }

    /// The verdict on `status` (each point's, in manifest order). `awaiting` closed points are
    /// about to run again (a retry) and their present status is not evidence.
    pub fn judge(
        &self,
        points: &[PointRecord],
        status: &[PointStatus],
        sample: &BTreeSet<usize>,
        awaiting: &BTreeSet<usize>,
    ) -> (Verdict, Vec<Refutation>) {
        if !self.enabled {
            return (Verdict::Off, Vec::new());
        }
        if !points.iter().any(|p| p.closed) {
            return (Verdict::NoneClosed, Vec::new());
        }
        let refuted_by: Vec<Refutation> = points
            .iter()
            .zip(status)
            .filter(|(p, _)| p.closed && !awaiting.contains(&p.index))
            .filter_map(|(p, s)| {
                let outcome = match s {
                    PointStatus::Done(r) if r.answer.value > 0.0 => format!("MFR {:.4}", r.answer.value),
                    PointStatus::Done(r) if !r.answer.value.is_finite() => format!("MFR {}", r.answer.value),
                    PointStatus::Failed(f) => format!("failed ({})", f.class.as_str()),
                    _ => return None,
                };
                Some(Refutation { index: p.index, outcome })
            })
            .collect();
        if !refuted_by.is_empty() {
            return (Verdict::Refuted, refuted_by);
        }
        let sample_ran =
            sample.iter().all(|&i| !awaiting.contains(&i) && matches!(status[i], PointStatus::Done(_)));
        (if sample_ran { Verdict::Verified } else { Verdict::Pending }, Vec::new())
    }

    /// Apply a verdict: under a verified screen every closed point without a run is `Screened`;
    /// under any other none is (back to pending). Returns how many are screened.
    pub fn apply(&self, verdict: Verdict, points: &[PointRecord], status: &mut [PointStatus]) -> usize {
        let verified = verdict == Verdict::Verified;
        for s in points.iter().zip(status.iter_mut()).filter(|(p, _)| p.closed).map(|(_, s)| s) {
            match s {
                PointStatus::Pending if verified => *s = PointStatus::Screened,
                PointStatus::Screened if !verified => *s = PointStatus::Pending,
                _ => {}
            }
        }
        status.iter().filter(|s| matches!(s, PointStatus::Screened)).count()
    }

    /// The report of a judged and applied screen.
    pub fn report(
        &self,
        points: &[PointRecord],
        status: &[PointStatus],
        sample: &BTreeSet<usize>,
        (verdict, refuted_by): (Verdict, Vec<Refutation>),
    ) -> ScreenReport {
        let closed: Vec<usize> = points.iter().filter(|p| p.closed).map(|p| p.index).collect();
        let count = |f: fn(&PointStatus) -> bool| closed.iter().filter(|&&i| f(&status[i])).count();
        ScreenReport {
            verdict,
            closed: closed.len(),
            sample: sample.len(),
            skipped: count(|s| matches!(s, PointStatus::Screened)),
            ran: count(|s| matches!(s, PointStatus::Done(_) | PointStatus::Failed(_))),
            refuted_by,
        }
    }

    /// Every point's status in a sweep directory, as results.csv, the statistics and `sweep
    /// status` count it: its run's outcome if it has one, else `Screened` under a verified
    /// screen, else pending. With the sample and the screen's report.
    pub fn statuses(
        &self,
        store: &Store,
        manifest: &Manifest,
    ) -> (Vec<PointStatus>, BTreeSet<usize>, ScreenReport) {
        let mut status: Vec<PointStatus> = manifest
            .points
            .iter()
            .map(|p| match store.point_finished(manifest, p) {
                Some(RunState::Done(r)) => PointStatus::Done(r),
                Some(RunState::Failed(f)) => PointStatus::Failed(f),
                _ => PointStatus::Pending,
            })
            .collect();
        let sample = self.sample(&manifest.points);
        let judged = self.judge(&manifest.points, &status, &sample, &BTreeSet::new());
        self.apply(judged.0, &manifest.points, &mut status);
        let report = self.report(&manifest.points, &status, &sample, judged);
        (status, sample, report)
    }
}

/// The screen's column of a design before anything runs (`sweep points --screen`): per point
/// (swept values, in file order), `closed`, `verification` or empty, as results.csv's `screen`
/// will say. The stand-in engine models no scene and closes nothing.
pub fn preview(sweep: &Sweep, values: &[Vec<f64>]) -> crate::Result<Vec<&'static str>> {
    let screen = Screen::of(sweep);
    let closes = screen.enabled && !crate::run::standin::selected(sweep);
    let points = values
        .iter()
        .enumerate()
        .map(|(index, v)| {
            let closed = closes && {
                let parameters = crate::point::resolve(sweep, v);
                crate::scenes::build(&parameters, &sweep.file.scene)
                    .map_err(|source| crate::point::PointError::Scene { path: sweep.path.clone(), source })?
                    .nothing_passes()
            };
            Ok(PointRecord { index, values: v.clone(), hash: String::new(), closed, seed: None })
        })
        .collect::<crate::Result<Vec<_>>>()?;
    let sample = screen.sample(&points);
    Ok(points
        .iter()
        .map(|p| match (p.closed, sample.contains(&p.index)) {
            (true, true) => "verification",
            (true, false) => "closed",
            (false, _) => "",
        })
        .collect())
}

/// The number in [0, 1) a closed point draws for the sample: the first 8 bytes of
/// sha256(seed, values) over 2⁶⁴. Independent of the engine and template (unlike the point's
/// content hash), so the same sweep draws the same sample on any machine.
fn sample_key(seed: u64, values: &[f64]) -> f64 {
    let mut h = Sha256::new();
    h.update(b"demsweep screen sample\n");
    h.update(seed.to_le_bytes());
    for v in values {
        h.update(v.to_bits().to_le_bytes());
    }
    let digest = h.finalize();
    let word = u64::from_le_bytes(digest[..8].try_into().expect("sha256 has 32 bytes"));
    (word >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::outcome::{FailureClass, RunFailure, RunResult, RESULT_FORMAT};

    fn points(n: usize, closed: impl Fn(usize) -> bool) -> Vec<PointRecord> {
        (0..n)
            .map(|i| PointRecord {
                index: i,
                values: vec![i as f64, 0.5],
                hash: format!("{i:064x}"),
                closed: closed(i),
                seed: None,
            })
            .collect()
    }

    fn screen(sample: f64, sample_min: usize) -> Screen {
        Screen { enabled: true, sample, sample_min, seed: 14 }
    }

    fn done(mfr: f64) -> PointStatus {
        PointStatus::Done(Box::new(RunResult {
            answer: crate::outcome::PointAnswer::mfr(mfr),
            mfr_flux: mfr,
            wall_time: 1.0,
            engine_version: String::new(),
            ..RunResult::default()
        }))
    }

    fn failed() -> PointStatus {
        PointStatus::Failed(Box::new(RunFailure {
            format: RESULT_FORMAT,
            hash: String::new(),
            class: FailureClass::Unsteady,
            reason: String::new(),
            log_tail: String::new(),
            wall_time: 1.0,
            measured: None,
        }))
    }

    #[test]
    fn the_sample_is_a_seeded_fraction_with_a_minimum_and_only_of_closed_points() {
        let p = points(1000, |i| i % 2 == 0);
        let s = screen(0.1, 3).sample(&p);
        assert!(s.iter().all(|&i| p[i].closed));
        // 500 closed points, each drawn with probability 0.1: 50 ± 3 SD (binomial).
        assert!((35..=65).contains(&s.len()), "{}", s.len());
        // The same settings draw the same sample; another seed another one.
        assert_eq!(s, screen(0.1, 3).sample(&p));
        assert_ne!(s, Screen { seed: 15, ..screen(0.1, 3) }.sample(&p));
        // The minimum tops it up; fewer closed points than the minimum are all in it.
        assert_eq!(screen(0.0, 3).sample(&p).len(), 3);
        assert_eq!(screen(0.0, 3).sample(&points(10, |i| i < 2)), BTreeSet::from([0, 1]));
        assert_eq!(screen(1.0, 3).sample(&p).len(), 500);
    }

    #[test]
    fn a_sample_drawn_before_an_extension_is_kept_by_it() {
        // Points keep their values when an LDS design grows: the drawn part stays.
        let small = points(200, |i| i % 3 == 0);
        let large = points(600, |i| i % 3 == 0);
        let a = screen(0.2, 1).sample(&small);
        let b = screen(0.2, 1).sample(&large);
        assert!(a.len() > 1 && a.is_subset(&b), "{a:?} {b:?}");
    }

    #[test]
    fn the_verdict_waits_for_the_sample_and_any_contradiction_refutes() {
        let sc = screen(0.0, 2);
        let p = points(6, |i| i >= 2);
        let sample = sc.sample(&p);
        assert_eq!(sample.len(), 2);
        let none = BTreeSet::new();
        let mut status = vec![PointStatus::Pending; 6];
        assert_eq!(sc.judge(&p, &status, &sample, &none).0, Verdict::Pending);
        // Open points do not count, whatever they gave.
        status[0] = done(0.2);
        status[1] = failed();
        let first = *sample.first().unwrap();
        status[first] = done(0.0);
        assert_eq!(sc.judge(&p, &status, &sample, &none).0, Verdict::Pending);
        let last = *sample.last().unwrap();
        status[last] = done(0.0);
        assert_eq!(sc.judge(&p, &status, &sample, &none).0, Verdict::Verified);
        // A sample point about to run again is not evidence yet.
        assert_eq!(sc.judge(&p, &status, &sample, &BTreeSet::from([last])).0, Verdict::Pending);
        // Applied: the two closed points without a run are screened, and back to pending when
        // the screen is refuted.
        assert_eq!(sc.apply(Verdict::Verified, &p, &mut status), 2);
        let report = sc.report(&p, &status, &sample, (Verdict::Verified, vec![]));
        assert_eq!((report.closed, report.sample, report.skipped, report.ran), (4, 2, 2, 2));
        status[last] = done(0.01);
        let (v, by) = sc.judge(&p, &status, &sample, &none);
        assert_eq!(
            (v, by),
            (Verdict::Refuted, vec![Refutation { index: last, outcome: "MFR 0.0100".into() }])
        );
        assert_eq!(sc.apply(v, &p, &mut status), 0);
        assert_eq!(status.iter().filter(|s| matches!(s, PointStatus::Pending)).count(), 2);
        // A failed run at a closed point refutes too, in or out of the sample.
        status[last] = done(0.0);
        let other = (2..6).find(|i| !sample.contains(i)).unwrap();
        status[other] = failed();
        assert_eq!(sc.judge(&p, &status, &sample, &none).0, Verdict::Refuted);
        // Off, or nothing closed.
        assert_eq!(Screen { enabled: false, ..sc }.judge(&p, &status, &sample, &none).0, Verdict::Off);
        assert_eq!(sc.judge(&points(6, |_| false), &status, &BTreeSet::new(), &none).0, Verdict::NoneClosed);
    }
}
