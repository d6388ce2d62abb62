//! What each pass left on the build plate, and the steady layer (docs/layers.md).
//!
//! The deck prints, after each pass k, the powder's mass whose centres lie over the plate
//! (`demsweep: layer k step S plate M count N`), and dumps those particles (`dump.layer.k`:
//! id x y z radius). From them, per pass:
//!
//! - **deposit**: the solid volume the pass added over the plate, over the plate's area (a
//!   height of solid): ΔM/(ρ·A) on a loose bed, M/(ρ·A) on a fused one (the bed before it is
//!   solid and no longer on the plate);
//! - **relative density**: the deposit over the platform's drop before the pass — Gaboriault et
//!   al. 2025's layer relative density; on a loose bed it tends to the bed's packing;
//! - **effective thickness**: the depth of powder the blade met, its tip's height over the mean
//!   top surface before the pass (loose; the bare plate before the first) or over the solid
//!   (fused; it tends to the drop over the layer's packing);
//! - **packing**: deposit over effective thickness;
//! - **covered fraction**: the share of the plate's area under the discs of the pass's own
//!   particles (new IDs) — its complement is the bare bed or solid the pass left;
//! - **roughness**: RMS of the top surface about its mean, in D.
//!
//! Surfaces are sampled on a grid of D/[`GRID_PER_D`] over the plate less [`EDGE_DIAMETERS`] at
//! each wall, where the walls order the packing.
//!
//! The steady layer: MSER truncation of the point's measure over the passes (relative density
//! on a loose bed, packing on a fused one — and the effective thickness too on a fused bed,
//! which converges geometrically), then mean and SE (SD / √n) of what is left. It is steady when
//! at least [`MIN_STEADY_PASSES`] passes remain and their least-squares slope is flat by a
//! Student t test with n − 2 degrees of freedom at [`TREND_FALSE_ALARM`] for the point (on a
//! fused bed, the effective thickness's too, each series at half of it). A fixed z limit would
//! not do: over the four passes a short steady layer may keep, |t| > 2.5 has a 13 % chance on
//! a series with no trend.
//!
//! A fused bed's passes are not independent: each pass's depth is the last one's plus the drop
//! less its deposit, so the depth wanders. Its SEs and its slope test allow for the lag-1
//! autocorrelation measured over steady records ([`FUSED_DEPTH_LAG1`], [`FUSED_PACKING_LAG1`]);
//! read as independent, a wander of eight passes at 0.65 exceeds the slope test's 2.5 % limit
//! 18 % of the time, and its mean's SE is short by 2.3 times.

use std::collections::HashSet;
use std::path::Path;

use super::fixed_point::fixed_point;
use super::result::{LayerSeries, PassRecord, RollerLoad, RollerSteady};
use super::{
    plan_of, Plan, FUSED_DEPTH_LAG1, FUSED_PACKING_LAG1, MIN_STEADY_PASSES, STOP_KEPT_PASSES,
    TREND_FALSE_ALARM,
};
use crate::engine::dump::read_dump;
use crate::measure::steady::{ar1_se_factor, mser, student_quantile, trend_z};
use crate::outcome::{FailureClass, RunResult, RESULT_FORMAT, VX_LAYERS};
use crate::scene::Scene;
use crate::scenes::{Finished, Rejected};

/// Grid cells per diameter for surfaces and coverage.
pub const GRID_PER_D: f64 = 4.0;
/// Plate length left out at each wall for surfaces and coverage, in diameters.
pub const EDGE_DIAMETERS: f64 = 2.0;

/// One sphere over the plate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grain {
    pub id: u64,
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub r: f64,
}

/// A pass's line of the log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassLine {
    pub k: usize,
    pub step: u64,
    /// Powder mass over the plate after the pass, kg.
    pub plate_mass: f64,
}

/// The fields after `prefix` on each log line that starts with it.
fn lines_after<'a>(log: &'a str, prefix: &'a str) -> impl Iterator<Item = Vec<&'a str>> + 'a {
    log.lines().filter_map(move |l| Some(l.trim().strip_prefix(prefix)?.split_whitespace().collect()))
}

