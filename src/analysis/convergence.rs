//! Convergence of the MFR statistics across nested spaces (thesis §3.3; docs/statistics.md "The convergence rules").
//!
//! A sweep's spaces (lattice levels, LDS prefixes) each have [`SpaceStats`]: the statistics and
//! the half-width of each one's 95 % bootstrap interval (its noise at that N). This module
//! compares each space with the one before and says whether, and where, the sweep converged:
//!
//! - `rule = "scaled"`, the default: *every* statistic passes two tests against the tolerance τ
//!   on that statistic's own scale ([`scale`]): it stopped moving, |s_k − s_{k−1}| ≤ τ·scale,
//!   and it is known, half-width of its bootstrap interval ≤ τ·scale; and this holds for `hold`
//!   consecutive comparisons. The scales: the mean against max(|mean|, std) (the MFR's own size
//!   or its spread, whichever is larger), the std against itself, the skewness (Pearson's, which
//!   lies in [−3, 3]) against max(|skewness|, 1), so a skewness near zero is judged by an
//!   absolute change of τ, and the kurtosis (always ≥ 1) against itself. No floor.
//! - `rule = "any"`, the thesis's rule (§3.3, after Eq. 21): the space converges when the
//!   relative change |s_k − s_{k−1}| / |s_{k−1}| of *any one* of mean, std, skewness and
//!   kurtosis is within the tolerance. Floor, noise and hold do not apply: the rule as published.
//! - `rule = "all"`: every statistic within the tolerance relatively, or moved by no more than
//!   `floor` in absolute terms, held for `hold` comparisons (the default before "scaled"; kept so
//!   that older sweep files mean what they meant).
//!
//! `statistics` names which of the four a rule judges (default all four): a sweep whose
//! question is the mean over its space (the demo) judges the mean alone, as the thesis's
//! 10,000-point lattice is what knows the skewness and kurtosis. A statistic not judged is still
//! computed and shown, and counts as within.
//!
//! Either way a space with fewer than `min_points` points is never the converged one (an
//! extended sweep is judged again only past its old extent). An undefined statistic (S = 0)
//! or a relative change from exactly zero is never "within".
//!
//! The run driver applies the rule while a sweep runs. Not responsible for computing the statistics
//! ([`crate::analysis::stats`], [`crate::analysis::weights`]) or for running the sweep
//! ([`crate::run`]).

use crate::analysis::stats::{Bootstrap, Interval, Moments, Statistic, STATISTICS};
use crate::analysis::weights::LatticeWeights;
use serde::{Deserialize, Serialize};

/// The sweep file's `[convergence]` section: which rule judges the statistics, and how strictly.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ConvergenceSettings {
    /// `"scaled"` (default: every statistic moved and known within the tolerance on its own
    /// scale, held for `hold` spaces), `"any"` (the thesis's rule: any one statistic within
    /// tolerance relatively; floor and hold do not apply) or `"all"` (every statistic within
    /// tolerance relatively or by the floor). See [`crate::analysis::convergence`].
    pub rule: String,
    /// Relative change of a statistic between consecutive spaces that counts as converged.
    pub tolerance: f64,
    /// Absolute change below which a statistic counts as converged whatever its relative change
    /// (rule "all" only).
    pub floor: f64,
    /// Consecutive spaces the rule must hold for.
    pub hold: usize,
    /// No space with fewer points counts as converged. `sweep lds --max M` on a converged
    /// directory sets it to the old extent, so that the extension is judged on its own.
    pub min_points: usize,
    /// `"trapezoid"` (default: a complete lattice's points weighted by the trapezoid rule) or
    /// `"equal"` (the thesis). See [`crate::analysis::weights`].
    pub lattice_weights: String,
    /// The statistics the rule judges, of `mean`, `std`, `skewness`, `kurtosis` (default all
    /// four; absent from a file that judges all four).
    #[serde(skip_serializing_if = "judges_all")]
    pub statistics: Vec<String>,
}

