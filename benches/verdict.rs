//! The verdict against the truth (BENCHMARKS.md "Verdict against the truth"): on functions whose
//! distribution over the space is known, how far the raw sample's statistics and the emulator's
//! are from the truth at N = 50..800, and how often each convergence rule calls a space
//! converged whose statistics are further from the truth than the tolerance.
//!
//!     cargo bench --bench verdict [-- --seeds 20 --emulator-seeds 20]
//!
//! Functions, both on the unit 4-cube (the thesis's 4-D space):
//! - `stand-in`: the stand-in engine's MFR (friction, diameter, gap, blade speed over the thesis
//!   ranges), zero below gap = 1.2 D, with its 4.2 % relative noise per point (the emulator is
//!   given that noise as each point's `mfr_se`);
//! - `kink`: max(0, u₁ + 0.8·u₂ − 0.6)·(1 + 0.5·u₃)·(1 − 0.3·u₄), zero over 22.5 % of the cube,
//!   no noise.
//!
//! The truth: the noiseless function's statistics on 2¹⁸ scrambled-Halton points. A statistic
//! is "off" when |s − truth| > τ × its scale (the scales of rule "scaled", taken from the truth:
//! mean max(|mean|, std), std itself, skewness max(|skew|, 1), kurtosis itself); a space is off
//! when any of the four is. Designs: scrambled Halton, one seed per replicate, nested prefixes
//! N = 50, 100, 200, 400, 800.

use demsweep::analysis::convergence::{judge, Criteria, Rule, SpaceStats};
use demsweep::analysis::emulator::Emulator;
use demsweep::analysis::stats::{moments, Bootstrap, Moments, Statistic, STATISTICS};
use demsweep::analysis::weights::LatticeWeights;
use demsweep::design::halton::halton;
use demsweep::scenes::stand_in::FlowPoint;
use demsweep::sweep::Scrambling;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

const NS: [usize; 5] = [50, 100, 200, 400, 800];
const MFR_NOISE: f64 = 0.042;

#[derive(Clone, Copy)]
enum F {
    StandIn,
    Kink,
}

impl F {
    fn name(self) -> &'static str {
        match self {
            F::StandIn => "stand-in",
            F::Kink => "kink",
        }
    }

    fn clean(self, u: &[f64]) -> f64 {
        match self {
            F::StandIn => FlowPoint {
                friction: 0.1 + 0.2 * u[0],
                diameter: 1.0 + 2.0 * u[1],
                gap: 1.0 + 4.0 * u[2],
                blade_speed: 1.2 + 0.4 * u[3],
            }
            .mean_mfr(),
            F::Kink => (u[0] + 0.8 * u[1] - 0.6).max(0.0) * (1.0 + 0.5 * u[2]) * (1.0 - 0.3 * u[3]),
        }
    }

    /// The measured value and its standard error.
    fn measure(self, u: &[f64], rng: &mut ChaCha8Rng) -> (f64, Option<f64>) {
        let c = self.clean(u);
        match self {
            F::StandIn => ((c * (1.0 + MFR_NOISE * normal(rng))).max(0.0), Some(MFR_NOISE * c)),
            F::Kink => (c, None),
        }
    }
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    use rand::Rng;
    let (u, v): (f64, f64) = (rng.gen_range(f64::EPSILON..1.0), rng.gen());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

fn scale(s: Statistic, t: &Moments) -> f64 {
    demsweep::analysis::convergence::scale(s, t).unwrap()
}

/// The largest |s − truth| / (τ-free scale) over the four statistics, and per statistic.
fn errors(m: &Moments, truth: &Moments) -> [f64; 4] {
    STATISTICS.map(|s| match s.of(m) {
        Some(v) => (v - s.of(truth).unwrap()).abs() / scale(s, truth),
        None => f64::INFINITY,
    })
}

fn off(m: &Moments, truth: &Moments, tol: f64) -> bool {
    errors(m, truth).iter().any(|e| *e > tol)
}

struct Replicate {
    raw: Vec<SpaceStats>,
    emu: Vec<Option<Moments>>,
}

fn replicate(f: F, seed: u64, emulate: bool) -> Replicate {
    let pts = halton(4, NS[NS.len() - 1], Scrambling::Random, 1000 + seed);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (y, se): (Vec<f64>, Vec<Option<f64>>) = pts.iter().map(|u| f.measure(u, &mut rng)).unzip();
    let b = Bootstrap::default();
    let raw = NS.iter().map(|&n| SpaceStats::of(n, &y[..n], None, &b)).collect();
    let emu = NS
        .iter()
        .map(|&n| {
            if !emulate {
                return None;
            }
            let e = Emulator::fit(&pts[..n], &y[..n], &se[..n])?;
            Some(e.space_statistics(4096, 50, seed).statistics)
        })
        .collect();
    Replicate { raw, emu }
}

