//! Maps over pairs of swept parameters: a measure (MFR, or a layer-quality measure) on a grid
//! of the pair, with the zero-MFR region drawn and the points overlaid; and the failure map,
//! where the failed points fall.
//!
//! From the points, a cell's value is the mean of the points that fall in it, whatever their
//! other parameters (a marginal mean: the other parameters are averaged over as the design
//! spreads them). A cell is in the zero-MFR region when every point in it passed nothing. A
//! surface (an emulator's prediction at the cell's centre, the other parameters at the middle
//! of their ranges) can stand in for the points through [`CellValue`].

use plotters::prelude::*;

use super::plots::{fmt_short, Area, Figure, Res, AXIS_FONT, FONT, TICK_FONT, TITLE_FONT};
use super::{Analysis, PointRow, PointState};

/// A point's value on a map: `None` where the point has none (failed, pending, not measured).
pub type Measure<'a> = &'a dyn Fn(&PointRow) -> Option<f64>;

/// How a cell gets its value: from the points inside it (`members`), or from a surface at the
/// cell's centre (`centre`: every swept parameter).
pub enum CellValue<'a> {
    Points,
    #[expect(dead_code, reason = "the emulator's hook: its predictions fill the cells once a sweep has one")]
    Surface(&'a dyn Fn(&[f64]) -> Option<f64>),
}

/// What a map shows.
pub struct MapSpec<'a> {
    /// File-name stem: `map-<stem>-<A>-<B>`.
    pub stem: &'a str,
    /// The measure in words with its unit, e.g. "MFR (–)".
    pub label: &'a str,
    pub value: Measure<'a>,
    pub cells: CellValue<'a>,
}

const ZERO: RGBColor = RGBColor(200, 200, 200);
const FAILED: RGBColor = RGBColor(215, 25, 28);

/// Viridis, by linear interpolation between five of its colours; `t` in [0, 1].
pub(super) fn viridis(t: f64) -> RGBColor {
    const C: [(f64, f64, f64); 5] =
        [(68., 1., 84.), (59., 82., 139.), (33., 145., 140.), (94., 201., 98.), (253., 231., 37.)];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * 4.0;
    let k = (t.floor() as usize).min(3);
    let f = t - k as f64;
    let mix = |a: f64, b: f64| (a + f * (b - a)).round() as u8;
    RGBColor(mix(C[k].0, C[k + 1].0), mix(C[k].1, C[k + 1].1), mix(C[k].2, C[k + 1].2))
}

/// The cell edges of one parameter: for a lattice, one cell per level (edges halfway between
/// levels); otherwise `n` equal cells over the points' range.
fn edges(values: &[f64], n: usize, lattice: bool) -> Vec<f64> {
    let mut levels: Vec<f64> = values.to_vec();
    levels.sort_by(f64::total_cmp);
    levels.dedup();
    let (lo, hi) = (levels[0], levels[levels.len() - 1]);
    if levels.len() == 1 || (lattice && levels.len() <= 12) {
        if levels.len() == 1 {
            let w = 0.1 * lo.abs().max(1e-3);
            return vec![lo - w, lo + w];
        }
        let mut e = vec![levels[0] - 0.5 * (levels[1] - levels[0])];
        e.extend(levels.windows(2).map(|w| 0.5 * (w[0] + w[1])));
        let k = levels.len();
        e.push(levels[k - 1] + 0.5 * (levels[k - 1] - levels[k - 2]));
        return e;
    }
    (0..=n).map(|i| lo + (hi - lo) * i as f64 / n as f64).collect()
}

fn cell_of(edges: &[f64], x: f64) -> usize {
    edges[1..edges.len() - 1].iter().take_while(|&&e| x >= e).count()
}

/// Cells per axis for scattered points: about three points per cell, 3 to 10 cells.
fn cells_for(n: usize) -> usize {
    ((n as f64 / 3.0).sqrt().round() as usize).clamp(3, 10)
}

