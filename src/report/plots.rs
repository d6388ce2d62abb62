//! The report's figures, drawn with plotters as SVG and rendered to PNG by resvg with an
//! embedded font (so a machine without fonts still gets labelled PNGs).
//!
//! - `histogram-K`: the MFR histogram of complete space K (thesis Fig. 4.19 / 4.21);
//! - `statistics`: mean, std, skewness and kurtosis against N with bootstrap intervals and the
//!   tolerance band around the last value (Fig. 4.20 / 4.22);
//! - `scatter`: MFR against each parameter, coloured by spreading quality;
//! - `profiles`: v_x profiles of chosen points per quality class (Fig. 4.2);
//! - `lattice-A-by-B`: for a lattice, v_x profiles as A varies, one panel per level of B, the
//!   other parameters at their middle value (Fig. 4.3–4.14).

use std::collections::HashMap;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Analysis, PointRow};
use crate::analysis::stats::STATISTICS;
use crate::measure::quality::Quality;
use crate::outcome::VX_LAYERS;
pub use crate::scene::plausible::short as fmt_short;

pub(super) use crate::error::Res;
pub(super) type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
/// N, the statistic, and its interval's bounds.
type StatPoint = (f64, Option<f64>, Option<f64>, Option<f64>);

pub(super) const FONT: &str = "sans-serif";
/// Font sizes (px): a figure is at most ~1,000 px wide, so at 800 px shown it keeps ≥ 12 px.
pub(super) const TICK_FONT: u32 = 15;
pub(super) const AXIS_FONT: u32 = 16;
pub(super) const TITLE_FONT: u32 = 19;
static FONT_DATA: &[u8] = include_bytes!("DejaVuSans.ttf");

/// One figure, in both formats.
pub struct Figure {
    /// File stem in `report/`.
    pub name: String,
    pub caption: String,
    /// Points drawn as labelled curves (`#index` in the legend), for a table beside the figure.
    pub points: Vec<usize>,
    pub svg: String,
    pub png: Vec<u8>,
}

pub fn quality_colour(q: Quality) -> RGBColor {
    match q {
        Quality::Ideal => RGBColor(0, 140, 60),
        Quality::Inefficient => RGBColor(230, 140, 0),
        Quality::Unstable => RGBColor(200, 30, 30),
        Quality::Unknown => RGBColor(140, 140, 140),
    }
}

/// Distinct colours for a few curves.
fn series_colour(i: usize) -> RGBColor {
    const C: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
    C[i % C.len()]
}

/// Draw into an SVG string of `size`, then render it to PNG.
pub(super) fn figure(
    name: String,
    caption: String,
    size: (u32, u32),
    draw: impl FnOnce(&Area) -> Res<()>,
) -> Res<Figure> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
    }
    let png = to_png(&svg)?;
    Ok(Figure { name, caption, points: Vec::new(), svg, png })
}

