//! `sweep bench designs`: the adaptive design against the LDS and the trapezoid lattice, on a
//! response surface whose answer is known.
//!
//! Two surfaces over a sweep's space: the stand-in engine's model (its deterministic per-point
//! noise on every run, [`crate::scenes::stand_in`]), or a replay of a recorded sweep directory (an
//! emulator fitted to all its done runs; a run is its mean plus normal noise at the SE the
//! nearest recorded run measured). The truth is the noiseless surface on [`TRUTH_POINTS`]
//! scrambled-Halton points: its four statistics, its first-order sensitivity ranking (with the
//! pairs of parameters it tells apart), and its best MFR.
//!
//! Each design is run in process (no sweep directory: the same design and analysis functions
//! the sweep uses) and its answer read at checkpoints: the LDS and the lattice as `sweep lds`
//! and `sweep lattice` report them (sample statistics, trapezoid weights on the lattice, sample
//! sensitivity indices), the LDS also through the emulator (to tell the design's gain from the
//! estimator's), and the adaptive design as `sweep adapt` does (the emulator's statistics and
//! its indices on the emulator's surface). The recommended point is the design's run the
//! emulator fitted to its runs ranks best (the report's "best settings"), scored by its true MFR.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use crate::analysis::adapt as criterion;
use crate::analysis::convergence::{judge, scale, Criteria, SpaceStats};
use crate::analysis::emulator::Emulator;
use crate::analysis::sensitivity;
use crate::analysis::stats::{moments, Bootstrap, Moments, STATISTICS};
use crate::design::halton::{halton, Scrambling};
use crate::scenes::stand_in::{FlowPoint, Noise};
use crate::sweep::Sweep;

/// Points of the truth.
pub const TRUTH_POINTS: usize = 20_000;
/// Seed of the truth's points (apart from every design's).
const TRUTH_SEED: u64 = 99;

/// The targets of the comparison: mean within 2 %, std within 3 %, skewness and kurtosis within
/// 5 % of their scale (the convergence rule's scales).
pub const MEAN_TOL: f64 = 0.02;
pub const STD_TOL: f64 = 0.03;
pub const SHAPE_TOL: f64 = 0.05;

/// A response surface: the true (noiseless) MFR at a unit point, and one run there.
pub trait Surface: Sync {
    fn truth(&self, u: &[f64]) -> f64;
    /// MFR of a run at `u` and the SE it records.
    fn run(&self, u: &[f64]) -> (f64, Option<f64>);
    /// The per-run noise SE at `u` (for "within one SE of the best").
    fn se(&self, u: &[f64]) -> f64;
    /// A run at `u` whose SE target is `scale` times the surface's: its deviation from the
    /// truth and the SE it records scaled by `scale`.
    fn run_scaled(&self, u: &[f64], scale: f64) -> (f64, Option<f64>) {
        let t = self.truth(u);
        let (y, se) = self.run(u);
        ((t + scale * (y - t)).max(0.0), se.map(|s| s * scale))
    }
}

/// The stand-in's model over a sweep's space.
pub struct StandInSurface {
    pub sweep: Sweep,
}

impl StandInSurface {
    fn point(&self, u: &[f64]) -> FlowPoint {
        let v = crate::sweep::space::scale_point(&self.sweep, u);
        let resolved = crate::point::resolve(&self.sweep, &v);
        let p = |k: &str| resolved.get(k).copied().unwrap_or(f64::NAN);
        FlowPoint {
            friction: p("friction"),
            diameter: p("diameter"),
            gap: p("gap"),
            blade_speed: p("blade_speed"),
        }
    }
}

/// Emulator fits of this process and their wall time in ns (what `sweep bench designs` reports
/// on stderr: the emulator's linear algebra is most of a fit, BENCHMARKS.md).
static FITS: AtomicU64 = AtomicU64::new(0);
static FIT_NANOS: AtomicU64 = AtomicU64::new(0);

/// [`Emulator::fit_censored`], timed into [`fit_time`].
fn fit(x: &[Vec<f64>], y: &[f64], se: &[Option<f64>]) -> Option<Emulator> {
    let started = Instant::now();
    let em = Emulator::fit_censored(x, y, se);
    FIT_NANOS.fetch_add(started.elapsed().as_nanos() as u64, Ordering::Relaxed);
    FITS.fetch_add(1, Ordering::Relaxed);
    em
}