/// Every ordered pair (i < j) of swept parameters.
pub fn pairs(d: usize) -> Vec<(usize, usize)> {
    (0..d).flat_map(|i| (i + 1..d).map(move |j| (i, j))).collect()
}

/// One map per pair of swept parameters. None when no point has a value.
pub fn pair_maps(a: &Analysis, spec: &MapSpec) -> Res<Vec<Figure>> {
    let valued: Vec<(&PointRow, f64)> =
        a.points.iter().filter_map(|p| (spec.value)(p).map(|v| (p, v))).collect();
    if valued.is_empty() || a.parameters.len() < 2 {
        return Ok(Vec::new());
    }
    let (vlo, vhi) =
        valued.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p.1), h.max(p.1)));
    let vhi = if vhi > vlo { vhi } else { vlo + 1e-3 };
    let mut out = Vec::new();
    for (i, j) in pairs(a.parameters.len()) {
        out.push(pair_map(a, spec, &valued, (i, j), (vlo, vhi))?);
    }
    Ok(out)
}

fn axis_label(a: &Analysis, k: usize) -> String {
    format!("{} ({})", a.parameters[k], a.units[k])
}

fn pair_map(
    a: &Analysis,
    spec: &MapSpec,
    valued: &[(&PointRow, f64)],
    (i, j): (usize, usize),
    (vlo, vhi): (f64, f64),
) -> Res<Figure> {
    let all: Vec<&PointRow> = a.points.iter().filter(|p| !matches!(p.state, PointState::Pending)).collect();
    let n = cells_for(valued.len());
    let xi: Vec<f64> = all.iter().map(|p| p.values[i]).collect();
    let xj: Vec<f64> = all.iter().map(|p| p.values[j]).collect();
    let lattice = matches!(a.design, crate::store::DesignRecord::Lattice { .. });
    let (ex, ey) = (edges(&xi, n, lattice), edges(&xj, n, lattice));
    let (nx, ny) = (ex.len() - 1, ey.len() - 1);
    // Per cell: sum, count, and whether every point in it had MFR = 0.
    let mut sum = vec![vec![0.0; ny]; nx];
    let mut cnt = vec![vec![0usize; ny]; nx];
    let mut zero = vec![vec![true; ny]; nx];
    let mut any_mfr = vec![vec![false; ny]; nx];
    for (p, v) in valued {
        let (cx, cy) = (cell_of(&ex, p.values[i]), cell_of(&ey, p.values[j]));
        sum[cx][cy] += v;
        cnt[cx][cy] += 1;
    }
    for p in &a.points {
        if let Some(m) = p.mfr() {
            let (cx, cy) = (cell_of(&ex, p.values[i]), cell_of(&ey, p.values[j]));
            any_mfr[cx][cy] = true;
            zero[cx][cy] &= m <= 0.0;
        }
    }
    let mid: Vec<f64> = (0..a.parameters.len())
        .map(|k| {
            let v = a.points.iter().map(|p| p.values[k]);
            let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| (l.min(x), h.max(x)));
            0.5 * (lo + hi)
        })
        .collect();
    let cell = |cx: usize, cy: usize| -> Option<f64> {
        match &spec.cells {
            CellValue::Points => (cnt[cx][cy] > 0).then(|| sum[cx][cy] / cnt[cx][cy] as f64),
            CellValue::Surface(f) => {
                let mut x = mid.clone();
                x[i] = 0.5 * (ex[cx] + ex[cx + 1]);
                x[j] = 0.5 * (ey[cy] + ey[cy + 1]);
                f(&x)
            }
        }
    };
    let (pi, pj) = (&a.parameters[i], &a.parameters[j]);
    let name = format!("map-{}-{pi}-{pj}", spec.stem);
    let how = match spec.cells {
        CellValue::Points => "cell: mean of the points in it",
        CellValue::Surface(_) => "emulator at the cell centre, other parameters mid-range",
    };
    let title = format!("{} over {pi} × {pj}", spec.label);
    let caption = format!(
        "{title} ({how}); grey: every point's {} = 0 (nothing passed); dots: points; red ×: failed runs",
        a.answer_name()
    );
    super::plots::figure(name, caption, (640, 470), |root| {
        let root = root.titled(&title, (FONT, TITLE_FONT))?;
        let (chart_area, bar_area) = root.split_horizontally(540);
        let mut c = ChartBuilder::on(&chart_area)
            .margin(8)
            .x_label_area_size(48)
            .y_label_area_size(62)
            .build_cartesian_2d(ex[0]..ex[nx], ey[0]..ey[ny])?;
        c.configure_mesh()
            .disable_mesh()
            .label_style((FONT, TICK_FONT))
            .axis_desc_style((FONT, AXIS_FONT))
            .x_desc(axis_label(a, i))
            .y_desc(axis_label(a, j))
            .x_label_formatter(&|v| fmt_short(*v))
            .y_label_formatter(&|v| fmt_short(*v))
            .draw()?;
        for cx in 0..nx {
            for cy in 0..ny {
                let r = [(ex[cx], ey[cy]), (ex[cx + 1], ey[cy + 1])];
                let colour = if any_mfr[cx][cy] && zero[cx][cy] {
                    Some(ZERO)
                } else {
                    cell(cx, cy).map(|v| viridis((v - vlo) / (vhi - vlo)))
                };
                if let Some(col) = colour {
                    c.draw_series(std::iter::once(Rectangle::new(r, col.filled())))?;
                }
            }
        }
        // Points: the design where it was run; failed ones as red crosses.
        c.draw_series(
            all.iter()
                .filter(|p| !matches!(p.state, PointState::Failed { .. }))
                .map(|p| Circle::new((p.values[i], p.values[j]), 2, BLACK.mix(0.6).filled())),
        )?;
        c.draw_series(
            all.iter()
                .filter(|p| matches!(p.state, PointState::Failed { .. }))
                .map(|p| Cross::new((p.values[i], p.values[j]), 5, FAILED.stroke_width(2))),
        )?;
        colour_bar(&bar_area, spec.label, vlo, vhi)
    })
}

