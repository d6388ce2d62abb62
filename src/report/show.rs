//! `sweep show DIR INDEX`: one design point's own page — its parameters (swept and fixed), its
//! status and result or failure, its spreading-quality measures, its v_x profile, its run
//! directory, and how to look at its particles.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::ReportError;
use crate::error::Result;
use crate::measure::quality::{self, Profile, Quality};
use crate::outcome::{RunFailure, RunResult};
use crate::run::screen::Screen;
use crate::store::{PointStatus, Store};
use crate::sweep::Sweep;

/// Everything `sweep show` prints (`--json` prints this).
#[derive(Debug, Clone, Serialize)]
pub struct PointPage {
    pub index: usize,
    /// `done`, `failed`, `screened` or `pending`.
    pub status: &'static str,
    /// Swept parameters, in the sweep file's units.
    pub swept: BTreeMap<String, f64>,
    /// Every other catalogue parameter.
    pub fixed: Vec<crate::point::FixedValue>,
    pub units: BTreeMap<String, String>,
    pub result: Option<RunResult>,
    pub failure: Option<RunFailure>,
    pub quality: Option<Quality>,
    pub profile: Option<Profile>,
    /// Height above the plate of each v_x layer, mm (z = gap + k·D/2); empty when the point
    /// has no result.
    pub vx_heights_mm: Vec<f64>,
    pub run_dir: PathBuf,
    /// Files in the run directory.
    pub files: Vec<String>,
    /// The command that reruns this point with particle and blade dumps for ParaView.
    pub view_command: String,
    /// What the layout prints of its result instead of MFR and v_x (a pour's angle of repose).
    #[serde(skip)]
    pub own_lines: Option<Vec<String>>,
}

