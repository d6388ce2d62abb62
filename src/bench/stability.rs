//! `sweep bench stability`: the stability edge of the scene's numerics (BENCHMARKS.md "Stability edge").
//!
//! At the harshest corner of a sweep's space ([`harshest_corner`]) the real point is run with
//! the timestep driven up in fractions of the Rayleigh time, and with the stiffness (Young's
//! modulus) driven down at the sweep's timestep fraction. Each ladder stops at its first level
//! that fails: a run lost atoms, its energy exploded, LIGGGHTS stopped with an error, the pile
//! never came to rest, or the mean MFR over the seeds drifted from the first level's beyond
//! [`drift_bound`]. The last level that passed is the safe bound; the first that failed is the
//! edge.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::{opt, BenchError};
use crate::error::{Error, Res, Result};
use crate::outcome::{FailureClass, RunOutcome};
use crate::point::{self, PointContext};
use crate::sweep::{ParamKind, Parameter, Sweep};
use crate::sys::process::CancelToken;

/// Floor of the MFR drift bound, relative to the first level's mean MFR.
pub const DRIFT_FLOOR: f64 = 0.10;
/// Median seed-to-seed spread of MFR at one point (sd / mean; BENCHMARKS.md "Scene
/// convergence"): the standard error used when a level has a single seed.
pub const MEDIAN_SEED_SPREAD: f64 = 0.08;
use crate::scene::MIN_YOUNGS_MPA;

/// Which way each parameter makes the scene harsher for the integrator. Smaller and softer
/// particles have shorter, deeper contacts; faster blades, more friction, more restitution
/// (less damping), denser particles and a larger gap (more moving powder) load them harder.
fn harsh_high(name: &str) -> Option<bool> {
    match name {
        "diameter" | "weibull_scale" | "weibull_shape" | "youngs_modulus" => Some(false),
        "blade_speed" | "friction" | "rolling_friction" | "restitution" | "density" | "gap" => Some(true),
        _ => None,
    }
}

/// The harshest corner of the sweep's space, as swept values in file order: each swept
/// parameter at the end [`harsh_high`] names (a parameter with no direction at its middle);
/// fixed parameters stay as given.
pub fn harshest_corner(sweep: &Sweep) -> Vec<f64> {
    sweep
        .swept
        .iter()
        .map(|p| match p.kind {
            ParamKind::Swept { lo, hi, .. } => match harsh_high(&p.name) {
                Some(true) => hi,
                Some(false) => lo,
                None => 0.5 * (lo + hi),
            },
            ParamKind::Fixed(v) => v,
        })
        .collect()
}

/// One ladder's rung: a timestep fraction and a modulus.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Level {
    pub fraction: f64,
    pub youngs_mpa: f64,
}

/// One run of a level.
#[derive(Debug, Clone)]
pub struct Run {
    pub seed: u64,
    /// `ok`, `unsteady` (ran to the end, MFR kept) or the failure class.
    pub status: String,
    pub mfr: Option<f64>,
    pub timestep: f64,
    pub wall: f64,
    pub reason: String,
}

impl Run {
    /// A numerical failure: the run did not reach a valid end (an unsteady flow is a property
    /// of the flow, not of the numerics: its MFR still counts for the drift).
    pub fn failed(&self) -> bool {
        self.mfr.is_none()
    }
}

/// One level with its runs and verdict.
#[derive(Debug, Clone)]
pub struct LevelResult {
    pub ladder: &'static str,
    pub level: Level,
    pub runs: Vec<Run>,
    pub mfr_mean: Option<f64>,
    pub mfr_se: Option<f64>,
    /// (mean − first level's mean) / first level's mean.
    pub drift: Option<f64>,
    pub bound: Option<f64>,
    /// `pass`, or why the level failed.
    pub verdict: String,
}