/// The pass lines of a log, in order: each pass's plate mass counts the held bed the passes
/// before it removed (`demsweep: buried k mass M count N`).
pub fn parse_log(log: &str) -> Vec<PassLine> {
    let buried = by_pass(log, "buried", "mass");
    lines_after(log, "demsweep: layer ")
        .filter_map(|f| {
            // k step S plate M count N
            if f.len() < 5 || f[1] != "step" || f[3] != "plate" {
                return None;
            }
            let k: usize = f[0].parse().ok()?;
            let removed: f64 = buried.iter().filter(|(j, _)| *j < k).map(|(_, m)| m).sum();
            let on_plate: f64 = f[4].parse().ok()?;
            Some(PassLine { k, step: f[2].parse().ok()?, plate_mass: on_plate + removed })
        })
        .collect()
}

/// The solid's top after each pass of a fused bed's log (`demsweep: solid k top Z`), by pass.
pub fn parse_solids(log: &str) -> Vec<(usize, f64)> {
    by_pass(log, "solid", "top")
}

/// The number after `key` on each `demsweep: WHAT k key V …` line of a log, by pass.
fn by_pass(log: &str, what: &str, key: &str) -> Vec<(usize, f64)> {
    lines_after(log, &format!("demsweep: {what} "))
        .filter_map(|f| {
            if f.len() < 3 || f[1] != key {
                return None;
            }
            Some((f[0].parse().ok()?, f[2].parse().ok()?))
        })
        .collect()
}

/// A roller's load in each pass of a log (`demsweep: roller k torque T turning P push F pushing
/// Q`, the deck's means over the roller's move for the whole slice), per metre of its width
/// `depth`, by pass.
pub fn parse_roller(log: &str, depth: f64) -> Vec<(usize, RollerLoad)> {
    lines_after(log, "demsweep: roller ")
        .filter_map(|f| {
            if f.len() < 9 || f[1] != "torque" || f[3] != "turning" || f[5] != "push" || f[7] != "pushing" {
                return None;
            }
            let per_m = |s: &str| s.parse::<f64>().ok().map(|v| v / depth);
            let load = RollerLoad {
                torque_nm_per_m: per_m(f[2])?,
                turning_power_w_per_m: per_m(f[4])?,
                push_n_per_m: per_m(f[6])?,
                pushing_power_w_per_m: per_m(f[8])?,
                ejected_kg_per_m: None,
            };
            Some((f[0].parse().ok()?, load))
        })
        .collect()
}

/// The powder a roller sent over its top in each pass of a log (`demsweep: ejected k mass M
/// count N`: the mass that crossed, going up, the plane through its highest line, for the whole
/// slice), per metre of its width `depth`, by pass.
pub fn parse_ejected(log: &str, depth: f64) -> Vec<(usize, f64)> {
    by_pass(log, "ejected", "mass").into_iter().map(|(k, m)| (k, m / depth)).collect()
}

/// A roller's steady load and the powder it sent over its top, as the terminal prints them.
pub fn roller_lines(r: &RollerSteady) -> Vec<String> {
    let mut lines = vec![format!(
        "roller load      torque {:.3e} ± {:.1e} N·m, turning {:.3e} ± {:.1e} W, pushing {:.3e} ± {:.1e} W a metre of its width",
        r.mean.torque_nm_per_m,
        r.se.torque_nm_per_m,
        r.mean.turning_power_w_per_m,
        r.se.turning_power_w_per_m,
        r.mean.pushing_power_w_per_m,
        r.se.pushing_power_w_per_m
    )];
    if let (Some(m), Some(se)) = (r.mean.ejected_kg_per_m, r.se.ejected_kg_per_m) {
        lines.push(format!(
            "ejected          {m:.3e} ± {se:.1e} kg a pass a metre of its width, over the roller's top"
        ));
    }
    lines
}

