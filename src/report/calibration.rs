//! The answer of a calibration directory (`sweep calibrate`, `sweep report` of one): the
//! posterior of each free parameter with its credible interval and how well it is identified,
//! the ridges, the residuals at the best run and at the posterior's mode, the batches; written
//! as `posterior.json`, `calibrated.toml` and `calibrated-ranges.toml` (the parameters a
//! spreading sweep includes) and `report/report.html` with a map of the posterior over each pair
//! of free parameters.

use std::path::{Path, PathBuf};

use serde::Serialize;

use serde_json::json;

use super::page::FigureView;
use super::plots::Figure;
use crate::analysis::calibration::Target;
use crate::error::Result;
use crate::run::calibrate::{self as cal, fmt, unit_value, CalibrationWatch};
use crate::store::PointStatus;
use crate::sweep::{ParamKind, Sweep};

pub use crate::run::calibrate::POSTERIOR;
/// The calibrated parameters as values, and with the credible intervals as ranges.
pub const CALIBRATED: &str = "calibrated.toml";
pub const CALIBRATED_RANGES: &str = "calibrated-ranges.toml";

/// One free parameter's posterior, in its units.
#[derive(Debug, Clone, Serialize)]
pub struct ParameterPosterior {
    pub name: String,
    pub unit: String,
    /// The sweep file's range (the uniform prior).
    pub prior: (f64, f64),
    pub median: f64,
    /// The 95 % credible interval.
    pub lo: f64,
    pub hi: f64,
    /// Posterior SD over prior SD, in unit coordinates.
    pub sd_ratio: f64,
    pub identification: String,
}

/// A target against what was simulated.
#[derive(Debug, Clone, Serialize)]
pub struct Residual {
    pub target: Target,
    pub simulated: f64,
    /// The run's SE of it, or the emulator's SD at a setting.
    pub se: Option<f64>,
    /// (simulated − target) / target SD.
    pub in_sd: f64,
}

impl Residual {
    /// How far the simulated value is from the target, in SDs of the two combined (the
    /// target's, and the run's SE or the emulator's SD).
    pub fn combined_sd(&self) -> f64 {
        let sd = (self.target.sd.powi(2) + self.se.unwrap_or(0.0).powi(2)).sqrt();
        (self.simulated - self.target.value).abs() / sd
    }
}

/// A target missed by more than this many combined SDs ([`Residual::combined_sd`]) at the best
/// run and at the posterior's mode is out of reach: no setting in the sweep file's ranges
/// reproduces it, and a posterior that has stopped moving says where the miss is smallest, not
/// what the powder is. Four: a reproduced target lies within 3 SD at 99.7 %, and the mode's
/// emulator SD is already in its SD.
pub const OUT_OF_REACH_SD: f64 = 4.0;

/// A setting with its residuals.
#[derive(Debug, Clone, Serialize)]
pub struct Setting {
    /// The point's index (a run), absent for the posterior's mode.
    pub index: Option<usize>,
    pub values: Vec<f64>,
    pub residuals: Vec<Residual>,
}

/// One batch as judged.
#[derive(Debug, Clone, Serialize)]
pub struct BatchRow {
    pub label: String,
    pub points: usize,
    /// Per free parameter: median and credible interval, in its units.
    pub intervals: Option<Vec<(f64, f64, f64)>>,
    pub change: Option<f64>,
}

/// The calibration's answer.
#[derive(Debug, Clone, Serialize)]
pub struct Calibration {
    pub dir: PathBuf,
    pub targets: Vec<Target>,
    pub parameters: Vec<ParameterPosterior>,
    /// Posterior correlations, row-major.
    pub correlation: Vec<f64>,
    /// Pairs on a ridge, in words.
    pub ridges: Vec<String>,
    pub effective_samples: Option<f64>,
    /// The run whose results come nearest every target, and the posterior's mode by the emulators.
    pub best_run: Option<Setting>,
    pub mode: Option<Setting>,
    pub batches: Vec<BatchRow>,
    /// "converged", "not converged" (at max, or unfinished), "out of reach" (a target no
    /// setting in the ranges reproduces: [`OUT_OF_REACH_SD`]) or "no posterior".
    pub status: String,
    pub reason: String,
    pub runs_done: usize,
    pub runs_failed: usize,
    pub cpu_s: f64,
    /// Runs with a CPU time (LIGGGHTS); the stand-in has none.
    pub cpu_runs: usize,
    /// Per target: the scatter of its runs between seeds beside their own SE, the noise the
    /// emulator took, and the nugget it fitted on top (the last batch's).
    pub noise: Vec<Noise>,
}