fn every_statistic() -> Vec<String> {
    STATISTICS.iter().map(|s| s.name().to_string()).collect()
}

fn judges_all(names: &[String]) -> bool {
    STATISTICS.iter().all(|s| names.iter().any(|n| n == s.name()))
}

/// `statistics` as the rule reads it: whether each of [`STATISTICS`] is judged; `None` for a
/// name that is none of the four, or for none at all.
pub fn judged_statistics(names: &[String]) -> Option<[bool; 4]> {
    if names.is_empty() || names.iter().any(|n| !STATISTICS.iter().any(|s| s.name() == n)) {
        return None;
    }
    Some(STATISTICS.map(|s| names.iter().any(|n| n == s.name())))
}

impl Default for ConvergenceSettings {
    fn default() -> Self {
        ConvergenceSettings {
            rule: "scaled".into(),
            tolerance: 0.05,
            floor: 0.01,
            hold: 2,
            min_points: 0,
            lattice_weights: "trapezoid".into(),
            statistics: every_statistic(),
        }
    }
}

/// Which statistics must be within tolerance, and how.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Rule {
    /// Any one, relatively (the thesis's rule).
    Any,
    /// All four, relatively or by the floor, held for `hold` comparisons.
    All,
    /// All four on their own scales, moved and known within τ, held for `hold` (the default).
    Scaled,
}

impl Rule {
    pub fn parse(s: &str) -> Option<Rule> {
        match s {
            "any" => Some(Rule::Any),
            "all" => Some(Rule::All),
            "scaled" => Some(Rule::Scaled),
            _ => None,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Rule::Any => "any",
            Rule::All => "all",
            Rule::Scaled => "scaled",
        }
    }
}

/// The settings a verdict is reached with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Criteria {
    pub rule: Rule,
    pub tolerance: f64,
    pub floor: f64,
    pub hold: usize,
    pub min_points: usize,
    /// How a complete lattice's points are weighted in its statistics.
    pub lattice_weights: LatticeWeights,
    /// Whether each of mean, std, skewness, kurtosis is judged (the others count as within).
    #[serde(skip_serializing_if = "all_true")]
    pub judged: [bool; 4],
}

fn all_true(j: &[bool; 4]) -> bool {
    j.iter().all(|&b| b)
}

impl Criteria {
    /// These criteria for a design that is a lattice or not: only a lattice's points are a
    /// quadrature's (a one-parameter LDS also has one point per distinct value, but its extremes
    /// are no faces of the box), so any other design weighs every point alike.
    pub fn for_design(mut self, lattice: bool) -> Criteria {
        if !lattice {
            self.lattice_weights = LatticeWeights::Equal;
        }
        self
    }

    /// From a validated sweep file's `[convergence]` (the sweep module checks the names).
    pub fn from_settings(c: &ConvergenceSettings) -> Criteria {
        Criteria {
            rule: Rule::parse(&c.rule).unwrap_or(Rule::Scaled),
            tolerance: c.tolerance,
            floor: c.floor,
            hold: c.hold.max(1),
            min_points: c.min_points,
            lattice_weights: LatticeWeights::parse(&c.lattice_weights).unwrap_or(LatticeWeights::Trapezoid),
            judged: judged_statistics(&c.statistics).unwrap_or([true; 4]),
        }
    }

    /// Whether statistic `s` is judged.
    pub fn judges(&self, s: Statistic) -> bool {
        STATISTICS.iter().zip(self.judged).any(|(&t, j)| t == s && j)
    }

    /// "every statistic", or "the mean", "the mean and std": what the rule's words name.
    fn which(&self) -> String {
        if all_true(&self.judged) {
            return "every statistic".into();
        }
        let names: Vec<&str> = STATISTICS.iter().filter(|&&s| self.judges(s)).map(|s| s.name()).collect();
        format!("the {}", names.join(" and "))
    }

