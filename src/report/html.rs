//! `report.html`: one self-contained page, rendered from `templates/report/report.html.tera`
//! ([`super::page`]). The figures are embedded as PNG data URIs and the style sheet is inline,
//! so the file loads nothing from anywhere (a test checks that every `src` and `href` in it is a
//! `data:` URI or a `#` anchor). This file turns the analysis into what the templates show:
//! every number formatted here, every text escaped by the engine.

use serde_json::{json, Value};

use super::page::{self, FigureView};
use super::plots::{fmt_short, Figure};
use super::Analysis;
use crate::analysis::stats::STATISTICS;

fn num(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{v:.4}"))
}

/// Four significant digits, for compact interval bounds.
fn sig(v: Option<f64>) -> String {
    v.map_or("–".into(), fmt_short_sig)
}

fn fmt_short_sig(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 8) as usize;
    format!("{v:.digits$}")
}

/// ` †` when `estimate` lies outside its interval (the table's note says why that can happen).
fn misses(estimate: Option<f64>, iv: crate::analysis::stats::Interval) -> &'static str {
    match (estimate, iv.lo, iv.hi) {
        (Some(v), Some(lo), Some(hi)) if v < lo || v > hi => " †",
        _ => "",
    }
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{v:.digits$}"))
}

/// The page.
pub fn render(a: &Analysis, figures: &[Figure]) -> String {
    let design = match &a.design {
        crate::store::DesignRecord::Lattice { levels } => {
            format!("lattice, levels {}", levels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(", "))
        }
        crate::store::DesignRecord::Lds { step, max, scrambling, seed } => {
            format!("scrambled Halton ({scrambling:?}, seed {seed}), step {step}, max {max}")
        }
        crate::store::DesignRecord::Adapt { first, batch, max, seed, .. } => format!(
            "adaptive: {first} scrambled-Halton points (seed {seed}), then batches of {batch} where the \
             emulator says the statistics are least known, max {max}; statistics from the emulator"
        ),
    };
    let measured = a.points.iter().any(|p| p.mfr().is_some());
    let c = &a.counts;
    let failures = if c.failures_by_class.is_empty() {
        "none".to_string()
    } else {
        c.failures_by_class.iter().map(|(k, v)| format!("{k}: {v}")).collect::<Vec<_>>().join(", ")
    };
    let answer = a.answer.as_ref().map(|x| {
        json!({
            "recommendation": x.recommendation,
            "layer_warning": x.layer_warning,
            "matters": x.matters,
            "verdict": x.verdict,
            "next": x.next,
        })
    });
    let context = json!({
        "name": a.name,
        // What each point answers with: MFR, or the layout's own measure.
        "q": a.answer_name(),
        // Points are ranked within their v_x class only where a run measures v_x (MFR sweeps).
        "classed": super::answer_kind(&a.setup.scene) == crate::outcome::AnswerKind::Mfr,
        "description": a.description,
        "design": design,
        "parameter_list": a.parameters.iter().zip(&a.units).map(|(p, u)| format!("{p} ({u})")).collect::<Vec<_>>().join(", "),
        "engine": a.engine,
        "tool": a.tool,
        "headers": a.parameters.iter().zip(&a.units).map(|(p, u)| json!({"name": p, "unit": u})).collect::<Vec<_>>(),
        "statistics": STATISTICS.iter().map(|s| s.name()).collect::<Vec<_>>(),
        "all_failed": !measured && c.failed > 0,
        "answer": answer,
        "counts": {
            "points": c.points,
            "done": c.done,
            "failed": c.failed,
            "failures": failures,
            "screened": c.screened,
            "pending": c.pending,
            "spaces_complete": c.spaces_complete,
            "spaces": c.spaces,
            "wall_time": format!("{:.0}", a.timing.wall_time_s),
            "core_seconds": format!("{:.0}", a.timing.core_seconds),
            "cpu_seconds": format!("{:.0}", a.timing.cpu_seconds),
            "runs_without_cpu": a.timing.runs_without_cpu,
        },
        "screen": a.screen.sentence(),
        "m": if measured { measured_sections(a, figures) } else { Value::Null },
        "measured": measured,
        "failures": failures_section(a, figures),
        "setup": setup_section(a),
    });
    page::render("report.html", &context)
}