/// Render SVG to PNG with the embedded font standing in for every generic family.
pub fn to_png(svg: &str) -> Res<Vec<u8>> {
    let mut opt = resvg::usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_font_data(FONT_DATA.to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    db.set_serif_family("DejaVu Sans");
    db.set_monospace_family("DejaVu Sans");
    opt.font_family = "DejaVu Sans".into();
    let tree = resvg::usvg::Tree::from_str(svg, &opt)?;
    let size = tree.size().to_int_size();
    let mut pix = resvg::tiny_skia::Pixmap::new(size.width(), size.height()).ok_or("empty figure")?;
    resvg::render(&tree, resvg::tiny_skia::Transform::default(), &mut pix.as_mut());
    Ok(pix.encode_png()?)
}

/// A tick label for a count: the integer, or nothing between integers.
fn integer(v: &f64) -> String {
    if (v - v.round()).abs() < 1e-6 {
        format!("{v:.0}")
    } else {
        String::new()
    }
}

/// A padded range around values, never empty.
pub(super) fn range(vals: impl IntoIterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.into_iter().filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = if hi > lo { 0.06 * (hi - lo) } else { 0.1 * lo.abs().max(1e-3) };
    (lo - pad, hi + pad)
}

pub(super) fn histogram(a: &Analysis, k: usize, members: &[usize]) -> Res<Figure> {
    let s = &a.spaces[k];
    let mfr: Vec<f64> = members.iter().filter_map(|&i| a.points[i].mfr()).collect();
    let top = a.points.iter().filter_map(|p| p.mfr()).fold(0.0f64, f64::max).max(1e-3);
    let bins = 30usize;
    let width = top * 1.0001 / bins as f64;
    let mut counts = vec![0usize; bins];
    for v in &mfr {
        counts[((v / width) as usize).min(bins - 1)] += 1;
    }
    let ymax = counts.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.1;
    let q = a.answer_name();
    let caption = format!("{q} distribution of {} (N = {}, {} with a value)", s.label, s.n, s.done);
    figure(format!("histogram-{}", k + 1), caption.clone(), (560, 380), |root| {
        let mut c = ChartBuilder::on(root)
            .caption(&caption, (FONT, AXIS_FONT))
            .margin(10)
            .x_label_area_size(46)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..top * 1.0001, 0.0..ymax)?;
        c.configure_mesh()
            .max_light_lines(0)
            .label_style((FONT, TICK_FONT))
            .axis_desc_style((FONT, AXIS_FONT))
            .x_desc(format!("{q} (–)"))
            .y_desc("runs")
            .y_label_formatter(&integer)
            .draw()?;
        c.draw_series(counts.iter().enumerate().map(|(b, &n)| {
            let x0 = b as f64 * width;
            Rectangle::new([(x0, 0.0), (x0 + width, n as f64)], RGBColor(31, 119, 180).mix(0.75).filled())
        }))?;
        Ok(())
    })
}

pub(super) fn statistics(a: &Analysis) -> Res<Figure> {
    let interval = if a.design.is_adaptive() {
        "the emulator's 95% posterior intervals"
    } else {
        "95% bootstrap intervals"
    };
    let q = a.answer_name();
    let caption = format!(
        "{q} statistics against N, with {interval}; band: ±{}% of the last value",
        a.criteria.tolerance * 100.0
    );
    let conv_n = a.verdict.n;
    let title = caption.clone();
    figure("statistics".into(), caption, (1000, 720), |root| {
        let root = root.titled(&title, (FONT, AXIS_FONT))?;
        let panels = root.split_evenly((2, 2));
        let (nlo, nhi) = range(a.spaces.iter().map(|s| s.n as f64));
        for (panel, st) in panels.iter().zip(STATISTICS) {
            let pts: Vec<StatPoint> = a
                .spaces
                .iter()
                .map(|s| {
                    let iv = s.intervals[st.name()];
                    (s.n as f64, st.of(&s.statistics), iv.lo, iv.hi)
                })
                .collect();
            let last = pts.iter().rev().find_map(|p| p.1);
            let band = last.map(|v| (v - a.criteria.tolerance * v.abs(), v + a.criteria.tolerance * v.abs()));
            let (ylo, yhi) = range(
                pts.iter()
                    .flat_map(|p| [p.1, p.2, p.3])
                    .flatten()
                    .chain(band.into_iter().flat_map(|(l, h)| [l, h])),
            );
            let unit =
                if st.name() == "std" || st.name() == "mean" { format!("{q} (–)") } else { "(–)".into() };
            let mut c = ChartBuilder::on(panel)
                .caption(
                    // A statistic the rule does not judge (`convergence.statistics`) says so.
                    format!(
                        "{} of {q}{}",
                        st.name(),
                        if a.criteria.judges(st) { "" } else { " (not judged)" }
                    ),
                    (FONT, AXIS_FONT),
                )
                .margin(10)
                .x_label_area_size(44)
                .y_label_area_size(72)
                .build_cartesian_2d(nlo..nhi, ylo..yhi)?;
            c.configure_mesh()
                .max_light_lines(0)
                .label_style((FONT, TICK_FONT))
                .axis_desc_style((FONT, AXIS_FONT))
                .y_desc(format!("{} {unit}", st.name()))
                .x_desc("N (runs in the space)")
                .x_label_formatter(&integer)
                .draw()?;
            if let Some((l, h)) = band {
                c.draw_series(std::iter::once(Rectangle::new(
                    [(nlo, l), (nhi, h)],
                    RGBColor(44, 160, 44).mix(0.15).filled(),
                )))?;
            }
            if let Some(n) = conv_n {
                c.draw_series(std::iter::once(PathElement::new(
                    vec![(n as f64, ylo), (n as f64, yhi)],
                    RGBColor(44, 160, 44).stroke_width(2),
                )))?;
            }
            let blue = RGBColor(31, 119, 180);
            c.draw_series(pts.iter().filter_map(|p| {
                Some(PathElement::new(vec![(p.0, p.2?), (p.0, p.3?)], blue.stroke_width(2)))
            }))?;
            c.draw_series(LineSeries::new(pts.iter().filter_map(|p| Some((p.0, p.1?))), blue))?;
            c.draw_series(pts.iter().filter_map(|p| Some(Circle::new((p.0, p.1?), 4, blue.filled()))))?;
        }
        Ok(())
    })
}