    /// One line for the terminal and the report.
    pub fn describe(&self) -> String {
        let t = self.tolerance * 100.0;
        let which = self.which();
        let one = if all_true(&self.judged) {
            "any one statistic".to_string()
        } else {
            format!("any one of {which}")
        };
        match self.rule {
            Rule::Any => {
                format!("rule \"any\" (thesis): {one} within {t}% of the previous space")
            }
            Rule::All => format!(
                "rule \"all\": {which} within {t}% (or {} absolute) of the previous space, \
                 for {} consecutive space(s)",
                self.floor, self.hold
            ),
            Rule::Scaled => format!(
                "rule \"scaled\": {which} moved by at most {t}% of its scale since the previous \
                 space and the half-width of its 95% interval at most {t}% of its scale, for {} \
                 consecutive space(s)",
                self.hold
            ),
        }
    }
}

/// A space as the rules see it: its point count (done and failed: what min_points counts), the
/// statistics of its done runs, and each statistic's noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SpaceStats {
    pub n: usize,
    pub moments: Moments,
    /// Half-width of the 95 % interval of mean, std, skewness, kurtosis: the bootstrap's of a
    /// sample, the emulator's posterior of an adaptive design.
    pub noise: [Option<f64>; 4],
}

impl SpaceStats {
    /// The (weighted) statistics of `x` and their bootstrap noise; `n` points in the space.
    pub fn of(n: usize, x: &[f64], w: Option<&[f64]>, boot: &Bootstrap) -> SpaceStats {
        Self::with_intervals(n, x, w, boot).0
    }

    /// [`SpaceStats::of`] and the bootstrap intervals its noise is read from, for a caller that
    /// reports them too (one bootstrap, not two).
    pub fn with_intervals(
        n: usize,
        x: &[f64],
        w: Option<&[f64]>,
        boot: &Bootstrap,
    ) -> (SpaceStats, [Interval; 4]) {
        let moments = crate::analysis::weights::moments(x, w);
        let iv = crate::analysis::weights::bootstrap(x, w, boot);
        let noise = iv.map(|i| i.lo.zip(i.hi).map(|(lo, hi)| (hi - lo) / 2.0));
        (SpaceStats { n, moments, noise }, iv)
    }
}

/// The scale a statistic of `m` is judged on by rule "scaled" (see the module docs).
pub fn scale(s: Statistic, m: &Moments) -> Option<f64> {
    match s {
        Statistic::Mean => Some(m.mean?.abs().max(m.std?)),
        Statistic::Std => m.std,
        Statistic::Skewness => Some(m.skewness?.abs().max(1.0)),
        Statistic::Kurtosis => m.kurtosis,
    }
}

/// How one statistic moved from the previous space, and the test it passed or failed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Change {
    /// s_k − s_{k−1}; `None` when either is undefined.
    pub abs: Option<f64>,
    /// |s_k − s_{k−1}| / |s_{k−1}|; `None` when either is undefined or s_{k−1} = 0 ≠ s_k.
    pub rel: Option<f64>,
    /// The statistic's scale ([`scale`], of space k; rule "scaled" only).
    pub scale: Option<f64>,
    /// Half-width of the statistic's 95 % bootstrap interval at space k.
    pub noise: Option<f64>,
    /// Whether it counts as converged under the rule.
    pub within: bool,
    /// The test in words, with its numbers, e.g. "passed: |Δ| 0.0012 ≤ 0.0031 and ±0.0020 ≤
    /// 0.0031 (5% of scale 0.0612)".
    pub test: String,
}

/// One space's standing.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Judgement {
    /// Changes of mean, std, skewness, kurtosis from the previous space; `None` for the first.
    pub changes: Option<[Change; 4]>,
    /// The rule holds against the previous space.
    pub holds: bool,
    /// Consecutive comparisons, ending here, where the rule held.
    pub streak: usize,
    /// The sweep counts as converged at this space (at or past min_points, streak ≥ hold).
    pub converged: bool,
}

fn g(v: f64) -> String {
    format!("{v:.4}")
}