/// The top surface over the plate's inner part that a pass whose blade's tip stood at `tip` left:
/// per grid cell the top of the highest sphere over it, or `floor` where none is. Returns (cells,
/// covered cells of `mine`), `mine` selecting the spheres whose discs count as covering.
///
/// The blade left nothing above its tip: a sphere whose centre is more than a largest diameter
/// over it is in flight when the pass is measured (a bouncy powder's, thrown up as the blade is
/// taken away, up to millimetres high), not part of the surface.
fn surface(
    scene: &Scene,
    plan: &Plan,
    grains: &[Grain],
    tip: f64,
    floor: f64,
    mine: &dyn Fn(&Grain) -> bool,
) -> (Vec<f64>, usize) {
    let d = scene.diameter;
    let (x0, x1) = (plan.plate_x0 + EDGE_DIAMETERS * d, plan.plate_x1 - EDGE_DIAMETERS * d);
    let h = d / GRID_PER_D;
    let nx = ((x1 - x0) / h).round().max(1.0) as usize;
    let ny = (scene.depth / h).round().max(1.0) as usize;
    let (hx, hy) = ((x1 - x0) / nx as f64, scene.depth / ny as f64);
    let mut top = vec![floor; nx * ny];
    let mut covered = vec![false; nx * ny];
    let highest = tip + plan.max_diameter();
    // Not above it, not `<=`: where no tip is known, NaN, every sphere counts.
    for g in grains.iter().filter(|g| g.z.partial_cmp(&highest) != Some(std::cmp::Ordering::Greater)) {
        let yi = g.y.rem_euclid(scene.depth);
        let (cx0, cx1) = (((g.x - g.r - x0) / hx).floor() as i64, ((g.x + g.r - x0) / hx).ceil() as i64);
        let (cy0, cy1) = (((yi - g.r) / hy).floor() as i64, ((yi + g.r) / hy).ceil() as i64);
        let counts = mine(g);
        for cx in cx0.max(0)..cx1.min(nx as i64) {
            let gx = x0 + (cx as f64 + 0.5) * hx;
            for cy in cy0..cy1 {
                let gy = (cy as f64 + 0.5) * hy;
                // The nearest periodic image of the cell's centre.
                let dy = (gy - yi + 0.5 * scene.depth).rem_euclid(scene.depth) - 0.5 * scene.depth;
                let d2 = (gx - g.x).powi(2) + dy * dy;
                if d2 < g.r * g.r {
                    let i = cx as usize * ny + cy.rem_euclid(ny as i64) as usize;
                    top[i] = top[i].max(g.z + (g.r * g.r - d2).sqrt());
                    covered[i] |= counts;
                }
            }
        }
    }
    let n_covered = covered.iter().filter(|&&c| c).count();
    (top, n_covered)
}

fn mean(y: &[f64]) -> f64 {
    y.iter().sum::<f64>() / y.len() as f64
}

/// Mean and SE (SD / √n, n − 1 divisor) of `y`.
pub(super) fn mean_se(y: &[f64]) -> (f64, f64) {
    let m = mean(y);
    if y.len() < 2 {
        return (m, f64::NAN);
    }
    let var = y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (y.len() - 1) as f64;
    (m, (var / y.len() as f64).sqrt())
}