/// A vertical colour bar with its range, in its own area beside the chart.
fn colour_bar(area: &Area, label: &str, lo: f64, hi: f64) -> Res<()> {
    let h = area.dim_in_pixel().1;
    let (top, bottom) = (66i32, h as i32 - 70);
    let x0 = 12i32;
    let steps = 60;
    for s in 0..steps {
        let t = s as f64 / (steps - 1) as f64;
        let y1 = bottom - ((bottom - top) as f64 * (s as f64 + 1.0) / steps as f64) as i32;
        let y0 = bottom - ((bottom - top) as f64 * s as f64 / steps as f64) as i32;
        area.draw(&Rectangle::new([(x0, y1), (x0 + 18, y0)], viridis(t).filled()))?;
    }
    let style = (FONT, TICK_FONT).into_font().color(&BLACK);
    area.draw(&Text::new(fmt_short(hi), (x0 + 22, top - 6), style.clone()))?;
    area.draw(&Text::new(fmt_short(lo), (x0 + 22, bottom - 8), style.clone()))?;
    // The label in lines of a word or two, to fit the bar's column.
    let mut lines: Vec<String> = Vec::new();
    for w in label.split_whitespace() {
        match lines.last_mut() {
            Some(l) if l.len() + w.len() < 10 => {
                l.push(' ');
                l.push_str(w);
            }
            _ => lines.push(w.to_string()),
        }
    }
    for (k, l) in lines.iter().enumerate() {
        area.draw(&Text::new(l.clone(), (2, 4 + 16 * k as i32), style.clone()))?;
    }
    area.draw(&Rectangle::new([(x0, bottom + 14), (x0 + 18, bottom + 30)], ZERO.filled()))?;
    area.draw(&Text::new("= 0", (x0 + 22, bottom + 14), style))?;
    Ok(())
}

