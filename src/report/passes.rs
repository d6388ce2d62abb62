//! The figures of a sweep whose points run pass by pass (a layers sweep): each point's answer
//! and covered fraction pass by pass, and a top view of the layer each point's last pass left.

use plotters::prelude::*;

use super::plots::{figure, Figure, Res, AXIS_FONT, FONT, TICK_FONT, TITLE_FONT};
use super::{Analysis, PointRow};
use crate::scenes::figures::{PassSeries, TopView};
use crate::scenes::Layout;

/// Panels of the pass figure side by side, and the top views' width, px.
const COLUMNS: usize = 3;
const STRIP_WIDTH: u32 = 960;
/// A top view's colours span this many diameters about the layer's median top.
const HEIGHT_SPAN_D: f64 = 1.0;

/// The point by its swept values, in the order of the sweep's parameters: "#3: 0.1 m/s, 0.055 mm"
/// (`long` names each parameter too).
fn label(a: &Analysis, p: &PointRow, long: bool) -> String {
    let values: Vec<String> = a
        .parameters
        .iter()
        .zip(&a.units)
        .zip(&p.values)
        .map(|((n, u), v)| {
            let value = format!("{} {u}", super::plots::fmt_short(*v));
            if long {
                format!("{n} {value}")
            } else {
                value
            }
        })
        .collect();
    format!("#{}: {}", p.index, values.join(", "))
}

/// Both figures, for a sweep whose layout gives them; none otherwise.
pub fn draw(a: &Analysis) -> Res<Vec<Figure>> {
    let Ok(layout) = crate::scenes::of(&a.setup.scene) else { return Ok(Vec::new()) };
    let series: Vec<(&PointRow, PassSeries)> =
        a.points.iter().filter_map(|p| Some((p, layout.pass_series(p.done()?.0)?))).collect();
    if series.is_empty() {
        return Ok(Vec::new());
    }
    let mut out = vec![pass_figure(a, &series)?];
    out.extend(top_views(a, layout, &series)?);
    Ok(out)
}

fn pass_figure(a: &Analysis, series: &[(&PointRow, PassSeries)]) -> Res<Figure> {
    let name = a.answer_name();
    let caption = format!(
        "Each done point pass by pass: its {name} (blue; hollow: the passes that searched for the \
         steady state), its covered fraction (orange), and the steady layer's mean (thin line) ± SE (band) over \
         the passes it was read from"
    );
    let rows = series.len().div_ceil(COLUMNS);
    let cols = series.len().min(COLUMNS);
    let last = series.iter().flat_map(|(_, s)| s.passes.iter().map(|p| p.0)).max().unwrap_or(1) as f64;
    let blue = RGBColor(31, 119, 180);
    let orange = RGBColor(255, 127, 14);
    figure("passes".into(), caption, (330 * cols as u32, 250 * rows as u32 + 40), |root| {
        let root = root.titled(&format!("{name} and covered fraction, pass by pass"), (FONT, TITLE_FONT))?;
        for (panel, (p, s)) in root.split_evenly((rows, cols)).iter().zip(series) {
            let mut c = ChartBuilder::on(panel)
                .caption(label(a, p, false), (FONT, AXIS_FONT))
                .margin(8)
                .x_label_area_size(40)
                .y_label_area_size(48)
                .build_cartesian_2d(0.5..last + 0.5, 0.0..1.05)?;
            c.configure_mesh()
                .max_light_lines(0)
                .x_labels(8)
                .y_labels(6)
                .label_style((FONT, TICK_FONT))
                .axis_desc_style((FONT, AXIS_FONT))
                .x_desc("pass")
                .x_label_formatter(&|k| format!("{k:.0}"))
                .draw()?;
            let end = s.passes.last().map_or(1, |q| q.0) as f64;
            let (m, se) = s.steady;
            if m.is_finite() && se.is_finite() {
                c.draw_series([Rectangle::new(
                    [(s.steady_from as f64 - 0.5, m - se), (end + 0.5, m + se)],
                    blue.mix(0.2).filled(),
                )])?;
                c.draw_series(LineSeries::new(
                    [(s.steady_from as f64 - 0.5, m), (end + 0.5, m)],
                    blue.mix(0.6).stroke_width(1),
                ))?;
            }
            c.draw_series(LineSeries::new(
                s.passes.iter().map(|q| (q.0 as f64, q.2)),
                orange.stroke_width(2),
            ))?;
            c.draw_series(LineSeries::new(s.passes.iter().map(|q| (q.0 as f64, q.1)), blue.stroke_width(2)))?;
            c.draw_series(s.passes.iter().map(|q| {
                let style = if q.0 <= s.search_passes { blue.stroke_width(2) } else { blue.filled() };
                Circle::new((q.0 as f64, q.1), 4, style)
            }))?;
        }
        Ok(())
    })
}

