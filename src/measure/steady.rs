//! MFR in a steady state (a layout that holds a heap in front of the blade: the conveyor): the block series of a run, where it became steady,
//! and the steady deposit rate with its standard error.
//!
//! The deck prints one line per block of substrate travel (`demsweep: block ...`): the mass
//! that reached the delete region, the mass on the strip between the blade's rear face and it,
//! and the heap. The deposit of block k — the mass that crossed the rear face — is the deleted
//! mass plus the strip's change; block k's MFR is that over a full flow through the gap for the
//! block's travel, ρ · w · h · v · Δt.
//!
//! - Transient: the warm-up blocks (a stated least transient, the deck's), then MSER
//!   truncation (White 1997) of the rest: the first d blocks are dropped where
//!   var(y_d..n) / (n − d) is least, d ≤ n/2. A series whose best d is its half is still
//!   developing.
//! - MFR: the mean over the steady window; its SE from batch means over every block after the
//!   warm-up, scaled to the window's length: [`settled_se`]. Not the window's own spread: MSER
//!   picks the truncation that makes that spread least, so an SE from it comes out low (two
//!   runs of a point with other seeds differed by 1.18 of their combined SE, RMS, over 89
//!   points; 0.96 with this SE). Blocks are batched in twos until the lag-1 autocorrelation of
//!   the batch means is at most [`MAX_BATCH_ACF`], zero (measured: 5 D blocks of millimetre
//!   spheres give −0.17 to −0.08 at 0.1–1.4 m/s, so batches of one block; a real powder's at
//!   0.063 m/s +0.12 to +0.16, so longer batches); the ACF is reported with the SE. The SE is widened
//!   by Student's t for the batches' degrees of freedom ([`t_allowance`]), and the deck stops on
//!   that widened SE: an SE from 8–12 blocks is often read low, and the run stops when it first
//!   dips under its target.
//! - Steady: no trend over the window ([`window_trend`]: the least-squares slope of the
//!   window's batch means, batched by the SE's rule on what the fitted line leaves, within
//!   Student's quantile at [`TREND_FALSE_ALARM`]), the heap at the window's end within [`HEAP_TOLERANCE`] of its start,
//!   and the MSER truncation short of the series' half.
//! - v_x: the profile of each block's snapshot of the 6 D in front of the blade (thesis
//!   Appendix A), in the lab frame (+v), averaged over the steady window, with the SE of each
//!   layer over the snapshots.

use crate::measure::frame::Frame;
use crate::measure::metrics::vx_profile;
use crate::outcome::steady::SteadyState;
use crate::outcome::VX_LAYERS;
use crate::scene::blade::{Blade, Window};
use crate::scene::Scene;
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Largest lag-1 autocorrelation of the batch means accepted as independent: none. Blocks of a
/// cohesive real powder at slow blades wander over a good part of a heap turnover while their
/// lag-1 autocorrelation is only 0.12–0.16 (docs/study/warmup-um.md "The slow wander at
/// 0.063 m/s"); at the 0.2 this bound was, their SE read 1/1.3 of the scatter between seeds.
/// On independent blocks a positive lag-1 estimate is chance, half the time, and the batches it
/// doubles still give an unbiased SE (its fewer degrees of freedom widened by t).
pub const MAX_BATCH_ACF: f64 = 0.0;
/// Two-sided chance with which the trend test calls a steady window unsteady: that of |z| > 3
/// on independent normal blocks.
pub const TREND_FALSE_ALARM: f64 = 0.0027;
/// Largest relative change of the heap's count from the window's start to its end.
pub const HEAP_TOLERANCE: f64 = 0.1;

/// One block as the deck printed it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Block {
    pub step: u64,
    /// Mass in the delete region at the block's end (deleted then), kg.
    pub gone: f64,
    /// Mass on the strip behind the blade at the block's end, kg.
    pub strip: f64,
    pub heap: u64,
    /// Mass of the heap at the block's end, kg (0 in a log that does not print it).
    pub heap_mass: f64,
}