fn crit(rule: Rule, tol: f64, hold: usize) -> Criteria {
    Criteria {
        rule,
        tolerance: tol,
        floor: 0.01,
        hold,
        min_points: 0,
        lattice_weights: LatticeWeights::Trapezoid,
        judged: [true; 4],
    }
}

fn arg(name: &str, default: usize) -> usize {
    let a: Vec<String> = std::env::args().collect();
    a.iter().position(|x| x == name).and_then(|i| a.get(i + 1)?.parse().ok()).unwrap_or(default)
}

fn main() {
    let seeds = arg("--seeds", 20) as u64;
    let emu_seeds = arg("--emulator-seeds", 20) as u64;
    for f in [F::StandIn, F::Kink] {
        let t0 = std::time::Instant::now();
        let truth_pts = halton(4, 1 << 18, Scrambling::Random, 7);
        let truth = moments(&truth_pts.iter().map(|u| f.clean(u)).collect::<Vec<_>>());
        let reps: Vec<Replicate> =
            (0..seeds).into_par_iter().map(|s| replicate(f, s, s < emu_seeds)).collect();
        println!("\n### {} (truth on 2^18 points: mean {:.5}, std {:.5}, skewness {:.4}, kurtosis {:.4}; {} design seeds, emulator on {}; {:.0} s)\n",
            f.name(), truth.mean.unwrap(), truth.std.unwrap(), truth.skewness.unwrap(), truth.kurtosis.unwrap(),
            seeds, emu_seeds.min(seeds), t0.elapsed().as_secs_f64());
        println!("Median over seeds of |statistic − truth| / scale (raw sample | emulator):\n");
        println!(
            "| N | mean | std | skewness | kurtosis | raw within 5 % (all four) | emulator within 5 % |"
        );
        println!("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
        for (k, n) in NS.iter().enumerate() {
            let med = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                if v.is_empty() {
                    f64::NAN
                } else {
                    v[v.len() / 2]
                }
            };
            let mut cells = Vec::new();
            for j in 0..4 {
                let mut r: Vec<f64> = reps.iter().map(|p| errors(&p.raw[k].moments, &truth)[j]).collect();
                let mut e: Vec<f64> =
                    reps.iter().filter_map(|p| p.emu[k].map(|m| errors(&m, &truth)[j])).collect();
                cells.push(format!("{:.1} % \\| {:.1} %", 100.0 * med(&mut r), 100.0 * med(&mut e)));
            }
            let raw_in = reps.iter().filter(|p| !off(&p.raw[k].moments, &truth, 0.05)).count();
            let emus: Vec<&Moments> = reps.iter().filter_map(|p| p.emu[k].as_ref()).collect();
            let emu_in = emus.iter().filter(|m| !off(m, &truth, 0.05)).count();
            println!("| {n} | {} | {raw_in}/{} | {emu_in}/{} |", cells.join(" | "), reps.len(), emus.len());
        }
        println!("\nConvergence calls over {} seeds (converged: seeds where the rule held by N = 800; false: of those, the converged space is off the truth by more than τ on some statistic's scale):\n", reps.len());
        println!("| rule | τ | converged | false | false rate | median N at the call |");
        println!("| --- | ---: | ---: | ---: | ---: | ---: |");
        for tol in [0.05, 0.10, 0.20] {
            for (label, c) in [
                ("scaled, hold 2 (default)", crit(Rule::Scaled, tol, 2)),
                ("scaled, hold 1", crit(Rule::Scaled, tol, 1)),
                ("any (thesis)", crit(Rule::Any, tol, 1)),
                ("all, floor 0.01, hold 2 (old default)", crit(Rule::All, tol, 2)),
            ] {
                let mut calls = Vec::new();
                let mut wrong = 0;
                for p in &reps {
                    let j = judge(&p.raw, &c);
                    if let Some(k) = j.iter().position(|j| j.converged) {
                        calls.push(NS[k]);
                        if off(&p.raw[k].moments, &truth, tol) {
                            wrong += 1;
                        }
                    }
                }
                calls.sort_unstable();
                let rate = if calls.is_empty() {
                    "–".to_string()
                } else {
                    format!("{:.0} %", 100.0 * wrong as f64 / calls.len() as f64)
                };
                let med = calls.get(calls.len() / 2).map_or("–".into(), |n| n.to_string());
                println!("| {label} | {tol} | {}/{} | {wrong} | {rate} | {med} |", calls.len(), reps.len());
            }
        }
    }
}
