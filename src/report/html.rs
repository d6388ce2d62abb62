//! `report.html`: one self-contained page. The figures are embedded as PNG data URIs and the
//! style sheet is inline, so the file loads nothing from anywhere (a test checks that every
//! `src` and `href` in it is a `data:` URI or a `#` anchor).

use base64::Engine as _;

use super::plots::{fmt_short, Figure};
use super::Analysis;
use crate::analysis::stats::STATISTICS;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

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

/// A table of the points a figure labels by `#index`.
fn points_table(a: &Analysis, f: &Figure) -> String {
    if f.points.is_empty() {
        return String::new();
    }
    let mut h = String::from("<table><tr><th>point</th>");
    for p in &a.parameters {
        h.push_str(&format!("<th>{}</th>", esc(p)));
    }
    h.push_str("<th>MFR</th><th class=\"l\">quality</th></tr>\n");
    for &i in &f.points {
        let Some(p) = a.points.iter().find(|p| p.index == i) else { continue };
        let Some((r, q)) = p.done() else { continue };
        h.push_str(&format!("<tr><td>#{i}</td>"));
        for v in &p.values {
            h.push_str(&format!("<td>{}</td>", fmt_short(*v)));
        }
        h.push_str(&format!("<td>{:.4}</td><td class=\"l\">{}</td></tr>\n", r.mfr, q.as_str()));
    }
    h.push_str("</table>\n");
    h
}