pub(super) fn scatter(a: &Analysis) -> Res<Figure> {
    let d = a.parameters.len();
    let cols = if d == 1 { 1 } else { 2 };
    let rows = d.div_ceil(cols);
    // Screened points at MFR = 0, grey (no v_x profile).
    let done: Vec<(&PointRow, f64, Quality)> = a
        .points
        .iter()
        .filter_map(|p| p.mfr().map(|m| (p, m, p.done().map_or(Quality::Unknown, |(_, q)| q))))
        .collect();
    let (mlo, mhi) = range(done.iter().map(|p| p.1));
    let name = a.answer_name();
    // Coloured by v_x class only where points have one (a layers sweep measures no v_x).
    let classed = done.iter().any(|p| p.2 != Quality::Unknown);
    let caption = if classed {
        format!(
            "{name} against each parameter; colour: spreading quality (green ideal, orange inefficient, red \
             unstable, grey unknown or screened)"
        )
    } else {
        format!("{name} against each parameter")
    };
    let radius = if done.len() > 2000 { 2 } else { 3 };
    let classes = [Quality::Ideal, Quality::Inefficient, Quality::Unstable, Quality::Unknown];
    figure("scatter".into(), caption, (480 * cols as u32, 330 * rows as u32 + 70), |root| {
        let root = root.titled(&format!("{name} against each swept parameter"), (FONT, TITLE_FONT))?;
        let h = root.dim_in_pixel().1;
        let (grid, legend) = root.split_vertically(h - 36);
        let style = (FONT, AXIS_FONT).into_font().color(&BLACK);
        for (n, q) in classes.iter().enumerate().filter(|_| classed) {
            let x = 20 + 180 * n as i32;
            legend.draw(&Circle::new((x + 6, 12), 5, quality_colour(*q).filled()))?;
            legend.draw(&Text::new(q.as_str(), (x + 16, 2), style.clone()))?;
        }
        let panels = grid.split_evenly((rows, cols));
        for (j, panel) in panels.iter().enumerate().take(d) {
            let (xlo, xhi) = range(done.iter().map(|p| p.0.values[j]));
            let mut c = ChartBuilder::on(panel)
                .margin(10)
                .x_label_area_size(46)
                .y_label_area_size(62)
                .build_cartesian_2d(xlo..xhi, mlo..mhi)?;
            c.configure_mesh()
                .max_light_lines(0)
                .label_style((FONT, TICK_FONT))
                .axis_desc_style((FONT, AXIS_FONT))
                .x_desc(format!("{} ({})", a.parameters[j], a.units[j]))
                .y_desc(format!("{name} (–)"))
                .draw()?;
            c.draw_series(
                done.iter().map(|p| {
                    Circle::new((p.0.values[j], p.1), radius, quality_colour(p.2).mix(0.6).filled())
                }),
            )?;
        }
        Ok(())
    })
}