/// One target's noise, as the last batch's emulator saw it.
#[derive(Debug, Clone, Serialize)]
pub struct Noise {
    #[serde(flatten)]
    pub scatter: crate::analysis::calibration::Scatter,
    pub nugget_sd: Option<f64>,
}

impl Noise {
    /// The noise in one line.
    pub fn line(&self) -> String {
        let s = &self.scatter;
        let own = s.own_se.map_or("none".into(), fmt);
        let between = match s.between_seed_sd {
            Some(b) => format!(
                "scatter between seeds {} ({} df over {} settings, {} runs) against the runs' own SE {own}",
                fmt(b),
                s.df,
                s.settings,
                s.runs
            ),
            None => format!(
                "scatter between seeds not measured (one run per setting; --repeats 2 or more measures it); the runs' own SE {own}"
            ),
        };
        let nugget = self.nugget_sd.map_or(String::new(), |n| format!("; the emulator's nugget {}", fmt(n)));
        format!("{}: {between}{nugget}", s.name)
    }
}

impl Calibration {
    /// The answer in a few lines, for the terminal.
    pub fn lines(&self) -> Vec<String> {
        let mut out = vec![format!("{}: {}", self.status, self.reason)];
        for p in &self.parameters {
            out.push(format!(
                "  {} = {} [{}, {}] {} (95 % credible; {}, posterior SD {:.0} % of the prior's)",
                p.name,
                fmt(p.median),
                fmt(p.lo),
                fmt(p.hi),
                if p.unit == "-" { "" } else { &p.unit },
                p.identification,
                100.0 * p.sd_ratio
            ));
        }
        for r in &self.ridges {
            out.push(format!("  ridge: {r}"));
        }
        for n in &self.noise {
            out.push(format!("  noise of {}", n.line()));
        }
        if let Some(b) = &self.best_run {
            let res: Vec<String> = b
                .residuals
                .iter()
                .map(|r| {
                    format!(
                        "{} {} against {} ({:+.1} SD)",
                        r.target.name,
                        fmt(r.simulated),
                        fmt(r.target.value),
                        r.in_sd
                    )
                })
                .collect();
            out.push(format!("  best run #{}: {}", b.index.unwrap_or(0), res.join(", ")));
        }
        let cpu = if self.cpu_runs > 0 {
            format!("{:.0} CPU s", self.cpu_s)
        } else {
            "no CPU time recorded".into()
        };
        out.push(format!(
            "  {} runs ({} failed), {cpu}; parameters for a sweep: {}",
            self.runs_done + self.runs_failed,
            self.runs_failed,
            self.dir.join(CALIBRATED).display()
        ));
        out.push(format!("report: {}", self.dir.join("report/report.html").display()));
        out
    }
}

/// Judge the calibration in `dir` and write its answer: posterior.json, the calibrated
/// parameters and the report.
pub fn write(dir: &Path) -> Result<Calibration> {
    let sweep = crate::run::load_dir_sweep(dir)?;
    let settings = cal::settings(dir).ok_or_else(|| crate::run::RunError::Dir {
        path: dir.to_path_buf(),
        why: format!("no {}: not a calibration directory", cal::SETTINGS),
    })?;
    let (manifest, _) = crate::store::Store::read_manifest(dir)?;
    let seed = match manifest.design {
        crate::store::DesignRecord::Adapt { seed, .. } => seed,
        _ => crate::sweep::DEFAULT_SEED,
    };
    let mut watch = CalibrationWatch::new(&sweep, settings.clone(), seed);
    let (manifest, status) = cal::judge_dir(dir, &mut watch)?;
    let c = answer(dir, &sweep, &settings.targets, &watch, &manifest, &status);
    let io = |path: PathBuf| move |e: std::io::Error| crate::run::RunError::Write { path, source: e };
    let json = serde_json::to_string_pretty(&c).expect("serialisable");
    crate::sys::atomic::write(&dir.join(POSTERIOR), json.as_bytes()).map_err(io(dir.join(POSTERIOR)))?;
    if !c.parameters.is_empty() {
        for (file, ranges) in [(CALIBRATED, false), (CALIBRATED_RANGES, true)] {
            let text = parameters_toml(&sweep, &c, ranges);
            crate::sys::atomic::write(&dir.join(file), text.as_bytes()).map_err(io(dir.join(file)))?;
        }
    }
    let figures = super::calibration_map::maps(&sweep, &watch, &manifest, &status)
        .map_err(|e| super::ReportError::Draw(e.to_string()))?;
    write_html(dir, &c, &sweep, &figures)?;
    Ok(c)
}

