//! `sweep bench fidelity`: run time against error (BENCHMARKS.md "Fidelity").
//!
//! A fixed seeded LDS draw of K points of a sweep's space is run under each fidelity preset
//! (and any extra variant of the fast knobs) with S pile seeds, jobs interleaved so that the
//! machine's load falls on every variant alike. Per point and variant: wall time, CPU time, MFR
//! and its error against the `reference` preset, and the v_x profile's error. Then per
//! variant: CPU per point, speed-up over `thesis` and over `reference` (ratios of CPU summed
//! over the same points in the same run), and the worst and mean MFR errors with their noise
//! (the standard error of the difference of two seed means).
//!
//! Runs live in `OUT/runs/<hash>`: a finished run is read back, not re-run, so an interrupted
//! bench resumes and a new variant costs only its own runs.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use plotters::prelude::*;

use crate::bench::{opt, BenchError};
use crate::error::{Error, Res, Result};
use crate::outcome::{FailureClass, RunOutcome, RunResult};
use crate::point::{self, PointContext};
use crate::sweep::Sweep;
use crate::sys::process::CancelToken;

/// A way of computing the points: a preset, or the fast preset with knobs changed.
#[derive(Debug, Clone)]
pub struct Variant {
    pub name: String,
    pub sweep: Sweep,
}

/// The variants to compare: each named preset, then each `NAME:key=value,...` of the fast
/// preset's knobs.
pub fn variants(sweep: &Sweep, presets: &[String], extra: &[String]) -> Result<Vec<Variant>> {
    let mut out: Vec<Variant> = Vec::new();
    for name in presets {
        let scene = crate::scenes::settings::with_knobs_of(&sweep.file.scene, name).map_err(|_| {
            let why = format!(
                "not a fidelity preset; expected some of {}",
                crate::scene::settings::FIDELITIES.join(", ")
            );
            BenchError::Flag { given: format!("--presets {name}"), why }
        })?;
        out.push(Variant { name: name.clone(), sweep: sweep.with_scene(scene)? });
    }
    for spec in extra {
        let variant = |why: String| BenchError::Flag { given: format!("--variant {spec}"), why };
        let (name, sets) =
            spec.split_once(':').ok_or_else(|| variant("expected NAME:key=value,...".into()))?;
        let name = name.trim();
        if name.is_empty() || out.iter().any(|v| v.name == name) {
            return Err(variant("expected a new, non-empty name".into()).into());
        }
        let mut scene = crate::scenes::settings::with_knobs_of(&sweep.file.scene, "fast")
            .map_err(|e| variant(e.to_string()))?;
        for set in sets.split(',').filter(|s| !s.trim().is_empty()) {
            let (k, v) =
                set.split_once('=').ok_or_else(|| variant(format!("`{set}`: expected key=value")))?;
            scene = crate::scenes::settings::with_knob(&scene, k.trim(), v.trim())
                .map_err(|e| variant(e.to_string()))?;
        }
        scene.fidelity = format!("fast+{name}");
        // Validation checks the preset's name; the variant's knobs are what it checks.
        let mut checked = scene.clone();
        checked.fidelity = "fast".into();
        let mut v = sweep.with_scene(checked)?;
        v.file.scene.fidelity = scene.fidelity;
        out.push(Variant { name: name.to_string(), sweep: v });
    }
    Ok(out)
}

/// One run of the bench.
#[derive(Debug, Clone)]
pub struct Run {
    pub point: usize,
    pub variant: usize,
    pub seed: u64,
    pub hash: String,
    /// `ok`, `unsteady` (ran to the end; MFR kept for the error, as the reference may be
    /// unsteady too) or the failure class.
    pub status: String,
    pub reason: String,
    pub result: Option<RunResult>,
    pub wall: f64,
    /// CPU seconds (wall seconds when the engine did not report it).
    pub cpu: f64,
    pub reused: bool,
}

impl Run {
    pub fn mfr(&self) -> Option<f64> {
        self.result.as_ref().map(|r| r.answer.value)
    }
}

/// What the bench was asked to do.
pub struct FidelityPlan {
    /// Swept values of each point, in file order.
    pub points: Vec<Vec<f64>>,
    pub seeds: u64,
    pub jobs: usize,
    pub out: PathBuf,
}