impl LevelResult {
    pub fn passed(&self) -> bool {
        self.verdict == "pass"
    }
    fn timestep(&self) -> f64 {
        self.runs.first().map_or(f64::NAN, |r| r.timestep)
    }
    fn wall(&self) -> f64 {
        self.runs.iter().map(|r| r.wall).sum()
    }
}

/// The MFR drift bound of a level against the first level, relative to the first level's
/// mean: max([`DRIFT_FLOOR`], 2 × the standard error of the difference of the two means).
pub fn drift_bound(base: (f64, f64), this: (f64, f64)) -> f64 {
    let se_diff = (base.1.powi(2) + this.1.powi(2)).sqrt();
    DRIFT_FLOOR.max(2.0 * se_diff / base.0)
}

/// What the bench was asked to do.
pub struct StabilityPlan {
    pub corner: Vec<f64>,
    /// The corner's Young's modulus, MPa: the timestep ladder's.
    pub corner_youngs_mpa: f64,
    pub fractions: Vec<f64>,
    pub moduli: Vec<f64>,
    pub seeds: u64,
    /// Whether the timestep ladder runs (`--ladder`).
    pub timestep_ladder: bool,
    /// Whether the stiffness ladder runs.
    pub stiffness_ladder: bool,
    pub jobs: usize,
    pub out: PathBuf,
}

/// The default stiffness ladder: the corner's modulus, halved down to [`MIN_YOUNGS_MPA`]
/// (which always ends it).
pub fn default_moduli(start: f64) -> Vec<f64> {
    let mut v = vec![start];
    let mut e = start / 2.0;
    while e > MIN_YOUNGS_MPA * 1.001 {
        v.push(e);
        e /= 2.0;
    }
    if start > MIN_YOUNGS_MPA {
        v.push(MIN_YOUNGS_MPA);
    }
    v
}

/// The sweep with the level's timestep fraction and modulus, and the swept values.
fn level_sweep(sweep: &Sweep, corner: &[f64], level: Level) -> (Sweep, Vec<f64>) {
    let mut sweep = sweep.clone();
    sweep.file.scene.rayleigh_fraction = level.fraction;
    sweep.file.scene.force_bounds = true;
    let mut values = corner.to_vec();
    match sweep.swept.iter().position(|p| p.name == "youngs_modulus") {
        Some(i) => values[i] = level.youngs_mpa,
        None => {
            sweep.fixed.retain(|p| p.name != "youngs_modulus");
            sweep.fixed.push(Parameter {
                name: "youngs_modulus".into(),
                unit: "MPa",
                kind: ParamKind::Fixed(level.youngs_mpa),
            });
        }
    }
    (sweep, values)
}

/// The ladders the plan runs, each with its levels in order.
fn levels(ctx: &PointContext, plan: &StabilityPlan) -> Vec<(&'static str, Vec<Level>)> {
    let default_fraction = ctx.sweep.file.scene.rayleigh_fraction;
    let e0 = plan.corner_youngs_mpa;
    let mut out = Vec::new();
    if plan.timestep_ladder {
        out.push((
            "timestep",
            plan.fractions.iter().map(|&f| Level { fraction: f, youngs_mpa: e0 }).collect(),
        ));
    }
    if plan.stiffness_ladder {
        let levels =
            plan.moduli.iter().map(|&e| Level { fraction: default_fraction, youngs_mpa: e }).collect();
        out.push(("stiffness", levels));
    }
    out
}

/// Every level's scene and deck build (bad input is found before anything runs).
pub fn check(ctx: &PointContext, plan: &StabilityPlan) -> Result<()> {
    for (_, ls) in levels(ctx, plan) {
        for level in ls {
            let (sweep, values) = level_sweep(&ctx.sweep, &plan.corner, level);
            let c = ctx.with_sweep(sweep);
            point::prepare(&c, &values)?;
        }
    }
    Ok(())
}

