//! What the sweep advises: whether the v_x classes go with a better layer, the recommended
//! settings by a stated criterion with their uncertainty, and the thesis's conclusions (Wu 2020,
//! §4.2–4.6 and §5.4) checked one by one against this sweep.

use std::collections::BTreeMap;

use serde::Serialize;

use super::answer::FULL_COVER;
use super::{PointRow, PointState};
use crate::analysis::sensitivity::Index;
use crate::measure::quality::Quality;
use crate::outcome::layer::Layer;
use crate::scene::plausible::show;

/// Points a conclusion needs before it is judged.
pub const MIN_POINTS: usize = 20;
/// An even layer: its CV along the travel within this multiple of its counting noise.
pub const EVEN_FACTOR: f64 = 2.0;
/// Recommended settings listed.
const LISTED: usize = 5;

/// The layer measures of one v_x class.
#[derive(Debug, Clone, Serialize)]
pub struct ClassLayer {
    pub class: &'static str,
    pub points: usize,
    pub mfr: Option<f64>,
    pub covered_fraction: Option<f64>,
    /// Mean of layer_cv / layer_cv_noise.
    pub cv_over_noise: Option<f64>,
    pub roughness_d: Option<f64>,
}

/// Whether the v_x classes go with the layer they leave.
#[derive(Debug, Clone, Serialize)]
pub struct ClassCheck {
    pub by_class: Vec<ClassLayer>,
    /// True when ideal and inefficient points both number ≥ 3 and the ideal ones' mean covered
    /// fraction exceeds the inefficient ones' by more than twice its standard error.
    pub discriminate: bool,
    pub sentence: String,
}

/// A recommended point.
#[derive(Debug, Clone, Serialize)]
pub struct Recommended {
    pub index: usize,
    pub parameters: BTreeMap<String, f64>,
    /// Its answer under its own keys (`mfr` and `mfr_se`, `relative_density` and
    /// `relative_density_se`, …), with an SE always: where the result states none, the counting
    /// noise, answer/√n over the n particles counted.
    #[serde(flatten)]
    pub answer: crate::outcome::PointAnswer,
    pub layer: Option<Layer>,
    /// What the layout adds after the answer (a layers point: the powder under the blade and
    /// the steady layer's passes).
    pub detail: Option<String>,
}

impl Recommended {
    /// Its answer's standard error (always stated).
    pub fn se(&self) -> f64 {
        self.answer.se.unwrap_or(f64::NAN)
    }
}

/// One of the thesis's conclusions against this sweep.
#[derive(Debug, Clone, Serialize)]
pub struct Conclusion {
    pub section: &'static str,
    pub claim: &'static str,
    /// `holds`, `fails` or `not enough points`.
    pub verdict: &'static str,
    pub evidence: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct Advice {
    pub classes: ClassCheck,
    pub criterion: String,
    pub recommended: Vec<Recommended>,
    /// Whether the best point's MFR is above the next one's by more than twice their combined SE.
    pub best_is_distinct: Option<bool>,
    pub conclusions: Vec<Conclusion>,
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn se(v: &[f64]) -> Option<f64> {
    let m = mean(v)?;
    (v.len() > 1).then(|| {
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64 / v.len() as f64).sqrt()
    })
}

/// Ranks (1-based, ties averaged).
fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        for &k in &idx[i..=j] {
            r[k] = (i + j) as f64 / 2.0 + 1.0;
        }
        i = j + 1;
    }
    r
}

/// Spearman's rank correlation; `None` when either variable is constant.
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    let (rx, ry) = (ranks(x), ranks(y));
    let (mx, my) = (mean(&rx)?, mean(&ry)?);
    let sxy: f64 = rx.iter().zip(&ry).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = rx.iter().map(|a| (a - mx).powi(2)).sum();
    let syy: f64 = ry.iter().map(|b| (b - my).powi(2)).sum();
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