/// The emulator fits this process has made so far, and their total wall time.
pub fn fit_time() -> (u64, Duration) {
    (FITS.load(Ordering::Relaxed), Duration::from_nanos(FIT_NANOS.load(Ordering::Relaxed)))
}

fn key(u: &[f64]) -> String {
    u.iter().map(|v| format!("{:016x}", v.to_bits())).collect()
}

impl Surface for StandInSurface {
    fn truth(&self, u: &[f64]) -> f64 {
        self.point(u).mean_mfr()
    }
    fn run(&self, u: &[f64]) -> (f64, Option<f64>) {
        (self.point(u).model(&mut Noise::new(&key(u))).0, None)
    }
    fn se(&self, u: &[f64]) -> f64 {
        crate::scenes::stand_in::MFR_NOISE * self.truth(u)
    }
}

/// A recorded sweep replayed: the emulator of its runs, with each run's noise at the SE of the
/// nearest recorded run.
pub struct ReplaySurface {
    pub emulator: Emulator,
    /// Unit points of the recorded runs and their SE.
    pub recorded: Vec<(Vec<f64>, f64)>,
}

impl ReplaySurface {
    fn nearest_se(&self, u: &[f64]) -> f64 {
        let d2 = |a: &[f64]| a.iter().zip(u).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
        self.recorded.iter().min_by(|a, b| d2(&a.0).total_cmp(&d2(&b.0))).map_or(0.0, |r| r.1)
    }
}

impl Surface for ReplaySurface {
    fn truth(&self, u: &[f64]) -> f64 {
        self.emulator.mean(u).max(0.0)
    }
    fn run(&self, u: &[f64]) -> (f64, Option<f64>) {
        let se = self.nearest_se(u);
        ((self.truth(u) + se * Noise::new(&key(u)).normal()).max(0.0), Some(se))
    }
    fn se(&self, u: &[f64]) -> f64 {
        self.nearest_se(u)
    }
}

/// A surface whose runs are quieter (or noisier): each run's deviation from the truth and the SE
/// it records scaled by `scale` — the runs of a sweep whose precision target is `scale` times
/// the other's, at the cost of a window 1/scale² as long. The targets stay the inner surface's
/// (`se` is not scaled), so that designs at different precisions are judged alike.
pub struct Scaled<'a> {
    pub inner: &'a dyn Surface,
    pub scale: f64,
}

impl Surface for Scaled<'_> {
    fn truth(&self, u: &[f64]) -> f64 {
        self.inner.truth(u)
    }
    fn run(&self, u: &[f64]) -> (f64, Option<f64>) {
        self.inner.run_scaled(u, self.scale)
    }
    fn se(&self, u: &[f64]) -> f64 {
        self.inner.se(u)
    }
    fn run_scaled(&self, u: &[f64], scale: f64) -> (f64, Option<f64>) {
        self.inner.run_scaled(u, self.scale * scale)
    }
}

/// The share of a run at the default SE target spent before its window (the warm-up): 0.73 in
/// the adaptive LIGGGHTS record of the thesis space (`docs/study/thesis/adapt-240`, 232 runs:
/// 10.8 blocks of warm-up and 29.4 of window a run on average). A run at `f` times the target
/// costs 0.73 + 0.27/f² of one at it.
pub const WARMUP_SHARE: f64 = 0.73;

/// The known answer.
#[derive(Debug, Clone)]
pub struct Truth {
    pub moments: Moments,
    /// Parameters by their first-order index, largest first.
    pub ranking: Vec<String>,
    /// The pairs (ahead, behind) of `ranking` the truth tells apart: their indices' 95 %
    /// bootstrap intervals on the truth's points do not overlap. A pair it does not tell apart
    /// (two indices of 0.057 and 0.058 on the replay) has no order a design could get right.
    pub ordered: Vec<(String, String)>,
    pub best: f64,
    pub best_se: f64,
}