/// Layer heights above the gap, in diameters: k·D/2 → k/2.
fn layer_height(k: usize) -> f64 {
    (k + 1) as f64 / 2.0
}

/// Lines of legend below a profile panel.
const PROFILE_LEGEND_LINES: u32 = 4;

/// One panel of v_x profiles: v_x / blade speed against layer height, one curve per point,
/// and its legend below the axes (never over the curves).
fn profile_panel(panel: &Area, title: &str, curves: &[(String, RGBColor, Vec<Option<f64>>, f64)]) -> Res<()> {
    let h = panel.dim_in_pixel().1;
    let (plot, legend) = panel.split_vertically(h - 22 * PROFILE_LEGEND_LINES - 8);
    let (xlo, xhi) =
        range(curves.iter().flat_map(|c| c.2.iter().flatten().map(move |v| v / c.3)).chain([0.8, 1.0]));
    let mut ch = ChartBuilder::on(&plot)
        .caption(title, (FONT, AXIS_FONT))
        .margin(8)
        .x_label_area_size(44)
        .y_label_area_size(56)
        .build_cartesian_2d(xlo..xhi, 0.0..layer_height(VX_LAYERS - 1) + 0.5)?;
    ch.configure_mesh()
        .max_light_lines(0)
        .x_labels(5)
        .label_style((FONT, TICK_FONT))
        .axis_desc_style((FONT, AXIS_FONT))
        .x_desc("v_x / blade speed (–)")
        .y_desc("height above gap (D)")
        .draw()?;
    let style = (FONT, TICK_FONT).into_font().color(&BLACK);
    for (n, (label, colour, vx, v)) in curves.iter().enumerate() {
        let pts: Vec<(f64, f64)> =
            vx.iter().enumerate().filter_map(|(k, x)| x.map(|x| (x / v, layer_height(k)))).collect();
        let col = *colour;
        ch.draw_series(LineSeries::new(pts.clone(), col.stroke_width(2)))?;
        ch.draw_series(pts.iter().map(|p| Circle::new(*p, 3, col.filled())))?;
        if (n as u32) < PROFILE_LEGEND_LINES {
            let y = 4 + 22 * n as i32;
            legend.draw(&PathElement::new(vec![(12, y + 8), (34, y + 8)], col.stroke_width(3)))?;
            legend.draw(&Text::new(label.clone(), (40, y), style.clone()))?;
        }
    }
    Ok(())
}

/// Per class, the points the profile figure shows: the best four ideal ones by MFR; for the
/// other classes four spread over the class's MFR range.
fn chosen_profiles(a: &Analysis, q: Quality) -> (usize, Vec<&PointRow>) {
    let mut pts: Vec<(&PointRow, f64)> = a
        .points
        .iter()
        .filter_map(|p| p.done().filter(|(_, pq)| *pq == q).map(|(r, _)| (p, r.answer.value)))
        .collect();
    pts.sort_by(|x, y| y.1.total_cmp(&x.1));
    let chosen = if q == Quality::Ideal || pts.len() <= 4 {
        pts.iter().take(4).map(|p| p.0).collect()
    } else {
        (0..4).map(|i| pts[i * (pts.len() - 1) / 3].0).collect()
    };
    (pts.len(), chosen)
}

pub(super) fn profiles(a: &Analysis) -> Res<Figure> {
    let classes = [Quality::Ideal, Quality::Inefficient, Quality::Unstable];
    let shown: Vec<usize> =
        classes.iter().flat_map(|&q| chosen_profiles(a, q).1.into_iter().map(|p| p.index)).collect();
    let caption = "v_x profiles in front of the blade (thesis Fig. 4.2): per class, up to four \
                   points spread over its MFR range (ideal: the best by MFR)"
        .to_string();
    figure("profiles".into(), caption, (1000, 560), |root| {
        let root = root.titled("v_x profiles in front of the blade, per class", (FONT, TITLE_FONT))?;
        let panels = root.split_evenly((1, 3));
        for (panel, q) in panels.iter().zip(classes) {
            let (count, chosen) = chosen_profiles(a, q);
            let curves: Vec<_> = chosen
                .iter()
                .enumerate()
                .filter_map(|(i, p)| {
                    let (r, _) = p.done()?;
                    let mfr = r.answer.value;
                    let v = r.parameters.get("blade_speed").copied().unwrap_or(1.0);
                    Some((format!("#{} MFR {:.3}", p.index, mfr), series_colour(i), r.vx.clone(), v))
                })
                .collect();
            profile_panel(panel, &format!("{} ({count} points)", q.as_str()), &curves)?;
        }
        Ok(())
    })
    .map(|f| Figure { points: shown, ..f })
}

