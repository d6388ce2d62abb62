//! Convergence of the MFR statistics across nested spaces (thesis §3.3; README "Convergence and the report").
//!
//! A sweep's spaces (lattice levels, LDS prefixes) each have [`Moments`]; this module compares
//! each space with the one before and says whether, and where, the sweep converged:
//!
//! - `rule = "any"`, the thesis's rule (§3.3, after Eq. 21): the space converges when the
//!   relative change |s_k − s_{k−1}| / |s_{k−1}| of *any one* of mean, std, skewness and
//!   kurtosis is within the tolerance. Floor and hold do not apply: this is the rule as published.
//! - `rule = "all"`, the default: *every* statistic must be within the tolerance, or have moved
//!   by no more than `floor` in absolute terms (a statistic near zero, such as the skewness of a
//!   symmetric set, makes any relative change meaningless), and this must hold for `hold`
//!   consecutive comparisons.
//!
//! Either way a space with fewer than `min_points` points is never the converged one (an
//! extended sweep is judged again only past its old extent). An undefined statistic (S = 0)
//! or a relative change from exactly zero is never "within".
//!
//! [`Watch`] applies the rule while a sweep runs. Not responsible for computing the statistics
//! ([`crate::analysis::stats`]) or for running the sweep ([`crate::run`]).

use serde::Serialize;

use crate::analysis::stats::{Moments, STATISTICS};
use crate::sweep::ConvergenceSettings;

/// Which statistics must be within tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Rule {
    /// Any one (the thesis's rule).
    Any,
    /// All four, with the floor, held for `hold` comparisons (the default).
    All,
}