/// The steady-state answers of a conveyor run.
#[derive(Debug, Clone, PartialEq)]
pub struct Steady {
    pub mfr: f64,
    pub mfr_se: f64,
    /// Deleted mass alone over the window (without the strip's change): a second count of the
    /// same flux, lagging it by the strip's transit.
    pub mfr_deleted: f64,
    pub particles: usize,
    pub state: SteadyState,
    pub vx: Vec<Option<f64>>,
    pub vx_se: Vec<Option<f64>>,
    /// Why the flow is not steady (None: steady).
    pub unsteady: Option<String>,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SteadyError {
    #[error("the log has {0} block lines (demsweep: block ...); at least 4 are needed")]
    TooFewBlocks(usize),
    #[error("unreadable block line: {0}")]
    Unreadable(String),
    #[error("the log says neither `demsweep: stop target` nor `demsweep: stop cap`")]
    NoStop,
}

/// A run's whole block series (every part's, for an extended run) and how it stopped: at least
/// 4 blocks, and a stop the log said.
pub fn series(blocks: Vec<Block>, stop: Option<String>) -> Result<(Vec<Block>, String), SteadyError> {
    let stop = stop.ok_or(SteadyError::NoStop)?;
    if blocks.len() < 4 {
        return Err(SteadyError::TooFewBlocks(blocks.len()));
    }
    Ok((blocks, stop))
}

/// The block lines of a conveyor log, however few (a part of an extended run may add one), and
/// how the run stopped, if the log says.
pub fn parse_blocks(log: &str) -> Result<(Vec<Block>, Option<String>), SteadyError> {
    let mut blocks = Vec::new();
    let mut stop = None;
    for line in log.lines().map(str::trim) {
        if let Some(rest) = line.strip_prefix("demsweep: block ") {
            let w: Vec<&str> = rest.split_whitespace().collect();
            let field = |key: &str| w.iter().position(|t| *t == key).and_then(|i| w.get(i + 1));
            let num = |key: &str| field(key).and_then(|v| v.parse::<f64>().ok());
            match (num("step"), num("gone"), num("strip"), num("heap")) {
                (Some(step), Some(gone), Some(strip), Some(heap)) => {
                    let heap_mass = num("heapmass").unwrap_or(0.0);
                    blocks.push(Block { step: step as u64, gone, strip, heap: heap as u64, heap_mass })
                }
                _ => return Err(SteadyError::Unreadable(line.to_string())),
            }
        } else if line.starts_with("demsweep: stop target") {
            stop = Some("target");
        } else if line.starts_with("demsweep: stop cap") {
            stop = Some("cap");
        }
    }
    Ok((blocks, stop.map(String::from)))
}

/// Each block's MFR: the mass it deposited (what reached the delete region, plus the strip's
/// change) over a full flow's mass through the gap in one block, `ideal`.
pub fn block_mfr(blocks: &[Block], ideal: f64) -> Vec<f64> {
    let mut before = 0.0;
    blocks
        .iter()
        .map(|b| {
            let m = (b.gone + b.strip - before) / ideal;
            before = b.strip;
            // A block that deposited nothing is exactly zero, not rounding residue of the
            // subtraction, so MSER's ties break as the deck's do.
            if m.abs() < 1e-9 {
                0.0
            } else {
                m
            }
        })
        .collect()
}

/// MSER truncation: the d ≤ n/2 that minimises var(y[d..]) / (n − d).
pub fn mser(y: &[f64]) -> usize {
    let n = y.len();
    (0..=n / 2)
        .map(|d| {
            let t = &y[d..];
            let k = t.len() as f64;
            let m = mean(t);
            (d, t.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (k * k))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(d, _)| d)
        .unwrap_or(0)
}

fn mean(y: &[f64]) -> f64 {
    y.iter().sum::<f64>() / y.len() as f64
}

/// Lag-1 autocorrelation (0 for a constant or too short series).
pub fn acf1(y: &[f64]) -> f64 {
    if y.len() < 3 {
        return 0.0;
    }
    let m = mean(y);
    let var: f64 = y.iter().map(|v| (v - m).powi(2)).sum();
    if var == 0.0 {
        return 0.0;
    }
    y.windows(2).map(|p| (p[0] - m) * (p[1] - m)).sum::<f64>() / var
}

/// Blocks per batch for batch means of `y`, doubled while the lag-1 autocorrelation of the
/// batch means is above [`MAX_BATCH_ACF`] and at least 8 batches remain; with that
/// autocorrelation.
fn batch_size(y: &[f64]) -> (usize, f64) {
    let mut b = 1;
    loop {
        let means: Vec<f64> = y.chunks_exact(b).map(mean).collect();
        let r = acf1(&means);
        if r <= MAX_BATCH_ACF || y.len() / (2 * b) < 8 {
            return (b, r);
        }
        b *= 2;
    }
}

/// Standard error of the mean by batch means: (SE, blocks per batch, lag-1 ACF of the batches).
pub fn batch_means_se(y: &[f64]) -> (f64, usize, f64) {
    let (b, r) = batch_size(y);
    let means: Vec<f64> = y.chunks_exact(b).map(mean).collect();
    let n = means.len() as f64;
    let m = mean(&means);
    let var = means.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    ((var / n).sqrt(), b, r)
}

/// Coefficients of Student's t₀.₉₇₅(ν) over 1.96 in powers of 1/ν (the Cornish–Fisher expansion
/// of the t quantile about the normal one, three terms): within 0.3 % of the exact ratio from 4
/// degrees of freedom on. The conveyor deck's stop rule writes the same three numbers.
pub const T_ALLOWANCE: [f64; 3] = [1.210_37, 1.440_10, 1.304_1];

/// How much wider Student's 95 % interval is than the normal one for an SE estimated with `dof`
/// degrees of freedom: t₀.₉₇₅(dof) / 1.96 by [`T_ALLOWANCE`] (1 for an SE known exactly).
pub fn t_allowance(dof: f64) -> f64 {
    let u = 1.0 / dof.max(1.0);
    1.0 + u * (T_ALLOWANCE[0] + u * (T_ALLOWANCE[1] + u * T_ALLOWANCE[2]))
}

/// The SE of the mean of the last `window` blocks of `settled` (every block after the warm-up):
/// batch means over all of `settled`, as if its spread were the window's. A transient that MSER
/// cut widens the spread, so this errs on the safe side; on a steady series it does not carry
/// MSER's choice of the least spread. Returns (SE, blocks per batch, lag-1 ACF of the batches).
pub fn settled_se(settled: &[f64], window: usize) -> (f64, usize, f64) {
    let (se, b, r) = batch_means_se(settled);
    let batches = (settled.len() / b) as f64;
    (se * (settled.len() as f64 / window.max(1) as f64).sqrt() * t_allowance(batches - 1.0), b, r)
}

/// How many times too short an SE is when computed as if `n` values were independent while
/// they follow an AR(1) process of lag-1 autocorrelation `rho`: the SE of their mean, or with
/// `slope` of their least-squares slope against the index (as [`trend_z`] computes it). Exact in
/// expectation: the estimator's variance over what the naive SE² reads from the residuals, which
/// a positive correlation shrinks too. 1 at `rho` = 0; √((1 + ρ)/(1 − ρ)) for a long series.
pub fn ar1_se_factor(n: usize, rho: f64, slope: bool) -> f64 {
    let fitted = if slope { 2 } else { 1 };
    if n <= fitted || rho == 0.0 {
        return 1.0;
    }
    let xm = (n - 1) as f64 / 2.0;
    let t: Vec<f64> = (0..n).map(|i| i as f64 - xm).collect();
    let sxx: f64 = t.iter().map(|v| v * v).sum();
    let w: Vec<f64> = if slope { t.iter().map(|v| v / sxx).collect() } else { vec![1.0 / n as f64; n] };
    // Quadratic forms in the correlation matrix ρ^|i−j|.
    let form = |a: &[f64], b: &[f64]| -> f64 {
        let row = |i: usize, ai: f64| -> f64 {
            b.iter().enumerate().map(|(j, bj)| ai * bj * rho.powi((i as i32 - j as i32).abs())).sum()
        };
        a.iter().enumerate().map(|(i, &ai)| row(i, ai)).sum()
    };
    let ones = vec![1.0; n];
    // The trace of the hat matrix times the correlation: what the fit takes out of the residuals.
    let taken = form(&ones, &ones) / n as f64 + if slope { form(&t, &t) / sxx } else { 0.0 };
    let naive = (n as f64 - taken) / (n - fitted) as f64 * w.iter().map(|v| v * v).sum::<f64>();
    (form(&w, &w) / naive).sqrt()
}

/// The least-squares line of `y` against its index: its slope, Σ(i − ī)², and what it leaves.
fn ols_line(y: &[f64]) -> (f64, f64, Vec<f64>) {
    let (xm, ym) = ((y.len() as f64 - 1.0) / 2.0, mean(y));
    let sxx: f64 = (0..y.len()).map(|i| (i as f64 - xm).powi(2)).sum();
    let slope = y.iter().enumerate().map(|(i, v)| (i as f64 - xm) * (v - ym)).sum::<f64>()
        / sxx.max(f64::MIN_POSITIVE);
    let residuals = y.iter().enumerate().map(|(i, v)| v - ym - slope * (i as f64 - xm)).collect();
    (slope, sxx, residuals)
}

/// OLS slope of y against its index, over its SE (0 when the residuals vanish).
pub fn trend_z(y: &[f64]) -> f64 {
    let n = y.len() as f64;
    if n < 3.0 {
        return 0.0;
    }
    let (slope, sxx, residuals) = ols_line(y);
    let rss: f64 = residuals.iter().map(|r| r * r).sum();
    let se = (rss / (n - 2.0) / sxx).sqrt();
    if se > 0.0 {
        slope / se
    } else {
        0.0
    }
}

/// The two-sided Student quantile: |t| with `dof` degrees of freedom exceeds it with chance
/// `level`. Infinite with no degrees of freedom.
pub fn student_quantile(dof: f64, level: f64) -> f64 {
    match StudentsT::new(0.0, 1.0, dof) {
        Ok(t) if dof >= 1.0 => t.inverse_cdf(1.0 - level / 2.0),
        _ => f64::INFINITY,
    }
}

/// The trend of the window `w`, judged on the units that are independent of one another: the
/// least-squares slope of the means of b-block batches (the earliest blocks that fill no batch
/// left out) over its SE, and the limit that |slope / SE| must stay within, Student's quantile
/// for batches − 2 degrees of freedom at [`TREND_FALSE_ALARM`]. b is chosen as the SE's batches
/// are, but on what the fitted line leaves: a trend makes neighbouring blocks alike and would
/// otherwise batch itself away. Why batches: a real powder's blocks wander over a good part of
/// a heap turnover (docs/study/warmup-um.md "The slow wander at 0.063 m/s"); over a long window
/// that wander reads as a trend of 3 single-block SEs and more on a steady flow, which the batch
/// means, whose scatter holds it, do not.
pub fn window_trend(w: &[f64]) -> (f64, f64) {
    let (b, _) = batch_size(&ols_line(w).2);
    let means: Vec<f64> = w[w.len() % b..].chunks_exact(b).map(mean).collect();
    (trend_z(&means), student_quantile(means.len() as f64 - 2.0, TREND_FALSE_ALARM))
}

/// What the steady-state rule reads of a held heap's run, beside the common scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldBlocks {
    /// Mass of a full flow through the gap over one block, kg.
    pub ideal_block_mass: f64,
    /// Blocks of the deck's warm-up: the least transient.
    pub warmup_blocks: u64,
    pub block_steps: u64,
    /// The count the heap is topped up to.
    pub heap_particles: usize,
}

/// The steady-state answers of a run that holds a heap (`c`) in front of `blade`, from its log's
/// blocks and its v_x snapshots (in the layers of `vx_layers`).
pub fn compute(
    scene: &Scene,
    (blade, vx_layers): (&Blade, &Window),
    c: &HeldBlocks,
    blocks: &[Block],
    stop: &str,
    frames: &[Frame],
) -> Steady {
    let ideal = c.ideal_block_mass;
    let y = block_mfr(blocks, ideal);
    // The warm-up is the least transient (the deck's stop rule starts after it); MSER may
    // extend it.
    let d0 = (c.warmup_blocks as usize).min(y.len().saturating_sub(4));
    let d = d0 + mser(&y[d0..]);
    let w = &y[d..];
    let mfr = mean(w);
    let (mfr_se, batch_blocks, batch_acf1) = settled_se(&y[d0..], w.len());
    let (trend_z, trend_limit) = window_trend(w);
    let q = (w.len() / 4).max(1);
    let drift = if mfr > 0.0 { (mean(&w[w.len() - q..]) - mean(&w[..q])) / mfr } else { 0.0 };
    let window = &blocks[d..];
    let gone: f64 = window.iter().map(|b| b.gone).sum();
    let particle_mass = scene.material.density * std::f64::consts::PI / 6.0 * scene.diameter.powi(3);
    // The heap at the window's start is the count at the end of the last dropped block.
    let heap_start = if d > 0 { blocks[d - 1].heap } else { blocks[0].heap };
    let heap_end = blocks.last().map(|b| b.heap).unwrap_or(0);
    let state = SteadyState {
        block_mfr: y.clone(),
        transient_blocks: d,
        window_blocks: w.len(),
        block_diameters: blade.blade_speed * scene.timestep * c.block_steps as f64 / scene.diameter,
        batch_blocks,
        batch_acf1,
        block_acf1: acf1(w),
        trend_z,
        trend_limit,
        drift,
        heap_start,
        heap_end,
        heap_target: c.heap_particles as u64,
        // kg per m of blade width is g per mm.
        heap_mass_per_width: window.iter().map(|b| b.heap_mass).sum::<f64>()
            / window.len() as f64
            / scene.depth,
        stop: stop.into(),
    };
    let mut why = Vec::new();
    if d - d0 >= (y.len() - d0) / 2 && y.len() - d0 >= 8 {
        why.push(format!(
            "still developing: MSER drops {} of the {} blocks after the warm-up (half of them)",
            d - d0,
            y.len() - d0
        ));
    }
    // A flow that stopped: nothing deposited over the kept window after deposits past the
    // warm-up. A jam under the blade is not a steady MFR of zero.
    if mfr == 0.0 {
        if let Some(last) = (d0..d).rev().find(|&k| y[k] > 0.0) {
            why.push(format!(
                "the flow stopped after block {} of {}: nothing passed under the blade since (a jam)",
                last + 1,
                y.len()
            ));
        }
    }
    if trend_z.abs() > trend_limit {
        why.push(format!("a trend over the window of {trend_z:.1} SE (limit {trend_limit:.1})"));
    }
    let heap_change = (heap_end as f64 - heap_start as f64).abs() / heap_start.max(1) as f64;
    if heap_change > HEAP_TOLERANCE {
        why.push(format!(
            "the heap changed from {heap_start} to {heap_end} particles (limit {:.0} %)",
            100.0 * HEAP_TOLERANCE
        ));
    }
    if (heap_start as f64) < (1.0 - HEAP_TOLERANCE) * c.heap_particles as f64 {
        why.push(format!("the heap holds {heap_start} of its {} particles", c.heap_particles));
    }
    // v_x over the steady window: each block's snapshot (taken at the block's end).
    let first_step = window.first().map(|b| b.step).unwrap_or(0);
    let profiles: Vec<Vec<Option<f64>>> = frames
        .iter()
        .filter(|f| f.step >= first_step)
        .map(|f| vx_profile(scene, blade, vx_layers, std::iter::once(f)))
        .collect();
    let (mut vx, mut vx_se) = (Vec::with_capacity(VX_LAYERS), Vec::with_capacity(VX_LAYERS));
    for k in 0..VX_LAYERS {
        // Lab frame: the blade moves at +v over a resting substrate.
        let vals: Vec<f64> = profiles.iter().filter_map(|p| p[k]).map(|v| v + blade.blade_speed).collect();
        if vals.is_empty() {
            vx.push(None);
            vx_se.push(None);
            continue;
        }
        let m = mean(&vals);
        vx.push(Some(m));
        let n = vals.len() as f64;
        vx_se.push(
            (n > 1.0).then(|| (vals.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt()),
        );
    }
    Steady {
        mfr,
        mfr_se,
        mfr_deleted: gone / (ideal * w.len() as f64),
        particles: (mfr * ideal * w.len() as f64 / particle_mass).round() as usize,
        state,
        vx,
        vx_se,
        unsteady: (!why.is_empty()).then(|| why.join("; ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ar1_factor_of_a_mean_is_the_closed_form_and_of_a_slope_what_noise_shows() {
        // The mean: Var(ȳ) = σ²g/n with g = 1 + 2 Σ (1 − k/n) ρ^k, E[s²] = σ²(n − g)/(n − 1).
        for (n, rho) in [(4, 0.3), (8, 0.65), (30, -0.4)] {
            let g = 1.0
                + 2.0 * (1..n).map(|k| (1.0 - k as f64 / n as f64) * f64::powi(rho, k as i32)).sum::<f64>();
            let want = (g * (n - 1) as f64 / (n as f64 - g)).sqrt();
            assert!((ar1_se_factor(n, rho, false) - want).abs() < 1e-12, "{n} {rho}");
        }
        // Long series: the familiar √((1 + ρ)/(1 − ρ)), for the mean and the slope alike.
        let long = f64::sqrt((1.0 + 0.5) / (1.0 - 0.5));
        assert!((ar1_se_factor(2000, 0.5, false) / long - 1.0).abs() < 0.01);
        assert!((ar1_se_factor(2000, 0.5, true) / long - 1.0).abs() < 0.01);
        assert_eq!(ar1_se_factor(8, 0.0, true), 1.0);
        // The slope over eight values of AR(1) noise: the RMS of the slope over its naive SE
        // (what trend_z returns) against E[slope²]/E[naive SE²] (the factor); RMS of t with
        // 6 dof is √(6/4) on independent noise, scaled by the factor here.
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (n, rho, trials) = (8, 0.65_f64, 40_000);
        let (mut slope2, mut se2) = (0.0, 0.0);
        for _ in 0..trials {
            let e: f64 = StandardNormal.sample(&mut rng);
            let mut x = e / (1.0 - rho * rho).sqrt();
            let y: Vec<f64> = (0..n)
                .map(|_| {
                    x = rho * x + {
                        let e: f64 = StandardNormal.sample(&mut rng);
                        e
                    };
                    x
                })
                .collect();
            let z = trend_z(&y);
            let xm = (n - 1) as f64 / 2.0;
            let sxx: f64 = (0..n).map(|i| (i as f64 - xm).powi(2)).sum();
            let slope = y.iter().enumerate().map(|(i, v)| (i as f64 - xm) * v).sum::<f64>() / sxx;
            slope2 += slope * slope;
            se2 += (slope / z).powi(2);
        }
        let seen = (slope2 / se2).sqrt();
        let f = ar1_se_factor(n, rho, true);
        assert!((seen / f - 1.0).abs() < 0.03, "seen {seen}, factor {f}");
        assert!(f > 1.8, "{f}: a correlated wander reads as a slope of more SEs than noise");
    }

    #[test]
    fn mser_drops_a_ramp_and_keeps_a_flat_series() {
        let flat: Vec<f64> = (0..20).map(|i| 1.0 + if i % 2 == 0 { 0.1 } else { -0.1 }).collect();
        assert_eq!(mser(&flat), 0);
        let mut ramp: Vec<f64> = (0..6).map(|i| i as f64 * 0.15).collect();
        ramp.extend(&flat);
        let d = mser(&ramp);
        assert!((5..=7).contains(&d), "{d}");
    }

    #[test]
    fn batch_means_of_alternating_blocks_stay_single_and_of_runs_double() {
        // Independent-looking (anti-correlated) blocks: one block per batch, SE = s/√n.
        let y: Vec<f64> = (0..32).map(|i| if i % 2 == 0 { 1.0 } else { 0.0 }).collect();
        let (se, b, _) = batch_means_se(&y);
        assert_eq!(b, 1);
        let s = (32.0 * 0.25 / 31.0f64).sqrt();
        assert!((se - s / 32f64.sqrt()).abs() < 1e-12, "{se}");
        // Runs of eight equal values are strongly correlated (lag-1 ACF of the blocks ≈ 0.75):
        // batches grow until their means' lag-1 ACF is small (at four blocks a batch, runs of
        // two: ACF ≈ 0). Runs of four would stop at two (period-4 means have lag-1 ACF ≈ 0).
        let y: Vec<f64> = (0..128).map(|i| ((i / 8) % 2) as f64).collect();
        let (_, b, r) = batch_means_se(&y);
        assert!(b >= 4 && r <= MAX_BATCH_ACF, "b={b} r={r}");
    }

    #[test]
    fn blocks_that_wander_slowly_under_their_noise_are_batched() {
        // White noise (xorshift) plus a slow wave of a tenth of its variance: the blocks' lag-1
        // autocorrelation is small and positive, as a real powder's at a slow blade, and the
        // wave makes the mean of one window scatter more than s/√n says.
        let mut x: u64 = 0x2545_f491_4f6c_dd1d;
        let y: Vec<f64> = (0..256)
            .map(|i| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let noise = (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                noise + 0.13 * (std::f64::consts::TAU * i as f64 / 64.0).sin()
            })
            .collect();
        let r = acf1(&y);
        assert!(r > 0.0 && r < 0.2, "the blocks' lag-1 autocorrelation {r}");
        let (se, b, rb) = batch_means_se(&y);
        assert!(b > 1 && rb <= MAX_BATCH_ACF, "b={b} r={rb}");
        let single = (y.iter().map(|v| (v - mean(&y)).powi(2)).sum::<f64>() / 255.0 / 256.0).sqrt();
        assert!(se > single, "batched {se}, as if independent {single}");
    }

    #[test]
    fn the_se_comes_from_every_settled_block_not_from_the_window_mser_chose() {
        // A steady series whose first two blocks happen to lie farthest from its mean: MSER
        // drops them, and the window's own spread is a fraction of the series'.
        let mut y = vec![1.6, 0.4];
        y.extend((0..14).map(|i| if i % 2 == 0 { 1.1 } else { 0.9 }));
        let d = mser(&y);
        assert_eq!(d, 2);
        let w = &y[d..];
        let (se, b, _) = settled_se(&y, w.len());
        assert_eq!(b, 1);
        let m = mean(&y);
        let sd = (y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / 15.0).sqrt();
        // Widened for the 15 degrees of freedom of its 16 batches.
        assert!((se - sd / 14f64.sqrt() * t_allowance(15.0)).abs() < 1e-12, "{se}");
        assert!(se > 2.0 * batch_means_se(w).0, "{se} {:?}", batch_means_se(w));
    }

    #[test]
    fn the_t_allowance_is_students_quantile_over_the_normal_one() {
        use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
        let z = Normal::new(0.0, 1.0).unwrap().inverse_cdf(0.975);
        for dof in [4.0, 5.0, 7.0, 10.0, 20.0, 50.0, 200.0, 1e4] {
            let exact = StudentsT::new(0.0, 1.0, dof).unwrap().inverse_cdf(0.975) / z;
            let a = t_allowance(dof);
            assert!((a / exact - 1.0).abs() < 0.003, "{dof}: {a} against {exact}");
        }
    }

    #[test]
    fn the_conveyor_deck_stops_on_the_se_its_result_reports() {
        let deck = include_str!("../../templates/conveyor.liggghts.tera");
        let [a, b, c] = T_ALLOWANCE;
        let widened = format!("variable se_t equal v_se*(1+v_tu*({a}+v_tu*({b}+v_tu*{c})))");
        assert!(deck.contains(&widened), "the deck's allowance is not {widened}");
        assert!(deck.contains("variable tu equal 1/(${k}-1)"));
    }

    #[test]
    fn trend_z_sees_a_slope_and_not_noise() {
        let noise: Vec<f64> = (0..24).map(|i| if i % 3 == 0 { 0.1 } else { -0.05 }).collect();
        assert!(trend_z(&noise).abs() < 1.0);
        let slope: Vec<f64> = noise.iter().enumerate().map(|(i, v)| v + 0.02 * i as f64).collect();
        assert!(trend_z(&slope) > 5.0);
    }

    /// One run's log as the conveyor's measure reads it.
    /// How often `trend` calls a window unsteady over `trials` windows of `n` blocks from `series`.
    fn alarm_rate(
        n: usize,
        trials: usize,
        mut series: impl FnMut(usize) -> Vec<f64>,
        trend: fn(&[f64]) -> bool,
    ) -> f64 {
        (0..trials).filter(|_| trend(&series(n))).count() as f64 / trials as f64
    }

    /// The rule's trend test: on batch means.
    fn batched(w: &[f64]) -> bool {
        let (z, limit) = window_trend(w);
        z.abs() > limit
    }

    /// The test it replaced: single blocks, |z| > 3.
    fn single(w: &[f64]) -> bool {
        trend_z(w).abs() > 3.0
    }

    #[test]
    fn a_steady_flow_that_wanders_is_not_called_a_trend_and_a_ramp_is() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut normal = move || -> f64 { StandardNormal.sample(&mut rng) };
        // Independent blocks: the false alarm is the stated one, at any length.
        for n in [20, 60, 400] {
            let rate = alarm_rate(n, 4000, |n| (0..n).map(|_| normal()).collect(), batched);
            assert!(rate < 0.01, "{n} independent blocks: {rate}");
        }
        // A real powder's blocks (docs/study/warmup-um.md): white noise plus a slow AR(1) wander
        // (0.99 a block, a time of 100 blocks) holding 15 % of a block's variance, which gives
        // the lag-1 autocorrelation of 0.12–0.16 the long runs had.
        let wander = |normal: &mut dyn FnMut() -> f64, n: usize| -> Vec<f64> {
            let phi: f64 = 0.99;
            let mut x = normal();
            (0..n)
                .map(|_| {
                    x = phi * x + (1.0 - phi * phi).sqrt() * normal();
                    normal() + 0.15_f64.sqrt() * x
                })
                .collect()
        };
        let old = alarm_rate(400, 2000, |n| wander(&mut normal, n), single);
        let new = alarm_rate(400, 2000, |n| wander(&mut normal, n), batched);
        assert!(old > 0.25, "single blocks called {old} of these steady windows unsteady");
        assert!(new < 0.5 * old && new < 0.2, "batched: {new}, single blocks: {old}");
        // A real drift, two blocks' SDs over a long window, is still found.
        let ramp = |normal: &mut dyn FnMut() -> f64, n: usize| -> Vec<f64> {
            (0..n).map(|i| normal() + 2.0 * (i as f64 / (n - 1) as f64 - 0.5)).collect()
        };
        let found = alarm_rate(400, 1000, |n| ramp(&mut normal, n), batched);
        assert!(found > 0.95, "a drift of 2 SD over 400 blocks found in {found}");
    }

    /// The blocks after the transient of a recorded LIGGGHTS run (its result or failure).
    fn recorded_window(path: &str) -> Vec<f64> {
        let path = format!("{}/docs/study/{path}", env!("CARGO_MANIFEST_DIR"));
        let record: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let state = &record["measured"]["steady_state"];
        let y: Vec<f64> =
            state["block_mfr"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        y[state["transient_blocks"].as_u64().unwrap() as usize..].to_vec()
    }

    #[test]
    fn of_two_long_liggghts_windows_refused_for_a_trend_the_wander_is_steady_and_the_relaxation_not() {
        // Ti-6Al-4V at 0.063 m/s, 400 blocks (seed 1 of docs/study/warmup-um.md "The slow
        // wander"): a trend of −3.2 single-block SEs, the wander of a steady flow.
        let wander = recorded_window("steady/seeds/ti64-v0.063-long/seed-1-failure.json");
        assert_eq!(wander.len(), 400);
        assert!(single(&wander), "{}", trend_z(&wander));
        assert!(!batched(&wander), "{:?}", window_trend(&wander));
        // 0.5 mm spheres at 1.4 m/s from rest with no warm-up (docs/study/recoater/README.md):
        // 266 blocks of a heap still relaxing, −5.3 single-block SEs; its residuals are not
        // correlated, so it keeps nearly every degree of freedom and stays unsteady.
        let relaxing = recorded_window("recoater/transient-long/D0.5-v1.4/failure.json");
        assert!(batched(&relaxing), "{:?}", window_trend(&relaxing));
    }

    fn parse_log(log: &str) -> Result<(Vec<Block>, String), SteadyError> {
        let (blocks, stop) = parse_blocks(log)?;
        series(blocks, stop)
    }

    #[test]
    fn the_log_gives_blocks_and_the_stop() {
        let log = "demsweep: settled at step 0\n\
                   demsweep: block 1 step 200 gone 0 strip 0.001 heap 900 heapmass 0.03\n\
                   demsweep: block 2 step 400 gone 0.0005 strip 0.0012 heap 901 heapmass 0.03\n\
                   demsweep: block 3 step 600 gone 0.0004 strip 0.0011 heap 899 heapmass 0.03\n\
                   demsweep: block 4 step 800 gone 0.0006 strip 0.0010 heap 900 heapmass 0.03\n\
                   demsweep: stop cap after 800 steps\n";
        let (b, stop) = parse_log(log).unwrap();
        assert_eq!(stop, "cap");
        assert_eq!(b[1], Block { step: 400, gone: 0.0005, strip: 0.0012, heap: 901, heap_mass: 0.03 });
        assert_eq!(parse_log("demsweep: stop target at step 3\n").unwrap_err(), SteadyError::TooFewBlocks(0));
        assert!(parse_log("demsweep: block 1 step x\n").is_err());
    }
}
