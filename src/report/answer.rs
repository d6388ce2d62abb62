//! The answer first: the settings to use and how sure they are, whether they give a full
//! layer, which parameters matter, and the verdict in plain words with what to do next. The
//! block on top of report.html and the lines a sweep ends with on stdout.

use serde::Serialize;

use super::Analysis;
use crate::analysis::convergence::Rule;
use crate::analysis::stats::STATISTICS;
use crate::scene::plausible::show;
use crate::store::DesignRecord;

/// A full layer: at least this share of the plate under particles (`covered_fraction`). A
/// dense, even layer covers nearly all of it; its complement is bare plate, the empty patches
/// of Nan et al. (2018) (docs/layer.md).
pub const FULL_COVER: f64 = 0.9;

/// The answer, each part one line.
#[derive(Debug, Clone, Serialize)]
pub struct Answer {
    /// What to set and how sure: `gap = 2.64 mm, blade_speed = 1.27 m/s (point #5): MFR
    /// 0.112 ± 0.005 (SE), covered fraction 0.36`; or why nothing is recommended.
    pub recommendation: String,
    /// When the recommended setting leaves most of the plate bare: how much, and whether any
    /// tested setting gives a full layer ([`FULL_COVER`]).
    pub layer_warning: Option<String>,
    /// The parameters ranked by their first-order index of MFR, with 95 % intervals.
    pub matters: Option<String>,
    /// The verdict in one sentence.
    pub verdict: String,
    /// What to do next, when anything.
    pub next: Option<String>,
}

impl Answer {
    /// The lines a sweep ends with: `recommended: …`, `warning: …`, `what matters: …`,
    /// `verdict: …`, `next: …`.
    pub fn lines(&self) -> Vec<String> {
        let mut out = vec![format!("recommended: {}", self.recommendation)];
        if let Some(w) = &self.layer_warning {
            out.push(format!("warning: {w}"));
        }
        if let Some(m) = &self.matters {
            out.push(format!("what matters: {m}"));
        }
        out.push(format!("verdict: {}", self.verdict));
        if let Some(n) = &self.next {
            out.push(format!("next: {n}"));
        }
        out
    }
}