pub fn advise(
    parameters: &[String],
    points: &[PointRow],
    sensitivity: &[Index],
    layout: Option<&dyn crate::scenes::Layout>,
    answer_name: &str,
) -> Advice {
    let done: Vec<(&PointRow, &crate::outcome::RunResult, Quality)> =
        points.iter().filter_map(|p| p.done().map(|(r, q)| (p, r, q))).collect();
    let classes = class_check(&done);
    let criterion = if answer_name == "MFR" {
        format!(
            "a whole layer before a higher MFR: the points whose layer covers at least {full} of the plate first, then \
             the rest, each by highest MFR (the layer's packing over the gap), among the points whose layer is even \
             along the travel (CV of the deposited mass along the travel within {EVEN_FACTOR}× its counting noise); \
             points without layer measures are ranked by MFR alone; of the points within twice their combined \
             standard error of the best, the fastest blade first. Uncertainty: the MFR's standard error where the \
             run measured one (batch means over the steady window), else its counting noise, MFR/√n over the n \
             particles counted",
            full = show(FULL_COVER)
        )
    } else {
        format!(
            "a whole layer before a higher {answer_name}: the points whose own pass covers at least {full} of the \
             plate first, then the rest, each by highest {answer_name}; of the points within twice their combined \
             standard error of the best, the fastest blade first. Uncertainty: its standard error over the steady \
             passes",
            full = show(FULL_COVER)
        )
    };
    // A layout that measures no CV along the travel (layers) leaves it NaN: not uneven.
    let even = |r: &crate::outcome::RunResult| {
        r.layer.is_none_or(|l| l.layer_cv.is_nan() || l.layer_cv <= EVEN_FACTOR * l.layer_cv_noise)
    };
    let mut ranked: Vec<&(&PointRow, &crate::outcome::RunResult, Quality)> = done
        .iter()
        .filter(|(_, r, _)| even(r) && r.answer.value.is_finite() && r.answer.value > 0.0)
        .collect();
    // Its standard error where the run measured one, else its counting noise.
    let se = |r: &crate::outcome::RunResult| {
        r.answer.se.unwrap_or(r.answer.value / (r.answer_particles.max(1) as f64).sqrt())
    };
    // A process engineer wants the plate covered before a denser patchy layer.
    let whole = |r: &crate::outcome::RunResult| r.layer.is_some_and(|l| l.covered_fraction >= FULL_COVER);
    ranked.sort_by(|a, b| whole(b.1).cmp(&whole(a.1)).then(b.1.answer.value.total_cmp(&a.1.answer.value)));
    // Of the points as good as the best within noise, a machine runs the fastest blade: it
    // spreads the same layer in less time.
    if let Some(speed) = parameters.iter().position(|n| n == "blade_speed") {
        if let Some(best) = ranked.first().map(|b| b.1) {
            let tied = ranked
                .iter()
                .take_while(|(_, r, _)| {
                    whole(r) == whole(best)
                        && best.answer.value - r.answer.value
                            <= 2.0 * (se(best).powi(2) + se(r).powi(2)).sqrt()
                })
                .count();
            let fastest =
                (0..tied).max_by(|&i, &j| ranked[i].0.values[speed].total_cmp(&ranked[j].0.values[speed]));
            if let Some(i) = fastest {
                let first = ranked.remove(i);
                ranked.insert(0, first);
            }
        }
    }
    let recommended: Vec<Recommended> = ranked
        .iter()
        .take(LISTED)
        .map(|(p, r, _)| Recommended {
            index: p.index,
            parameters: parameters.iter().cloned().zip(p.values.iter().copied()).collect(),
            answer: crate::outcome::PointAnswer { se: Some(se(r)), ..r.answer },
            layer: r.layer,
            detail: layout.and_then(|l| l.answer_detail(r)),
        })
        .collect();
    let best_is_distinct = (recommended.len() >= 2).then(|| {
        let (a, b) = (&recommended[0], &recommended[1]);
        a.answer.value - b.answer.value > 2.0 * (a.se().powi(2) + b.se().powi(2)).sqrt()
    });
    // The thesis's claims are of MFR under a blade: a layout that answers with another quantity
    // (a steady layer's packing) is not judged by them.
    let conclusions = if answer_name == "MFR" {
        conclusions(parameters, points, sensitivity, recommended.first())
    } else {
        Vec::new()
    };
    Advice { classes, criterion, recommended, best_is_distinct, conclusions }
}