impl Truth {
    /// Whether `ranking` orders every pair the truth tells apart as the truth does.
    pub fn ranks_alike(&self, ranking: &[String]) -> bool {
        let at = |p: &str| ranking.iter().position(|r| r == p);
        self.ordered.iter().all(|(a, b)| matches!((at(a), at(b)), (Some(i), Some(j)) if i < j))
    }

    /// The ranking in words, `≈` between neighbours the truth does not tell apart.
    pub fn ranking_text(&self) -> String {
        let mut out = self.ranking.first().cloned().unwrap_or_default();
        for w in self.ranking.windows(2) {
            let apart = self.ordered.iter().any(|(a, b)| *a == w[0] && *b == w[1]);
            out.push_str(if apart { " > " } else { " ≈ " });
            out.push_str(&w[1]);
        }
        out
    }
}

fn ranking(names: &[String], x: &[Vec<f64>], y: &[f64]) -> Vec<String> {
    sensitivity::ranked(sensitivity::first_order(names, x, y)).into_iter().map(|i| i.parameter).collect()
}

/// The pairs of `indices` (ranked, with intervals) whose intervals do not overlap, ahead first.
fn told_apart(indices: &[sensitivity::Index]) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (i, a) in indices.iter().enumerate() {
        for b in &indices[i + 1..] {
            if let (Some(alo), Some(bhi)) = (a.lo, b.hi) {
                if alo > bhi {
                    out.push((a.parameter.clone(), b.parameter.clone()));
                }
            }
        }
    }
    out
}

pub fn truth(s: &dyn Surface, names: &[String]) -> Truth {
    let pts = halton(names.len(), TRUTH_POINTS, Scrambling::Random, TRUTH_SEED);
    let y: Vec<f64> = pts.iter().map(|u| s.truth(u)).collect();
    let (bi, best) = y.iter().enumerate().fold((0, f64::MIN), |a, (i, v)| if *v > a.1 { (i, *v) } else { a });
    let boot = Bootstrap { resamples: 200, ..Bootstrap::default() };
    let indices = sensitivity::ranked(sensitivity::with_intervals(names, &pts, &y, &boot));
    Truth {
        moments: moments(&y),
        ranking: indices.iter().map(|i| i.parameter.clone()).collect(),
        ordered: told_apart(&indices),
        best,
        best_se: s.se(&pts[bi]),
    }
}

/// A design's answer at one checkpoint, against the truth.
#[derive(Debug, Clone)]
pub struct Row {
    pub design: String,
    pub seed: u64,
    pub runs: usize,
    pub moments: Moments,
    pub ranking: Vec<String>,
    /// True MFR at the recommended run.
    pub recommended: f64,
    /// The CPU of the runs so far, in runs at the surface's own SE target.
    pub cost: f64,
    /// The space as the convergence rule reads it (statistics and their noise); `None` for the
    /// lattice.
    pub rule: Option<SpaceStats>,
}

impl Row {
    /// Errors of mean and std (relative), skewness and kurtosis (over their scale).
    pub fn errors(&self, t: &Truth) -> [Option<f64>; 4] {
        let m = &self.moments;
        let tm = &t.moments;
        let over = |a: Option<f64>, b: Option<f64>, scale: Option<f64>| Some((a? - b?).abs() / scale?);
        let abs = |v: Option<f64>| v.map(f64::abs);
        [
            over(m.mean, tm.mean, abs(tm.mean)),
            over(m.std, tm.std, tm.std),
            over(m.skewness, tm.skewness, tm.skewness.map(|s| s.abs().max(1.0))),
            over(m.kurtosis, tm.kurtosis, tm.kurtosis),
        ]
    }

    /// Which targets hold: the four statistics, the ranking, the recommended point.
    pub fn within(&self, t: &Truth) -> [bool; 6] {
        let e = self.errors(t);
        let ok = |e: Option<f64>, tol: f64| e.is_some_and(|e| e <= tol);
        [
            ok(e[0], MEAN_TOL),
            ok(e[1], STD_TOL),
            ok(e[2], SHAPE_TOL),
            ok(e[3], SHAPE_TOL),
            t.ranks_alike(&self.ranking),
            self.recommended >= t.best - t.best_se,
        ]
    }
}