/// Run one level: every seed, `jobs` at a time, in `dir/<name>-s<seed>`.
fn run_level(
    ctx: &PointContext,
    plan: &StabilityPlan,
    level: Level,
    name: &str,
    cancel: &CancelToken,
) -> Result<Vec<Run>> {
    let (sweep, values) = level_sweep(&ctx.sweep, &plan.corner, level);
    let base_seed = sweep.file.scene.seed;
    let seeds: Vec<u64> = (0..plan.seeds).map(|k| base_seed + k).collect();
    let mut runs = Vec::new();
    for chunk in seeds.chunks(plan.jobs.max(1)) {
        let outcomes: Vec<Result<Run>> = std::thread::scope(|s| {
            let handles: Vec<_> = chunk
                .iter()
                .map(|&seed| {
                    let mut sw = sweep.clone();
                    sw.file.scene.seed = seed;
                    let values = values.clone();
                    let dir = plan.out.join("runs").join(format!("{name}-s{seed}"));
                    s.spawn(move || -> Result<Run> {
                        let c = ctx.with_sweep(sw);
                        let mut prepared = point::prepare(&c, &values)?;
                        let timestep = prepared.scene.timestep;
                        prepared.parameters.insert("rayleigh_fraction".into(), level.fraction);
                        Ok(match point::execute(&c, &prepared, &dir, cancel) {
                            RunOutcome::Done(r) => Run {
                                seed,
                                status: "ok".into(),
                                mfr: Some(r.answer.value),
                                timestep,
                                wall: r.wall_time,
                                reason: String::new(),
                            },
                            RunOutcome::Failed(f)
                                if f.class == FailureClass::Unsteady && f.measured.is_some() =>
                            {
                                Run {
                                    seed,
                                    status: "unsteady".into(),
                                    mfr: f.measured.as_ref().map(|m| m.answer.value),
                                    timestep,
                                    wall: f.wall_time,
                                    reason: f.reason,
                                }
                            }
                            RunOutcome::Failed(f) => Run {
                                seed,
                                status: f.class.as_str().into(),
                                mfr: None,
                                timestep,
                                wall: f.wall_time,
                                reason: f.reason,
                            },
                            RunOutcome::Cancelled => return Err(Error::Interrupted),
                        })
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|_| Err(BenchError::Panicked.into())))
                .collect()
        });
        for o in outcomes {
            runs.push(o?);
        }
    }
    Ok(runs)
}

/// Judge a level against the ladder's first (`base`: its mean and SE).
fn judge(ladder: &'static str, level: Level, runs: Vec<Run>, base: Option<(f64, f64)>) -> LevelResult {
    let failed: Vec<&Run> = runs.iter().filter(|r| r.failed()).collect();
    let mfrs: Vec<f64> = runs.iter().filter_map(|r| r.mfr).collect();
    let ms = mean_se(&mfrs);
    let (mut drift, mut bound) = (None, None);
    let verdict = if let Some(f) = failed.first() {
        format!(
            "{} of {} runs failed: {} (seed {}: {})",
            failed.len(),
            runs.len(),
            f.status,
            f.seed,
            f.reason
        )
    } else if let (Some(b), Some(m)) = (base, ms) {
        let d = (m.0 - b.0) / b.0;
        let bd = drift_bound(b, m);
        drift = Some(d);
        bound = Some(bd);
        if d.abs() > bd {
            format!("MFR drift {:+.1}% beyond ±{:.1}%", 100.0 * d, 100.0 * bd)
        } else {
            "pass".into()
        }
    } else {
        "pass".into()
    };
    LevelResult {
        ladder,
        level,
        runs,
        mfr_mean: ms.map(|m| m.0),
        mfr_se: ms.map(|m| m.1),
        drift,
        bound,
        verdict,
    }
}

/// Run the plan's ladders, each up to its first failing level. `progress` is told of each level.
pub fn run(
    ctx: &PointContext,
    plan: &StabilityPlan,
    cancel: &CancelToken,
    progress: &dyn Fn(&LevelResult),
) -> Result<Vec<LevelResult>> {
    let mut out = Vec::new();
    for (ladder, levels) in levels(ctx, plan) {
        let mut base = None;
        for (k, level) in levels.into_iter().enumerate() {
            // The stiffness ladder's first level is the timestep ladder's: reuse it.
            let reuse = (ladder == "stiffness" && k == 0)
                .then(|| out.iter().find(|r: &&LevelResult| r.ladder == "timestep" && r.level == level))
                .flatten()
                .cloned();
            let r = match reuse {
                Some(mut r) => {
                    r.ladder = ladder;
                    r
                }
                None => {
                    let name = format!("{ladder}-f{}-e{}", level.fraction, level.youngs_mpa);
                    let runs = run_level(ctx, plan, level, &name, cancel)?;
                    judge(ladder, level, runs, base)
                }
            };
            progress(&r);
            if k == 0 {
                base = r.mfr_mean.zip(r.mfr_se);
            }
            let stop = !r.passed();
            out.push(r);
            if stop {
                break;
            }
        }
    }
    Ok(out)
}

/// The ladder's summary: last passing level, first failing level.
pub fn edge<'a>(
    results: &'a [LevelResult],
    ladder: &str,
) -> (Option<&'a LevelResult>, Option<&'a LevelResult>) {
    let rows: Vec<&LevelResult> = results.iter().filter(|r| r.ladder == ladder).collect();
    (rows.iter().rev().find(|r| r.passed()).copied(), rows.iter().find(|r| !r.passed()).copied())
}

/// One row per level.
pub fn levels_csv(results: &[LevelResult]) -> String {
    let head = [
        "ladder",
        "rayleigh_fraction",
        "youngs_modulus_mpa",
        "timestep_s",
        "runs",
        "failed",
        "mfr_mean",
        "mfr_se",
        "drift",
        "bound",
        "wall_s",
        "verdict",
    ];
    let rows = results.iter().map(|r| {
        vec![
            r.ladder.to_string(),
            r.level.fraction.to_string(),
            r.level.youngs_mpa.to_string(),
            format!("{:.4e}", r.timestep()),
            r.runs.len().to_string(),
            r.runs.iter().filter(|x| x.failed()).count().to_string(),
            opt(r.mfr_mean, 5),
            opt(r.mfr_se, 5),
            opt(r.drift, 4),
            opt(r.bound, 4),
            format!("{:.1}", r.wall()),
            r.verdict.clone(),
        ]
    });
    super::csv_text(head.iter().map(|s| s.to_string()).collect(), rows)
}

/// One row per run.
pub fn runs_csv(results: &[LevelResult]) -> String {
    let head = [
        "ladder",
        "rayleigh_fraction",
        "youngs_modulus_mpa",
        "timestep_s",
        "seed",
        "status",
        "mfr",
        "wall_s",
        "reason",
    ];
    let rows = results.iter().flat_map(|r| {
        r.runs.iter().map(move |x| {
            vec![
                r.ladder.to_string(),
                r.level.fraction.to_string(),
                r.level.youngs_mpa.to_string(),
                format!("{:.4e}", x.timestep),
                x.seed.to_string(),
                x.status.to_string(),
                opt(x.mfr, 5),
                format!("{:.1}", x.wall),
                x.reason.clone(),
            ]
        })
    });
    super::csv_text(head.iter().map(|s| s.to_string()).collect(), rows)
}

/// The stability map: mean MFR ± 2 SE per level against the timestep fraction (left) and the
/// modulus (right); failed levels as red crosses on the axis.
pub fn plot_svg(results: &[LevelResult], title: &str) -> Res<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1000, 420)).into_drawing_area();
        root.fill(&WHITE)?;
        let root = root.titled(title, ("sans-serif", 16))?;
        let panels = root.split_evenly((1, 2));
        let ymax = results
            .iter()
            .filter_map(|r| r.mfr_mean.zip(r.mfr_se).map(|(m, s)| m + 2.0 * s))
            .fold(0.0f64, f64::max)
            .max(0.01)
            * 1.15;
        for (panel, (ladder, xlabel)) in panels
            .iter()
            .zip([("timestep", "timestep / Rayleigh time"), ("stiffness", "Young's modulus, MPa")])
        {
            let rows: Vec<&LevelResult> = results.iter().filter(|r| r.ladder == ladder).collect();
            let x =
                |r: &LevelResult| if ladder == "timestep" { r.level.fraction } else { r.level.youngs_mpa };
            let (lo, hi) = rows
                .iter()
                .map(|r| x(r))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |a, v| (a.0.min(v), a.1.max(v)));
            let (lo, hi) = if lo.is_finite() { (lo * 0.9, hi * 1.1) } else { (0.0, 1.0) };
            let mut chart = ChartBuilder::on(panel)
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(55)
                .caption(format!("{ladder} ladder"), ("sans-serif", 14))
                .build_cartesian_2d(lo..hi, 0.0..ymax)?;
            chart.configure_mesh().x_desc(xlabel).y_desc("MFR (mean ± 2 SE over seeds)").draw()?;
            let ok: Vec<(f64, f64, f64)> = rows
                .iter()
                .filter(|r| r.passed())
                .filter_map(|r| r.mfr_mean.zip(r.mfr_se).map(|(m, s)| (x(r), m, s)))
                .collect();
            chart.draw_series(LineSeries::new(ok.iter().map(|p| (p.0, p.1)), &BLUE))?;
            chart.draw_series(ok.iter().map(|p| Circle::new((p.0, p.1), 4, BLUE.filled())))?;
            chart.draw_series(
                ok.iter()
                    .map(|p| PathElement::new(vec![(p.0, p.1 - 2.0 * p.2), (p.0, p.1 + 2.0 * p.2)], BLUE)),
            )?;
            let red = RGBColor(200, 30, 30);
            for r in rows.iter().filter(|r| !r.passed()) {
                let y = r.mfr_mean.unwrap_or(0.02 * ymax);
                chart.draw_series(std::iter::once(Cross::new((x(r), y), 7, red.stroke_width(3))))?;
                let failed = r.runs.iter().filter(|x| x.failed()).count();
                let label = match r.runs.iter().find(|x| x.failed()) {
                    Some(f) => format!("{} ({failed}/{})", f.status, r.runs.len()),
                    None => "MFR drift".to_string(),
                };
                chart.draw_series(std::iter::once(Text::new(
                    label,
                    (x(r), y + 0.06 * ymax),
                    ("sans-serif", 11).into_font().color(&red),
                )))?;
            }
        }
        root.present()?;
    }
    Ok(svg)
}

