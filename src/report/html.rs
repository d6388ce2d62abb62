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

/// ` †` when `estimate` lies outside its interval (the table's note says why that can happen).
fn misses(estimate: Option<f64>, iv: crate::analysis::stats::Interval) -> &'static str {
    match (estimate, iv.lo, iv.hi) {
        (Some(v), Some(lo), Some(hi)) if v < lo || v > hi => " †",
        _ => "",
    }
}

/// The answer first: what to set and how sure, the layer it gives, what matters, the verdict
/// and what to do next.
fn answer_block(a: &Analysis) -> String {
    let Some(x) = &a.answer else { return String::new() };
    let mut h = String::from("<div class=\"answer\"><h2>The answer</h2>\n");
    h.push_str(&format!("<p><b>Recommended settings:</b> {}.</p>\n", esc(&x.recommendation)));
    if let Some(w) = &x.layer_warning {
        h.push_str(&format!("<p class=\"warn\"><b>Warning:</b> {}.</p>\n", esc(w)));
    }
    if let Some(m) = &x.matters {
        h.push_str(&format!("<p><b>What matters:</b> {}.</p>\n", esc(m)));
    }
    h.push_str(&format!("<p><b>Verdict:</b> {}.</p>\n", esc(&x.verdict)));
    if let Some(n) = &x.next {
        h.push_str(&format!("<p><b>Next:</b> {}.</p>\n", esc(n)));
    }
    h.push_str(&format!(
        "<p class=\"muted\">How these are found: the recommendation by the criterion of <a href=\"#advice\">Spreading \
         quality and recommended settings</a>; the ranking in <a href=\"#matters\">Which parameter matters</a>; the \
         verdict in <a href=\"#convergence\">Convergence</a>{}.</p></div>\n",
        if a.failures.is_empty() { "" } else { "; the failed runs in <a href=\"#failures\">Failures</a>" }
    ));
    h
}