/// Every pass's record from the log's masses and each pass's particles over the plate. A fused
/// bed's floor under pass k is the solid the log printed after pass k − 1 (`solids`); where it
/// printed none, the deposits so far.
pub fn passes(
    scene: &Scene,
    plan: &Plan,
    lines: &[PassLine],
    solids: &[(usize, f64)],
    grains: &[Vec<Grain>],
) -> Vec<PassRecord> {
    let d = scene.diameter;
    let area = plan.plate_area;
    let mut out = Vec::with_capacity(lines.len());
    // A warm-started fused bed's first pass lies on the solid it was given, not the plate.
    let (mut mass_before, mut floor_before, mut surface_before) = (0.0, plan.first_floor.unwrap_or(0.0), 0.0);
    let mut ids_before: HashSet<u64> = HashSet::new();
    let mut volume_after_first = 0.0;
    for (line, gs) in lines.iter().zip(grains) {
        let k = line.k;
        let tip = plan.passes.get(k - 1).map_or(f64::NAN, |p| p.tip);
        let deposit = if plan.fused { line.plate_mass } else { line.plate_mass - mass_before }
            / (scene.material.density * area);
        let effective = tip - if plan.fused { floor_before } else { surface_before };
        // A fused bed's plate holds only this pass's particles (the last pass's became solid and
        // were deleted, renumbering every ID left: delete_atoms.cpp's `compress`); a loose bed's
        // new particles are those whose IDs the last pass's dump did not hold.
        let new = |g: &Grain| plan.fused || !ids_before.contains(&g.id);
        let (top, covered) = surface(scene, plan, gs, tip, floor_before, &new);
        let m = mean(&top);
        let roughness = (top.iter().map(|z| (z - m).powi(2)).sum::<f64>() / top.len() as f64).sqrt() / d;
        let volume = line.plate_mass / (scene.material.density * area);
        if k == 1 {
            volume_after_first = volume;
        }
        out.push(PassRecord {
            k,
            search: k <= plan.search_passes,
            deposit_m: deposit,
            relative_density: deposit / plan.drop_before(k),
            effective_thickness_m: effective,
            packing: deposit / effective,
            covered_fraction: covered as f64 / top.len() as f64,
            roughness_d: roughness,
            bed_relative_density: (!plan.fused && k > 1)
                .then(|| (volume - volume_after_first) / ((k - 1) as f64 * plan.layer_thickness)),
            particles: gs.iter().filter(|g| new(g)).count(),
            roller: None,
        });
        mass_before = line.plate_mass;
        if plan.fused {
            floor_before = solids.iter().find(|(j, _)| *j == k).map_or(floor_before + deposit, |s| s.1);
        }
        surface_before = m;
        ids_before = gs.iter().map(|g| g.id).collect();
    }
    out
}

/// The steady layer over `passes`: a fused bed's search passes are never part of it.
pub fn steady_layer(plan: &Plan, passes: Vec<PassRecord>) -> LayerSeries {
    let (answer, depth) = tested_series(plan, &passes);
    let first = plan.search_passes.min(passes.len());
    let (answer_laid, depth_laid) = (&answer[first..], &depth[first..]);
    let cut = first + if plan.fused { mser(answer_laid).max(mser(depth_laid)) } else { mser(answer_laid) };
    let (deposit_lag1, depth_lag1) = lag1(plan);
    // A fused bed is steady once its depth has stopped growing too: its packing can settle
    // passes before the depth reaches the drop over it.
    let series = series_tested(plan);
    let flat = |y: &[f64], lag1: f64| trend_z(y).abs() <= trend_limit(y.len(), series, lag1);
    let steady = passes.len() - cut >= MIN_STEADY_PASSES
        && flat(&answer[cut..], deposit_lag1)
        && (!plan.fused || flat(&depth[cut..], depth_lag1));
    series_from(plan, passes, cut + 1, steady, (deposit_lag1, depth_lag1))
}