/// The one-factor panels of the last complete lattice level with at least 3 values per
/// dimension: for each ordered pair (A, B), v_x profiles as A varies, in panels at the lowest,
/// middle and highest level of B, the other parameters at their middle level.
pub(super) fn lattice_panels(a: &Analysis) -> Res<Vec<Figure>> {
    let d = a.parameters.len();
    if d < 2 || !matches!(a.design, crate::store::DesignRecord::Lattice { .. }) {
        return Ok(Vec::new());
    }
    let Some(space) = a.spaces.iter().rev().find(|s| {
        let l = (s.n as f64).powf(1.0 / d as f64).round() as usize;
        l >= 3
    }) else {
        return Ok(Vec::new());
    };
    let members: Vec<&PointRow> = space.members.iter().map(|&i| &a.points[i]).collect();
    // Level index of each point in each dimension.
    let levels: Vec<Vec<f64>> = (0..d)
        .map(|j| {
            let mut v: Vec<f64> = members.iter().map(|p| p.values[j]).collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        })
        .collect();
    let idx = |j: usize, x: f64| levels[j].iter().position(|&l| l == x).unwrap_or(0);
    let by_coords: HashMap<Vec<usize>, &PointRow> =
        members.iter().map(|p| ((0..d).map(|j| idx(j, p.values[j])).collect(), *p)).collect();
    let mid: Vec<usize> = levels.iter().map(|l| (l.len() - 1) / 2).collect();
    let mut out = Vec::new();
    for va in 0..d {
        for vb in 0..d {
            if va == vb {
                continue;
            }
            let (na, nb) = (&a.parameters[va], &a.parameters[vb]);
            let lb = levels[vb].len();
            let b_levels = [0, (lb - 1) / 2, lb - 1];
            let others: Vec<String> = (0..d)
                .filter(|&j| j != va && j != vb)
                .map(|j| format!("{} = {}", a.parameters[j], fmt_short(levels[j][mid[j]])))
                .collect();
            let caption = format!(
                "v_x profiles as {na} varies, panels at three levels of {nb} ({}; {})",
                space.label,
                if others.is_empty() { "no other parameters".into() } else { others.join(", ") }
            );
            let title = format!("v_x profiles as {na} varies, at three levels of {nb}");
            out.push(figure(format!("lattice-{na}-by-{nb}"), caption, (1000, 560), |root| {
                let root = root.titled(&title, (FONT, TITLE_FONT))?;
                let panels = root.split_evenly((1, 3));
                for (panel, &ib) in panels.iter().zip(&b_levels) {
                    let curves: Vec<_> = (0..levels[va].len())
                        .filter_map(|ia| {
                            let mut c = mid.clone();
                            c[va] = ia;
                            c[vb] = ib;
                            let p = by_coords.get(&c)?;
                            let (r, q) = p.done()?;
                            let v = r.parameters.get("blade_speed").copied().unwrap_or(1.0);
                            Some((
                                format!(
                                    "{} {}: MFR {:.3}",
                                    fmt_short(levels[va][ia]),
                                    q.as_str(),
                                    r.answer.value
                                ),
                                series_colour(ia),
                                r.vx.clone(),
                                v,
                            ))
                        })
                        .collect();
                    let a_unit = &a.units[vb];
                    profile_panel(panel, &format!("{nb} = {} {a_unit}", fmt_short(levels[vb][ib])), &curves)?;
                }
                Ok(())
            })?);
        }
    }
    Ok(out)
}