/// Where the failed points fall: one panel per pair of swept parameters (one axis when the
/// sweep has one parameter), every finished point in grey, the failed ones coloured by class.
pub fn failure_map(a: &Analysis) -> Res<Option<Figure>> {
    let failed: Vec<(&PointRow, &str)> = a
        .points
        .iter()
        .filter_map(|p| match &p.state {
            PointState::Failed { class, .. } => Some((p, class.as_str())),
            _ => None,
        })
        .collect();
    if failed.is_empty() {
        return Ok(None);
    }
    let mut classes: Vec<&str> = failed.iter().map(|f| f.1).collect();
    classes.sort();
    classes.dedup();
    let d = a.parameters.len();
    let panels: Vec<(usize, usize)> = if d == 1 { vec![(0, 0)] } else { pairs(d) };
    let cols = panels.len().min(2);
    let rows = panels.len().div_ceil(cols);
    let legend_h = 34 + 24 * classes.len().div_ceil(2) as u32;
    let size = (440 * cols as u32, 380 * rows as u32 + legend_h);
    let title = format!("Where the {} failed run(s) fall", failed.len());
    let caption = format!(
        "{title}: failed points coloured by class over every pair of swept parameters; grey: finished points"
    );
    let colour = |c: &str| -> RGBColor {
        const C: [RGBColor; 6] = [
            RGBColor(215, 25, 28),
            RGBColor(253, 174, 97),
            RGBColor(44, 123, 182),
            RGBColor(128, 0, 128),
            RGBColor(0, 150, 150),
            RGBColor(90, 90, 90),
        ];
        C[classes.iter().position(|k| *k == c).unwrap_or(0) % C.len()]
    };
    let range = |k: usize| super::plots::range(a.points.iter().map(|p| p.values[k]));
    super::plots::figure("failures".into(), caption, size, |root| {
        let root = root.titled(&title, (FONT, TITLE_FONT))?;
        let (h, _) = (root.dim_in_pixel().1, 0);
        let (grid, legend) = root.split_vertically(h - legend_h);
        for (panel, &(i, j)) in grid.split_evenly((rows, cols)).iter().zip(&panels) {
            let (x0, x1) = range(i);
            let (y0, y1) = if d == 1 { (0.0, 1.0) } else { range(j) };
            let y = |p: &PointRow| if d == 1 { 0.5 } else { p.values[j] };
            let mut c = ChartBuilder::on(panel)
                .margin(8)
                .x_label_area_size(46)
                .y_label_area_size(if d == 1 { 10 } else { 62 })
                .build_cartesian_2d(x0..x1, y0..y1)?;
            let mut mesh = c.configure_mesh();
            mesh.max_light_lines(0)
                .label_style((FONT, TICK_FONT))
                .axis_desc_style((FONT, AXIS_FONT))
                .x_desc(axis_label(a, i))
                .x_label_formatter(&|v| fmt_short(*v));
            if d > 1 {
                mesh.y_desc(axis_label(a, j)).y_label_formatter(&|v| fmt_short(*v));
            } else {
                mesh.disable_y_axis();
            }
            mesh.draw()?;
            c.draw_series(
                a.points
                    .iter()
                    .filter(|p| !matches!(p.state, PointState::Failed { .. } | PointState::Pending))
                    .map(|p| Circle::new((p.values[i], y(p)), 2, RGBColor(160, 160, 160).filled())),
            )?;
            c.draw_series(
                failed.iter().map(|(p, k)| Cross::new((p.values[i], y(p)), 6, colour(k).stroke_width(2))),
            )?;
        }
        let style = (FONT, AXIS_FONT).into_font().color(&BLACK);
        for (n, k) in classes.iter().enumerate() {
            let (cx, cy) = (20 + 300 * (n % 2) as i32, 10 + 24 * (n / 2) as i32);
            legend.draw(&Cross::new((cx + 6, cy + 9), 6, colour(k).stroke_width(2)))?;
            let count = failed.iter().filter(|f| f.1 == *k).count();
            legend.draw(&Text::new(format!("{k} ({count})"), (cx + 20, cy), style.clone()))?;
        }
        Ok(())
    })
    .map(Some)
}