/// The layer read from pass `from` (from 1) on: each measure's mean over those passes and its
/// SE, widened for the lag-1 autocorrelations `(deposit, depth)` of its series (0: independent).
pub fn series_from(
    plan: &Plan,
    passes: Vec<PassRecord>,
    from: usize,
    steady: bool,
    lag1: (f64, f64),
) -> LayerSeries {
    let kept = &passes[from - 1..];
    let pick = |f: &dyn Fn(&PassRecord) -> f64, lag1: f64| {
        let (m, se) = mean_se(&kept.iter().map(f).collect::<Vec<f64>>());
        (m, se * ar1_se_factor(kept.len(), lag1, false))
    };
    let (packing, mut packing_se) = pick(&|p| p.packing, lag1.0);
    let (relative_density, relative_density_se) = pick(&|p| p.relative_density, lag1.0);
    let (effective, mut effective_se) = pick(&|p| p.effective_thickness_m, lag1.1);
    // A fused bed's depth is known no better than the fixed point its passes locate.
    let fixed =
        if plan.fused { fixed_point(passes.get(1..).unwrap_or(&[]), plan.layer_thickness) } else { None };
    if let Some(fixed) = fixed {
        effective_se = effective_se.max(fixed.se);
        packing_se = packing_se.max(packing * fixed.se / fixed.depth);
    }
    LayerSeries {
        bed: if plan.fused { "fused" } else { "loose" }.into(),
        layer_thickness_m: plan.layer_thickness,
        steady_from: from,
        steady,
        packing,
        packing_se,
        relative_density,
        relative_density_se,
        effective_thickness_m: effective,
        effective_thickness_se_m: effective_se,
        covered_fraction: pick(&|p| p.covered_fraction, 0.0).0,
        roughness_d: pick(&|p| p.roughness_d, 0.0).0,
        roller: roller_steady(kept),
        passes,
        numerical_error: None,
    }
}

/// A roller's load over `kept` passes, when every one of them has it: each measure's mean and SE.
fn roller_steady(kept: &[PassRecord]) -> Option<RollerSteady> {
    let loads: Vec<RollerLoad> = kept.iter().map(|p| p.roller).collect::<Option<_>>()?;
    if loads.is_empty() {
        return None;
    }
    let of = |f: fn(&RollerLoad) -> f64| mean_se(&loads.iter().map(f).collect::<Vec<f64>>());
    let (torque, turning, push, pushing) = (
        of(|l| l.torque_nm_per_m),
        of(|l| l.turning_power_w_per_m),
        of(|l| l.push_n_per_m),
        of(|l| l.pushing_power_w_per_m),
    );
    // Measured in every kept pass, or not at all (a result from before it was).
    let ejected = loads.iter().map(|l| l.ejected_kg_per_m).collect::<Option<Vec<f64>>>().map(|e| mean_se(&e));
    let load = |pick: fn((f64, f64)) -> f64| RollerLoad {
        torque_nm_per_m: pick(torque),
        turning_power_w_per_m: pick(turning),
        push_n_per_m: pick(push),
        pushing_power_w_per_m: pick(pushing),
        ejected_kg_per_m: ejected.map(pick),
    };
    Some(RollerSteady { mean: load(|v| v.0), se: load(|v| v.1) })
}

/// The |t| of a least-squares slope over `passes` passes beyond which one of `series` series
/// shows a trend: the Student quantile with passes − 2 degrees of freedom at the two-sided level
/// [`TREND_FALSE_ALARM`] / `series`, widened by what a lag-1 autocorrelation `lag1` of the
/// passes adds to the slope's scatter. Infinite under three passes (no slope can be judged).
pub fn trend_limit(passes: usize, series: usize, lag1: f64) -> f64 {
    student_quantile(passes as f64 - 2.0, TREND_FALSE_ALARM / series.max(1) as f64)
        * ar1_se_factor(passes, lag1, true)
}

/// The two series of `passes` the steady rule reads: the point's measure (relative density on a
/// loose bed, packing on a fused one) and the depth under the blade (a fused bed's second test).
fn tested_series(plan: &Plan, passes: &[PassRecord]) -> (Vec<f64>, Vec<f64>) {
    let answer = passes.iter().map(|p| if plan.fused { p.packing } else { p.relative_density }).collect();
    (answer, passes.iter().map(|p| p.effective_thickness_m).collect())
}

/// The lag-1 autocorrelation allowed for in a bed's passes: (its deposit's — packing and
/// relative density —, its depth's). A loose bed's passes showed none.
fn lag1(plan: &Plan) -> (f64, f64) {
    if plan.fused {
        (FUSED_PACKING_LAG1, FUSED_DEPTH_LAG1)
    } else {
        (0.0, 0.0)
    }
}

/// The series a bed's steadiness tests: a loose bed its relative density, a fused one its
/// packing and its depth.
fn series_tested(plan: &Plan) -> usize {
    if plan.fused {
        2
    } else {
        1
    }
}

