//! `sweep status`: the counts of a sweep directory, its first failures grouped by reason, and
//! the screen's verdict.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::plan::design_label;
use crate::error::Result;
use crate::run::screen::{Screen, ScreenReport};
use crate::store::{self, DesignRecord, PointStatus, RunState, Store};
use crate::sweep::Sweep;

/// `sweep status DIR`.
#[derive(Debug, Clone, Serialize)]
pub struct StatusReport {
    pub dir: PathBuf,
    pub name: String,
    pub design: DesignRecord,
    pub points: usize,
    pub done: usize,
    pub failed: usize,
    /// Claimed by a live process.
    pub running: usize,
    /// Closed points skipped by a verified screen (MFR = 0, no run).
    pub screened: usize,
    pub pending: usize,
    /// Of the pending runs, those whose last attempt was cut off: killed (a claim left by a
    /// process that is gone) or cancelled (Ctrl-C, SIGTERM).
    pub interrupted: usize,
    /// Result files that cannot be read (their runs count as pending and run again).
    pub damaged: Vec<String>,
    /// Who holds each running claim: point, hash, holder, age and lease (the first few).
    pub holders: Vec<String>,
    /// Failures by class: count and the first few (by point index) with their reasons.
    pub failures: BTreeMap<String, FailureGroup>,
    /// Convergence verdict of the last report (summary.json); `None` before the first.
    pub converged: Option<bool>,
    /// What the screen did.
    pub screen: ScreenReport,
}

#[derive(Debug, Clone, Default, Serialize)]
pub struct FailureGroup {
    pub count: usize,
    pub first: Vec<FailureNote>,
}

#[derive(Debug, Clone, Serialize)]
pub struct FailureNote {
    pub index: usize,
    pub hash: String,
    pub reason: String,
}

/// Failures listed per class in `sweep status`.
const FIRST_FAILURES: usize = 3;

pub fn status(dir: &Path) -> Result<StatusReport> {
    let (manifest, toml) = Store::read_manifest(dir)?;
    let sweep = Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    let store = Store::open(dir);
    let (statuses, _, screen) = Screen::of(&sweep).statuses(&store, &manifest);
    let mut r = StatusReport {
        dir: dir.to_path_buf(),
        name: manifest.name.clone(),
        design: manifest.design.clone(),
        points: manifest.points.len(),
        done: 0,
        failed: 0,
        running: 0,
        screened: 0,
        pending: 0,
        interrupted: 0,
        damaged: Vec::new(),
        holders: Vec::new(),
        failures: BTreeMap::new(),
        converged: read_verdict(dir),
        screen,
    };
    // The last attempt of each run, for runs cancelled part-way.
    let mut last: HashMap<String, String> = HashMap::new();
    if let Ok(lines) = store::read_joblog(dir) {
        for l in lines {
            last.insert(l.hash, l.status);
        }
    }
    let cut_off = |h: &str| last.get(h).is_some_and(|s| s == "cancelled" || s == "interrupted");
    for p in &manifest.points {
        match store.point_state(&manifest, p) {
            RunState::Done(_) => r.done += 1,
            RunState::Failed(f) => {
                r.failed += 1;
                let g = r.failures.entry(f.class.as_str().to_string()).or_default();
                g.count += 1;
                if g.first.len() < FIRST_FAILURES {
                    g.first.push(FailureNote {
                        index: p.index,
                        hash: p.hash.clone(),
                        reason: f.reason.clone(),
                    });
                }
            }
            RunState::Running(c) => {
                r.running += 1;
                if r.holders.len() < FIRST_FAILURES {
                    let h = store::short(&p.hash);
                    let passes = passes_done(&store, &p.hash);
                    r.holders.push(format!(
                        "point {} ({h}): {}{passes}",
                        p.index,
                        store::holders::describe(&c)
                    ));
                }
            }
            RunState::Interrupted(_) => {
                r.pending += 1;
                r.interrupted += 1;
            }
            RunState::Damaged { file, reason } => {
                r.pending += 1;
                r.damaged.push(format!("{}: {reason}", file.display()));
            }
            RunState::Incomplete | RunState::Pending
                if matches!(statuses[p.index], PointStatus::Screened) =>
            {
                r.screened += 1
            }
            RunState::Incomplete | RunState::Pending => {
                r.pending += 1;
                if cut_off(&p.hash) {
                    r.interrupted += 1;
                }
            }
        }
    }
    // What `sweep resume` would refuse before running anything.
    if let Err(e) = store.check_joblog() {
        r.damaged.push(format!("{e}; `sweep resume` refuses to run until it is moved away"));
    }
    Ok(r)
}