fn figures_named(figures: &[Figure], pick: impl Fn(&str) -> bool) -> Vec<FigureView<()>> {
    figures.iter().filter(|f| pick(&f.name)).map(FigureView::of).collect()
}

/// A point's swept values, as the tables show them.
fn values(a: &Analysis, parameters: &std::collections::BTreeMap<String, f64>) -> Vec<String> {
    a.parameters.iter().map(|p| fmt_short(parameters[p])).collect()
}

fn failures_section(a: &Analysis, figures: &[Figure]) -> Value {
    if a.failures.is_empty() {
        return Value::Null;
    }
    let rows: Vec<Value> = a
        .failures
        .iter()
        .map(|f| {
            let dir = f.run_dir.strip_prefix(&a.dir).unwrap_or(&f.run_dir);
            json!({
                "index": f.index,
                "values": values(a, &f.parameters),
                "class": f.class,
                "reason": f.reason,
                "dir": dir.display().to_string(),
            })
        })
        .collect();
    json!({ "rows": rows, "figures": figures_named(figures, |n| n == "failures") })
}

/// How the runs started and how precisely they ran: warm starts, and the sweep's precision.
fn started_line(st: &crate::report::Setup, done: usize) -> Option<String> {
    let mut parts = Vec::new();
    if st.warm_started > 0 {
        parts.push(format!(
            "{} of {done} done runs started from the steady heap of a finished neighbour, the others from rest",
            st.warm_started
        ));
    }
    if let Some(p) = &st.precision {
        let why = if p.adaptive {
            "½·σ·√(τ/3): at that noise the emulator knows the skewness to the rule's tolerance within a few hundred runs"
        } else {
            "σ·√(τ/3): each point's noise biases the statistics by at most half the tolerance"
        };
        parts.push(format!(
            "after its first {} points (MFR's spread σ = {}), the sweep ran its points to an SE of MFR of at most {} ({why})",
            p.points,
            fmt_short_sig(p.spread),
            fmt_short_sig(p.mfr_abs_se)
        ));
        if st.coarser > 0 {
            parts.push(format!(
                "{} done runs ran before that, to the scene's own target, and are coarser (sweep extend brings them to it without running them again)",
                st.coarser
            ));
        }
    }
    if st.extended > 0 {
        parts.push(format!("{} runs were continued to a tighter SE by sweep extend", st.extended));
    }
    (!parts.is_empty()).then(|| parts.join("; "))
}