/// Write stability.csv, stability-runs.csv, stability.svg and stability.png in `out`.
pub fn write(out: &Path, results: &[LevelResult], title: &str) -> Result<Vec<PathBuf>> {
    let tables = vec![("stability.csv", levels_csv(results)), ("stability-runs.csv", runs_csv(results))];
    let paths = super::write_outputs(out, "stability", tables, || plot_svg(results, title))?;
    Ok(paths)
}

/// The corner as `name=value` pairs, for the table's heading.
pub fn describe_corner(sweep: &Sweep, corner: &[f64]) -> String {
    let values: BTreeMap<String, f64> = point::resolve(sweep, corner);
    [
        "diameter",
        "gap",
        "blade_speed",
        "friction",
        "restitution",
        "rolling_friction",
        "youngs_modulus",
        "density",
    ]
    .iter()
    .filter_map(|n| values.get(*n).map(|v| format!("{n}={v}")))
    .collect::<Vec<_>>()
    .join(" ")
}

/// Mean and standard error of the mean over seeds (`MEDIAN_SEED_SPREAD` of the mean for one).
pub fn mean_se(v: &[f64]) -> Option<(f64, f64)> {
    if v.is_empty() {
        return None;
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let se = if v.len() < 2 {
        MEDIAN_SEED_SPREAD * mean
    } else {
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / n.sqrt()
    };
    Some((mean, se))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_is_small_fast_and_rough() {
        let text = r#"
name = "t"
[parameters]
friction    = { lo = 0.1, hi = 0.3 }
diameter    = { lo = 1.0, hi = 3.0, unit = "mm" }
gap         = { lo = 1.0, hi = 5.0, unit = "mm" }
blade_speed = { lo = 1.2, hi = 1.6, unit = "m/s" }
poisson     = { lo = 0.2, hi = 0.4 }
restitution = 0.5
"#;
        let sweep = Sweep::parse(text, Path::new("t.toml")).unwrap();
        let c = harshest_corner(&sweep);
        assert_eq!(c[..4], [0.3, 1.0, 5.0, 1.6]);
        assert!((c[4] - 0.3).abs() < 1e-12, "poisson has no direction: its middle");
    }

    #[test]
    fn moduli_halve_down_to_the_catalogue_minimum() {
        assert_eq!(default_moduli(21.0), vec![21.0, 10.5, 5.25, 5.0]);
        assert_eq!(default_moduli(5.0), vec![5.0]);
    }

    #[test]
    fn drift_bound_has_a_floor_and_grows_with_noise() {
        assert_eq!(drift_bound((0.1, 0.001), (0.1, 0.001)), DRIFT_FLOOR);
        let b = drift_bound((0.1, 0.006), (0.1, 0.008));
        assert!((b - 0.2).abs() < 1e-12, "{b}");
        let (m, se) = mean_se(&[0.1]).unwrap();
        assert_eq!((m, se), (0.1, 0.1 * MEDIAN_SEED_SPREAD));
    }

    fn run(mfr: Option<f64>) -> Run {
        Run {
            seed: 1,
            status: if mfr.is_some() { "ok" } else { "lost-atoms" }.into(),
            mfr,
            timestep: 1e-5,
            wall: 1.0,
            reason: String::new(),
        }
    }

    #[test]
    fn a_level_fails_on_a_failed_run_or_a_drift() {
        let l = Level { fraction: 0.4, youngs_mpa: 21.0 };
        assert!(judge("timestep", l, vec![run(Some(0.1)), run(Some(0.11))], Some((0.1, 0.005))).passed());
        assert!(!judge("timestep", l, vec![run(Some(0.1)), run(None)], Some((0.1, 0.005))).passed());
        let drifted = judge("timestep", l, vec![run(Some(0.13)), run(Some(0.131))], Some((0.1, 0.001)));
        assert!(drifted.verdict.starts_with("MFR drift"), "{}", drifted.verdict);
        let csv = levels_csv(&[drifted]);
        assert_eq!(csv.lines().count(), 2);
        let svg = plot_svg(&[judge("timestep", l, vec![run(None)], None)], "t").unwrap();
        assert!(crate::report::to_png(&svg).unwrap().starts_with(b"\x89PNG"));
    }

    #[test]
    fn a_reason_with_a_quote_and_a_comma_reads_back_whole() {
        let l = Level { fraction: 0.4, youngs_mpa: 21.0 };
        let reason = "lost atoms: \"3 of 1,000\", then \"nan\"";
        let failed = Run { reason: reason.into(), ..run(None) };
        let csv = runs_csv(&[judge("timestep", l, vec![failed, run(Some(0.1))], None)]);
        let mut r = csv::Reader::from_reader(csv.as_bytes());
        let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].len(), 9);
        assert_eq!(&rows[0][8], reason);
        // An ordinary row: plain fields, nothing quoted.
        assert_eq!(csv.lines().nth(2), Some("timestep,0.4,21,1.0000e-5,1,ok,0.10000,1.0,"));
    }
}