/// ", 4 passes done" for a point run pass by pass (a layers point) that has finished some: it
/// runs for hours, and a claim's age alone does not say how far it is.
fn passes_done(store: &Store, hash: &str) -> String {
    match crate::point::passes::finished_passes(&store.run_dir(hash), hash).map(|d| d.len()) {
        Ok(1) => ", 1 pass done".into(),
        Ok(n) if n > 1 => format!(", {n} passes done"),
        _ => String::new(),
    }
}

/// The verdict of the last report (`DIR/summary.json`, or a calibration's
/// `DIR/posterior.json`), if one was written.
fn read_verdict(dir: &Path) -> Option<bool> {
    let cap = crate::store::OUTCOME_CAP;
    if let Ok(text) = crate::sys::read::read_text_capped(&dir.join(super::calibrate::POSTERIOR), cap) {
        let v: serde_json::Value = serde_json::from_str(&text).ok()?;
        return Some(v.get("status")?.as_str()? == "converged");
    }
    let text =
        crate::sys::read::read_text_capped(&dir.join("summary.json"), crate::store::OUTCOME_CAP).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v.get("verdict")?.get("converged")?.as_bool()
}

impl StatusReport {
    /// The human-readable form.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "{} ({}, {}): {} points\n  done     {}\n  failed   {}\n  running  {}\n",
            self.dir.display(),
            self.name,
            design_label(&self.design),
            self.points,
            self.done,
            self.failed,
            self.running,
        );
        if self.screened > 0 {
            s.push_str(&format!("  screened {} (closed, MFR = 0 without a run)\n", self.screened));
        }
        s.push_str(&format!("  pending  {}\n", self.pending));
        if self.interrupted > 0 {
            s.insert_str(
                s.len() - 1,
                &format!("  ({} interrupted: killed or cancelled part-way)", self.interrupted),
            );
        }
        for h in &self.holders {
            s.push_str(&format!("    {h}\n"));
        }
        if self.running > self.holders.len() {
            s.push_str(&format!("    and {} more\n", self.running - self.holders.len()));
        }
        if self.running > 0 {
            s.push_str(&format!(
                "    a claim whose holder is gone for good (a lost node, a clock far ahead): `sweep unclaim {}` releases it\n",
                crate::sys::shell::quote_path(&self.dir)
            ));
        }
        for d in &self.damaged {
            s.push_str(&format!("  warning: {d}\n"));
        }
        for (class, g) in &self.failures {
            s.push_str(&format!("  {class}: {}\n", g.count));
            for n in &g.first {
                s.push_str(&format!(
                    "    point {} ({}): {}\n",
                    n.index,
                    &n.hash[..12.min(n.hash.len())],
                    n.reason
                ));
            }
            if g.count > g.first.len() {
                s.push_str(&format!("    and {} more\n", g.count - g.first.len()));
            }
        }
        if let Some(line) = self.screen.sentence() {
            s.push_str(&format!("  {line}\n"));
        }
        s.push_str(&format!(
            "  converged: {}\n",
            self.converged.map_or("unknown", |c| if c { "yes" } else { "no" })
        ));
        s
    }
}

/// Rewrite `DIR/results.csv` from the run dirs (`sweep report`: a directory written by an older
/// version gains the newer columns, such as `quality`).
pub fn rewrite_results(dir: &Path) -> Result<()> {
    let (m, toml) = Store::read_manifest(dir)?;
    let sweep = Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    let (status, sample, _) = Screen::of(&sweep).statuses(&Store::open(dir), &m);
    let columns = crate::store::Columns {
        fixed: crate::point::fixed_columns(&sweep),
        layout: crate::scenes::of(&sweep.file.scene).map_err(crate::point::PointError::Layout)?,
    };
    Ok(crate::store::write_results(dir, &m.parameters, &columns, &m.points, &status, &sample)?)
}