fn setup_section(a: &Analysis) -> Value {
    let st = &a.setup;
    let sc = &st.scene;
    // Only what the points read: a layers sweep's page lists no gap, a mono-sized powder's no
    // Weibull parameters.
    let read = |name: &str| crate::scenes::ignored(sc, name).is_none();
    let fixed: Vec<Value> = st
        .fixed
        .iter()
        .filter(|f| read(&f.name))
        .map(|f| {
            json!({
                "name": f.name,
                "value": fmt_short(f.value),
                "unit": f.unit,
                "written": f.written,
                "description": f.description,
            })
        })
        .collect();
    let layout_rows = crate::scenes::lookup(&sc.layout).map(|l| l.setup_rows(sc)).unwrap_or_default();
    let mut rows: Vec<(&str, String)> = vec![("layout", sc.layout.clone())];
    if read("scene.substrate") {
        rows.push(("substrate", sc.substrate.clone()));
    }
    rows.extend(layout_rows.head);
    rows.extend([
        ("size distribution", sc.size_distribution.describe()),
        ("fidelity preset", sc.fidelity.clone()),
        (
            "timestep (× Rayleigh time; fixed step if > 0: s)",
            format!("{} ({} s)", fmt_short(sc.rayleigh_fraction), sc.timestep_s),
        ),
        ("stiffness factor (–)", fmt_short(sc.stiffness_factor)),
        ("blade mesh cells across the depth", sc.mesh_cells_across.to_string()),
        ("domain depth (D)", fmt_short(sc.depth_diameters)),
    ]);
    rows.extend(layout_rows.tail);
    rows.push(("neighbour skin (D)", fmt_short(sc.skin_diameters)));
    if read("scene.vx_band_diameters") {
        rows.push((
            "v_x band half-height (D)",
            if sc.thesis_band { "±1 mm (thesis)".into() } else { fmt_short(sc.vx_band_diameters) },
        ));
    }
    rows.extend([
        ("seed", sc.seed.to_string()),
        ("engine", format!("{} ({})", st.engine_version, st.engine_path)),
    ]);
    let centre = st.centre.as_ref().map(|c| {
        let at = c
            .parameters
            .iter()
            .map(|(k, v)| format!("{k} = {}", fmt_short(*v)))
            .collect::<Vec<_>>()
            .join(", ");
        json!({
            "at": at,
            "particles": c.particles,
            "runs": c.runs,
            "substrate_particles": c.substrate_particles,
            "length": format!("{:.1}", c.domain_length_mm),
            "depth": format!("{:.1}", c.domain_depth_mm),
            "height": format!("{:.1}", c.domain_height_mm),
            // A layout that starts from a pile (not one dosed pass by pass) says how long it is
            // and over how much travel it measured.
            "pile": c.heap_length_mm > 0.0,
            "heap_length": format!("{:.1}", c.heap_length_mm),
            "heap_height": format!("{:.1}", c.heap_height_mm),
            "window_travel": format!("{:.1}", c.window_travel_mm),
            "timestep": format!("{:.3e}", c.timestep_s),
            "fraction": format!("{:.2}", c.timestep_s / c.rayleigh_time_s),
            "rayleigh": format!("{:.3e}", c.rayleigh_time_s),
        })
    });
    let held = st.centre.as_ref().and_then(|c| c.held_heap.as_ref()).map(|cv| {
        json!({
            "heap_particles": cv.heap_particles,
            "heap_height_mm": format!("{:.1}", cv.heap_height_mm),
            "block_travel_mm": format!("{:.1}", cv.block_travel_mm),
            "warmup_blocks": cv.warmup_blocks,
            "min_window_blocks": cv.min_window_blocks,
            "cap_travel_mm": format!("{:.0}", cv.cap_travel_mm),
        })
    });
    json!({
        "fixed": fixed,
        "rows": rows,
        "started": started_line(st, a.counts.done),
        "centre": centre,
        "held": held,
    })
}