/// Run every (point, variant, seed), `jobs` at a time; `progress` is told of each finished run.
pub fn run(
    variants: &[Variant],
    contexts: &[PointContext],
    plan: &FidelityPlan,
    cancel: &CancelToken,
    progress: &(dyn Fn(&Run, usize, usize) + Sync),
) -> Result<Vec<Run>> {
    // Seed-major, then point, then variant: each variant sees the same load over the bench.
    let mut jobs = Vec::new();
    for k in 0..plan.seeds {
        for p in 0..plan.points.len() {
            for v in 0..variants.len() {
                jobs.push((p, v, k));
            }
        }
    }
    // Every deck first: a bad one is bad input, found before anything runs.
    let mut prepared = Vec::with_capacity(jobs.len());
    for &(p, v, k) in &jobs {
        let ctx = &contexts[v];
        let mut c = ctx.with_sweep(ctx.sweep.clone());
        c.sweep.file.scene.seed = ctx.sweep.file.scene.seed + k;
        let prep = point::prepare(&c, &plan.points[p])?;
        prepared.push((c, prep));
    }
    std::fs::create_dir_all(&plan.out)
        .map_err(|source| BenchError::Create { path: plan.out.clone(), source })?;
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let runs: Mutex<Vec<Run>> = Mutex::new(Vec::new());
    let total = jobs.len();
    std::thread::scope(|s| {
        for _ in 0..plan.jobs.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                if i >= total || cancel.is_cancelled() {
                    break;
                }
                let (p, v, _) = jobs[i];
                let (c, prep) = &prepared[i];
                let dir = plan.out.join("runs").join(&prep.hash);
                let base = Run {
                    point: p,
                    variant: v,
                    seed: c.sweep.file.scene.seed,
                    hash: prep.hash.clone(),
                    status: "ok".into(),
                    reason: String::new(),
                    result: None,
                    wall: 0.0,
                    cpu: 0.0,
                    reused: false,
                };
                let done_run = |r: RunResult, reused: bool| Run {
                    wall: r.wall_time,
                    cpu: r.cpu_time.unwrap_or(r.wall_time),
                    result: Some(r),
                    reused,
                    ..base.clone()
                };
                let run = match read_result(&dir) {
                    Some(r) => done_run(r, true),
                    None => match point::execute(c, prep, &dir, cancel) {
                        RunOutcome::Done(r) => done_run(r, false),
                        RunOutcome::Failed(f) => {
                            // An unsteady run keeps its MFR: the reference may be unsteady too.
                            let measured =
                                (f.class == FailureClass::Unsteady).then_some(f.measured).flatten();
                            Run {
                                status: f.class.as_str().into(),
                                reason: f.reason,
                                wall: f.wall_time,
                                cpu: measured.as_ref().and_then(|m| m.cpu_time).unwrap_or(f.wall_time),
                                result: measured.map(|m| *m),
                                ..base.clone()
                            }
                        }
                        RunOutcome::Cancelled => continue,
                    },
                };
                let n = done.fetch_add(1, Ordering::SeqCst) + 1;
                progress(&run, n, total);
                runs.lock().unwrap_or_else(|e| e.into_inner()).push(run);
            });
        }
    });
    if cancel.is_cancelled() {
        return Err(Error::Interrupted);
    }
    let mut runs = runs.into_inner().unwrap_or_else(|e| e.into_inner());
    runs.sort_by_key(|r| (r.point, r.variant, r.seed));
    Ok(runs)
}

fn read_result(dir: &Path) -> Option<RunResult> {
    let text = std::fs::read_to_string(dir.join(point::RESULT)).ok()?;
    serde_json::from_str(&text).ok()
}

/// One point under one variant, over its seeds.
#[derive(Debug, Clone)]
pub struct Cell {
    pub point: usize,
    pub variant: usize,
    pub runs: usize,
    pub failed: usize,
    pub mfr: Option<f64>,
    /// Standard error of `mfr` over the seeds (the median seed spread for a single seed).
    pub mfr_se: Option<f64>,
    /// `mfr` − the reference's at this point, and its standard error.
    pub mfr_error: Option<f64>,
    pub mfr_error_se: Option<f64>,
    /// Root mean square over the layers both have of (v_x − reference v_x) / blade speed.
    pub vx_error: Option<f64>,
    pub wall: f64,
    pub cpu: f64,
}