fn class_check(done: &[(&PointRow, &crate::outcome::RunResult, Quality)]) -> ClassCheck {
    let by_class: Vec<ClassLayer> = [Quality::Ideal, Quality::Inefficient, Quality::Unstable]
        .iter()
        .map(|&q| {
            let members: Vec<_> = done.iter().filter(|d| d.2 == q).collect();
            let layers: Vec<Layer> = members.iter().filter_map(|d| d.1.layer).collect();
            ClassLayer {
                class: q.as_str(),
                points: members.len(),
                mfr: mean(&members.iter().map(|d| d.1.answer.value).collect::<Vec<_>>()),
                covered_fraction: mean(&layers.iter().map(|l| l.covered_fraction).collect::<Vec<_>>()),
                cv_over_noise: mean(
                    &layers
                        .iter()
                        .filter(|l| l.layer_cv_noise > 0.0)
                        .map(|l| l.layer_cv / l.layer_cv_noise)
                        .collect::<Vec<_>>(),
                ),
                roughness_d: mean(&layers.iter().map(|l| l.roughness_d).collect::<Vec<_>>()),
            }
        })
        .collect();
    let covered = |q: Quality| -> Vec<f64> {
        done.iter().filter(|d| d.2 == q).filter_map(|d| d.1.layer.map(|l| l.covered_fraction)).collect()
    };
    let (ideal, ineff) = (covered(Quality::Ideal), covered(Quality::Inefficient));
    let counts: BTreeMap<&str, usize> = by_class.iter().map(|c| (c.class, c.points)).collect();
    let (discriminate, sentence) = if ideal.len() < 3 || ineff.len() < 3 {
        (
            false,
            format!(
                "The v_x classes do not separate this sweep: {} ideal, {} inefficient and {} unstable points with layer \
                 measures ({} and {} needed in the first two), so they cannot be checked against the layer; the \
                 recommendation below uses the layer measures instead",
                counts["ideal"], counts["inefficient"], counts["unstable"], 3, 3
            ),
        )
    } else {
        let (mi, mn) = (mean(&ideal).unwrap_or(0.0), mean(&ineff).unwrap_or(0.0));
        let s = (se(&ideal).unwrap_or(0.0).powi(2) + se(&ineff).unwrap_or(0.0).powi(2)).sqrt();
        let d = mi - mn > 2.0 * s;
        (
            d,
            format!(
                "Ideal points cover {:.3} of the substrate on average against {:.3} for inefficient ones (difference {:+.3}, \
                 SE {:.3}): the classes {} with a better layer on this sweep{}",
                mi,
                mn,
                mi - mn,
                s,
                if d { "go" } else { "do not go" },
                if d { "" } else { "; the recommendation below uses the layer measures instead" }
            ),
        )
    };
    ClassCheck { by_class, discriminate, sentence }
}