/// Read point `index` of the sweep directory `dir`.
pub fn show(dir: &Path, index: usize) -> Result<PointPage> {
    let (manifest, toml) = Store::read_manifest(dir)?;
    let sweep = Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    let n = manifest.points.len();
    let Some(point) = manifest.points.get(index) else {
        return Err(ReportError::NoPoint { dir: dir.to_path_buf(), index, points: n }.into());
    };
    let store = Store::open(dir);
    let (statuses, _, _) = Screen::of(&sweep).statuses(&store, &manifest);
    let run_dir = store.run_dir(&point.hash);
    let mut files: Vec<String> = std::fs::read_dir(&run_dir)
        .map(|d| d.filter_map(|e| e.ok()).map(|e| e.file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    files.sort();
    let swept: BTreeMap<String, f64> =
        manifest.parameters.iter().cloned().zip(point.values.iter().copied()).collect();
    let units = sweep.swept.iter().map(|p| (p.name.clone(), p.unit.to_string())).collect();
    let set = manifest
        .parameters
        .iter()
        .zip(&point.values)
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(",");
    let view_command = format!(
        "sweep run {} --set {set} --vtk --out {}",
        dir.join("sweep.toml").display(),
        dir.join("view").join(index.to_string()).display()
    );
    let (status, result, failure) = match statuses.into_iter().nth(index) {
        Some(PointStatus::Done(r)) => ("done", Some(*r), None),
        Some(PointStatus::Failed(f)) => ("failed", None, Some(*f)),
        Some(PointStatus::Screened) => ("screened", None, None),
        _ => ("pending", None, None),
    };
    let measured = result.as_ref().or(failure.as_ref().and_then(|f| f.measured.as_deref()));
    let vx_heights_mm = measured.map_or_else(Vec::new, |r| layer_heights_mm(&sweep, r));
    let (quality, profile) = match measured {
        Some(r) => {
            let v = r.parameters.get("blade_speed").copied().unwrap_or(f64::NAN);
            (Some(quality::of_result(r)), quality::measure(&r.vx, v))
        }
        None => (None, None),
    };
    let own_lines =
        crate::scenes::of(&sweep.file.scene).ok().zip(measured).and_then(|(l, r)| l.result_lines(r));
    Ok(PointPage {
        own_lines,
        index,
        status,
        swept,
        fixed: crate::point::fixed_values(&sweep),
        units,
        result,
        failure,
        quality,
        profile,
        vx_heights_mm,
        run_dir,
        files,
        view_command,
    })
}

/// The height of each v_x layer of a result, mm, from its parameters and the sweep's scene (a
/// point run with `--force` is outside the bounds, so they are not checked here).
fn layer_heights_mm(sweep: &Sweep, r: &RunResult) -> Vec<f64> {
    let mut settings = sweep.file.scene.clone();
    settings.force_bounds = true;
    match crate::scenes::build(&r.parameters, &settings) {
        Ok(s) => (1..=r.vx.len()).map_while(|k| s.layer_height(k)).map(|z| z * 1e3).collect(),
        Err(_) => Vec::new(),
    }
}

impl PointPage {
    /// The page as text for a terminal.
    pub fn to_text(&self) -> String {
        let mut t = String::new();
        let _ = writeln!(t, "point #{}: {}", self.index, self.status);
        let _ = writeln!(t, "\nswept parameters:");
        for (k, v) in &self.swept {
            let _ = writeln!(t, "  {k:<16} {v} {}", self.units.get(k).map_or("", String::as_str));
        }
        let _ = writeln!(t, "fixed parameters (default: not written in the sweep file):");
        for f in &self.fixed {
            let _ = writeln!(
                t,
                "  {:<16} {} {}{}",
                f.name,
                f.value,
                f.unit,
                if f.written { "" } else { "  (default)" }
            );
        }
        let measured = self.result.as_ref().or(self.failure.as_ref().and_then(|f| f.measured.as_deref()));
        if let Some(f) = &self.failure {
            let _ = writeln!(t, "\nfailed: {} — {}", f.class.as_str(), f.reason);
            if measured.is_some() {
                let _ = writeln!(
                    t,
                    "(what the run measured is shown below for diagnosis; it is in no statistic)"
                );
            }
        }
        if self.status == "screened" {
            let _ = writeln!(
                t,
                "\nscreened: nothing can pass under the blade here; counted as MFR = 0 without a run"
            );
        }
        if let (Some(r), Some(own)) = (measured, &self.own_lines) {
            let _ = writeln!(t, "\nresult:");
            for line in own {
                let _ = writeln!(t, "  {line}");
            }
            let _ = writeln!(t, "  particles        {}", r.particles);
            let _ = writeln!(t, "  wall time        {:.1} s", r.wall_time);
        } else if let Some(r) = measured {
            let _ = writeln!(t, "\nresult:");
            let se = r.answer.se.map_or(String::new(), |se| format!(" ± {se:.4} (SE)"));
            let _ = writeln!(
                t,
                "  MFR              {:.4}{se} (–), from {} particle crossings",
                r.answer.value, r.answer_particles
            );
            let _ = writeln!(t, "  MFR (flux check) {:.4} (–)", r.mfr_flux);
            let w: Vec<String> = r.answer_windows.iter().map(|v| format!("{v:.4}")).collect();
            let _ = writeln!(t, "  sub-window MFR   {}", w.join(", "));
            let _ = writeln!(
                t,
                "  steadiness p     {:.3} ({})",
                r.steady_p,
                if r.steady { "steady" } else { "unsteady" }
            );
            let _ = writeln!(t, "  particles        {}", r.particles);
            let _ = writeln!(t, "  wall time        {:.1} s", r.wall_time);
            if r.extensions > 0 {
                let _ = writeln!(
                    t,
                    "  extended         {} time(s) by `sweep extend`, to an SE of {} (the parts in the run directory's extension-N/; the times are every part's)",
                    r.extensions,
                    r.mfr_se_target.map_or("?".into(), |x| format!("{x:.4}")),
                );
            }
            if let (Some(q), Some(p)) = (self.quality, self.profile) {
                let _ = writeln!(
                    t,
                    "  v_x class        {} (jitter {:.3}, rise {:.3} of the blade speed)",
                    q.as_str(),
                    p.jitter,
                    p.rise
                );
            }
            let v = r.parameters.get("blade_speed").copied().unwrap_or(f64::NAN);
            let _ = writeln!(t, "\nv_x profile in front of the blade (layer k at gap + k·D/2):");
            let _ = writeln!(t, "  {:>5} {:>8} {:>12} {:>14}", "k", "z (mm)", "v_x (m/s)", "v_x / v (–)");
            for (k, x) in r.vx.iter().enumerate() {
                let z = self.vx_heights_mm.get(k).map_or("?".to_string(), |z| format!("{z:.2}"));
                match x {
                    Some(x) => {
                        let _ = writeln!(t, "  {:>5} {:>8} {:>12.4} {:>14.4}", k + 1, z, x, x / v);
                    }
                    None => {
                        let _ = writeln!(t, "  {:>5} {:>8} {:>12} {:>14}", k + 1, z, "empty", "");
                    }
                }
            }
        }
        let _ = writeln!(t, "\nrun directory: {}", self.run_dir.display());
        if self.files.is_empty() {
            let _ = writeln!(t, "  (absent: the point has not run)");
        } else {
            let _ = writeln!(t, "  {}", self.files.join("  "));
        }
        let _ = writeln!(
            t,
            "\nto look at its particles in ParaView, rerun it with dumps:\n  {}",
            self.view_command
        );
        let _ = writeln!(
            t,
            "  then open <out>/vtk/particles_*.vtk (Glyph filter, sphere, scale by radius) and <out>/vtk/blade_*.vtk"
        );
        t
    }
}