/// Per-variant summary over the points.
#[derive(Debug, Clone)]
pub struct Summary {
    pub variant: usize,
    pub cpu_per_point: f64,
    pub wall_per_point: f64,
    /// Σ CPU of `thesis` / Σ CPU of this variant over the same points (None without `thesis`).
    pub speedup_vs_thesis: Option<f64>,
    pub speedup_vs_reference: Option<f64>,
    pub worst_error: Option<f64>,
    pub mean_abs_error: Option<f64>,
    /// Mean standard error of the errors: what |error| is at pure seed noise.
    pub mean_error_se: Option<f64>,
    pub mean_vx_error: Option<f64>,
    pub worst_vx_error: Option<f64>,
    pub failed: usize,
}

impl Summary {
    /// The speedups (2 decimals) and the errors (4), in the order of the tables (`fidelity-
    /// summary.csv`, the terminal's), `absent` for one there is none of.
    pub fn measure_cells(&self, absent: &str) -> [String; 7] {
        [
            (self.speedup_vs_thesis, 2),
            (self.speedup_vs_reference, 2),
            (self.worst_error, 4),
            (self.mean_abs_error, 4),
            (self.mean_error_se, 4),
            (self.mean_vx_error, 4),
            (self.worst_vx_error, 4),
        ]
        .map(|(v, digits)| super::opt_or(v, digits, absent))
    }
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn max(v: impl IntoIterator<Item = f64>) -> Option<f64> {
    v.into_iter().reduce(f64::max)
}

/// Per (point, variant) cells and per variant summaries; `reference` is the variant errors are
/// measured against, `thesis` the one speed-ups are quoted over.
pub fn analyse(
    runs: &[Run],
    variants: &[Variant],
    points: usize,
    reference: Option<usize>,
    thesis: Option<usize>,
) -> (Vec<Cell>, Vec<Summary>) {
    let mut cells = Vec::new();
    for p in 0..points {
        for v in 0..variants.len() {
            let rs: Vec<&Run> = runs.iter().filter(|r| r.point == p && r.variant == v).collect();
            let mfrs: Vec<f64> = rs.iter().filter_map(|r| r.mfr()).collect();
            let ms = crate::bench::stability::mean_se(&mfrs);
            cells.push(Cell {
                point: p,
                variant: v,
                runs: rs.len(),
                failed: rs.iter().filter(|r| r.result.is_none()).count(),
                mfr: ms.map(|m| m.0),
                mfr_se: ms.map(|m| m.1),
                mfr_error: None,
                mfr_error_se: None,
                vx_error: None,
                wall: mean(&rs.iter().map(|r| r.wall).collect::<Vec<_>>()).unwrap_or(0.0),
                cpu: mean(&rs.iter().map(|r| r.cpu).collect::<Vec<_>>()).unwrap_or(0.0),
            });
        }
    }
    let nv = variants.len();
    if let Some(rf) = reference {
        for p in 0..points {
            let r = cells[p * nv + rf].clone();
            let ref_vx = mean_profile(runs, p, rf);
            for v in 0..nv {
                let c = &mut cells[p * nv + v];
                if let (Some(m), Some(se), Some(rm), Some(rse)) = (c.mfr, c.mfr_se, r.mfr, r.mfr_se) {
                    c.mfr_error = Some(m - rm);
                    c.mfr_error_se = Some((se * se + rse * rse).sqrt());
                }
                c.vx_error = profile_error(&mean_profile(runs, p, v), &ref_vx, blade_speed(runs, p));
            }
        }
    }
    let total_cpu = |v: usize| cells.iter().filter(|c| c.variant == v).map(|c| c.cpu).sum::<f64>();
    let summaries = (0..nv)
        .map(|v| {
            let cs: Vec<&Cell> = cells.iter().filter(|c| c.variant == v).collect();
            let errs: Vec<f64> = cs.iter().filter_map(|c| c.mfr_error).collect();
            let vx: Vec<f64> = cs.iter().filter_map(|c| c.vx_error).collect();
            let ratio = |base: Option<usize>| base.map(|b| total_cpu(b) / total_cpu(v).max(1e-9));
            Summary {
                variant: v,
                cpu_per_point: total_cpu(v) / points.max(1) as f64,
                wall_per_point: cs.iter().map(|c| c.wall).sum::<f64>() / points.max(1) as f64,
                speedup_vs_thesis: ratio(thesis),
                speedup_vs_reference: ratio(reference),
                worst_error: max(errs.iter().map(|e| e.abs())),
                mean_abs_error: mean(&errs.iter().map(|e| e.abs()).collect::<Vec<_>>()),
                mean_error_se: mean(&cs.iter().filter_map(|c| c.mfr_error_se).collect::<Vec<_>>()),
                mean_vx_error: mean(&vx),
                worst_vx_error: max(vx.iter().copied()),
                failed: cs.iter().map(|c| c.failed).sum(),
            }
        })
        .collect();
    (cells, summaries)
}

fn blade_speed(runs: &[Run], p: usize) -> f64 {
    runs.iter()
        .filter(|r| r.point == p)
        .find_map(|r| r.result.as_ref().and_then(|x| x.parameters.get("blade_speed").copied()))
        .unwrap_or(1.0)
}

/// Mean v_x per layer over the seeds' results (a layer empty in every seed is `None`).
fn mean_profile(runs: &[Run], p: usize, v: usize) -> Vec<Option<f64>> {
    let results: Vec<&RunResult> =
        runs.iter().filter(|r| r.point == p && r.variant == v).filter_map(|r| r.result.as_ref()).collect();
    (0..crate::outcome::VX_LAYERS)
        .map(|k| mean(&results.iter().filter_map(|r| r.vx.get(k).copied().flatten()).collect::<Vec<_>>()))
        .collect()
}

/// Root mean square of (a − b) / speed over the layers both have; `None` if they share none.
pub fn profile_error(a: &[Option<f64>], b: &[Option<f64>], speed: f64) -> Option<f64> {
    let d: Vec<f64> =
        a.iter().zip(b).filter_map(|(x, y)| Some(((*x)? - (*y)?) / speed)).map(|e| e * e).collect();
    mean(&d).map(f64::sqrt)
}

/// A header: `before`, the parameter names, `after`.
fn header(before: &[&str], names: &[&str], after: &[&str]) -> Vec<String> {
    before.iter().chain(names).chain(after).map(|s| s.to_string()).collect()
}

/// One row per run.
pub fn runs_csv(runs: &[Run], variants: &[Variant], points: &[Vec<f64>], names: &[&str]) -> String {
    let head = header(
        &["point"],
        names,
        &[
            "variant",
            "seed",
            "status",
            "mfr",
            "wall_s",
            "cpu_s",
            "steps",
            "particles",
            "reused",
            "hash",
            "reason",
        ],
    );
    let rows = runs.iter().map(|r| {
        let mut row = vec![r.point.to_string()];
        row.extend(points[r.point].iter().map(|v| format!("{v:.6}")));
        row.extend([
            variants[r.variant].name.to_string(),
            r.seed.to_string(),
            r.status.to_string(),
            opt(r.mfr(), 5),
            format!("{:.2}", r.wall),
            format!("{:.2}", r.cpu),
            r.result.as_ref().map_or(String::new(), |x| x.steps.to_string()),
            r.result.as_ref().map_or(String::new(), |x| x.particles.to_string()),
            r.reused.to_string(),
            r.hash.clone(),
            r.reason.clone(),
        ]);
        row
    });
    super::csv_text(head, rows)
}

/// One row per point and variant.
pub fn cells_csv(cells: &[Cell], variants: &[Variant], points: &[Vec<f64>], names: &[&str]) -> String {
    let head = header(
        &["point"],
        names,
        &[
            "variant",
            "runs",
            "failed",
            "mfr",
            "mfr_se",
            "mfr_error",
            "mfr_error_se",
            "vx_error",
            "wall_s",
            "cpu_s",
        ],
    );
    let rows = cells.iter().map(|c| {
        let mut row = vec![c.point.to_string()];
        row.extend(points[c.point].iter().map(|v| format!("{v:.6}")));
        row.extend([
            variants[c.variant].name.to_string(),
            c.runs.to_string(),
            c.failed.to_string(),
            opt(c.mfr, 5),
            opt(c.mfr_se, 5),
            opt(c.mfr_error, 5),
            opt(c.mfr_error_se, 5),
            opt(c.vx_error, 4),
            format!("{:.2}", c.wall),
            format!("{:.2}", c.cpu),
        ]);
        row
    });
    super::csv_text(head, rows)
}

/// One row per variant.
pub fn summary_csv(summaries: &[Summary], variants: &[Variant]) -> String {
    let head = header(
        &[
            "variant",
            "cpu_s_per_point",
            "wall_s_per_point",
            "speedup_vs_thesis",
            "speedup_vs_reference",
            "worst_mfr_error",
            "mean_abs_mfr_error",
            "mean_error_se",
            "mean_vx_error",
            "worst_vx_error",
            "failed",
        ],
        &[],
        &[],
    );
    let rows = summaries.iter().map(|m| {
        let mut row = vec![
            variants[m.variant].name.to_string(),
            format!("{:.2}", m.cpu_per_point),
            format!("{:.2}", m.wall_per_point),
        ];
        row.extend(m.measure_cells(""));
        row.push(m.failed.to_string());
        row
    });
    super::csv_text(head, rows)
}

/// The frontier: per variant, CPU seconds per point (log x) against the mean |MFR error|
/// (filled) and the worst (hollow), with the mean noise of an error as a dashed line.
pub fn plot_svg(summaries: &[Summary], variants: &[Variant], title: &str) -> Res<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (820, 480)).into_drawing_area();
        root.fill(&WHITE)?;
        let cpu: Vec<f64> = summaries.iter().map(|s| s.cpu_per_point.max(1e-3)).collect();
        let (lo, hi) = cpu.iter().fold((f64::INFINITY, 0.0f64), |a, &c| (a.0.min(c), a.1.max(c)));
        let (lo, hi) = if lo.is_finite() { (lo / 1.5, hi * 1.5) } else { (0.1, 10.0) };
        let ymax = summaries.iter().filter_map(|s| s.worst_error).fold(0.02f64, f64::max) * 1.2;
        let mut chart = ChartBuilder::on(&root)
            .margin(14)
            .caption(title, ("sans-serif", 15))
            .x_label_area_size(42)
            .y_label_area_size(60)
            .build_cartesian_2d((lo..hi).log_scale(), 0.0..ymax)?;
        chart
            .configure_mesh()
            .x_desc("CPU seconds per point (log)")
            .y_desc("|MFR − reference|: mean (●), worst (○)")
            .draw()?;
        let target = RGBColor(120, 120, 120);
        for (y, label) in [(0.01, "target: mean 0.01"), (0.02, "target: worst 0.02")] {
            chart.draw_series(LineSeries::new([(lo, y), (hi, y)], target.stroke_width(1)))?;
            chart.draw_series(std::iter::once(Text::new(
                label,
                (lo * 1.05, y + 0.002),
                ("sans-serif", 11),
            )))?;
        }
        for (i, s) in summaries.iter().enumerate() {
            let colour = Palette99::pick(i).to_rgba();
            let x = cpu[i];
            if let Some(m) = s.mean_abs_error {
                chart.draw_series(std::iter::once(Circle::new((x, m), 5, colour.filled())))?;
            }
            if let Some(w) = s.worst_error {
                chart.draw_series(std::iter::once(Circle::new((x, w), 5, colour.stroke_width(2))))?;
            }
            let y = s.worst_error.or(s.mean_abs_error).unwrap_or(0.0);
            chart.draw_series(std::iter::once(Text::new(
                variants[s.variant].name.clone(),
                (x * 1.04, y + 0.03 * ymax),
                ("sans-serif", 12).into_font().color(&colour),
            )))?;
        }
        root.present()?;
    }
    Ok(svg)
}