fn answer(
    dir: &Path,
    sweep: &Sweep,
    targets: &[Target],
    watch: &CalibrationWatch,
    manifest: &crate::store::Manifest,
    status: &[PointStatus],
) -> Calibration {
    let done: Vec<(usize, &crate::outcome::RunResult)> = status
        .iter()
        .enumerate()
        .filter_map(|(i, s)| if let PointStatus::Done(r) = s { Some((i, r.as_ref())) } else { None })
        .collect();
    let runs_failed = status.iter().filter(|s| matches!(s, PointStatus::Failed(_))).count();
    let cpu: Vec<f64> = done.iter().filter_map(|(_, r)| r.cpu_time).collect();
    let last = watch.batches.iter().rev().find(|b| b.posterior.is_some());
    let post = last.and_then(|b| b.posterior.as_ref());
    let parameters: Vec<ParameterPosterior> = post.map_or(Vec::new(), |p| {
        sweep
            .swept
            .iter()
            .enumerate()
            .map(|(j, par)| {
                let m = &p.marginals[j];
                let v = |u: f64| unit_value(sweep, j, u);
                ParameterPosterior {
                    name: par.name.clone(),
                    unit: par.unit.to_string(),
                    prior: (v(0.0), v(1.0)),
                    median: v(m.median),
                    lo: v(m.lo),
                    hi: v(m.hi),
                    sd_ratio: m.sd_ratio(),
                    identification: m.identification().to_string(),
                }
            })
            .collect()
    });
    let ridges = post.map_or(Vec::new(), |p| {
        p.ridges()
            .into_iter()
            .map(|(i, j, r)| {
                let (a, b) = (&sweep.swept[i].name, &sweep.swept[j].name);
                let how = if r < 0.0 { "more of one is matched by less of the other" } else { "they rise together" };
                format!(
                    "{a} and {b} trade off (posterior correlation {r:+.2}): pairs along the ridge reproduce the targets alike, {how}; only their combination is known"
                )
            })
            .collect()
    });
    // The best run: the done run nearest every target, in target SDs (with its own SE).
    let best_run = done
        .iter()
        .filter_map(|(i, r)| {
            let residuals: Option<Vec<Residual>> = targets
                .iter()
                .map(|t| {
                    let q = cal::quantity(&t.name)?;
                    let (v, se) = q.read(r)?;
                    Some(Residual { target: t.clone(), simulated: v, se, in_sd: (v - t.value) / t.sd })
                })
                .collect();
            let residuals = residuals?;
            let chi2: f64 = residuals.iter().map(|r| r.in_sd * r.in_sd).sum();
            Some((chi2, Setting { index: Some(*i), values: manifest.points[*i].values.clone(), residuals }))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|x| x.1);
    let mode = post.zip(watch.emulators()).map(|(p, ems)| Setting {
        index: None,
        values: crate::sweep::space::scale_point(sweep, &p.best),
        residuals: targets
            .iter()
            .zip(ems)
            .map(|(t, em)| {
                let (m, s) = em.predict(&p.best);
                Residual { target: t.clone(), simulated: m, se: Some(s), in_sd: (m - t.value) / t.sd }
            })
            .collect(),
    });
    // Targets that neither the nearest run nor the posterior's mode comes near.
    let missed: Vec<&Residual> = best_run.as_ref().map_or(Vec::new(), |b| {
        b.residuals
            .iter()
            .enumerate()
            .filter(|(k, r)| {
                r.combined_sd() > OUT_OF_REACH_SD
                    && mode.as_ref().is_none_or(|m| m.residuals[*k].combined_sd() > OUT_OF_REACH_SD)
            })
            .map(|(_, r)| r)
            .collect()
    });
    let mut parameters = parameters;
    if !missed.is_empty() {
        for p in &mut parameters {
            p.identification = "not identified: the targets are out of reach".into();
        }
    }
    let batches = watch
        .batches
        .iter()
        .map(|b| BatchRow {
            label: b.label.clone(),
            points: b.points,
            intervals: b.posterior.as_ref().map(|p| {
                p.marginals
                    .iter()
                    .enumerate()
                    .map(|(j, m)| {
                        (
                            unit_value(sweep, j, m.median),
                            unit_value(sweep, j, m.lo),
                            unit_value(sweep, j, m.hi),
                        )
                    })
                    .collect()
            }),
            change: b.change,
        })
        .collect();
    let settings = watch.settings();
    let pending = status.iter().filter(|s| !s.is_finished()).count();
    let (st, reason) = match (watch.converged_at, post) {
        _ if !missed.is_empty() => {
            let which: Vec<String> = missed
                .iter()
                .map(|r| {
                    format!(
                        "{} = {} ± {} (the nearest run gives {}, {:+.1} SD)",
                        r.target.name,
                        fmt(r.target.value),
                        fmt(r.target.sd),
                        fmt(r.simulated),
                        r.in_sd
                    )
                })
                .collect();
            (
                "out of reach".to_string(),
                format!(
                    "no setting in the sweep file's ranges reproduces {}, nor does the posterior's best setting \
                     (more than {OUT_OF_REACH_SD} SD off); check the targets' values and units, or widen the ranges",
                    which.join(" and ")
                ),
            )
        }
        (_, None) => ("no posterior".to_string(), "too few runs measured every target for an emulator".to_string()),
        (Some(k), _) => (
            "converged".to_string(),
            format!(
                "the credible intervals moved by at most {:.0} % of their width for {} batches in a row, after {} ({} points)",
                100.0 * settings.tolerance,
                settings.hold,
                watch.batches[k].label,
                watch.batches[k].points
            ),
        ),
        (None, Some(_)) if pending > 0 => {
            ("not converged".to_string(), format!("{pending} planned points are not finished; `sweep resume {}`", crate::sys::shell::quote_path(dir)))
        }
        (None, Some(_)) => (
            "not converged".to_string(),
            format!(
                "the credible intervals did not stay within {:.0} % of their width for {} batches in a row by {} points; a larger --max continues",
                100.0 * settings.tolerance,
                settings.hold.max(1),
                manifest.points.len()
            ),
        ),
    };
    Calibration {
        dir: dir.to_path_buf(),
        targets: targets.to_vec(),
        parameters,
        correlation: post.map_or(Vec::new(), |p| p.correlation.clone()),
        ridges,
        effective_samples: post.map(|p| p.ess),
        best_run,
        mode,
        batches,
        status: st,
        reason,
        runs_done: done.len(),
        runs_failed,
        cpu_s: cpu.iter().fold(0.0, |a, b| a + b),
        cpu_runs: cpu.len(),
        noise: watch.batches.last().map_or(Vec::new(), |b| {
            b.scatter
                .iter()
                .zip(&b.nugget_sd)
                .map(|(s, n)| Noise { scatter: s.clone(), nugget_sd: *n })
                .collect()
        }),
    }
}

/// The calibrated `[parameters]` table: the free parameters at their posterior medians (or, with
/// `ranges`, over their credible intervals), then the sweep file's fixed parameters: the powder
/// as calibrated, for a spreading sweep's `include`.
fn parameters_toml(sweep: &Sweep, c: &Calibration, ranges: bool) -> String {
    let targets: Vec<String> =
        c.targets.iter().map(|t| format!("{} = {} ± {}", t.name, t.value, t.sd)).collect();
    let mut s = format!(
        "# The powder calibrated by `sweep calibrate` in {} against {} ({}: {}).\n",
        c.dir.display(),
        targets.join(", "),
        c.status,
        c.reason
    );
    s.push_str(if ranges {
        "# The free parameters over their 95 % credible intervals: sweep the powder's uncertainty.\n"
    } else {
        "# The free parameters at their posterior medians; their 95 % credible intervals beside them.\n"
    });
    s.push_str(
        "# Include it from a sweep file: include = [\"this file\"]; the sweep file's own entries win.\n",
    );
    s.push_str(
        "# Sizes and the rest of [scene] are not parameters: copy them from the calibration's sweep.toml.\n",
    );
    s.push_str("[parameters]\n");
    let unit = |u: &str| if u == "-" { String::new() } else { format!(", unit = \"{u}\"") };
    for p in &c.parameters {
        if ranges {
            s.push_str(&format!(
                "{} = {{ lo = {}, hi = {}{} }}\n",
                p.name,
                fmt(p.lo),
                fmt(p.hi),
                unit(&p.unit)
            ));
        } else {
            s.push_str(&format!(
                "{} = {{ value = {}{} }}   # 95 % credible [{}, {}], {}\n",
                p.name,
                toml_num(p.median),
                unit(&p.unit),
                fmt(p.lo),
                fmt(p.hi),
                p.identification
            ));
        }
    }
    for f in &sweep.fixed {
        if let ParamKind::Fixed(v) = f.kind {
            s.push_str(&format!("{} = {{ value = {:?}{} }}\n", f.name, v, unit(f.unit)));
        }
    }
    s
}

/// A TOML float in four significant figures (always with its point: `2.0`, not the integer `2`).
fn toml_num(v: f64) -> String {
    let s = fmt(v);
    if s.contains(['.', 'e', 'n', 'i']) {
        s
    } else {
        format!("{s}.0")
    }
}

/// Write `report/report.html` and the maps (SVG and PNG) of the calibration in `dir`.
fn write_html(dir: &std::path::Path, c: &Calibration, sweep: &Sweep, figures: &[Figure]) -> Result<()> {
    let rdir = dir.join("report");
    let io =
        |path: std::path::PathBuf| move |e: std::io::Error| crate::run::RunError::Write { path, source: e };
    std::fs::create_dir_all(&rdir).map_err(io(rdir.clone()))?;
    for f in figures {
        for (ext, bytes) in [("svg", f.svg.as_bytes()), ("png", f.png.as_slice())] {
            let p = rdir.join(format!("{}.{ext}", f.name));
            crate::sys::atomic::write(&p, bytes).map_err(io(p.clone()))?;
        }
    }
    let n = fmt;
    let targets: Vec<serde_json::Value> = c
        .targets
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let best = c.best_run.as_ref().map(|b| &b.residuals[k]);
            let mode = c.mode.as_ref().map(|m| &m.residuals[k]);
            json!({
                "name": t.name,
                "value": n(t.value),
                "sd": n(t.sd),
                "best": best.map_or("–".into(), |r| n(r.simulated)),
                "residual": best.map_or("–".into(), |r| format!("{:+.2}", r.in_sd)),
                "mode": mode.map_or("–".into(), |r| format!("{} ± {}", n(r.simulated), n(r.se.unwrap_or(0.0)))),
            })
        })
        .collect();
    let parameters: Vec<serde_json::Value> = c
        .parameters
        .iter()
        .map(|p| {
            json!({
                "name": p.name,
                "unit": p.unit,
                "prior_lo": n(p.prior.0),
                "prior_hi": n(p.prior.1),
                "median": n(p.median),
                "lo": n(p.lo),
                "hi": n(p.hi),
                "sd_ratio": format!("{:.2}", p.sd_ratio),
                "identification": p.identification,
            })
        })
        .collect();
    let best_run = c.best_run.as_ref().map(|b| {
        let vals: Vec<String> =
            sweep.names().iter().zip(&b.values).map(|(k, v)| format!("{k} = {}", n(*v))).collect();
        json!({ "index": b.index.unwrap_or(0), "values": vals.join(", ") })
    });
    let cpu = if c.cpu_runs > 0 {
        format!("{:.0} CPU s over the {} runs that record it", c.cpu_s, c.cpu_runs)
    } else {
        "no CPU time recorded".into()
    };
    let batches: Vec<serde_json::Value> = c
        .batches
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let intervals = b
                .intervals
                .as_ref()
                .map(|iv| iv.iter().map(|(m, lo, hi)| [n(*m), n(*lo), n(*hi)]).collect::<Vec<_>>());
            json!({
                "number": k + 1,
                "label": b.label,
                "points": b.points,
                "intervals": intervals,
                "change": b.change.map_or("–".into(), |v| format!("{:.0} %", 100.0 * v)),
            })
        })
        .collect();
    let context = json!({
        "name": sweep.file.name,
        "class": if c.status == "converged" { "converged" } else { "open" },
        "status": c.status,
        "reason": c.reason,
        "targets": targets,
        "parameters": parameters,
        "ridges": c.ridges,
        "noise": c.noise.iter().map(Noise::line).collect::<Vec<_>>(),
        "best_run": best_run,
        "runs_done": c.runs_done,
        "runs_failed": c.runs_failed,
        "cpu": cpu,
        "effective_samples": c.effective_samples.map_or("–".into(), |e| format!("{e:.0}")),
        "figures": figures.iter().map(FigureView::of).collect::<Vec<_>>(),
        "names": sweep.names(),
        "batches": batches,
    });
    let h = super::page::render("calibration.html", &context);
    let p = rdir.join("report.html");
    crate::sys::atomic::write(&p, h.as_bytes()).map_err(io(p.clone()))?;
    Ok(())
}