/// The run of the design the emulator of its runs ranks best, by its true MFR.
fn recommended(s: &dyn Surface, x: &[Vec<f64>], em: Option<&Emulator>, y: &[f64]) -> f64 {
    let i = match em {
        Some(em) => em.rank(x, 1).first().map_or(0, |r| r.0),
        None => y.iter().enumerate().fold((0, f64::MIN), |a, (i, v)| if *v > a.1 { (i, *v) } else { a }).0,
    };
    x.get(i).map_or(f64::NAN, |u| s.truth(u))
}

fn run_all(s: &dyn Surface, x: &[Vec<f64>]) -> (Vec<f64>, Vec<Option<f64>>) {
    x.iter().map(|u| s.run(u)).unzip()
}

/// The answer from an emulator of the runs: its statistics and its indices over the space.
fn emulated(names: &[String], n: usize, em: Option<&Emulator>) -> (SpaceStats, Vec<String>) {
    let (st, _) = criterion::space_stats(n, em, crate::run::adapt::STATS_SEED);
    let Some(em) = em else { return (st, Vec::new()) };
    let pts = halton(names.len(), criterion::DRAWS, Scrambling::Random, 15);
    let y: Vec<f64> = pts.iter().map(|u| em.mean(u).max(0.0)).collect();
    (st, ranking(names, &pts, &y))
}

/// The LDS at each of `checkpoints` runs: as `sweep lds` reports it, and through the emulator
/// (up to `emulate_to` runs).
pub fn lds(
    s: &dyn Surface,
    names: &[String],
    seed: u64,
    checkpoints: &[usize],
    emulate_to: usize,
    run_cost: f64,
) -> Vec<Row> {
    let max = checkpoints.iter().copied().max().unwrap_or(0);
    let x = halton(names.len(), max, Scrambling::Random, seed);
    let (y, se) = run_all(s, &x);
    let mut rows = Vec::new();
    for &n in checkpoints {
        let em = fit(&x[..n], &y[..n], &se[..n]);
        let rec = recommended(s, &x[..n], em.as_ref(), &y[..n]);
        rows.push(Row {
            design: "lds".into(),
            seed,
            runs: n,
            moments: moments(&y[..n]),
            ranking: ranking(names, &x[..n], &y[..n]),
            recommended: rec,
            rule: Some(SpaceStats::of(n, &y[..n], None, &Bootstrap::default())),
            cost: n as f64 * run_cost,
        });
        if n <= emulate_to {
            let (st, r) = emulated(names, n, em.as_ref());
            rows.push(Row {
                design: "lds+emulator".into(),
                seed,
                runs: n,
                moments: st.moments,
                ranking: r,
                recommended: rec,
                rule: Some(st),
                cost: n as f64 * run_cost,
            });
        }
    }
    rows
}

/// The trapezoid lattice of each of `levels`.
pub fn lattice(s: &dyn Surface, names: &[String], levels: &[usize], run_cost: f64) -> Vec<Row> {
    levels
        .iter()
        .map(|&l| {
            let x = crate::design::lattice::lattice(names.len(), l);
            let (y, se) = run_all(s, &x);
            let w = crate::analysis::weights::trapezoid(&x);
            let em = fit(&x, &y, &se);
            Row {
                design: "lattice".into(),
                seed: 0,
                runs: x.len(),
                moments: crate::analysis::weights::moments(&y, w.as_deref()),
                ranking: ranking(names, &x, &y),
                recommended: recommended(s, &x, em.as_ref(), &y),
                rule: None,
                cost: x.len() as f64 * run_cost,
            }
        })
        .collect()
}