/// Write fidelity-runs.csv, fidelity.csv, fidelity-summary.csv, fidelity.svg and .png in `out`.
pub fn write(
    plan: &FidelityPlan,
    runs: &[Run],
    cells: &[Cell],
    summaries: &[Summary],
    variants: &[Variant],
    names: &[&str],
    title: &str,
) -> Result<Vec<PathBuf>> {
    let tables = vec![
        ("fidelity-runs.csv", runs_csv(runs, variants, &plan.points, names)),
        ("fidelity.csv", cells_csv(cells, variants, &plan.points, names)),
        ("fidelity-summary.csv", summary_csv(summaries, variants)),
    ];
    let paths = super::write_outputs(&plan.out, "fidelity", tables, || plot_svg(summaries, variants, title))?;
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn result(mfr: f64, vx: Vec<Option<f64>>) -> RunResult {
        RunResult {
            format: 1,
            parameters: BTreeMap::from([("blade_speed".to_string(), 2.0)]),
            answer: crate::outcome::PointAnswer::mfr(mfr),
            mfr_flux: mfr,
            answer_particles: 100,
            vx,
            particles: 10,
            steps: 10,
            wall_time: 1.0,
            cpu_time: Some(1.0),
            engine_version: String::new(),
            ..RunResult::default()
        }
    }

    fn run(point: usize, variant: usize, mfr: Option<f64>, cpu: f64) -> Run {
        Run {
            point,
            variant,
            seed: 0,
            hash: String::new(),
            status: if mfr.is_some() { "ok" } else { "lost-atoms" }.into(),
            reason: String::new(),
            result: mfr.map(|m| result(m, vec![Some(1.0), None, Some(0.5)])),
            wall: cpu,
            cpu,
            reused: false,
        }
    }

    #[test]
    fn the_profile_error_is_the_rms_over_shared_layers_over_the_speed() {
        // Layers 1 and 3 shared: differences 0.2 and 0.4 at speed 2 → 0.1, 0.2 → √(0.025).
        let e =
            profile_error(&[Some(1.2), Some(9.0), Some(0.9)], &[Some(1.0), None, Some(0.5)], 2.0).unwrap();
        assert!((e - 0.025f64.sqrt()).abs() < 1e-12, "{e}");
        assert_eq!(profile_error(&[None], &[Some(1.0)], 1.0), None);
    }

    #[test]
    fn errors_are_against_the_reference_and_speedups_are_ratios_of_summed_cpu() {
        let sweep =
            Sweep::parse("name = \"t\"\n[parameters]\ngap = { lo = 1.0, hi = 2.0 }\n", Path::new("t.toml"))
                .unwrap();
        let variants: Vec<Variant> = ["fast", "reference", "thesis"]
            .iter()
            .map(|n| Variant { name: n.to_string(), sweep: sweep.clone() })
            .collect();
        // Two points; the fast variant is off by +0.01 and −0.03, and failed one seed at point 1.
        let runs = vec![
            run(0, 0, Some(0.11), 1.0),
            run(0, 1, Some(0.10), 10.0),
            run(0, 2, Some(0.10), 20.0),
            run(1, 0, Some(0.05), 3.0),
            run(1, 0, None, 1.0),
            run(1, 1, Some(0.08), 30.0),
            run(1, 2, Some(0.08), 40.0),
        ];
        let (cells, s) = analyse(&runs, &variants, 2, Some(1), Some(2));
        let fast: Vec<&Cell> = cells.iter().filter(|c| c.variant == 0).collect();
        assert!((fast[0].mfr_error.unwrap() - 0.01).abs() < 1e-12);
        assert!((fast[1].mfr_error.unwrap() + 0.03).abs() < 1e-12);
        assert_eq!((fast[1].runs, fast[1].failed), (2, 1));
        assert!((s[0].worst_error.unwrap() - 0.03).abs() < 1e-12);
        assert!((s[0].mean_abs_error.unwrap() - 0.02).abs() < 1e-12);
        // CPU per point: point 0 = 1, point 1 = mean(3, 1) = 2; thesis 20 + 40 = 60 over 3.
        assert!((s[0].cpu_per_point - 1.5).abs() < 1e-12);
        assert!((s[0].speedup_vs_thesis.unwrap() - 20.0).abs() < 1e-12);
        assert!((s[0].speedup_vs_reference.unwrap() - 40.0 / 3.0).abs() < 1e-12);
        assert_eq!(s[1].worst_error, Some(0.0));
        assert_eq!(s[0].failed, 1);
        let svg = plot_svg(&s, &variants, "t").unwrap();
        assert!(crate::report::to_png(&svg).unwrap().starts_with(b"\x89PNG"));
    }

    #[test]
    fn a_variant_changes_only_knobs_and_names_a_bad_one() {
        let sweep =
            Sweep::parse("name = \"t\"\n[parameters]\ngap = { lo = 1.0, hi = 2.0 }\n", Path::new("t.toml"))
                .unwrap();
        let v =
            variants(&sweep, &["reference".into()], &["x:rayleigh_fraction=0.3,mesh_cells_across=2".into()])
                .unwrap();
        let conveyor = crate::scenes::lookup("conveyor").unwrap();
        assert_eq!(v[0].sweep.file.scene, crate::scenes::settings::preset(conveyor, "reference").unwrap());
        assert_eq!(v[1].sweep.file.scene.rayleigh_fraction, 0.3);
        assert_eq!(v[1].sweep.file.scene.mesh_cells_across, 2);
        for bad in ["x", "x:gap=1", "x:rayleigh_fraction=1.5", "x:depth_diameters=-1"] {
            let e = variants(&sweep, &[], &[bad.into()]).unwrap_err().to_string();
            assert!(
                !e.contains('\n')
                    && (e.contains("--variant") || e.contains("rayleigh") || e.contains("depth")),
                "{bad}: {e}"
            );
        }
        assert!(variants(&sweep, &["fastest".into()], &[]).is_err());
    }
}