fn img(f: &Figure) -> String {
    format!(
        "<figure><img alt=\"{}\" src=\"data:image/png;base64,{}\"><figcaption>{} <span class=\"file\">(report/{}.svg, .png)</span></figcaption></figure>\n",
        esc(&f.caption),
        base64::engine::general_purpose::STANDARD.encode(&f.png),
        esc(&f.caption),
        esc(&f.name)
    )
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1240px;margin:1em auto;padding:0 1em;color:#222}
h1{margin-bottom:0}h2{border-bottom:1px solid #ccc;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0;font-size:.9em}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right;white-space:nowrap}
td small{color:#666}
th{background:#f2f2f2}td.l,th.l{text-align:left}
.verdict{padding:.7em 1em;border-radius:6px;font-size:1.1em;margin:1em 0}
.converged{background:#e3f5e6;border:1px solid #3a3}.not-converged{background:#fde8e8;border:1px solid #c33}
.unfinished{background:#fff4dc;border:1px solid #d90}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #eee}figcaption{font-size:.9em;color:#444}
.grid{display:flex;flex-wrap:wrap;gap:8px}.grid figure{width:560px;margin:0}.file{color:#888}
.bar{display:inline-block;height:.8em;background:#1f77b4}.muted{color:#666}";

/// The page.
pub fn render(a: &Analysis, figures: &[Figure]) -> String {
    let mut h = String::new();
    let push = |h: &mut String, s: &str| h.push_str(s);
    push(
        &mut h,
        &format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{} — sweep report</title><style>{STYLE}</style></head><body>\n",
            esc(&a.name)
        ),
    );
    let design = match &a.design {
        crate::store::DesignRecord::Lattice { levels } => {
            format!("lattice, levels {}", levels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(", "))
        }
        crate::store::DesignRecord::Lds { step, max, scrambling, seed } => {
            format!("scrambled Halton ({scrambling:?}, seed {seed}), step {step}, max {max}")
        }
    };
    push(
        &mut h,
        &format!(
            "<h1>{}</h1><p class=\"muted\">{}<br>Design: {}. Parameters: {}. Engine: {}. Written by {}.</p>\n",
            esc(&a.name),
            esc(&a.description),
            esc(&design),
            esc(&a.parameters.iter().zip(&a.units).map(|(p, u)| format!("{p} ({u})")).collect::<Vec<_>>().join(", ")),
            esc(&a.engine),
            esc(&a.tool)
        ),
    );
    push(
        &mut h,
        &format!(
            "<div class=\"verdict {}\"><b>{}</b>: {}</div>\n",
            a.verdict.status,
            a.verdict.status,
            esc(&a.verdict.reason)
        ),
    );
    // Counts and cost.
    let c = &a.counts;
    let failures = if c.failures_by_class.is_empty() {
        "none".to_string()
    } else {
        c.failures_by_class.iter().map(|(k, v)| format!("{k}: {v}")).collect::<Vec<_>>().join(", ")
    };
    push(
        &mut h,
        &format!(
            "<table><tr><th class=\"l\">points</th><td>{}</td></tr><tr><th class=\"l\">done</th><td>{}</td></tr>\
             <tr><th class=\"l\">failed (left out of every statistic)</th><td>{} ({})</td></tr>\
             <tr><th class=\"l\">screened (closed gap, MFR = 0 without a run)</th><td>{}</td></tr>\
             <tr><th class=\"l\">pending</th><td>{}</td></tr><tr><th class=\"l\">spaces complete</th><td>{} of {}</td></tr>\
             <tr><th class=\"l\">wall time (runs going)</th><td>{:.0} s</td></tr><tr><th class=\"l\">core-seconds</th><td>{:.0}</td></tr></table>\n",
            c.points, c.done, c.failed, esc(&failures), c.screened, c.pending, c.spaces_complete, c.spaces,
            a.timing.wall_time_s, a.timing.core_seconds
        ),
    );
    if let Some(line) = a.screen.sentence() {
        push(&mut h, &format!("<p>{}.</p>\n", esc(&line)));
    }
    // Convergence table.
    push(&mut h, "<h2>Convergence</h2>\n");
    push(&mut h, &format!("<p>{}.", esc(&a.criteria.describe())));
    if a.criteria.min_points > 0 {
        push(
            &mut h,
            &format!(" Spaces below {} points are not judged (an extended sweep).", a.criteria.min_points),
        );
    }
    push(&mut h, " Intervals: 95% percentile bootstrap, 1,000 resamples.</p>\n<table><tr><th class=\"l\">space</th><th>N</th><th>done</th><th>failed</th>");
    for s in STATISTICS {
        push(&mut h, &format!("<th>{} <small>[95% interval]</small></th><th>change</th>", s.name()));
    }
    push(&mut h, "<th>rule holds</th><th>converged</th></tr>\n");
    for s in &a.spaces {
        push(
            &mut h,
            &format!(
                "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td>",
                esc(&s.label),
                s.n,
                s.done,
                s.failed
            ),
        );
        for st in STATISTICS {
            let iv = s.intervals[st.name()];
            let ch = s.changes.as_ref().map(|c| &c[st.name()]);
            // On the scaled rule the change is shown on the statistic's own scale; the cell's
            // tooltip holds the whole test in words.
            let change = match ch {
                None => "".to_string(),
                Some(c) => format!(
                    "<span title=\"{}\">{}{}</span>",
                    esc(&c.test),
                    match (c.abs, c.scale, c.rel) {
                        (Some(d), Some(sc), _) if sc > 0.0 =>
                            format!("{:.1}% of scale", d.abs() / sc * 100.0),
                        (_, _, Some(r)) => format!("{:.1}%", r * 100.0),
                        _ => "undef.".into(),
                    },
                    if c.within { " ✓" } else { "" }
                ),
            };
            push(
                &mut h,
                &format!(
                    "<td>{} <small>[{}, {}]</small></td><td>{}</td>",
                    num(st.of(&s.statistics)),
                    sig(iv.lo),
                    sig(iv.hi),
                    change
                ),
            );
        }
        push(
            &mut h,
            &format!(
                "<td>{}</td><td>{}</td></tr>\n",
                if s.holds { "yes" } else { "" },
                if s.converged { "<b>yes</b>" } else { "" }
            ),
        );
    }
    push(&mut h, "</table>\n");
    if let Some(s) = a.spaces.iter().find(|s| s.converged).or(a.spaces.last()) {
        if let Some(ch) = &s.changes {
            push(&mut h, &format!("<p>The tests at {} (N = {}):</p>\n<ul>\n", esc(&s.label), s.n));
            for st in STATISTICS {
                push(&mut h, &format!("<li>{}: {}</li>\n", st.name(), esc(&ch[st.name()].test)));
            }
            push(&mut h, "</ul>\n");
        }
        push(&mut h, &format!("<p>{}</p>\n", esc(&super::weights_sentence(s))));
        match &s.noise {
            Some(n) => push(
                &mut h,
                &format!(
                    "<p>Noise in each point ({} points with a standard error): variance of MFR {:.3e}, of which the \
                     per-point noise (mean se²) {:.3e} ({:.1}%); std {:.4} raw, {:.4} with the noise removed.</p>\n",
                    n.points_with_se,
                    n.variance,
                    n.noise_variance,
                    n.noise_share * 100.0,
                    n.std_raw,
                    n.std_without_noise
                ),
            ),
            None => push(&mut h, "<p>No point records its MFR's standard error, so the spread above holds the per-point noise unseen.</p>\n"),
        }
    }
    for f in figures.iter().filter(|f| f.name == "statistics") {
        push(&mut h, &img(f));
    }
    push(&mut h, "<h2>MFR distribution per space</h2>\n<div class=\"grid\">\n");
    for f in figures.iter().filter(|f| f.name.starts_with("histogram-")) {
        push(&mut h, &img(f));
    }
    push(&mut h, "</div>\n");
    // Sensitivity.
    push(
        &mut h,
        "<h2>Which parameter matters</h2>\n<p>First-order sensitivity indices of MFR over every done point \
         (adjusted correlation ratio: the share of MFR's variance explained by one parameter alone; no extra runs).</p>\n\
         <table><tr><th class=\"l\">parameter</th><th>S₁</th><th>95% interval</th><th class=\"l\"></th><th>bins</th></tr>\n",
    );
    for s in &a.sensitivity {
        let w = s.first_order.unwrap_or(0.0) * 300.0;
        push(
            &mut h,
            &format!(
                "<tr><td class=\"l\">{}</td><td>{}</td><td>[{}, {}]</td><td class=\"l\"><span class=\"bar\" style=\"width:{w:.0}px\"></span></td><td>{}</td></tr>\n",
                esc(&s.parameter),
                num(s.first_order),
                num(s.lo),
                num(s.hi),
                s.bins
            ),
        );
    }
    push(&mut h, "</table>\n");
    push(&mut h, &format!("<p>{}.</p>\n", esc(&a.sensitivity_note)));
    for f in figures.iter().filter(|f| f.name == "scatter") {
        push(&mut h, &img(f));
    }
    push(&mut h, &emulator_section(a));
    // Quality and recommendation.
    push(
        &mut h,
        "<h2>Spreading quality and recommended settings</h2>\n<p>Each done point's v_x profile in front of the blade \
         (thesis §4.1) is <b>unstable</b> when its layers depart from their neighbours' mean by more than 3% of the \
         blade speed (RMS), else <b>inefficient</b> when the top three layers move less than 6% of the blade speed \
         faster than the bottom three (nearly uniform), else <b>ideal</b>.</p>\n<table><tr>",
    );
    for k in a.quality.keys() {
        push(&mut h, &format!("<th>{k}</th>"));
    }
    push(&mut h, "</tr><tr>");
    for v in a.quality.values() {
        push(&mut h, &format!("<td>{v}</td>"));
    }
    push(&mut h, "</tr></table>\n");
    if a.best_ideal.is_empty() {
        push(&mut h, "<p>No point has an ideal profile, so none is recommended.</p>\n");
    } else {
        push(&mut h, "<p>Highest MFR among the ideal points:</p>\n<table><tr><th>point</th>");
        for p in &a.parameters {
            push(&mut h, &format!("<th>{}</th>", esc(p)));
        }
        push(&mut h, "<th>MFR</th></tr>\n");
        for b in &a.best_ideal {
            push(&mut h, &format!("<tr><td>{}</td>", b.index));
            for p in &a.parameters {
                push(&mut h, &format!("<td>{}</td>", fmt_short(b.parameters[p])));
            }
            push(&mut h, &format!("<td>{:.4}</td></tr>\n", b.mfr));
        }
        push(&mut h, "</table>\n");
    }
    for f in figures.iter().filter(|f| f.name == "profiles") {
        push(&mut h, &img(f));
        push(&mut h, &points_table(a, f));
    }
    let lattice: Vec<&Figure> = figures.iter().filter(|f| f.name.starts_with("lattice-")).collect();
    if !lattice.is_empty() {
        push(&mut h, "<h2>One-factor v_x panels (thesis Fig. 4.3–4.14)</h2>\n");
        for f in lattice {
            push(&mut h, &img(f));
        }
    }
    push(&mut h, "</body></html>\n");
    h
}

/// The emulator: how well it predicts left-out points, the space's statistics from it beside
/// the raw sample's, its verdict, the zero region and the best settings per quality class.
fn emulator_section(a: &Analysis) -> String {
    let mut h = String::from("<h2>Emulator of MFR over the space</h2>\n");
    let Some(e) = &a.emulator else {
        h.push_str("<p>No emulator: too few done points, or MFR does not vary.</p>\n");
        return h;
    };
    let cv = &e.cross_validation;
    h.push_str(&format!(
        "<p>A Gaussian process (Matérn 5/2, constant mean, each point's own noise where it records an \
         <code>mfr_se</code> plus a fitted nugget) fitted to {} points. Leave-one-out: RMSE {:.4} against a \
         per-point noise of {:.4}; Q² = {:.3} (share of MFR's variance predicted out of sample); {:.0}% of \
         left-out points within their 95% band.</p>\n",
        e.points,
        cv.rmse,
        cv.noise_se,
        cv.q2,
        cv.coverage95 * 100.0
    ));
    h.push_str("<table><tr><th class=\"l\">statistic</th><th>raw sample</th><th>emulator <small>[95% interval]</small></th></tr>\n");
    let raw = a.statistics;
    for (k, st) in STATISTICS.iter().enumerate() {
        let iv = e.statistics.intervals[k];
        h.push_str(&format!(
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{} <small>[{}, {}]</small></td></tr>\n",
            st.name(),
            num(raw.as_ref().and_then(|m| st.of(m))),
            num(st.of(&e.statistics.statistics)),
            sig(iv.lo),
            sig(iv.hi)
        ));
    }
    h.push_str("</table>\n");
    if let Some(v) = &e.verdict {
        h.push_str(&format!(
            "<p>The rule on the emulator's statistics of the last two spaces: {}.</p>\n<ul>\n",
            if v.holds { "holds" } else { "does not hold" }
        ));
        for st in STATISTICS {
            h.push_str(&format!("<li>{}: {}</li>\n", st.name(), esc(&v.changes[st.name()].test)));
        }
        h.push_str("</ul>\n");
    }
    h.push_str(&format!(
        "<p>MFR is zero (the emulator's mean below {:.4}) over {:.1}% of the space; for sure (its upper 95% \
         bound below it) over {:.1}%.</p>\n",
        e.zero_level,
        e.zero_fraction * 100.0,
        e.zero_fraction_sure * 100.0
    ));
    for (class, list) in &e.best {
        if list.is_empty() {
            continue;
        }
        h.push_str(&format!(
            "<p>Best {class} points by the emulator's MFR:</p>\n<table><tr><th>point</th><th>run MFR</th><th>emulator MFR ± SE</th></tr>\n"
        ));
        for b in list {
            h.push_str(&format!(
                "<tr><td>#{}</td><td>{:.4}</td><td>{:.4} ± {:.4}</td></tr>\n",
                b.index, b.mfr, b.emulator_mfr, b.emulator_se
            ));
        }
        h.push_str("</table>\n");
    }
    h
}