/// The adaptive design, batch by batch to `max` runs, as `sweep adapt` plans and judges it:
/// every run at the surface's SE target, or with `p.per_run` each run the criterion places at
/// the one of [`criterion::SE_SCALES`] it chooses.
pub fn adapt(s: &dyn Surface, names: &[String], seed: u64, p: &Plan) -> Vec<Row> {
    let (first, batch, max, explore) = (p.first, p.batch, p.max, p.explore);
    let d = names.len();
    let mut x = halton(d, first, Scrambling::Random, seed);
    let (mut y, mut se) = run_all(s, &x);
    let mut scales = vec![1.0; x.len()];
    let mut cost = x.len() as f64 * p.run_cost(1.0);
    let levels: &'static [f64] = if p.per_run { &criterion::SE_SCALES } else { &[1.0] };
    let refs = criterion::reference(d, seed);
    let mut rows = Vec::new();
    let mut k = 0;
    loop {
        let em = fit(&x, &y, &se);
        let (st, r) = emulated(names, x.len(), em.as_ref());
        rows.push(Row {
            design: if p.per_run { "adapt per-run".into() } else { "adapt".into() },
            seed,
            runs: x.len(),
            moments: st.moments,
            ranking: r,
            recommended: recommended(s, &x, em.as_ref(), &y),
            rule: Some(st),
            cost,
        });
        let size = batch.min(max.saturating_sub(x.len()));
        if size == 0 {
            return rows;
        }
        let cands = criterion::batch_candidates(d, k, seed, em.as_ref(), &x);
        let chosen: Vec<(Vec<f64>, f64)> = em
            .as_ref()
            .and_then(|em| {
                let noise = criterion::RunNoise {
                    warmup_share: WARMUP_SHARE,
                    scales: levels,
                    ..criterion::RunNoise::of(em, &se, &scales)
                };
                let split = criterion::Split::of(size, explore);
                criterion::next_batch(em, &noise, &cands, &refs, &x, size, split)
            })
            .map_or_else(
                || cands[..size].iter().map(|u| (u.clone(), 1.0)).collect(),
                |(c, _)| c.into_iter().map(|c| (c.point, c.se_scale)).collect(),
            );
        for (u, scale) in chosen {
            let (v, e) = s.run_scaled(&u, scale);
            x.push(u);
            y.push(v);
            se.push(e);
            scales.push(scale);
            cost += p.run_cost(scale);
        }
        k += 1;
    }
}

/// Per design and seed: the fewest runs from which every target holds at every later
/// checkpoint, per target and for all at once (`None`: not by the last checkpoint).
pub fn runs_needed(rows: &[Row], t: &Truth) -> BTreeMap<(String, u64), [Option<usize>; 7]> {
    let mut by: BTreeMap<(String, u64), Vec<&Row>> = BTreeMap::new();
    for r in rows {
        by.entry((r.design.clone(), r.seed)).or_default().push(r);
    }
    by.into_iter()
        .map(|(k, mut rs)| {
            rs.sort_by_key(|r| r.runs);
            let flags: Vec<[bool; 6]> = rs.iter().map(|r| r.within(t)).collect();
            let from = |ok: &dyn Fn(&[bool; 6]) -> bool| -> Option<usize> {
                let last_bad = flags.iter().rposition(|f| !ok(f));
                match last_bad {
                    None => rs.first().map(|r| r.runs),
                    Some(i) => rs.get(i + 1).map(|r| r.runs),
                }
            };
            let mut out = [None; 7];
            for (j, slot) in out.iter_mut().enumerate().take(6) {
                *slot = from(&|f: &[bool; 6]| f[j]);
            }
            out[6] = from(&|f: &[bool; 6]| f.iter().all(|b| *b));
            (k, out)
        })
        .collect()
}

/// The settings of one comparison.
#[derive(Debug, Clone)]
pub struct Plan {
    pub seeds: Vec<u64>,
    pub first: usize,
    pub batch: usize,
    pub max: usize,
    /// The share of each adaptive batch placed for coverage.
    pub explore: f64,
    pub lds: Vec<usize>,
    pub emulate_to: usize,
    pub levels: Vec<usize>,
    /// The runs' SE target as a multiple of the surface's (`--noise-scale`), for their cost.
    pub noise_scale: f64,
    /// The adaptive design chooses each run's SE target ([`criterion::SE_SCALES`]).
    pub per_run: bool,
}

impl Plan {
    /// The cost of a run at `scale` times the design's SE target, in runs at the surface's.
    pub fn run_cost(&self, scale: f64) -> f64 {
        let f = self.noise_scale * scale;
        WARMUP_SHARE + (1.0 - WARMUP_SHARE) / (f * f)
    }
}