pub(super) fn read_grains(path: &Path) -> Result<Vec<Grain>, String> {
    let snaps = read_dump(path, &["id", "x", "y", "z", "radius"]).map_err(|e| e.to_string())?;
    let last = snaps.last().ok_or_else(|| format!("{}: no snapshot", path.display()))?;
    let c = |n| last.column(n).expect("required column");
    let (id, x, y, z, r) = (c("id"), c("x"), c("y"), c("z"), c("radius"));
    Ok((0..last.len())
        .map(|i| Grain {
            id: last.get(i, id) as u64,
            x: last.get(i, x),
            y: last.get(i, y),
            z: last.get(i, z),
            r: last.get(i, r),
        })
        .collect())
}

/// The dump the deck writes after pass `k` (from 1): the particles over the plate.
pub fn layer_dump(k: usize) -> String {
    format!("dump.layer.{k}")
}

/// Whether a steady layer keeps the drop: a fused bed's steady passes each keep a whole layer of
/// solid, so their mean relative density is 1 within Student's quantile at [`TREND_FALSE_ALARM`]
/// of its SE; one that creeps behind can look flat over a few passes (a fused bed fed half the
/// dose, replayed, would have stopped at pass 12 of 24, its packing 5 SE off). A loose bed
/// keeps what it keeps.
pub fn keeps_the_drop(plan: &Plan, series: &LayerSeries) -> bool {
    if !plan.fused {
        return true;
    }
    let kept = series.passes.len() + 1 - series.steady_from;
    let limit = student_quantile(kept as f64 - 1.0, TREND_FALSE_ALARM);
    (1.0 - series.relative_density).abs() <= limit * series.relative_density_se
}

/// Why a series is not steady. A fused bed whose passes after the transient each leave less
/// than the drop, beyond a Student t test of their mean at [`TREND_FALSE_ALARM`], falls behind
/// the platform: that is said first, with what may make it keep pace.
pub fn unsteady_why(plan: &Plan, series: &LayerSeries) -> String {
    let (from, to) = (series.steady_from, series.passes.len());
    let kept = to + 1 - from;
    let behind = 1.0 - series.relative_density;
    let limit = student_quantile(kept as f64 - 1.0, TREND_FALSE_ALARM);
    if plan.fused && kept >= 2 && behind > limit * series.relative_density_se {
        return format!(
            "the bed falls behind: passes {from}–{to} each leave {:.2} ± {:.2} of the drop, where a steady fused bed keeps all of it (a larger dose, scene.supply_factor, or a slower blade may keep pace)",
            series.relative_density, series.relative_density_se
        );
    }
    if to + 1 - from < MIN_STEADY_PASSES {
        format!("fewer than {MIN_STEADY_PASSES} passes after the transient (MSER kept passes {from}–{to})")
    } else {
        // The series that trends: the point's measure, or on a fused bed its depth.
        let (answer, depth) = tested_series(plan, &series.passes[from - 1..]);
        let (deposit_lag1, depth_lag1) = lag1(plan);
        let series = series_tested(plan);
        let (name, y, lag1) =
            if plan.fused && trend_z(&answer).abs() <= trend_limit(kept, series, deposit_lag1) {
                ("its depth under the blade", depth, depth_lag1)
            } else {
                (if plan.fused { "its packing" } else { "its relative density" }, answer, deposit_lag1)
            };
        let limit = trend_limit(kept, series, lag1);
        format!(
            "{name} trends over passes {from}–{to}: a slope of {:.1} SE, beyond {limit:.1}",
            trend_z(&y).abs()
        )
    }
}