/// The change of statistic `s` from space `prev` to `cur`.
pub fn change(s: Statistic, prev: &SpaceStats, cur: &SpaceStats, c: &Criteria) -> Change {
    let idx = STATISTICS.iter().position(|&t| t == s).expect("one of the four");
    let noise = cur.noise[idx];
    if !c.judged[idx] {
        let (p, v) = (s.of(&prev.moments), s.of(&cur.moments));
        let abs = p.zip(v).map(|(p, v)| v - p);
        let rel = p.zip(abs).and_then(|(p, a)| (p != 0.0).then(|| a.abs() / p.abs()));
        let scale = scale(s, &cur.moments);
        let test = "not judged (convergence.statistics)".to_string();
        return Change { abs, rel, scale, noise, within: true, test };
    }
    let (Some(p), Some(v)) = (s.of(&prev.moments), s.of(&cur.moments)) else {
        let test = "failed: undefined (no spread in the space)".to_string();
        return Change { abs: None, rel: None, scale: None, noise, within: false, test };
    };
    let abs = v - p;
    let rel = if abs == 0.0 {
        Some(0.0)
    } else if p == 0.0 {
        None
    } else {
        Some(abs.abs() / p.abs())
    };
    let t = c.tolerance;
    let pct = t * 100.0;
    let by_rel = rel.is_some_and(|r| r <= t);
    let rel_words = rel.map_or("undefined (from 0)".into(), |r| format!("{:.1}%", r * 100.0));
    let verdict = |ok: bool| if ok { "passed" } else { "failed" };
    match c.rule {
        Rule::Any => {
            let test = format!("{}: relative change {rel_words} vs {pct}%", verdict(by_rel));
            Change { abs: Some(abs), rel, scale: None, noise, within: by_rel, test }
        }
        Rule::All => {
            let within = by_rel || abs.abs() <= c.floor;
            let test = format!(
                "{}: relative change {rel_words} vs {pct}%, or |Δ| {} vs floor {}",
                verdict(within),
                g(abs.abs()),
                c.floor
            );
            Change { abs: Some(abs), rel, scale: None, noise, within, test }
        }
        Rule::Scaled => {
            let sc = scale(s, &cur.moments).expect("defined where the statistic is");
            let limit = t * sc;
            let moved = abs.abs() <= limit;
            let known = noise.is_some_and(|h| h <= limit);
            let within = moved && known;
            let noise_words = noise.map_or("noise unknown".into(), |h| format!("±{}", g(h)));
            let what = match (moved, known) {
                (true, true) => "passed",
                (false, true) => "failed (moved)",
                (true, false) => "failed (noisy)",
                (false, false) => "failed (moved, noisy)",
            };
            let test = format!(
                "{what}: |Δ| {} {} {}, {noise_words} {} {} ({pct}% of scale {})",
                g(abs.abs()),
                if moved { "≤" } else { ">" },
                g(limit),
                if known { "≤" } else { ">" },
                g(limit),
                g(sc)
            );
            Change { abs: Some(abs), rel, scale: Some(sc), noise, within, test }
        }
    }
}

/// Judge every space of a sweep, in order.
pub fn judge(spaces: &[SpaceStats], c: &Criteria) -> Vec<Judgement> {
    let mut out: Vec<Judgement> = Vec::with_capacity(spaces.len());
    for (k, cur) in spaces.iter().enumerate() {
        let Some(prev) = k.checked_sub(1).map(|i| &spaces[i]) else {
            out.push(Judgement { changes: None, holds: false, streak: 0, converged: false });
            continue;
        };
        let changes = STATISTICS.map(|s| change(s, prev, cur, c));
        let holds = match c.rule {
            Rule::Any => changes.iter().zip(c.judged).any(|(ch, j)| j && ch.within),
            Rule::All | Rule::Scaled => changes.iter().all(|ch| ch.within),
        };
        let streak = if holds { out[k - 1].streak + 1 } else { 0 };
        let needed = match c.rule {
            Rule::Any => 1,
            Rule::All | Rule::Scaled => c.hold,
        };
        let converged = streak >= needed && cur.n >= c.min_points;
        out.push(Judgement { changes: Some(changes), holds, streak, converged });
    }
    out
}