/// Every design's rows on `s`.
pub fn compare(s: &dyn Surface, names: &[String], p: &Plan) -> Vec<Row> {
    let mut rows = lattice(s, names, &p.levels, p.run_cost(1.0));
    for &seed in &p.seeds {
        rows.extend(lds(s, names, seed, &p.lds, p.emulate_to, p.run_cost(1.0)));
        rows.extend(adapt(s, names, seed, p));
    }
    rows
}

fn pct(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{:.1} %", v * 100.0))
}

fn runs(v: Option<usize>) -> String {
    v.map_or("not by the end".into(), |n| n.to_string())
}

/// The tables of BENCHMARKS.md: the truth; runs needed per design and seed; errors at equal runs.
pub fn tables(t: &Truth, rows: &[Row]) -> String {
    let f = |v: Option<f64>| v.map_or("–".into(), |v| format!("{v:.4}"));
    let m = &t.moments;
    let mut out = format!(
        "Truth ({TRUTH_POINTS} points): mean {}, std {}, skewness {}, kurtosis {}; ranking {}; best MFR {:.4} (one SE {:.4})\n\n",
        f(m.mean),
        f(m.std),
        f(m.skewness),
        f(m.kurtosis),
        t.ranking_text(),
        t.best,
        t.best_se
    );
    out.push_str("Runs from which each target holds at every later checkpoint:\n\n");
    out.push_str("| design | seed | mean ±2 % | std ±3 % | skewness ±5 % | kurtosis ±5 % | ranking | best within 1 SE | all |\n");
    out.push_str("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    for ((d, seed), n) in runs_needed(rows, t) {
        out.push_str(&format!("| {d} | {seed} | {} |\n", n.map(runs).join(" | ")));
    }
    out.push_str(&rule_table(t, rows));
    out.push_str("\nErrors at equal runs (mean over seeds; skewness and kurtosis over their scale), and the seeds where all six targets hold:\n\n");
    out.push_str(
        "| runs | design | mean | std | skewness | kurtosis | ranking right | best within 1 SE | all six |\n",
    );
    out.push_str("| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    let mut keys: Vec<(usize, String)> = rows.iter().map(|r| (r.runs, r.design.clone())).collect();
    keys.sort();
    keys.dedup();
    for (n, d) in keys {
        let rs: Vec<&Row> = rows.iter().filter(|r| r.runs == n && r.design == d).collect();
        let k = rs.len();
        let mean_err = |j: usize| {
            let e: Vec<f64> = rs.iter().filter_map(|r| r.errors(t)[j]).collect();
            (e.len() == k).then(|| e.iter().sum::<f64>() / k as f64)
        };
        let count = |j: usize| rs.iter().filter(|r| r.within(t)[j]).count();
        let all = rs.iter().filter(|r| r.within(t).iter().all(|b| *b)).count();
        out.push_str(&format!(
            "| {n} | {d} | {} | {} | {} | {} | {}/{k} | {}/{k} | {all}/{k} |\n",
            pct(mean_err(0)),
            pct(mean_err(1)),
            pct(mean_err(2)),
            pct(mean_err(3)),
            count(4),
            count(5)
        ));
    }
    out
}

/// Where the default rule (`scaled`, τ = 0.05, hold 2) says each design and seed converged, and
/// whether its answer there is within every target.
fn rule_table(t: &Truth, rows: &[Row]) -> String {
    let c = Criteria::from_settings(&crate::sweep::ConvergenceSettings::default());
    let mut by: BTreeMap<(String, u64), Vec<&Row>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.rule.is_some()) {
        by.entry((r.design.clone(), r.seed)).or_default().push(r);
    }
    let mut out = String::from(
        "\nThe default rule (scaled, τ = 0.05, hold 2) applied checkpoint to checkpoint, and the answer where it held:\n\n\
         | design | seed | the rule holds at (runs) | CPU there (runs at the surface's SE) | all six targets there | CPU at the last checkpoint | last checkpoint: 95 % half-widths over τ·scale (mean, std, skewness, kurtosis) | truth inside the intervals |\n\
         | --- | ---: | ---: | ---: | --- | ---: | --- | ---: |\n",
    );
    for ((d, seed), mut rs) in by {
        rs.sort_by_key(|r| r.runs);
        let spaces: Vec<SpaceStats> = rs.iter().filter_map(|r| r.rule).collect();
        let at = judge(&spaces, &c).iter().position(|j| j.converged);
        let (n, cpu, ok) = match at {
            Some(i) => (
                rs[i].runs.to_string(),
                format!("{:.0}", rs[i].cost),
                if rs[i].within(t).iter().all(|b| *b) { "yes" } else { "no" },
            ),
            None => ("never".into(), "–".into(), "–"),
        };
        let end = rs.last().map_or("–".into(), |r| format!("{:.0}", r.cost));
        let (widths, inside) = rs
            .last()
            .and_then(|r| r.rule)
            .map_or(("–".into(), "–".into()), |st| known(&st, t, c.tolerance));
        out.push_str(&format!("| {d} | {seed} | {n} | {cpu} | {ok} | {end} | {widths} | {inside} |\n"));
    }
    out
}