/// Everything that needs at least one MFR: convergence, distributions, sensitivity, maps,
/// quality and the recommendation.
fn measured_sections(a: &Analysis, figures: &[Figure]) -> Value {
    // An adaptive sweep's spaces are its batches: the table says what each batch left known.
    let adaptive = a.spaces.first().is_some_and(|s| s.weights == super::adaptive::WEIGHTS);
    let spaces: Vec<Value> = a
        .spaces
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let head = if adaptive {
                let before = k.checked_sub(1).map_or(0, |i| a.spaces[i].n);
                vec![format!("{} ({})", k + 1, s.label), s.n.to_string(), s.n.saturating_sub(before).to_string()]
            } else {
                vec![s.label.clone(), s.n.to_string(), s.done.to_string()]
            };
            let head: Vec<String> = head.into_iter().chain([s.failed.to_string()]).collect();
            let cells: Vec<Value> = STATISTICS
                .iter()
                .map(|st| {
                    let iv = s.intervals[st.name()];
                    // On the scaled rule the change is shown on the statistic's own scale; the
                    // cell's tooltip holds the whole test in words.
                    let change = s.changes.as_ref().map(|c| &c[st.name()]).map(|c| {
                        let text = match (c.abs, c.scale, c.rel) {
                            (Some(d), Some(sc), _) if sc > 0.0 => format!("{:.1}% of scale", d.abs() / sc * 100.0),
                            (_, _, Some(r)) => format!("{:.1}%", r * 100.0),
                            _ => "undef.".into(),
                        };
                        json!({ "test": c.test, "text": format!("{text}{}", if c.within { " ✓" } else { "" }) })
                    });
                    json!({
                        "value": num(st.of(&s.statistics)),
                        "lo": sig(iv.lo),
                        "hi": sig(iv.hi),
                        "misses": misses(st.of(&s.statistics), iv),
                        "change": change,
                    })
                })
                .collect();
            json!({ "head": head, "cells": cells, "holds": s.holds, "converged": s.converged })
        })
        .collect();
    let judged = a.spaces.iter().find(|s| s.converged).or(a.spaces.last()).map(|s| {
        let tests = s.changes.as_ref().map(|ch| {
            STATISTICS.iter().map(|st| (st.name(), ch[st.name()].test.clone())).collect::<Vec<_>>()
        });
        let failed =
            s.changes.as_ref().map_or(0, |ch| STATISTICS.iter().filter(|st| !ch[st.name()].within).count());
        let noise = s.noise.as_ref().map(|n| {
            json!({
                "points": n.points_with_se,
                "variance": format!("{:.3e}", n.variance),
                "noise_variance": format!("{:.3e}", n.noise_variance),
                "share": format!("{:.1}", n.noise_share * 100.0),
                "std_raw": format!("{:.4}", n.std_raw),
                "std_without": format!("{:.4}", n.std_without_noise),
            })
        });
        json!({
            "label": s.label,
            "n": s.n,
            "failed": failed,
            "tests": tests,
            "weights": super::weights_sentence(s),
            "noise": noise,
        })
    });
    let sensitivity: Vec<Value> = a
        .sensitivity
        .iter()
        .map(|s| {
            json!({
                "parameter": s.parameter,
                "first_order": num(s.first_order),
                "lo": num(s.lo),
                "hi": num(s.hi),
                "width": format!("{:.0}", s.first_order.unwrap_or(0.0) * 240.0),
                "bins": s.bins,
            })
        })
        .collect();
    let profiles: Vec<FigureView<Value>> = figures
        .iter()
        .filter(|f| f.name == "profiles")
        .map(|f| FigureView::with_rows(f, points_rows(a, f)))
        .collect();
    json!({
        "status": a.verdict.status,
        "verdict": a.answer.as_ref().map_or(&a.verdict.reason, |x| &x.verdict),
        "criteria": a.criteria.describe(),
        "min_points": a.criteria.min_points,
        "adaptive": adaptive,
        "adaptive_design": a.design.is_adaptive(),
        "spaces": spaces,
        "judged": judged,
        "sensitivity": sensitivity,
        "sensitivity_note": a.sensitivity_note,
        "emulator": emulator_section(a),
        "advice": advice_section(a),
        "figures": {
            "statistics": figures_named(figures, |n| n == "statistics"),
            "histograms": figures_named(figures, |n| n.starts_with("histogram-")),
            "scatter": figures_named(figures, |n| n == "scatter"),
            "maps": figures_named(figures, |n| n.starts_with(&format!("map-{}-", a.answer_key()))),
            "covered": figures_named(figures, |n| n.starts_with("map-covered-")),
            "profiles": profiles,
            "lattice": figures_named(figures, |n| n.starts_with("lattice-")),
            "passes": figures_named(figures, |n| n == "passes" || n == "top-view"),
        },
    })
}

/// The rows of the points a figure labels by `#index`.
fn points_rows(a: &Analysis, f: &Figure) -> Vec<Value> {
    f.points
        .iter()
        .filter_map(|&i| {
            let p = a.points.iter().find(|p| p.index == i)?;
            let (r, q) = p.done()?;
            Some(json!({
                "index": i,
                "values": p.values.iter().map(|v| fmt_short(*v)).collect::<Vec<_>>(),
                "mfr": format!("{:.4}", r.answer.value),
                "quality": q.as_str(),
            }))
        })
        .collect()
}