/// The run's result: every pass, the steady layer as the point's answer (its relative density
/// on a loose bed, its packing on a fused one: [`LayerSeries::answer`]). A run not steady by its last pass fails
/// as `unsteady`, its numbers kept.
pub fn measure(run: &Finished) -> Result<RunResult, Rejected> {
    let scene = run.scene;
    let plan = plan_of(scene);
    // The deck warns rather than stops on a lost atom (see its thermo_modify): a loss is a failure.
    if let Some(line) = run.run.log.lines().find(|l| l.contains("Lost atoms")) {
        return Err(Rejected::new(FailureClass::LostAtoms, line.trim().to_string()));
    }
    let lines = parse_log(&run.run.log);
    let reached = plan.reached();
    if lines.len() != reached || lines.iter().enumerate().any(|(i, l)| l.k != i + 1) {
        return Err(Rejected::new(
            FailureClass::Unparsable,
            format!("the log reports {} of {reached} passes", lines.len()),
        ));
    }
    let grains: Vec<Vec<Grain>> = lines
        .iter()
        .map(|l| read_grains(&run.run_dir.join(layer_dump(l.k))))
        .collect::<Result<_, _>>()
        .map_err(|e| Rejected::new(FailureClass::Unparsable, e))?;
    let solids = parse_solids(&run.run.log);
    let mut records = passes(scene, &plan, &lines, &solids, &grains);
    for (k, load) in parse_roller(&run.run.log, scene.depth) {
        if let Some(p) = k.checked_sub(1).and_then(|i| records.get_mut(i)) {
            p.roller = Some(load);
        }
    }
    for (k, ejected) in parse_ejected(&run.run.log, scene.depth) {
        if let Some(load) = k.checked_sub(1).and_then(|i| records.get_mut(i)).and_then(|p| p.roller.as_mut())
        {
            load.ejected_kg_per_m = Some(ejected);
        }
    }
    let series = LayerSeries {
        numerical_error: Some(super::numerics::of(scene, &plan)),
        ..steady_layer(&plan, records)
    };
    let steps = lines.last().map_or(0, |l| l.step);
    let result = RunResult {
        format: RESULT_FORMAT,
        hash: run.hash.to_string(),
        parameters: run.parameters.clone(),
        answer: series.answer(),
        mfr_flux: f64::NAN,
        answer_particles: series.passes.iter().map(|p| p.particles).sum(),
        answer_windows: series
            .passes
            .iter()
            .map(|p| if plan.fused { p.packing } else { p.relative_density })
            .collect(),
        steady: series.steady,
        steady_p: f64::NAN,
        // The layers layout measures no v_x profile.
        vx: vec![None; VX_LAYERS],
        particles: scene.particles,
        layer: Some(crate::outcome::layer::Layer {
            layer_cv: f64::NAN,
            layer_cv_noise: f64::NAN,
            covered_fraction: series.covered_fraction,
            roughness_d: series.roughness_d,
            height_d: series.effective_thickness_m / scene.diameter,
            particles: series.passes.last().map_or(0, |p| p.particles),
        }),
        layer_thickness: Some(series.effective_thickness_m),
        layer_packing: Some(series.packing),
        layer_packing_se: Some(series.packing_se),
        own: crate::outcome::OwnResult::new(series.clone()),
        ..run.record(steps)
    };
    let kept = series.passes.len() + 1 - series.steady_from;
    if series.steady && reached < plan.most() && (kept < STOP_KEPT_PASSES || !keeps_the_drop(&plan, &series))
    {
        return Err(Rejected::measured(
            FailureClass::Unsteady,
            format!(
                "steady over passes {}–{reached} only: a point stops short of its {} passes once {STOP_KEPT_PASSES} are{}",
                series.steady_from,
                plan.most(),
                if plan.fused { " and they keep the whole drop" } else { "" }
            ),
            result,
        ));
    }
    if !series.steady {
        let why = unsteady_why(&plan, &series);
        return Err(Rejected::measured(
            FailureClass::Unsteady,
            format!("layers not steady by pass {}: {why}", series.passes.len()),
            result,
        ));
    }
    let answer = result.answer.value;
    if !(answer.is_finite() && answer > 0.0 && answer < 0.75) {
        return Err(Rejected::measured(
            FailureClass::Implausible,
            format!("steady layer {answer:.3}: outside (0, 0.75), beyond the densest packing of spheres"),
            result,
        ));
    }
    Ok(result)
}