/// How well a space knows each statistic as the rule reads it (its 95 % half-width over τ times
/// the statistic's scale: above 1 the rule cannot hold), and for how many of the four the truth
/// lies within that half-width of the estimate (the rule's reading of the interval; the
/// emulator's own intervals are not symmetric).
fn known(st: &SpaceStats, t: &Truth, tolerance: f64) -> (String, String) {
    let mut widths = Vec::new();
    let (mut inside, mut outside) = (0, Vec::new());
    for (k, s) in STATISTICS.iter().enumerate() {
        let (Some(v), Some(h), Some(sc), Some(truth)) =
            (s.of(&st.moments), st.noise[k], scale(*s, &st.moments), s.of(&t.moments))
        else {
            widths.push("–".to_string());
            continue;
        };
        widths.push(format!("{:.1}", h / (tolerance * sc)));
        if (v - truth).abs() <= h {
            inside += 1;
        } else {
            outside.push(s.name());
        }
    }
    let missed =
        if outside.is_empty() { String::new() } else { format!(" (not the {})", outside.join(", ")) };
    (widths.join(", "), format!("{inside}/4{missed}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn index(p: &str, v: f64, half: f64) -> sensitivity::Index {
        sensitivity::Index {
            parameter: p.into(),
            first_order: Some(v),
            bins: 10,
            lo: Some(v - half),
            hi: Some(v + half),
        }
    }

    /// A plane with a run 0.01 above it, SE 0.01, at every point.
    struct Plane;
    impl Surface for Plane {
        fn truth(&self, u: &[f64]) -> f64 {
            0.1 + 0.05 * u[0]
        }
        fn run(&self, u: &[f64]) -> (f64, Option<f64>) {
            (self.truth(u) + 0.01, Some(0.01))
        }
        fn se(&self, _: &[f64]) -> f64 {
            0.01
        }
    }

    #[test]
    fn a_quieter_surface_scales_each_run_s_deviation_and_se_but_not_the_truth_or_the_target() {
        let q = Scaled { inner: &Plane, scale: 0.25 };
        let u = [0.4];
        let (y, se) = q.run(&u);
        assert!((y - (0.12 + 0.0025)).abs() < 1e-15, "{y}");
        assert!((se.unwrap() - 0.0025).abs() < 1e-15);
        assert_eq!((q.truth(&u), q.se(&u)), (Plane.truth(&u), 0.01));
    }

    #[test]
    fn a_ranking_must_order_only_the_pairs_the_truth_tells_apart() {
        let idx =
            [index("gap", 0.63, 0.01), index("blade_speed", 0.0577, 0.003), index("friction", 0.0570, 0.003)];
        let ordered = told_apart(&idx);
        assert_eq!(ordered.len(), 2, "{ordered:?}");
        let t = Truth {
            moments: moments(&[]),
            ranking: idx.iter().map(|i| i.parameter.clone()).collect(),
            ordered,
            best: 0.0,
            best_se: 0.0,
        };
        let r = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(t.ranks_alike(&r(&["gap", "blade_speed", "friction"])));
        assert!(t.ranks_alike(&r(&["gap", "friction", "blade_speed"])));
        assert!(!t.ranks_alike(&r(&["friction", "gap", "blade_speed"])));
        assert!(!t.ranks_alike(&r(&["gap", "friction"])));
        assert_eq!(t.ranking_text(), "gap > blade_speed ≈ friction");
    }
}