/// `gap = 2.64 mm, blade_speed = 1.27 m/s`.
fn setting(a: &Analysis, values: &dyn Fn(&str) -> Option<f64>) -> String {
    a.parameters
        .iter()
        .zip(&a.units)
        .filter_map(|(p, u)| {
            let v = show_3(values(p)?);
            Some(if u == "-" { format!("{p} = {v}") } else { format!("{p} = {v} {u}") })
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Three significant digits: a setting to dial in, not a record.
fn show_3(v: f64) -> String {
    crate::scene::plausible::round_to(v, 3)
}

pub fn answer(a: &Analysis) -> Answer {
    let (recommendation, layer_warning) = recommendation(a);
    Answer { recommendation, layer_warning, matters: matters(a), verdict: verdict(a), next: next(a) }
}

fn recommendation(a: &Analysis) -> (String, Option<String>) {
    let Some(r) = a.advice.recommended.first() else {
        let why = if a.counts.done == 0 && a.counts.failed > 0 {
            let classes: Vec<String> =
                a.counts.failures_by_class.iter().map(|(c, n)| format!("{n} {c}")).collect();
            format!(
                "no point is done: {} failed ({}; `sweep status` says why)",
                a.counts.failed,
                classes.join(", ")
            )
        } else if a.counts.done == 0 {
            "no point has run yet".to_string()
        } else {
            format!("no done point with {} > 0 has an even layer", a.answer_name())
        };
        return (format!("none: {why}"), None);
    };
    let covered = r.layer.map(|l| l.covered_fraction);
    let text = format!(
        "{} (point #{}): {} {:.3} ± {:.3} (SE){}{}",
        setting(a, &|p| r.parameters.get(p).copied()),
        r.index,
        a.answer_name(),
        r.answer.value,
        r.se(),
        r.detail.as_ref().map_or(String::new(), |d| format!(", {d}")),
        covered.map_or(String::new(), |c| format!(", covered fraction {c:.2}"))
    );
    let warning = covered.filter(|&c| c < FULL_COVER).map(|c| {
        let name = a.answer_name();
        let bare = format!(
            "this setting leaves {:.0}% of the plate bare (covered fraction {c:.2}; a full layer covers at least {})",
            (1.0 - c) * 100.0,
            show(FULL_COVER)
        );
        let layers: Vec<(&super::PointRow, f64, f64)> = a
            .points
            .iter()
            .filter_map(|p| p.done().and_then(|(res, _)| res.layer.map(|l| (p, res.answer.value, l.covered_fraction))))
            .collect();
        let full: Vec<&(&super::PointRow, f64, f64)> = layers.iter().filter(|l| l.2 >= FULL_COVER).collect();
        let at = |p: &super::PointRow| {
            setting(a, &|name| a.parameters.iter().position(|q| q == name).map(|j| p.values[j]))
        };
        match full.iter().max_by(|x, y| x.1.total_cmp(&y.1)) {
            Some((p, mfr, c)) => format!(
                "{bare}; {} of {} tested settings give a full layer, the one of highest {name} is point #{} ({}): {name} {mfr:.3}, covered fraction {c:.2}",
                full.len(),
                layers.len(),
                p.index,
                at(p)
            ),
            None => match layers.iter().max_by(|x, y| x.2.total_cmp(&y.2)) {
                Some((p, _, c)) => format!(
                    "{bare}; no tested setting gives a full layer: the most covered is point #{} ({}), {c:.2}",
                    p.index,
                    at(p)
                ),
                None => bare,
            },
        }
    });
    (text, warning)
}

fn matters(a: &Analysis) -> Option<String> {
    let ranked: Vec<String> = a
        .sensitivity
        .iter()
        .filter_map(|s| {
            let v = s.first_order?;
            let iv = match (s.lo, s.hi) {
                (Some(lo), Some(hi)) => format!(" [{lo:.2}, {hi:.2}]"),
                _ => String::new(),
            };
            Some(format!("{} {v:.2}{iv}", s.parameter))
        })
        .collect();
    if ranked.is_empty() {
        return None;
    }
    if let [only] = a.sensitivity.as_slice() {
        return Some(format!("{} alone is swept: there is nothing to rank", only.parameter));
    }
    // Every interval reaching zero: no parameter is shown to matter, so no order is.
    let unranked =
        a.sensitivity.iter().filter(|s| s.first_order.is_some()).all(|s| s.lo.is_some_and(|lo| lo < 0.005));
    if unranked {
        return Some(format!(
            "cannot rank yet: every parameter's first-order index of {} has a 95% interval that reaches 0 ({}); more \
             points narrow them",
            a.answer_name(),
            ranked.join(", ")
        ));
    }
    let trust = if a.sensitivity_reliable { String::new() } else { format!("; {}", a.sensitivity_note) };
    Some(format!(
        "{} (first-order index of {}: the share of its variance each explains alone, 95% interval){trust}",
        ranked.join(" > "),
        a.answer_name()
    ))
}

fn verdict(a: &Analysis) -> String {
    let v = &a.verdict;
    match v.status {
        "converged" => format!(
            "converged at N = {} ({}): the {} statistics have settled by rule \"{}\"",
            v.n.unwrap_or(0),
            v.space.as_deref().unwrap_or("?"),
            a.answer_name(),
            rule_name(a.criteria.rule)
        ),
        "unfinished" => format!(
            "unfinished: {} of {} spaces complete, {} point(s) pending",
            a.counts.spaces_complete, a.counts.spaces, a.counts.pending
        ),
        _ => {
            let n = a.spaces.last().map_or(0, |s| s.n);
            let failing = failing_tests(a);
            if failing.is_empty() {
                format!("not converged after N = {n}: rule \"{}\" did not hold", rule_name(a.criteria.rule))
            } else {
                format!("not converged after N = {n}: {}", failing.join("; "))
            }
        }
    }
}

fn rule_name(r: Rule) -> &'static str {
    match r {
        Rule::Any => "any",
        Rule::All => "all",
        Rule::Scaled => "scaled",
    }
}

/// `mean and std still move by more than 5% of their scale`, `skewness is known only to ±…`:
/// the tests of the last space that failed, grouped by why.
fn failing_tests(a: &Analysis) -> Vec<String> {
    let Some(ch) = a.spaces.last().and_then(|s| s.changes.as_ref()) else { return Vec::new() };
    let t = a.criteria.tolerance * 100.0;
    let (mut moved, mut noisy) = (Vec::new(), Vec::new());
    for st in STATISTICS {
        let Some(c) = ch.get(st.name()) else { continue };
        if c.within {
            continue;
        }
        let head = c.test.split(':').next().unwrap_or("");
        if head.contains("moved") || !head.contains("noisy") {
            moved.push(st.name());
        }
        if head.contains("noisy") {
            noisy.push(st.name());
        }
    }
    let verb =
        |v: &[&str], one: &str, many: &str| if v.len() == 1 { one.to_string() } else { many.to_string() };
    let mut out = Vec::new();
    if !moved.is_empty() {
        out.push(format!(
            "{} still {} by more than {t}% of {} scale since the previous space",
            moved.join(", "),
            verb(&moved, "moves", "move"),
            verb(&moved, "its", "their")
        ));
    }
    if !noisy.is_empty() {
        let interval = if a.design.is_adaptive() { "95% posterior interval" } else { "95% bootstrap" };
        out.push(format!(
            "{} {} known only to more than ±{t}% of {} scale ({interval})",
            noisy.join(", "),
            verb(&noisy, "is", "are"),
            verb(&noisy, "its", "their")
        ));
    }
    out
}

/// Rule "scaled": the points at which every judged statistic's 95% bootstrap interval would be within
/// the tolerance of its scale, if the half-widths of the last space narrow as 1/√N (a multiple
/// of `step`), and the statistic whose interval is the widest; `None` under another rule or
/// without intervals.
fn points_to_know(a: &Analysis, step: usize) -> Option<(usize, &'static str)> {
    if a.criteria.rule != Rule::Scaled {
        return None;
    }
    let changes = a.spaces.last()?.changes.as_ref()?;
    let (ratio, widest) = STATISTICS
        .iter()
        .filter(|&&st| a.criteria.judges(st))
        .filter_map(|st| {
            let c = changes.get(st.name())?;
            let r = c.noise? / (a.criteria.tolerance * c.scale?);
            r.is_finite().then_some((r, st.name()))
        })
        .max_by(|x, y| x.0.total_cmp(&y.0))?;
    let n = a.counts.points as f64 * ratio * ratio;
    let step = step.max(1) as f64;
    (n.is_finite() && n < 1e9).then(|| (((n / step).ceil() * step) as usize, widest))
}

/// What to do next: resume, extend the design, look at the failures.
fn next(a: &Analysis) -> Option<String> {
    // Words a user pastes into a shell: a name with a space or a `*` stays one word.
    let quote = |p: &std::path::Path| crate::sys::shell::quote_path(p).into_owned();
    let (dir, file) = (quote(&a.dir), quote(&a.dir.join("sweep.toml")));
    let mut steps = Vec::new();
    match a.verdict.status {
        "unfinished" => steps.push(format!("`sweep resume {dir}` runs the pending points")),
        "not-converged" => steps.push(match &a.design {
            DesignRecord::Lds { max, step, .. } => {
                let more = format!(
                    "raise design.lds.max: `sweep lds {file} --max {} --out {dir}` keeps the {} points run and adds {}",
                    2 * max,
                    a.counts.points,
                    max
                );
                match points_to_know(a, *step) {
                    Some((n, widest)) if n > 2 * max => format!(
                        "{more}; the 95% intervals narrow as 1/√N, and the widest, the {widest}'s, is {:.0}× the \
                         tolerance at N = {}: every one is within it at about {n} points",
                        ((n as f64) / a.counts.points.max(1) as f64).sqrt(),
                        a.counts.points
                    ),
                    Some((n, _)) => format!(
                        "{more}; the 95% intervals narrow as 1/√N: every statistic the rule judges is known \
                         within the tolerance at about {n} points"
                    ),
                    _ => more,
                }
            }
            DesignRecord::Lattice { levels } => {
                let more: Vec<String> =
                    levels.iter().chain(levels.last().map(|l| l + 1).as_ref()).map(|l| l.to_string()).collect();
                format!(
                    "add a finer level: `sweep lattice {file} --levels {} --out {dir}` keeps the points run",
                    more.join(",")
                )
            }
            DesignRecord::Adapt { max, .. } => format!(
                "raise design.adapt.max: `sweep adapt {file} --max {} --out {dir}` keeps the {} points run and adds batches",
                2 * max,
                a.counts.points
            ),
        }),
        _ => {}
    }
    if a.counts.failed > 0 {
        steps.push(format!(
            "{} run(s) failed and are left out: `sweep status {dir}` says why, `sweep resume {dir} --retry-failed` runs them again",
            a.counts.failed
        ));
    }
    (!steps.is_empty()).then(|| steps.join("; "))
}