fn conclusions(
    parameters: &[String],
    points: &[PointRow],
    sensitivity: &[Index],
    best: Option<&Recommended>,
) -> Vec<Conclusion> {
    let measured: Vec<(&PointRow, f64)> = points
        .iter()
        .filter(|p| !matches!(p.state, PointState::Failed { .. } | PointState::Pending))
        .filter_map(|p| p.mfr().map(|m| (p, m)))
        .collect();
    let n = measured.len();
    let col = |name: &str| parameters.iter().position(|p| p == name);
    let s1 = |name: &str| sensitivity.iter().find(|s| s.parameter == name).and_then(|s| s.first_order);
    let few = |need: &[&str]| -> Option<String> {
        let missing: Vec<&str> = need.iter().copied().filter(|p| col(p).is_none()).collect();
        if !missing.is_empty() {
            Some(format!("{} not swept", missing.join(", ")))
        } else if n < MIN_POINTS {
            Some(format!("{n} measured points, {MIN_POINTS} needed"))
        } else {
            None
        }
    };
    // `Some(true)`: holds, `Some(false)`: fails, `None`: the data cannot tell (overlapping
    // intervals, or no significant trend).
    let judged = |section, claim, need: &[&str], f: &dyn Fn() -> (Option<bool>, String)| -> Conclusion {
        match few(need) {
            Some(why) => Conclusion { section, claim, verdict: "not enough points", evidence: why },
            None => {
                let (ok, evidence) = f();
                let verdict = match ok {
                    Some(true) => "holds",
                    Some(false) => "fails",
                    None => "cannot tell",
                };
                Conclusion { section, claim, verdict, evidence }
            }
        }
    };
    let fmt = |v: Option<f64>| v.map_or("undefined".into(), |v| format!("{v:.2}"));
    let index = |name: &str| sensitivity.iter().find(|s| s.parameter == name);
    let shown = |name: &str| match index(name) {
        Some(Index { first_order: Some(v), lo: Some(lo), hi: Some(hi), .. }) => {
            format!("{name} {v:.2} [{lo:.2}, {hi:.2}]")
        }
        _ => format!("{name} {}", fmt(s1(name))),
    };
    // Whether every index of `big` exceeds every index of `small`, by their 95 % intervals.
    let exceeds = |big: &[&str], small: &[&str]| -> Option<bool> {
        let bound = |n: &str, upper: bool| {
            index(n).and_then(|s| if upper { s.hi.or(s.first_order) } else { s.lo.or(s.first_order) })
        };
        let min_lo = big
            .iter()
            .map(|n| bound(n, false))
            .collect::<Option<Vec<f64>>>()?
            .into_iter()
            .fold(f64::MAX, f64::min);
        let max_hi = small
            .iter()
            .map(|n| bound(n, true))
            .collect::<Option<Vec<f64>>>()?
            .into_iter()
            .fold(f64::MIN, f64::max);
        let max_lo = small
            .iter()
            .map(|n| bound(n, false))
            .collect::<Option<Vec<f64>>>()?
            .into_iter()
            .fold(f64::MIN, f64::max);
        let min_hi = big
            .iter()
            .map(|n| bound(n, true))
            .collect::<Option<Vec<f64>>>()?
            .into_iter()
            .fold(f64::MAX, f64::min);
        if min_lo > max_hi {
            Some(true)
        } else if max_lo > min_hi {
            Some(false)
        } else {
            None
        }
    };
    // Rank correlation of MFR with one parameter, significant beyond ±2/√(n−1): the sign the
    // claim expects (holds), the other (fails), or neither (cannot tell).
    let trend = |name: &str, expect_negative: bool| -> (Option<bool>, String) {
        let j = col(name).unwrap_or(0);
        let x: Vec<f64> = measured.iter().map(|m| m.0.values[j]).collect();
        let y: Vec<f64> = measured.iter().map(|m| m.1).collect();
        let (rho, band) = (spearman(&x, &y), 2.0 / ((n.max(2) - 1) as f64).sqrt());
        let verdict = rho.and_then(|r| {
            let r = if expect_negative { -r } else { r };
            (r.abs() > band).then_some(r > 0.0)
        });
        (verdict, format!("rank correlation of MFR with {name} {} (significant beyond ±{band:.2})", fmt(rho)))
    };
    let mut out = Vec::new();
    out.push(judged(
        "§5.4 (1), §4.2",
        "particle diameter is the most dominant factor",
        &["diameter"],
        &|| {
            let others: Vec<&str> =
                parameters.iter().map(String::as_str).filter(|p| *p != "diameter").collect();
            let top = sensitivity.first().map(|s| s.parameter.clone()).unwrap_or_default();
            let verdict = if top == "diameter" {
                exceeds(&["diameter"], &others)
            } else {
                exceeds(&["diameter"], &[top.as_str()])
            };
            (verdict, format!("first-order indices [95 %]: {}; the largest is {top}", shown("diameter")))
        },
    ));
    out.push(judged(
        "§5.4 (1), §4.3",
        "a gap of about twice the diameter spreads best",
        &["diameter", "gap"],
        &|| match best {
            Some(b) => {
                let r = b.parameters["gap"] / b.parameters["diameter"];
                (
                    Some((1.5..=2.5).contains(&r)),
                    format!(
                        "the recommended point #{} has gap/D = {r:.2} (1.5–2.5 counts as about 2)",
                        b.index
                    ),
                )
            }
            None => (None, "no point is recommended".into()),
        },
    ));
    out.push(judged(
        "§5.4 (2)",
        "blade speed and friction matter less than diameter and gap",
        &["diameter", "gap", "blade_speed", "friction"],
        &|| {
            (
                exceeds(&["diameter", "gap"], &["blade_speed", "friction"]),
                format!(
                    "first-order indices [95 %]: {}, {}, {}, {}",
                    shown("diameter"),
                    shown("gap"),
                    shown("blade_speed"),
                    shown("friction")
                ),
            )
        },
    ));
    out.push(judged(
        "§5.4 (2)",
        "blade speed matters more than friction",
        &["blade_speed", "friction"],
        &|| {
            (
                exceeds(&["blade_speed"], &["friction"]),
                format!("first-order indices [95 %]: {}, {}", shown("blade_speed"), shown("friction")),
            )
        },
    ));
    out.push(judged(
        "§4.4, §5.4 (2)",
        "a lower blade speed spreads better (higher MFR)",
        &["blade_speed"],
        &|| trend("blade_speed", true),
    ));
    out.push(judged(
        "§4.5, §5.4 (3)",
        "higher friction deteriorates spreading (lower MFR)",
        &["friction"],
        &|| trend("friction", true),
    ));
    out.push(judged("§4.2", "smaller particles spread better (higher MFR)", &["diameter"], &|| {
        trend("diameter", true)
    }));
    out.push(judged(
        "§4.6, §5.4 (4)",
        "a narrower size distribution spreads better (higher MFR with a larger Weibull shape)",
        &["weibull_shape"],
        &|| trend("weibull_shape", false),
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::layers::settings::{with_own, LayersSettings};

    #[test]
    fn a_comparison_of_indices_holds_only_where_their_intervals_part() {
        let parameters: Vec<String> =
            ["diameter", "gap", "blade_speed", "friction"].iter().map(|s| s.to_string()).collect();
        let points: Vec<PointRow> = (0..30)
            .map(|i| PointRow {
                index: i,
                values: vec![1.0 + i as f64 / 30.0, 2.0, 1.4, 0.2],
                hash: String::new(),
                state: PointState::Screened,
                mfr_se: None,
            })
            .collect();
        let index = |p: &str, v: f64, lo: f64, hi: f64| Index {
            parameter: p.into(),
            first_order: Some(v),
            bins: 10,
            lo: Some(lo),
            hi: Some(hi),
        };
        let sensitivity = vec![
            index("diameter", 0.6, 0.5, 0.7),
            index("gap", 0.2, 0.1, 0.3),
            index("friction", 0.04, 0.02, 0.06),
            index("blade_speed", 0.02, 0.0, 0.05),
        ];
        let c = conclusions(&parameters, &points, &sensitivity, None);
        let verdict = |claim: &str| c.iter().find(|c| c.claim.starts_with(claim)).unwrap().verdict;
        assert_eq!(verdict("particle diameter is the most dominant"), "holds");
        assert_eq!(verdict("blade speed and friction matter less"), "holds");
        // 0.02 [0, 0.05] against 0.04 [0.02, 0.06]: the intervals overlap.
        assert_eq!(verdict("blade speed matters more than friction"), "cannot tell");
        // Every MFR is 0: no rank correlation to read.
        assert_eq!(verdict("smaller particles"), "cannot tell");
        assert_eq!(verdict("a narrower size distribution"), "not enough points");
    }

    #[test]
    fn spearman_by_hand() {
        // Monotone: ±1 whatever the spacing; a tie shares its ranks.
        assert_eq!(spearman(&[1.0, 2.0, 10.0], &[3.0, 4.0, 100.0]), Some(1.0));
        assert_eq!(spearman(&[1.0, 2.0, 10.0], &[3.0, 2.0, 1.0]), Some(-1.0));
        assert_eq!(ranks(&[5.0, 1.0, 5.0]), vec![2.5, 1.0, 2.5]);
        // x ranks 1 2 3 4, y ranks 2 1 4 3: Σd² = 4, ρ = 1 − 6·4/(4·15) = 0.6.
        assert!((spearman(&[1.0, 2.0, 3.0, 4.0], &[2.0, 1.0, 4.0, 3.0]).unwrap() - 0.6).abs() < 1e-12);
        assert_eq!(spearman(&[1.0, 1.0], &[1.0, 2.0]), None);
    }

    #[test]
    fn a_layers_point_is_recommended_by_its_steady_layer_with_the_powder_under_the_blade() {
        use crate::scenes::layers::result::LayerSeries;
        // A layers point measures no CV along the travel (NaN): it is not thereby uneven.
        let point = |index: usize, packing: f64, covered: f64| {
            let series = LayerSeries {
                bed: "fused".into(),
                layer_thickness_m: 5e-5,
                passes: Vec::new(),
                steady_from: 11,
                steady: true,
                packing,
                packing_se: 0.002,
                relative_density: 0.99,
                relative_density_se: 0.01,
                effective_thickness_m: 1.07e-4,
                effective_thickness_se_m: 7e-7,
                covered_fraction: covered,
                roughness_d: 0.5,
                numerical_error: None,
                roller: None,
            };
            let result = crate::outcome::RunResult {
                answer: crate::outcome::PointAnswer {
                    se: Some(0.002),
                    ..crate::outcome::PointAnswer::mfr(packing).as_kind(series.answer_kind())
                },
                layer: Some(Layer {
                    layer_cv: f64::NAN,
                    layer_cv_noise: f64::NAN,
                    covered_fraction: covered,
                    roughness_d: 0.5,
                    height_d: 3.4,
                    particles: 400,
                }),
                own: crate::outcome::OwnResult::new(series),
                ..crate::outcome::RunResult::default()
            };
            PointRow {
                index,
                values: vec![0.1 * (index + 1) as f64],
                hash: String::new(),
                state: PointState::Done { result: Box::new(result), quality: Quality::Unknown },
                mfr_se: Some(0.002),
            }
        };
        // Two points the same within noise: the faster blade first, whichever is denser.
        let tied = vec![point(0, 0.426, 0.95), point(1, 0.425, 0.95), point(2, 0.40, 0.95)];
        let advice = advise(
            &["blade_speed".to_string()],
            &tied,
            &[],
            Some(crate::scenes::lookup("layers").unwrap()),
            "p",
        );
        let order: Vec<usize> = advice.recommended.iter().map(|r| r.index).collect();
        assert_eq!(order, [1, 0, 2], "the faster of the tied first; the distinct one after");
        assert_eq!(advice.best_is_distinct, Some(false));
        let points = vec![point(0, 0.46, 0.84), point(1, 0.39, 0.77)];
        let layout = crate::scenes::lookup("layers").unwrap();
        let advice = advise(&["blade_speed".to_string()], &points, &[], Some(layout), "steady-layer packing");
        assert_eq!(advice.recommended.len(), 2);
        let best = &advice.recommended[0];
        assert_eq!(best.index, 0, "the denser steady layer first");
        let detail = best.detail.as_deref().unwrap();
        assert!(
            detail.contains("107.0 ± 0.7 µm of powder under the blade (2.1 × the layer thickness)"),
            "{detail}"
        );
        assert!(detail.contains("steady from pass 11"), "{detail}");
        let names = |bed: &str| {
            let s = with_own(LayersSettings::default().settings(), |l| l.bed = bed.into());
            layout.answer_name(&s)
        };
        assert_eq!(names("fused"), "steady-layer packing");
        assert_eq!(names("loose"), "steady-layer relative density");
    }
}