/// The layer, the v_x classes against it, the recommended settings, the thesis's conclusions.
fn advice_section(a: &Analysis) -> Value {
    let ad = &a.advice;
    let classes: Vec<Value> = ad
        .classes
        .by_class
        .iter()
        .map(|c| {
            json!({
                "class": c.class,
                "points": c.points,
                "mfr": opt(c.mfr, 4),
                "covered": opt(c.covered_fraction, 3),
                "cv": opt(c.cv_over_noise, 2),
                "roughness": opt(c.roughness_d, 3),
            })
        })
        .collect();
    let recommended: Vec<Value> = ad
        .recommended
        .iter()
        .map(|r| {
            let l = r.layer;
            json!({
                "index": r.index,
                "values": values(a, &r.parameters),
                "mfr": format!("{:.4}", r.answer.value),
                "mfr_se": format!("{:.4}", r.se()),
                "covered": opt(l.map(|l| l.covered_fraction), 3),
                "cv": opt(l.filter(|l| l.layer_cv_noise > 0.0).map(|l| l.layer_cv / l.layer_cv_noise), 2),
                "roughness": opt(l.map(|l| l.roughness_d), 3),
            })
        })
        .collect();
    let conclusions: Vec<Value> = ad
        .conclusions
        .iter()
        .map(|c| {
            let mark = match c.verdict {
                "holds" => "✓ holds",
                "fails" => "✗ fails",
                "cannot tell" => "cannot tell",
                _ => "not enough points",
            };
            json!({ "section": c.section, "claim": c.claim, "mark": mark, "evidence": c.evidence })
        })
        .collect();
    json!({
        "classes": classes,
        "sentence": ad.classes.sentence,
        "criterion": ad.criterion,
        "recommended": recommended,
        "distinct": ad.best_is_distinct,
        "conclusions": conclusions,
    })
}

/// The emulator: how well it predicts left-out points, the space's statistics from it beside
/// the raw sample's, its verdict, the zero region and the best settings per quality class.
fn emulator_section(a: &Analysis) -> Value {
    let Some(e) = &a.emulator else { return Value::Null };
    let cv = &e.cross_validation;
    // An adaptive design's space statistics are the emulator's; its runs are not a sample of the space.
    let (raw_head, raw) = if a.design.is_adaptive() {
        let runs: Vec<f64> = a.points.iter().filter_map(|p| p.mfr()).collect();
        ("its runs (not a sample of the space)", Some(crate::analysis::stats::moments(&runs)))
    } else {
        ("raw sample", a.statistics)
    };
    let rows: Vec<Value> = STATISTICS
        .iter()
        .enumerate()
        .map(|(k, st)| {
            let iv = e.statistics.intervals[k];
            json!({
                "name": st.name(),
                "raw": num(raw.as_ref().and_then(|m| st.of(m))),
                "value": num(st.of(&e.statistics.statistics)),
                "lo": sig(iv.lo),
                "hi": sig(iv.hi),
                "misses": misses(st.of(&e.statistics.statistics), iv),
            })
        })
        .collect();
    let verdict = e.verdict.as_ref().map(|v| {
        json!({
            "holds": v.holds,
            "tests": STATISTICS.iter().map(|st| (st.name(), v.changes[st.name()].test.clone())).collect::<Vec<_>>(),
        })
    });
    let best: Vec<Value> = e
        .best
        .iter()
        .filter(|(_, list)| !list.is_empty())
        .map(|(class, list)| {
            let rows: Vec<Value> = list
                .iter()
                .map(|b| {
                    json!({
                        "index": b.index,
                        "mfr": format!("{:.4}", b.answer.value),
                        "emulator_mfr": format!("{:.4}", b.emulator_mfr),
                        "emulator_se": format!("{:.4}", b.emulator_se),
                    })
                })
                .collect();
            json!({ "class": class, "rows": rows })
        })
        .collect();
    json!({
        "points": e.points,
        "rmse": format!("{:.4}", cv.rmse),
        "noise_se": format!("{:.4}", cv.noise_se),
        "q2": format!("{:.3}", cv.q2),
        "coverage": format!("{:.0}", cv.coverage95 * 100.0),
        "paths": e.statistics.paths,
        "raw_head": raw_head,
        "rows": rows,
        "verdict": verdict,
        "zero_level": format!("{:.4}", e.zero_level),
        "zero_fraction": format!("{:.1}", e.zero_fraction * 100.0),
        "zero_fraction_sure": format!("{:.1}", e.zero_fraction_sure * 100.0),
        "best": best,
    })
}
