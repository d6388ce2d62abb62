//! The calibration's figures: a map of the posterior density over each pair of free parameters
//! (the others at their posterior medians), with the runs, the posterior's mode and the credible
//! intervals drawn.

use plotters::prelude::*;

use super::plots::{Figure, Res, AXIS_FONT, FONT, TICK_FONT, TITLE_FONT};
use crate::analysis::calibration::{log_density, Emulated};
use crate::run::calibrate::{unit_value, CalibrationWatch};
use crate::scene::plausible::round_to;
use crate::store::{Manifest, PointStatus};
use crate::sweep::Sweep;

/// Cells per side of a map.
const CELLS: usize = 60;

/// The posterior maps: one per pair of free parameters, on the last batch's emulators; for one
/// free parameter, its curve ([`curve`]).
pub fn maps(
    sweep: &Sweep,
    watch: &CalibrationWatch,
    manifest: &Manifest,
    status: &[PointStatus],
) -> Res<Vec<Figure>> {
    let Some(post) = watch.batches.iter().rev().find_map(|b| b.posterior.as_ref()) else {
        return Ok(Vec::new());
    };
    let d = sweep.dim();
    if d == 1 {
        return Ok(curve(sweep, watch, post)?.into_iter().collect());
    }
    let mut out = Vec::new();
    for i in 0..d {
        for j in i + 1..d {
            let base: Vec<f64> = post.marginals.iter().map(|m| m.median).collect();
            let mut grid = vec![vec![f64::NEG_INFINITY; CELLS]; CELLS];
            for (a, row) in grid.iter_mut().enumerate() {
                for (b, cell) in row.iter_mut().enumerate() {
                    let mut u = base.clone();
                    u[i] = (a as f64 + 0.5) / CELLS as f64;
                    u[j] = (b as f64 + 0.5) / CELLS as f64;
                    *cell = density_at(watch, &u).unwrap_or(f64::NEG_INFINITY);
                }
            }
            let top = grid.iter().flatten().copied().fold(f64::NEG_INFINITY, f64::max);
            let runs: Vec<(Vec<f64>, bool)> = manifest
                .points
                .iter()
                .zip(status)
                .filter(|(_, s)| s.is_finished())
                .map(|(p, s)| {
                    (crate::sweep::space::unit_point(sweep, &p.values), matches!(s, PointStatus::Failed(_)))
                })
                .collect();
            let (mi, mj) = (&post.marginals[i], &post.marginals[j]);
            let (ni, nj) = (&sweep.swept[i].name, &sweep.swept[j].name);
            let title = format!("posterior over {ni} × {nj}");
            let others = if d > 2 { ", the other parameters at their posterior medians" } else { "" };
            let caption = format!(
                "{title}: density relative to its highest (colour{others}); dots: runs, red ×: failed runs; \
                 white lines: each parameter's 95 % credible interval; white ○: the posterior's mode. \
                 A diagonal band is a ridge: pairs along it reproduce the targets alike."
            );
            let vi = |u: f64| unit_value(sweep, i, u);
            let vj = |u: f64| unit_value(sweep, j, u);
            let fig =
                super::plots::figure(format!("map-posterior-{ni}-{nj}"), caption, (640, 540), |root| {
                    let root = root.titled(&title, (FONT, TITLE_FONT))?;
                    let mut c = ChartBuilder::on(&root)
                        .margin(10)
                        .x_label_area_size(48)
                        .y_label_area_size(66)
                        .build_cartesian_2d(0.0..1.0, 0.0..1.0)?;
                    c.configure_mesh()
                        .disable_mesh()
                        .label_style((FONT, TICK_FONT))
                        .axis_desc_style((FONT, AXIS_FONT))
                        .x_desc(format!("{ni} ({})", sweep.swept[i].unit))
                        .y_desc(format!("{nj} ({})", sweep.swept[j].unit))
                        .x_label_formatter(&|u| tick(vi(*u)))
                        .y_label_formatter(&|u| tick(vj(*u)))
                        .draw()?;
                    let w = 1.0 / CELLS as f64;
                    for (a, row) in grid.iter().enumerate() {
                        for (b, l) in row.iter().enumerate() {
                            let t = if top.is_finite() { (l - top).exp() } else { 0.0 };
                            let r = [(a as f64 * w, b as f64 * w), ((a + 1) as f64 * w, (b + 1) as f64 * w)];
                            c.draw_series(std::iter::once(Rectangle::new(
                                r,
                                super::maps::viridis(t).filled(),
                            )))?;
                        }
                    }
                    let line = WHITE.stroke_width(2);
                    for x in [mi.lo, mi.hi] {
                        c.draw_series(std::iter::once(PathElement::new(vec![(x, 0.0), (x, 1.0)], line)))?;
                    }
                    for y in [mj.lo, mj.hi] {
                        c.draw_series(std::iter::once(PathElement::new(vec![(0.0, y), (1.0, y)], line)))?;
                    }
                    c.draw_series(
                        runs.iter()
                            .filter(|r| !r.1)
                            .map(|(u, _)| Circle::new((u[i], u[j]), 3, BLACK.mix(0.8).filled())),
                    )?;
                    c.draw_series(
                        runs.iter()
                            .filter(|r| r.1)
                            .map(|(u, _)| Cross::new((u[i], u[j]), 5, RED.stroke_width(2))),
                    )?;
                    c.draw_series(std::iter::once(Circle::new(
                        (post.best[i], post.best[j]),
                        7,
                        WHITE.stroke_width(3),
                    )))?;
                    Ok(())
                })?;
            out.push(fig);
        }
    }
    Ok(out)
}