/// The first converged space, if any.
pub fn converged_at(judged: &[Judgement]) -> Option<usize> {
    judged.iter().position(|j| j.converged)
}

/// Command-line overrides of a sweep file's `[convergence]` (`--rule`, `--tolerance`,
/// `--floor`, `--hold`).
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    pub rule: Option<String>,
    pub tolerance: Option<f64>,
    pub floor: Option<f64>,
    pub hold: Option<usize>,
}

/// A command-line override the sweep file would refuse: `--tolerance -1: expected ...`.
#[derive(Debug, thiserror::Error)]
#[error("{flag} {why}")]
pub struct OverrideError {
    pub flag: &'static str,
    pub why: String,
}

impl From<OverrideError> for crate::Error {
    fn from(e: OverrideError) -> Self {
        crate::Error::Input(Box::new(e))
    }
}

impl Overrides {
    /// Apply to `c`, refusing values the sweep file would refuse (naming the flag).
    pub fn apply(&self, c: &mut ConvergenceSettings) -> Result<(), OverrideError> {
        let bad = |flag: &'static str, why: String| OverrideError { flag, why };
        if let Some(r) = &self.rule {
            if Rule::parse(r).is_none() {
                return Err(bad("--rule", format!("{r}: expected \"scaled\", \"any\" or \"all\"")));
            }
            c.rule = r.clone();
        }
        for (flag, v, slot) in
            [("--tolerance", self.tolerance, &mut c.tolerance), ("--floor", self.floor, &mut c.floor)]
        {
            if let Some(v) = v {
                if !v.is_finite() || v < 0.0 {
                    return Err(bad(flag, format!("{v}: expected a finite number ≥ 0")));
                }
                *slot = v;
            }
        }
        if let Some(h) = self.hold {
            if h == 0 {
                return Err(bad("--hold", "0: expected at least 1".into()));
            }
            c.hold = h;
        }
        Ok(())
    }
}