/// A colour for a height about the median, `span` either way: blue low, white level, red high.
fn height_colour(h: f64, span: f64) -> RGBColor {
    let t = (h / span).clamp(-1.0, 1.0);
    let mix = |a: u8, b: u8, f: f64| (a as f64 + (b as f64 - a as f64) * f).round() as u8;
    if t < 0.0 {
        RGBColor(mix(255, 33, -t), mix(255, 102, -t), mix(255, 172, -t))
    } else {
        RGBColor(mix(255, 178, t), mix(255, 24, t), mix(255, 43, t))
    }
}

fn top_views(a: &Analysis, layout: &dyn Layout, series: &[(&PointRow, PassSeries)]) -> Res<Option<Figure>> {
    let mut views: Vec<(String, TopView, f64)> = Vec::new();
    let mut missing: Vec<String> = Vec::new();
    for (p, _) in series {
        let Some((r, _)) = p.done() else { continue };
        let scene = match crate::scenes::build(&r.parameters, &a.setup.scene) {
            Ok(s) => s,
            Err(e) => {
                missing.push(format!("#{}: {e}", p.index));
                continue;
            }
        };
        match layout.top_view(&scene, &a.dir.join("runs").join(&p.hash), r) {
            Some(Ok(v)) => views.push((label(a, p, true), v, scene.diameter)),
            Some(Err(e)) => missing.push(format!("#{}: {e}", p.index)),
            None => {}
        }
    }
    let Some((_, first, _)) = views.first() else { return Ok(None) };
    let scale = |v: &TopView| STRIP_WIDTH as f64 / (v.x.1 - v.x.0);
    let strip = (((first.y.1 - first.y.0) * scale(first)).round() as u32).max(24);
    // Room above and below a strip for what a disc centred past its edge reaches (a diameter), covered.
    let overhang = views
        .iter()
        .flat_map(|(_, v, _)| v.discs.iter().map(|d| (2.0 * d.r * scale(v)).ceil() as u32))
        .max()
        .unwrap_or(0);
    let row = strip + 2 * overhang + 30;
    let mut caption = format!(
        "The layer each point's last pass left, seen from above over the plate (travel left to right): \
         every particle over it, the highest on top, coloured by its top's height about the median of \
         the pass's own particles (blue {span} D below, white level, red {span} D above); grey: the \
         bed below showing through",
        span = HEIGHT_SPAN_D
    );
    if !missing.is_empty() {
        caption.push_str(&format!("; not drawn: {}", missing.join("; ")));
    }
    let height = row * views.len() as u32 + 50;
    let fig = figure("top-view".into(), caption, (STRIP_WIDTH + 40, height), |root| {
        let root = root.titled("The last pass's layer, from above", (FONT, TITLE_FONT))?;
        let style = (FONT, TICK_FONT).into_font().color(&BLACK);
        let white = WHITE.filled();
        let width = STRIP_WIDTH as i32;
        for (i, (text, v, d)) in views.iter().enumerate() {
            let top = (row * i as u32) as i32;
            let scale = scale(v);
            let depth = v.y.1 - v.y.0;
            let h = (depth * scale).round() as i32;
            let origin = (20, top + overhang as i32 + 24);
            root.draw(&Rectangle::new(
                [origin, (origin.0 + width, origin.1 + h)],
                RGBColor(250, 250, 245).filled(),
            ))?;
            for disc in &v.discs {
                if disc.x + disc.r < v.x.0 || disc.x - disc.r > v.x.1 {
                    continue;
                }
                let colour =
                    disc.height.map_or(RGBColor(170, 170, 170), |z| height_colour(z, HEIGHT_SPAN_D * d));
                let radius = ((disc.r * scale).round() as i32).max(1);
                // The periodic images across the strip's two long edges.
                for shift in [-depth, 0.0, depth] {
                    let y = disc.y - v.y.0 + shift;
                    if y + disc.r < 0.0 || y - disc.r > depth {
                        continue;
                    }
                    let centre = (
                        origin.0 + ((disc.x - v.x.0) * scale).round() as i32,
                        origin.1 + h - (y * scale).round() as i32,
                    );
                    root.draw(&Circle::new(centre, radius, colour.filled()))?;
                    root.draw(&Circle::new(centre, radius, RGBColor(90, 90, 90).stroke_width(1)))?;
                }
            }
            // What lies past the strip's edges is covered, then the label and frame drawn.
            root.draw(&Rectangle::new([(0, top), (width + 40, origin.1)], white))?;
            root.draw(&Rectangle::new(
                [(0, origin.1 + h), (width + 40, origin.1 + h + overhang as i32 + 1)],
                white,
            ))?;
            root.draw(&Rectangle::new([(0, origin.1), (origin.0, origin.1 + h)], white))?;
            root.draw(&Rectangle::new([(origin.0 + width, origin.1), (width + 40, origin.1 + h)], white))?;
            root.draw(&Text::new(
                format!("{text} — pass {}, {:.2} × {:.2} mm", v.pass, (v.x.1 - v.x.0) * 1e3, depth * 1e3),
                (20, origin.1 - 20),
                style.clone(),
            ))?;
            root.draw(&Rectangle::new([origin, (origin.0 + width, origin.1 + h)], BLACK.stroke_width(1)))?;
        }
        Ok(())
    })?;
    Ok(Some(fig))
}