/// The posterior's log density at unit point `u` from the watch's last emulators.
/// One free parameter: above, the first target's emulator (mean and 95 % band) with the runs'
/// values and the target's band; below, the posterior density with its credible interval.
fn curve(
    sweep: &Sweep,
    watch: &CalibrationWatch,
    post: &crate::analysis::calibration::Posterior,
) -> Res<Option<Figure>> {
    let (Some(ems), Some(data)) = (watch.emulators(), watch.data()) else { return Ok(None) };
    let (em, (xs, ys, ses)) = (&ems[0], &data[0]);
    let target = &watch.settings().targets[0];
    let grid: Vec<f64> = (0..=200).map(|k| k as f64 / 200.0).collect();
    let pred: Vec<(f64, f64)> = grid.iter().map(|u| em.predict(&[*u])).collect();
    let dens: Vec<f64> = grid.iter().map(|u| density_at(watch, &[*u]).unwrap_or(f64::NEG_INFINITY)).collect();
    let top = dens.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut lo = target.value - 2.0 * target.sd;
    let mut hi = target.value + 2.0 * target.sd;
    for ((m, s), y) in pred.iter().zip(ys.iter().chain(std::iter::repeat(&f64::NAN))) {
        for v in [m - 1.96 * s, m + 1.96 * s, *y] {
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    let pad = 0.05 * (hi - lo);
    let name = &sweep.swept[0].name;
    let m = &post.marginals[0];
    let v = |u: f64| unit_value(sweep, 0, u);
    let title = format!("{} against {name}", target.name);
    let caption = format!(
        "{title}: above, the emulator's mean (line) and 95 % band, the runs (dots, ± their SE) and the target ± its SD          (grey band); below, the posterior density of {name} relative to its highest, its 95 % credible interval between          the dashed lines."
    );
    let fig = super::plots::figure(format!("posterior-{name}"), caption, (640, 620), |root| {
        let root = root.titled(&title, (FONT, TITLE_FONT))?;
        let (upper, lower) = root.split_vertically(360);
        let mut c = ChartBuilder::on(&upper)
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(66)
            .build_cartesian_2d(0.0..1.0, (lo - pad)..(hi + pad))?;
        c.configure_mesh()
            .disable_mesh()
            .label_style((FONT, TICK_FONT))
            .axis_desc_style((FONT, AXIS_FONT))
            .y_desc(target.name.clone())
            .x_label_formatter(&|u| tick(v(*u)))
            .y_label_formatter(&|y| round_to(*y, 3))
            .draw()?;
        let band = [(0.0, target.value - target.sd), (1.0, target.value + target.sd)];
        c.draw_series(std::iter::once(Rectangle::new(band, RGBColor(200, 200, 200).mix(0.6).filled())))?;
        let upper_band: Vec<(f64, f64)> =
            grid.iter().zip(&pred).map(|(u, (m, s))| (*u, m + 1.96 * s)).collect();
        let lower_band: Vec<(f64, f64)> =
            grid.iter().zip(&pred).rev().map(|(u, (m, s))| (*u, m - 1.96 * s)).collect();
        let poly: Vec<(f64, f64)> = upper_band.into_iter().chain(lower_band).collect();
        c.draw_series(std::iter::once(Polygon::new(poly, super::maps::viridis(0.3).mix(0.25).filled())))?;
        c.draw_series(LineSeries::new(
            grid.iter().zip(&pred).map(|(u, (m, _))| (*u, *m)),
            super::maps::viridis(0.3).stroke_width(2),
        ))?;
        for ((x, y), se) in xs.iter().zip(ys).zip(ses) {
            if let Some(se) = se {
                c.draw_series(std::iter::once(PathElement::new(
                    vec![(x[0], y - se), (x[0], y + se)],
                    BLACK,
                )))?;
            }
        }
        c.draw_series(xs.iter().zip(ys).map(|(x, y)| Circle::new((x[0], *y), 3, BLACK.filled())))?;
        let mut c = ChartBuilder::on(&lower)
            .margin(10)
            .x_label_area_size(48)
            .y_label_area_size(66)
            .build_cartesian_2d(0.0..1.0, 0.0..1.05)?;
        c.configure_mesh()
            .disable_mesh()
            .label_style((FONT, TICK_FONT))
            .axis_desc_style((FONT, AXIS_FONT))
            .x_desc(format!("{name} ({})", sweep.swept[0].unit))
            .y_desc("posterior")
            .x_label_formatter(&|u| tick(v(*u)))
            .y_label_formatter(&|y| round_to(*y, 2))
            .draw()?;
        let curve =
            grid.iter().zip(&dens).map(|(u, l)| (*u, if top.is_finite() { (l - top).exp() } else { 0.0 }));
        c.draw_series(LineSeries::new(curve, super::maps::viridis(0.3).stroke_width(2)))?;
        for x in [m.lo, m.hi] {
            c.draw_series(DashedLineSeries::new(vec![(x, 0.0), (x, 1.05)], 6, 4, BLACK.stroke_width(1)))?;
        }
        Ok(())
    })?;
    Ok(Some(fig))
}

fn density_at(watch: &CalibrationWatch, u: &[f64]) -> Option<f64> {
    let ems = watch.emulators()?;
    let outs: Vec<Emulated> = watch
        .settings()
        .targets
        .iter()
        .zip(ems)
        .map(|(target, emulator)| Emulated { target, emulator })
        .collect();
    Some(log_density(&outs, u))
}

/// An axis tick: three significant figures, and below 10⁻³ in scientific notation
/// (`1.2e-5`), so that neighbouring ticks of a small quantity do not run into each other.
fn tick(v: f64) -> String {
    if v != 0.0 && v.abs() < 1e-3 {
        let e = format!("{v:.1e}");
        e.replace(".0e", "e")
    } else {
        round_to(v, 3)
    }
}

#[cfg(test)]
mod tests {
    use super::tick;

    #[test]
    fn small_ticks_are_short_and_tell_their_neighbours_apart() {
        assert_eq!(tick(1.2e-5), "1.2e-5");
        assert_eq!(tick(1.4e-5), "1.4e-5");
        assert_eq!(tick(2e-6), "2e-6");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(34.0), "34");
    }
}
