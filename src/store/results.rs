//! `results.csv`: one row per design point, rewritten whole (atomically) as points finish.

use std::path::Path;

use super::{io, PointRecord, StoreError};
use crate::outcome::{RunFailure, RunResult, VX_LAYERS};
use crate::scenes::Layout;

/// results.csv's columns of the spread layer's quality.
pub const LAYER_COLUMNS: [&str; 4] = ["layer_cv", "layer_cv_noise", "covered_fraction", "roughness_d"];

/// The columns of results.csv besides the common ones: the fixed parameters' (after the swept
/// ones) and the layout's own quantities (last).
pub struct Columns {
    pub fixed: Vec<(String, f64)>,
    pub layout: &'static dyn Layout,
}

/// The state of one design point in results.csv.
#[derive(Debug, Clone, PartialEq)]
pub enum PointStatus {
    Pending,
    Done(Box<RunResult>),
    Failed(Box<RunFailure>),
    /// Closed by a verified screen and not run: MFR = 0 ([`crate::run::screen`]).
    Screened,
}

impl PointStatus {
    pub fn is_finished(&self) -> bool {
        !matches!(self, PointStatus::Pending)
    }
}

/// Write `DIR/results.csv`: one row per design point, in index order, atomically.
///
/// Columns: index, the swept parameters, the fixed ones (every other catalogue parameter, the
/// same on every row, so a row says the whole point), status (`done`, `failed`, `pending`, `screened`),
/// failure (class), mfr (the answer; 0 when screened), mfr_flux, mfr_particles (the result's
/// `answer_particles`, under the name it had beside `mfr`), steady, vx_1..vx_12 (m/s,
/// empty for an empty layer), runtime_s, hash, quality (of the v_x profile, [`crate::measure::quality`];
/// empty unless done), screen (`closed` for a point the screen closes, `verification` for one of
/// its verification sample, empty for an open point), mfr_se (the standard error of MFR, from
/// batch means over the steady window), stop (`target` or `cap`: what ended the window), and
/// the spread layer's quality where the run measured it ([`crate::measure::layer`]): layer_cv and
/// layer_cv_noise (–), covered_fraction (–), roughness_d (top-surface RMS height, in D); then
/// layer_packing and its SE (the deposit's packing over the gap and the pockets it fills); last,
/// the layout's own quantities by their names ([`Layout::result_columns`]: a layers point's
/// steady layer, a pour's heap), of a done run or of what a failed one measured.
pub fn write_results(
    dir: &Path,
    parameters: &[String],
    columns: &Columns,
    points: &[PointRecord],
    status: &[PointStatus],
    sample: &std::collections::BTreeSet<usize>,
) -> Result<(), StoreError> {
    let path = dir.join("results.csv");
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header: Vec<String> = vec!["index".into()];
    header.extend(parameters.iter().cloned());
    let fixed = &columns.fixed;
    header.extend(fixed.iter().map(|f| f.0.clone()));
    header.extend(["status", "failure", "mfr", "mfr_flux", "mfr_particles", "steady"].map(String::from));
    header.extend((1..=VX_LAYERS).map(|k| format!("vx_{k}")));
    header.extend(["runtime_s", "hash", "quality", "screen", "mfr_se", "stop"].map(String::from));
    header.extend(LAYER_COLUMNS.map(String::from));
    header.extend(["layer_packing", "layer_packing_se"].map(String::from));
    let own = columns.layout.result_columns();
    header.extend(own.iter().map(|c| c.to_string()));
    w.write_record(&header).expect("in-memory csv");
    for (p, s) in points.iter().zip(status) {
        let mut row: Vec<String> = vec![p.index.to_string()];
        row.extend(p.values.iter().map(|v| v.to_string()));
        row.extend(fixed.iter().map(|f| f.1.to_string()));
        match s {
            PointStatus::Pending => {
                row.push("pending".into());
                row.extend(std::iter::repeat_n(String::new(), 5 + VX_LAYERS + 1));
            }
            PointStatus::Done(r) => {
                row.extend([
                    "done".into(),
                    String::new(),
                    r.answer.value.to_string(),
                    r.mfr_flux.to_string(),
                    r.answer_particles.to_string(),
                    r.steady.to_string(),
                ]);
                row.extend(
                    (0..VX_LAYERS)
                        .map(|k| r.vx.get(k).copied().flatten().map_or(String::new(), |v| v.to_string())),
                );
                row.push(format!("{:.3}", r.wall_time));
            }
            PointStatus::Failed(f) => {
                row.extend(["failed".into(), f.class.as_str().into()]);
                row.extend(std::iter::repeat_n(String::new(), 4 + VX_LAYERS));
                row.push(format!("{:.3}", f.wall_time));
            }
            PointStatus::Screened => {
                row.extend(["screened".into(), String::new(), "0".into()]);
                row.extend(std::iter::repeat_n(String::new(), 3 + VX_LAYERS + 1));
            }
        }
        row.push(p.hash.clone());
        row.push(match s {
            PointStatus::Done(r) => crate::measure::quality::of_result(r).as_str().into(),
            _ => String::new(),
        });
        row.push(match (p.closed, sample.contains(&p.index)) {
            (true, true) => "verification".into(),
            (true, false) => "closed".into(),
            (false, _) => String::new(),
        });
        // The steady-state measurement's SE and what ended its window (empty for a layout
        // without them).
        let (se, stop) = match s {
            PointStatus::Done(r) => (
                r.answer.se.map_or(String::new(), |v| v.to_string()),
                r.steady_state.as_ref().map_or(String::new(), |st| st.stop.clone()),
            ),
            PointStatus::Failed(f) => (
                f.measured.as_ref().and_then(|r| r.answer.se).map_or(String::new(), |v| v.to_string()),
                String::new(),
            ),
            _ => (String::new(), String::new()),
        };
        row.extend([se, stop]);
        let layer = match s {
            PointStatus::Done(r) => r.layer,
            _ => None,
        };
        row.extend(match layer {
            Some(l) => {
                [l.layer_cv, l.layer_cv_noise, l.covered_fraction, l.roughness_d].map(|v| v.to_string())
            }
            None => std::array::from_fn(|_| String::new()),
        });
        let packing = match s {
            PointStatus::Done(r) => (r.layer_packing, r.layer_packing_se),
            PointStatus::Failed(f) => {
                f.measured.as_ref().map_or((None, None), |r| (r.layer_packing, r.layer_packing_se))
            }
            _ => (None, None),
        };
        row.extend([packing.0, packing.1].map(|v| v.map_or(String::new(), |v| v.to_string())));
        let measured = match s {
            PointStatus::Done(r) => Some(&**r),
            PointStatus::Failed(f) => f.measured.as_deref(),
            _ => None,
        };
        match measured {
            Some(r) => row.extend(columns.layout.result_values(r)),
            None => row.extend(std::iter::repeat_n(String::new(), own.len())),
        }
        w.write_record(&row).expect("in-memory csv");
    }
    let bytes = w.into_inner().expect("in-memory csv");
    crate::sys::atomic::write(&path, &bytes).map_err(io(&path))
}