/// A table of the points a figure labels by `#index`.
fn points_table(a: &Analysis, f: &Figure) -> String {
    if f.points.is_empty() {
        return String::new();
    }
    let mut h = format!("<div class=\"wide\"><table><tr><th>point</th>{}", parameter_headers(a));
    h.push_str("<th>MFR (–)</th><th class=\"l\">quality</th></tr>\n");
    for &i in &f.points {
        let Some(p) = a.points.iter().find(|p| p.index == i) else { continue };
        let Some((r, q)) = p.done() else { continue };
        h.push_str(&format!("<tr><td>#{i}</td>"));
        for v in &p.values {
            h.push_str(&format!("<td>{}</td>", fmt_short(*v)));
        }
        h.push_str(&format!("<td>{:.4}</td><td class=\"l\">{}</td></tr>\n", r.mfr, q.as_str()));
    }
    h.push_str("</table></div>\n");
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

// Readable from 800 px up: tables wrap their text cells rather than widen the page, figures
// shrink to the column, grids fall to one column.
const STYLE: &str = "body{font-family:sans-serif;max-width:1240px;margin:1em auto;padding:0 1em;color:#222;overflow-wrap:anywhere}
h1{margin-bottom:0}h2{border-bottom:1px solid #ccc;margin-top:1.6em}
.wide{max-width:100%;overflow-x:auto}
table{border-collapse:collapse;margin:.5em 0;font-size:.9em}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}
th{overflow-wrap:normal}td small{color:#666}td.path{font-family:monospace;font-size:.85em;text-align:left;word-break:break-all}
th{background:#f2f2f2}td.l,th.l{text-align:left}
.verdict{padding:.7em 1em;border-radius:6px;font-size:1.1em;margin:1em 0}
.converged{background:#e3f5e6;border:1px solid #3a3}.not-converged{background:#fde8e8;border:1px solid #c33}
.unfinished{background:#fff4dc;border:1px solid #d90}
.allfailed{background:#c33;color:#fff;padding:.8em 1em;border-radius:6px;font-size:1.15em;margin:1em 0}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}figcaption{font-size:.9em;color:#444}
.grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(min(100%,560px),1fr));gap:8px}.grid figure{margin:0}.file{color:#888}
.bar{display:inline-block;height:.8em;background:#1f77b4}.muted{color:#666}
.answer{border:2px solid #1f77b4;border-radius:6px;padding:.4em 1em;margin:1em 0;background:#f5f9fd}
.answer h2{border:0;margin:.3em 0}.answer p{margin:.45em 0}.warn{background:#fff4dc;border-left:4px solid #d90;padding:.3em .6em}
details{margin:.5em 0}summary{cursor:pointer;color:#1f5f99}";

/// Header cells of the swept parameters, with units.
fn parameter_headers(a: &Analysis) -> String {
    a.parameters.iter().zip(&a.units).map(|(p, u)| format!("<th>{} ({})</th>", esc(p), esc(u))).collect()
}

/// How the runs started and how precisely they ran: warm starts, and the sweep's precision.
fn started_line(st: &crate::report::Setup, done: usize) -> String {
    let mut parts = Vec::new();
    if st.warm_started > 0 {
        parts.push(format!(
            "{} of {done} done runs started from the steady heap of a finished neighbour, the others from rest",
            st.warm_started
        ));
    }
    if let Some(p) = &st.precision {
        parts.push(format!(
            "after its first {} points (MFR's spread σ = {}), the sweep ran its points to an SE of MFR of at most {} \
             (σ·√(τ/3): each point's noise biases the statistics by at most half the tolerance)",
            p.points,
            fmt_short_sig(p.spread),
            fmt_short_sig(p.mfr_abs_se)
        ));
    }
    if parts.is_empty() {
        return String::new();
    }
    format!("<p>{}.</p>\n", esc(&parts.join("; ")))
}

fn setup_section(a: &Analysis) -> String {
    let st = &a.setup;
    let mut h = String::from("<h2>Setup: what every point shares</h2>\n");
    h.push_str(
        "<p>Fixed parameters (the same in every run; <i>default</i>: not written in the sweep file, the scene's default):</p>\n\
         <div class=\"wide\"><table><tr><th class=\"l\">parameter</th><th>value</th><th class=\"l\">unit</th><th class=\"l\">source</th><th class=\"l\">what it is</th></tr>\n",
    );
    for f in &st.fixed {
        h.push_str(&format!(
            "<tr><td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td></tr>\n",
            esc(&f.name),
            fmt_short(f.value),
            esc(f.unit),
            if f.written { "sweep file" } else { "<i>default</i>" },
            esc(f.description)
        ));
    }
    h.push_str("</table></div>\n");
    let sc = &st.scene;
    let psd = serde_json::to_value(&sc.size_distribution).map(|v| v.to_string()).unwrap_or_default();
    let layout_rows = crate::scenes::lookup(&sc.layout).map(|l| l.setup_rows(sc)).unwrap_or_default();
    let mut rows: Vec<(&str, String)> =
        vec![("layout", sc.layout.clone()), ("substrate", sc.substrate.clone())];
    rows.extend(layout_rows.head);
    rows.extend([
        ("size distribution", psd),
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
    rows.extend([
        ("neighbour skin (D)", fmt_short(sc.skin_diameters)),
        (
            "v_x band half-height (D)",
            if sc.thesis_band { "±1 mm (thesis)".into() } else { fmt_short(sc.vx_band_diameters) },
        ),
        ("seed", sc.seed.to_string()),
        ("engine", format!("{} ({})", st.engine_version, st.engine_path)),
    ]);
    h.push_str("<p>Scene, preset and its knobs:</p>\n<div class=\"wide\"><table>\n");
    for (k, v) in rows {
        h.push_str(&format!("<tr><th class=\"l\">{}</th><td class=\"l\">{}</td></tr>\n", esc(k), esc(&v)));
    }
    h.push_str("</table></div>\n");
    h.push_str(&started_line(st, a.counts.done));
    if let Some(c) = &st.centre {
        let at = c
            .parameters
            .iter()
            .map(|(k, v)| format!("{k} = {}", fmt_short(*v)))
            .collect::<Vec<_>>()
            .join(", ");
        if let Some(cv) = &c.held_heap {
            h.push_str(&format!(
                "<p>At the centre of the space ({}): a heap of {} particles, {:.1} mm tall, held in front of the blade \
                 on {} substrate spheres; domain {:.1} × {:.1} × {:.1} mm (travel × depth × height); blocks of {:.1} mm \
                 of substrate travel, {} of warm-up, then at least {} before the target can stop the run, at most \
                 {:.0} mm in all; timestep {:.3e} s ({:.2} of the Rayleigh time {:.3e} s).</p>\n",
                esc(&at),
                cv.heap_particles,
                cv.heap_height_mm,
                c.substrate_particles,
                c.domain_length_mm,
                c.domain_depth_mm,
                c.domain_height_mm,
                cv.block_travel_mm,
                cv.warmup_blocks,
                cv.min_window_blocks,
                cv.cap_travel_mm,
                c.timestep_s,
                c.timestep_s / c.rayleigh_time_s,
                c.rayleigh_time_s
            ));
            return h;
        }
        h.push_str(&format!(
            "<p>At the centre of the space ({}): {} particles on {} substrate spheres; domain {:.1} × {:.1} × {:.1} mm \
             (travel × depth × height); initial pile {:.1} mm long, {:.1} mm tall; MFR measured over {:.1} mm of blade travel; \
             timestep {:.3e} s ({:.2} of the Rayleigh time {:.3e} s).</p>\n",
            esc(&at),
            c.particles,
            c.substrate_particles,
            c.domain_length_mm,
            c.domain_depth_mm,
            c.domain_height_mm,
            c.heap_length_mm,
            c.heap_height_mm,
            c.window_travel_mm,
            c.timestep_s,
            c.timestep_s / c.rayleigh_time_s,
            c.rayleigh_time_s
        ));
    }
    h
}

fn failures_section(a: &Analysis, figures: &[Figure]) -> String {
    if a.failures.is_empty() {
        return String::new();
    }
    let mut h = format!(
        "<h2 id=\"failures\">Failures ({} of {} points)</h2>\n<p>Failed runs are left out of every statistic, map and \
         recommendation. Each row: the point, its class, the reason the run gave, and its run directory \
         (log.liggghts and failure.json are there; <code>sweep show DIR INDEX</code> prints the point).</p>\n",
        a.failures.len(),
        a.counts.points
    );
    for f in figures.iter().filter(|f| f.name == "failures") {
        h.push_str(&img(f));
    }
    h.push_str(&format!(
        "<div class=\"wide\"><table><tr><th>point</th>{}<th class=\"l\">class</th><th class=\"l\">reason</th><th class=\"l\">run directory</th></tr>\n",
        parameter_headers(a)
    ));
    for f in &a.failures {
        h.push_str(&format!("<tr><td>#{}</td>", f.index));
        for p in &a.parameters {
            h.push_str(&format!("<td>{}</td>", fmt_short(f.parameters[p])));
        }
        let dir = f.run_dir.strip_prefix(&a.dir).unwrap_or(&f.run_dir);
        h.push_str(&format!(
            "<td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"path\">{}</td></tr>\n",
            esc(&f.class),
            esc(&f.reason),
            esc(&dir.display().to_string())
        ));
    }
    h.push_str("</table></div>\n");
    h
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{v:.digits$}"))
}

/// The layer, the v_x classes against it, the recommended settings, the thesis's conclusions.
fn advice_section(a: &Analysis, figures: &[Figure]) -> String {
    let ad = &a.advice;
    let mut h = String::from(
        "<h2>The spread layer</h2>\n<p>Measured on the deposit behind the blade at the window's end (docs/layer.md): \
         <b>covered fraction</b>, the share of the substrate under the layer (its complement is the empty-patch area, \
         after Nan et al. 2018); <b>CV / noise</b>, the coefficient of variation of the deposited mass along the travel \
         (in bins of 3 D; on the conveyor, per block of travel) over what independently placed particles would give (≈ 1: even; above: gaps and clumps); \
         <b>roughness</b>, the RMS height of the top surface (D).</p>\n",
    );
    let maps: Vec<&Figure> = figures.iter().filter(|f| f.name.starts_with("map-covered-")).collect();
    if !maps.is_empty() {
        h.push_str("<div class=\"grid\">\n");
        for f in maps {
            h.push_str(&img(f));
        }
        h.push_str("</div>\n");
    }
    h.push_str(
        "<h2 id=\"advice\">Spreading quality and recommended settings</h2>\n<p>Each done point's v_x profile in front of the blade \
         (thesis §4.1) is <b>unstable</b> when its layers depart from their neighbours' mean by more than 3% of the \
         blade speed (RMS), else <b>inefficient</b> when the top three layers move less than 6% of the blade speed \
         faster than the bottom three (nearly uniform), else <b>ideal</b>. The classes against the layer they leave:</p>\n\
         <div class=\"wide\"><table><tr><th class=\"l\">v_x class</th><th>points</th><th>mean MFR (–)</th><th>covered fraction (–)</th>\
         <th>CV / noise (–)</th><th>roughness (D)</th></tr>\n",
    );
    for c in &ad.classes.by_class {
        h.push_str(&format!(
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            c.class,
            c.points,
            opt(c.mfr, 4),
            opt(c.covered_fraction, 3),
            opt(c.cv_over_noise, 2),
            opt(c.roughness_d, 3)
        ));
    }
    h.push_str(&format!("</table></div>\n<p><b>{}.</b></p>\n", esc(&ad.classes.sentence)));
    h.push_str(&format!("<p>Recommended settings, by this criterion: {}.</p>\n", esc(&ad.criterion)));
    if ad.recommended.is_empty() {
        h.push_str("<p>No point meets the criterion, so none is recommended.</p>\n");
    } else {
        h.push_str(&format!(
            "<div class=\"wide\"><table><tr><th>point</th>{}<th>MFR ± SE (–)</th><th>covered fraction (–)</th><th>CV / noise (–)</th><th>roughness (D)</th></tr>\n",
            parameter_headers(a)
        ));
        for r in &ad.recommended {
            h.push_str(&format!("<tr><td>#{}</td>", r.index));
            for p in &a.parameters {
                h.push_str(&format!("<td>{}</td>", fmt_short(r.parameters[p])));
            }
            let l = r.layer;
            h.push_str(&format!(
                "<td>{:.4} ± {:.4}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                r.mfr,
                r.mfr_se,
                opt(l.map(|l| l.covered_fraction), 3),
                opt(l.filter(|l| l.layer_cv_noise > 0.0).map(|l| l.layer_cv / l.layer_cv_noise), 2),
                opt(l.map(|l| l.roughness_d), 3)
            ));
        }
        h.push_str("</table></div>\n");
        if let Some(d) = ad.best_is_distinct {
            h.push_str(&format!(
                "<p>{}</p>\n",
                if d {
                    "The first point's MFR is above the second's by more than twice their combined standard error."
                } else {
                    "The first two points' MFRs differ by less than twice their combined standard error: within noise, either will do."
                }
            ));
        }
    }
    h.push_str(
        "<h2>The thesis's conclusions against this sweep</h2>\n<div class=\"wide\"><table><tr><th class=\"l\">thesis</th>\
         <th class=\"l\">claim</th><th class=\"l\">here</th><th class=\"l\">evidence</th></tr>\n",
    );
    for c in &ad.conclusions {
        let mark = match c.verdict {
            "holds" => "✓ holds",
            "fails" => "✗ fails",
            "cannot tell" => "cannot tell",
            _ => "not enough points",
        };
        h.push_str(&format!(
            "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\"><b>{}</b></td><td class=\"l\">{}</td></tr>\n",
            esc(c.section),
            esc(c.claim),
            mark,
            esc(&c.evidence)
        ));
    }
    h.push_str("</table></div>\n");
    h
}

/// The page.
pub fn render(a: &Analysis, figures: &[Figure]) -> String {
    let mut h = String::new();
    let push = |h: &mut String, s: &str| h.push_str(s);
    push(
        &mut h,
        &format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>{} — sweep report</title><style>{STYLE}</style></head><body>\n",
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
        crate::store::DesignRecord::Adapt { first, batch, max, seed, .. } => format!(
            "adaptive: {first} scrambled-Halton points (seed {seed}), then batches of {batch} where the \
             emulator says the statistics are least known, max {max}; statistics from the emulator"
        ),
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
    let measured = a.points.iter().any(|p| p.mfr().is_some());
    let c = &a.counts;
    let failures = if c.failures_by_class.is_empty() {
        "none".to_string()
    } else {
        c.failures_by_class.iter().map(|(k, v)| format!("{k}: {v}")).collect::<Vec<_>>().join(", ")
    };
    if !measured && c.failed > 0 {
        push(
            &mut h,
            &format!(
                "<div class=\"allfailed\"><b>Every run failed</b> ({} of {} points; {}). No MFR was measured, so this \
                 report has no statistics, maps or recommendations. <a href=\"#failures\" style=\"color:#fff\">The failures</a> \
                 say where and why.</div>\n",
                c.failed,
                c.points,
                esc(&failures)
            ),
        );
    } else {
        push(&mut h, &answer_block(a));
    }
    push(
        &mut h,
        &format!(
            "<table><tr><th class=\"l\">points</th><td>{}</td></tr><tr><th class=\"l\">done</th><td>{}</td></tr>\
             <tr><th class=\"l\">failed (left out of every statistic)</th><td>{} ({})</td></tr>\
             <tr><th class=\"l\">screened (closed gap, MFR = 0 without a run)</th><td>{}</td></tr>\
             <tr><th class=\"l\">pending</th><td>{}</td></tr><tr><th class=\"l\">spaces complete</th><td>{} of {}</td></tr>\
             <tr><th class=\"l\">wall time (runs going)</th><td>{:.0} s</td></tr><tr><th class=\"l\">core-seconds</th><td>{:.0} s</td></tr></table>\n",
            c.points, c.done, c.failed, esc(&failures), c.screened, c.pending, c.spaces_complete, c.spaces,
            a.timing.wall_time_s, a.timing.core_seconds
        ),
    );
    if let Some(line) = a.screen.sentence() {
        push(&mut h, &format!("<p>{}.</p>\n", esc(&line)));
    }
    if measured {
        push(&mut h, &measured_sections(a, figures));
    }
    push(&mut h, &failures_section(a, figures));
    push(&mut h, &setup_section(a));
    push(&mut h, "</body></html>\n");
    h
}

/// Everything that needs at least one MFR: convergence, distributions, sensitivity, maps,
/// quality and the recommendation.
fn measured_sections(a: &Analysis, figures: &[Figure]) -> String {
    let mut h = String::new();
    let push = |h: &mut String, s: &str| h.push_str(s);
    // Convergence table: one cell per statistic (value, interval, change), so it fits 800 px.
    push(&mut h, "<a id=\"convergence\"></a><h2>Convergence</h2>\n");
    push(
        &mut h,
        &format!(
            "<div class=\"verdict {}\"><b>{}</b>: {}</div>\n",
            a.verdict.status,
            a.verdict.status,
            esc(a.answer.as_ref().map_or(&a.verdict.reason, |x| &x.verdict))
        ),
    );
    push(&mut h, &format!("<p>{}.", esc(&a.criteria.describe())));
    if a.criteria.min_points > 0 {
        push(
            &mut h,
            &format!(" Spaces below {} points are not judged (an extended sweep).", a.criteria.min_points),
        );
    }
    // An adaptive sweep's spaces are its batches: the table says what each batch left known.
    let adaptive = a.spaces.first().is_some_and(|s| s.weights == super::adaptive::WEIGHTS);
    if adaptive {
        push(
            &mut h,
            " One row per batch of the adaptive design, judged once its last run finished (batches.csv says \
             where each of its points went and why). Each cell: the statistic of MFR over the whole space from the \
             emulator fitted to the runs so far (–), its 95% interval from the emulator's posterior, and its change \
             from the previous batch (✓: within the rule); the sweep stops at the first batch where the rule has \
             held as often in a row as it asks.</p>\n<div class=\"wide\"><table><tr><th class=\"l\">batch</th>\
             <th>points</th><th>new</th><th>failed</th>",
        );
    } else {
        push(
            &mut h,
            " Each cell: the statistic of MFR (–), its 95% percentile bootstrap interval (1,000 resamples) and its change from \
             the previous space (✓: within the rule). †: the interval misses the estimate, which a percentile \
             bootstrap interval of a skewed or bounded statistic can do on few points (the resamples' statistic is \
             biased against the sample's).</p>\n<div class=\"wide\"><table><tr><th class=\"l\">space</th><th>N</th><th>done</th><th>failed</th>",
        );
    }
    for s in STATISTICS {
        push(&mut h, &format!("<th>{} (–)</th>", s.name()));
    }
    push(
        &mut h,
        if adaptive {
            "<th>rule holds</th><th>stop</th></tr>\n"
        } else {
            "<th>rule holds</th><th>converged</th></tr>\n"
        },
    );
    for (k, s) in a.spaces.iter().enumerate() {
        let row = if adaptive {
            let before = k.checked_sub(1).map_or(0, |i| a.spaces[i].n);
            format!(
                "<tr><td class=\"l\">{} ({})</td><td>{}</td><td>{}</td><td>{}</td>",
                k + 1,
                esc(&s.label),
                s.n,
                s.n.saturating_sub(before),
                s.failed
            )
        } else {
            format!(
                "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td>",
                esc(&s.label),
                s.n,
                s.done,
                s.failed
            )
        };
        push(&mut h, &row);
        for st in STATISTICS {
            let iv = s.intervals[st.name()];
            let ch = s.changes.as_ref().map(|c| &c[st.name()]);
            // On the scaled rule the change is shown on the statistic's own scale; the cell's
            // tooltip holds the whole test in words.
            let change = match ch {
                None => "".to_string(),
                Some(c) => format!(
                    "<br><span title=\"{}\">{}{}</span>",
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
                    "<td>{}<br><small>[{}, {}]{}</small>{}</td>",
                    num(st.of(&s.statistics)),
                    sig(iv.lo),
                    sig(iv.hi),
                    misses(st.of(&s.statistics), iv),
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
    push(&mut h, "</table></div>\n");
    if let Some(s) = a.spaces.iter().find(|s| s.converged).or(a.spaces.last()) {
        if let Some(ch) = &s.changes {
            let failed = STATISTICS.iter().filter(|st| !ch[st.name()].within).count();
            push(
                &mut h,
                &format!(
                    "<details><summary>The rule's tests at {} (N = {}): {} of {} failed</summary>\n<ul>\n",
                    esc(&s.label),
                    s.n,
                    failed,
                    STATISTICS.len()
                ),
            );
            for st in STATISTICS {
                push(&mut h, &format!("<li>{}: {}</li>\n", st.name(), esc(&ch[st.name()].test)));
            }
            push(&mut h, "</ul></details>\n");
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
    if a.design.is_adaptive() {
        push(
            &mut h,
            "<h2>MFR of the runs</h2>\n<p>The runs of an adaptive design crowd where MFR varies, so this is the \
             distribution of its runs, not of the space: the space's statistics above are the emulator's.</p>\n\
             <div class=\"grid\">\n",
        );
    } else {
        push(&mut h, "<h2>MFR distribution per space</h2>\n<div class=\"grid\">\n");
    }
    for f in figures.iter().filter(|f| f.name.starts_with("histogram-")) {
        push(&mut h, &img(f));
    }
    push(&mut h, "</div>\n");
    // Sensitivity.
    push(
        &mut h,
        "<h2 id=\"matters\">Which parameter matters</h2>\n<p>First-order sensitivity indices of MFR over every done point \
         (adjusted correlation ratio: the share of MFR's variance explained by one parameter alone; no extra runs).</p>\n\
         <table><tr><th class=\"l\">parameter</th><th>S₁ (–)</th><th>95% interval</th><th class=\"l\"></th><th>bins</th></tr>\n",
    );
    for s in &a.sensitivity {
        let w = s.first_order.unwrap_or(0.0) * 240.0;
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
    let maps: Vec<&Figure> = figures.iter().filter(|f| f.name.starts_with("map-mfr-")).collect();
    if !maps.is_empty() {
        push(
            &mut h,
            "<h2>Maps over pairs of parameters</h2>\n<p>Each cell is the mean of the points that fall in it, whatever \
             their other parameters; grey cells passed nothing (MFR = 0 at every point in them: the zero-MFR region); \
             empty cells have no point.</p>\n<div class=\"grid\">\n",
        );
        for f in maps {
            push(&mut h, &img(f));
        }
        push(&mut h, "</div>\n");
    }
    push(&mut h, &advice_section(a, figures));
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
    h.push_str(&format!(
        "<p>The space's statistics from the emulator: each the posterior median over {} sample paths of the \
         fitted process, with its 95% posterior interval (not the statistics of the mean surface, which is smoother \
         than any function the emulator deems possible, and so less spread out).</p>\n",
        e.statistics.paths
    ));
    // An adaptive design's space statistics are the emulator's; its runs are not a sample of the space.
    let (raw_head, raw) = if a.design.is_adaptive() {
        let runs: Vec<f64> = a.points.iter().filter_map(|p| p.mfr()).collect();
        ("its runs (not a sample of the space)", Some(crate::analysis::stats::moments(&runs)))
    } else {
        ("raw sample", a.statistics)
    };
    h.push_str(&format!(
        "<table><tr><th class=\"l\">statistic</th><th>{raw_head}</th><th>emulator: posterior median <small>[95% interval]</small></th></tr>\n"
    ));
    for (k, st) in STATISTICS.iter().enumerate() {
        let iv = e.statistics.intervals[k];
        h.push_str(&format!(
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{} <small>[{}, {}]{}</small></td></tr>\n",
            st.name(),
            num(raw.as_ref().and_then(|m| st.of(m))),
            num(st.of(&e.statistics.statistics)),
            sig(iv.lo),
            sig(iv.hi),
            misses(st.of(&e.statistics.statistics), iv)
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
            "<p>Highest MFR by the emulator among the points whose v_x profile is <i>{class}</i> (a ranking within \
             the class, not a recommendation; the recommended settings are above):</p>\n<table><tr><th>point</th><th>run MFR</th><th>emulator MFR ± SE</th></tr>\n"
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