impl Rule {
    pub fn parse(s: &str) -> Option<Rule> {
        match s {
            "any" => Some(Rule::Any),
            "all" => Some(Rule::All),
            _ => None,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Rule::Any => "any",
            Rule::All => "all",
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
}

impl Criteria {
    /// From a validated sweep file's `[convergence]` (the sweep module checks the rule's name).
    pub fn from_settings(c: &ConvergenceSettings) -> Criteria {
        Criteria {
            rule: Rule::parse(&c.rule).unwrap_or(Rule::All),
            tolerance: c.tolerance,
            floor: c.floor,
            hold: c.hold.max(1),
            min_points: c.min_points,
        }
    }

    /// One line for the terminal and the report.
    pub fn describe(&self) -> String {
        match self.rule {
            Rule::Any => format!(
                "rule \"any\" (thesis): any one statistic within {}% of the previous space",
                self.tolerance * 100.0
            ),
            Rule::All => format!(
                "rule \"all\": every statistic within {}% (or {} absolute) of the previous space, \
                 for {} consecutive space(s)",
                self.tolerance * 100.0,
                self.floor,
                self.hold
            ),
        }
    }
}

/// How one statistic moved from the previous space.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Change {
    /// s_k − s_{k−1}; `None` when either is undefined.
    pub abs: Option<f64>,
    /// |s_k − s_{k−1}| / |s_{k−1}|; `None` when either is undefined or s_{k−1} = 0 ≠ s_k.
    pub rel: Option<f64>,
    /// Whether it counts as converged under the rule.
    pub within: bool,
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

/// The change of one statistic between two spaces.
pub fn change(prev: Option<f64>, cur: Option<f64>, rule: Rule, c: &Criteria) -> Change {
    let (Some(p), Some(s)) = (prev, cur) else {
        return Change { abs: None, rel: None, within: false };
    };
    let abs = s - p;
    let rel = if abs == 0.0 {
        Some(0.0)
    } else if p == 0.0 {
        None
    } else {
        Some(abs.abs() / p.abs())
    };
    let by_rel = rel.is_some_and(|r| r <= c.tolerance);
    let within = match rule {
        Rule::Any => by_rel,
        Rule::All => by_rel || abs.abs() <= c.floor,
    };
    Change { abs: Some(abs), rel, within }
}

/// Judge every space of a sweep, in order; `spaces` holds each space's point count (done and
/// failed: what min_points counts) and the statistics of its done runs.
pub fn judge(spaces: &[(usize, Moments)], c: &Criteria) -> Vec<Judgement> {
    let mut out: Vec<Judgement> = Vec::with_capacity(spaces.len());
    for (k, (n, m)) in spaces.iter().enumerate() {
        let Some((_, prev)) = k.checked_sub(1).map(|i| &spaces[i]) else {
            out.push(Judgement { changes: None, holds: false, streak: 0, converged: false });
            continue;
        };
        let changes = STATISTICS.map(|s| change(s.of(prev), s.of(m), c.rule, c));
        let holds = match c.rule {
            Rule::Any => changes.iter().any(|ch| ch.within),
            Rule::All => changes.iter().all(|ch| ch.within),
        };
        let streak = if holds { out[k - 1].streak + 1 } else { 0 };
        let needed = match c.rule {
            Rule::Any => 1,
            Rule::All => c.hold,
        };
        let converged = streak >= needed && *n >= c.min_points;
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

impl Overrides {
    /// Apply to `c`, refusing values the sweep file would refuse (naming the flag).
    pub fn apply(&self, c: &mut ConvergenceSettings) -> crate::Result<()> {
        let bad = |flag: &str, what: String| crate::Error::input(format!("{flag} {what}"));
        if let Some(r) = &self.rule {
            if Rule::parse(r).is_none() {
                return Err(bad("--rule", format!("{r}: expected \"all\" or \"any\"")));
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
        Criteria { rule: Rule::All, tolerance: tol, floor, hold, min_points: 0 }
    }

    fn any(tol: f64) -> Criteria {
        Criteria { rule: Rule::Any, tolerance: tol, floor: 0.0, hold: 1, min_points: 0 }
    }

    fn spaces(ms: &[Moments]) -> Vec<(usize, Moments)> {
        ms.iter().enumerate().map(|(k, m)| (400 * (k + 1), *m)).collect()
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
        let ch = j[1].changes.unwrap();
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
        let ch = judge(&s, &any(0.05))[1].changes.unwrap();
        assert_eq!(ch.map(|c| c.within), [false, false, false, true]);
    }

    #[test]
    fn a_statistic_crossing_zero_is_judged_by_the_floor() {
        // Skewness 0.004 → −0.003: a relative change of 175 %, an absolute one of 0.007.
        let s = spaces(&[m(0.2, 0.1, 0.004, 2.0), m(0.201, 0.1005, -0.003, 2.01)]);
        let strict = judge(&s, &all(0.05, 0.0, 1));
        let skew = strict[1].changes.unwrap()[2];
        assert!((skew.rel.unwrap() - 1.75).abs() < 1e-12);
        assert!(!skew.within && converged_at(&strict).is_none(), "no floor: the zero crossing blocks");
        let floored = judge(&s, &all(0.05, 0.01, 1));
        assert!(floored[1].changes.unwrap()[2].within);
        assert_eq!(converged_at(&floored), Some(1));
        // A large swing across zero stays blocked by the floor.
        let big = spaces(&[m(0.2, 0.1, 0.3, 2.0), m(0.2, 0.1, -0.3, 2.0)]);
        assert_eq!(converged_at(&judge(&big, &all(0.05, 0.01, 1))), None);
    }

    #[test]
    fn a_change_from_exactly_zero_has_no_relative_size() {
        let c = all(0.05, 0.0, 1);
        assert_eq!(change(Some(0.0), Some(0.1), Rule::All, &c).rel, None);
        assert_eq!(change(Some(0.0), Some(0.0), Rule::All, &c).rel, Some(0.0));
        assert!(change(Some(0.0), Some(0.0), Rule::Any, &c).within);
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
        c.min_points = 1200;
        assert_eq!(converged_at(&judge(&s, &c)), Some(2), "space 2 holds 1,200 points");
    }
}