/// The MFR values of a space's points that count (`None`: failed, left out) and their weights:
/// trapezoid weights when the points form a complete lattice and `lw` asks for them.
pub fn space_values(
    values: &[&[f64]],
    mfr: &[Option<f64>],
    lw: LatticeWeights,
) -> (Vec<f64>, Option<Vec<f64>>) {
    let all: Vec<Vec<f64>> = values.iter().map(|v| v.to_vec()).collect();
    let w = match lw {
        LatticeWeights::Trapezoid => crate::analysis::weights::trapezoid(&all),
        LatticeWeights::Equal => None,
    };
    let x: Vec<f64> = mfr.iter().flatten().copied().collect();
    let w = w.map(|w| w.iter().zip(mfr).filter(|(_, m)| m.is_some()).map(|(w, _)| *w).collect());
    (x, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Statistics given directly (the rules only read mean, std, skewness, kurtosis).
    fn m(mean: f64, std: f64, skew: f64, kurt: f64) -> Moments {
        Moments {
            n: 0,
            mean: Some(mean),
            std: Some(std),
            skewness: Some(skew),
            kurtosis: Some(kurt),
            moment_skewness: None,
            median: None,
        }
    }

    fn all(tol: f64, floor: f64, hold: usize) -> Criteria {
        Criteria {
            rule: Rule::All,
            tolerance: tol,
            floor,
            hold,
            min_points: 0,
            lattice_weights: LatticeWeights::Equal,
            judged: [true; 4],
        }
    }

    fn any(tol: f64) -> Criteria {
        Criteria {
            rule: Rule::Any,
            tolerance: tol,
            floor: 0.0,
            hold: 1,
            min_points: 0,
            lattice_weights: LatticeWeights::Equal,
            judged: [true; 4],
        }
    }

    fn scaled(tol: f64, hold: usize) -> Criteria {
        Criteria {
            rule: Rule::Scaled,
            tolerance: tol,
            floor: 0.0,
            hold,
            min_points: 0,
            lattice_weights: LatticeWeights::Equal,
            judged: [true; 4],
        }
    }

    /// Spaces of 400, 800, ... points with no bootstrap noise.
    fn spaces(ms: &[Moments]) -> Vec<SpaceStats> {
        ms.iter()
            .enumerate()
            .map(|(k, m)| SpaceStats { n: 400 * (k + 1), moments: *m, noise: [Some(0.0); 4] })
            .collect()
    }

    #[test]
    fn a_rule_that_judges_the_mean_alone_converges_while_the_skewness_still_moves() {
        // Mean 0.50 → 0.51 → 0.505: moved 2 % and 1 % of its scale 0.5 (≤ 5 %); the skewness
        // swings 0.1 → 0.9 → −0.5, beyond 5 % of its scale (1) every time.
        let mut s = spaces(&[m(0.50, 0.1, 0.1, 2.0), m(0.51, 0.1, 0.9, 2.0), m(0.505, 0.1, -0.5, 2.0)]);
        for sp in &mut s {
            sp.noise = [Some(0.01); 4];
        }
        let every = judge(&s, &scaled(0.05, 2));
        assert!(every.iter().all(|j| !j.converged), "the skewness moves: not converged");
        let names = vec!["mean".to_string()];
        let mean_only = Criteria { judged: judged_statistics(&names).unwrap(), ..scaled(0.05, 2) };
        let j = judge(&s, &mean_only);
        assert_eq!(j.iter().map(|j| j.converged).collect::<Vec<_>>(), [false, false, true]);
        let skew = &j[2].changes.as_ref().unwrap()[2];
        assert!(skew.within && skew.test.starts_with("not judged"), "{skew:?}");
        assert_eq!(skew.abs, Some(-1.4), "a statistic not judged is still measured");
        assert!(mean_only.describe().contains("the mean moved by at most 5%"), "{}", mean_only.describe());
        // A mean that moves fails it, whatever the others do.
        let moved = spaces(&[m(0.50, 0.1, 0.0, 2.0), m(0.60, 0.1, 0.0, 2.0), m(0.70, 0.1, 0.0, 2.0)]);
        assert!(judge(&moved, &mean_only).iter().all(|j| !j.converged));
        // Names other than the four, or none, are refused.
        assert_eq!(judged_statistics(&["median".to_string()]), None);
        assert_eq!(judged_statistics(&[]), None);
        assert_eq!(judged_statistics(&every_statistic()), Some([true; 4]));
    }

    #[test]
    fn a_settling_sequence_converges_where_the_hold_is_met() {
        // Relative changes, worked by hand (mean; std; skew; kurt):
        // 1→2: 0.25→0.20 = 20 %; 0.10→0.12 = 20 %; 0.5→0.6 = 20 %; 2.0→2.4 = 20 %   no
        // 2→3: 0.20→0.209 = 4.5 %;  0.12→0.118 = 1.7 %; 0.6→0.59 = 1.7 %; 2.4→2.45 = 2.1 % holds
        // 3→4: 0.209→0.212 = 1.4 %; 0.118→0.119 = 0.85 %; 0.59→0.6 = 1.7 %; 2.45→2.44 = 0.4 % holds
        let s = spaces(&[
            m(0.25, 0.10, 0.5, 2.0),
            m(0.20, 0.12, 0.6, 2.4),
            m(0.209, 0.118, 0.59, 2.45),
            m(0.212, 0.119, 0.6, 2.44),
        ]);
        let j = judge(&s, &all(0.05, 0.0, 2));
        assert_eq!(j.iter().map(|j| j.holds).collect::<Vec<_>>(), [false, false, true, true]);
        assert_eq!(j.iter().map(|j| j.streak).collect::<Vec<_>>(), [0, 0, 1, 2]);
        assert_eq!(converged_at(&j), Some(3));
        // Held once is enough with hold = 1.
        assert_eq!(converged_at(&judge(&s, &all(0.05, 0.0, 1))), Some(2));
        let ch = j[1].changes.clone().unwrap();
        assert!((ch[0].rel.unwrap() - 0.2).abs() < 1e-12 && (ch[0].abs.unwrap() + 0.05).abs() < 1e-12);
    }

    #[test]
    fn a_wandering_sequence_never_converges_under_either_rule() {
        // Every statistic moves by 10–30 % each time.
        let s = spaces(&[
            m(0.2, 0.1, 0.4, 2.0),
            m(0.25, 0.12, 0.5, 2.5),
            m(0.2, 0.1, 0.4, 2.0),
            m(0.26, 0.13, 0.3, 2.6),
        ]);
        assert_eq!(converged_at(&judge(&s, &all(0.05, 0.0, 1))), None);
        assert_eq!(converged_at(&judge(&s, &any(0.05))), None);
    }

    #[test]
    fn the_thesis_rule_accepts_one_quiet_statistic_while_the_mean_moves() {
        // Kurtosis changes 1 %, the mean 30 %: "any" calls it converged, "all" does not.
        let s = spaces(&[m(0.2, 0.1, 0.4, 3.0), m(0.26, 0.13, 0.5, 3.03)]);
        assert_eq!(converged_at(&judge(&s, &any(0.05))), Some(1));
        assert_eq!(converged_at(&judge(&s, &all(0.05, 0.01, 1))), None);
        let ch = judge(&s, &any(0.05))[1].changes.clone().unwrap();
        assert_eq!(ch.map(|c| c.within), [false, false, false, true]);
    }

    #[test]
    fn a_statistic_crossing_zero_is_judged_by_the_floor() {
        // Skewness 0.004 → −0.003: a relative change of 175 %, an absolute one of 0.007.
        let s = spaces(&[m(0.2, 0.1, 0.004, 2.0), m(0.201, 0.1005, -0.003, 2.01)]);
        let strict = judge(&s, &all(0.05, 0.0, 1));
        let skew = strict[1].changes.clone().unwrap()[2].clone();
        assert!((skew.rel.unwrap() - 1.75).abs() < 1e-12);
        assert!(!skew.within && converged_at(&strict).is_none(), "no floor: the zero crossing blocks");
        let floored = judge(&s, &all(0.05, 0.01, 1));
        assert!(floored[1].changes.clone().unwrap()[2].within);
        assert_eq!(converged_at(&floored), Some(1));
        // A large swing across zero stays blocked by the floor.
        let big = spaces(&[m(0.2, 0.1, 0.3, 2.0), m(0.2, 0.1, -0.3, 2.0)]);
        assert_eq!(converged_at(&judge(&big, &all(0.05, 0.01, 1))), None);
    }

    #[test]
    fn a_change_from_exactly_zero_has_no_relative_size() {
        let c = all(0.05, 0.0, 1);
        let one = |mean: f64| spaces(&[m(0.0, 0.1, 0.0, 2.0), m(mean, 0.1, 0.0, 2.0)]);
        let s = one(0.1);
        assert_eq!(change(Statistic::Mean, &s[0], &s[1], &c).rel, None);
        let s = one(0.0);
        assert_eq!(change(Statistic::Mean, &s[0], &s[1], &c).rel, Some(0.0));
        assert!(change(Statistic::Mean, &s[0], &s[1], &any(0.05)).within);
    }

    #[test]
    fn scaled_rule_judges_each_statistic_on_its_own_scale() {
        // MFR ≈ 0.06 with std 0.02: the mean's scale is max(0.06, 0.02) = 0.06, so 5 % is
        // 0.003; the std's is 0.02 (limit 0.001); the skewness 0.01 → −0.02 (a relative change
        // of 300 %) is judged on scale max(|−0.02|, 1) = 1 (limit 0.05); the kurtosis on 2.5
        // (limit 0.125).
        let s = spaces(&[m(0.0610, 0.0205, 0.01, 2.45), m(0.0600, 0.0200, -0.02, 2.5)]);
        let j = judge(&s, &scaled(0.05, 1));
        let ch = j[1].changes.clone().unwrap();
        assert_eq!(ch.each_ref().map(|c| c.within), [true, true, true, true]);
        assert!((ch[0].scale.unwrap() - 0.06).abs() < 1e-15);
        assert_eq!(ch[2].scale, Some(1.0));
        assert!(ch[2].rel.unwrap() > 2.9, "the thesis's relative change would read 300 %");
        assert!(ch[0].test.starts_with("passed: |Δ| 0.0010 ≤ 0.0030"), "{}", ch[0].test);
        // Rule `all`'s floor of 0.01 would let the std move by half itself; here 0.0020 → fails.
        let s = spaces(&[m(0.06, 0.0220, 0.0, 2.5), m(0.06, 0.0200, 0.0, 2.5)]);
        let ch = judge(&s, &scaled(0.05, 1))[1].changes.clone().unwrap();
        assert!(!ch[1].within && ch[1].test.starts_with("failed (moved)"), "{}", ch[1].test);
        assert!(judge(&s, &all(0.05, 0.01, 1))[1].holds, "rule `all` passes it by the floor");
    }

    #[test]
    fn scaled_rule_needs_the_statistic_known_not_only_still() {
        // Nothing moved, but the std's bootstrap half-width 0.003 exceeds 5 % of 0.02.
        let mut s = spaces(&[m(0.06, 0.02, 0.1, 2.5), m(0.06, 0.02, 0.1, 2.5)]);
        s[1].noise = [Some(0.001), Some(0.003), Some(0.01), Some(0.05)];
        let j = judge(&s, &scaled(0.05, 1));
        let ch = j[1].changes.clone().unwrap();
        assert_eq!(ch.each_ref().map(|c| c.within), [true, false, true, true]);
        assert!(
            ch[1].test.starts_with("failed (noisy): |Δ| 0.0000 ≤ 0.0010, ±0.0030 > 0.0010"),
            "{}",
            ch[1].test
        );
        assert_eq!(converged_at(&j), None);
        s[1].noise[1] = None;
        assert!(!judge(&s, &scaled(0.05, 1))[1].holds, "unknown noise never passes");
    }

    #[test]
    fn bootstrap_noise_of_a_real_sample_shrinks_as_root_n() {
        // Uniform values: the mean's half-width ≈ 1.96·0.2887/√N.
        let x: Vec<f64> = (0..1600).map(|i| ((i as f64) * 0.618_033_988_75).fract()).collect();
        let b = Bootstrap::default();
        let (a, c) = (SpaceStats::of(400, &x[..400], None, &b), SpaceStats::of(1600, &x, None, &b));
        let (ha, hc) = (a.noise[0].unwrap(), c.noise[0].unwrap());
        assert!((ha - 1.96 * 0.2887 / 20.0).abs() < 0.005, "{ha}");
        assert!((ha / hc - 2.0).abs() < 0.35, "{ha} {hc}");
    }

    #[test]
    fn an_undefined_statistic_never_counts_as_within() {
        let mut a = m(0.0, 0.0, 0.0, 0.0);
        a.skewness = None;
        a.kurtosis = None;
        let s = spaces(&[a, a, a]);
        // Mean and std are equal (0 → 0), skewness and kurtosis undefined.
        assert_eq!(converged_at(&judge(&s, &all(0.05, 0.01, 1))), None);
        // The thesis rule takes the unchanged mean.
        assert_eq!(converged_at(&judge(&s, &any(0.05))), Some(1));
    }

    #[test]
    fn min_points_delays_the_verdict_to_an_extension() {
        let q = m(0.2, 0.1, 0.4, 2.0);
        let s = spaces(&[q, q, q, q]);
        let mut c = all(0.05, 0.0, 1);
        assert_eq!(converged_at(&judge(&s, &c)), Some(1));
        assert_eq!(converged_at(&judge(&s, &scaled(0.05, 1))), Some(1));
        c.min_points = 1200;
        assert_eq!(converged_at(&judge(&s, &c)), Some(2), "space 2 holds 1,200 points");
    }
}
