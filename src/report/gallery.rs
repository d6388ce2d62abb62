//! The report's figures, in the order the page shows them: the failure map, then per space
//! the MFR histogram, the statistics against N, the scatter, the pair maps, the v_x profiles and
//! the lattice panels; a sweep run pass by pass, each point's passes and a top view of its layer.

use super::plots::{self, Figure, Res};
use super::{maps, passes, Analysis, PointRow};

/// Every figure of the report. With no MFR measured (every run failed) only the failure map:
/// empty plots say nothing.
pub fn draw_all(a: &Analysis) -> Res<Vec<Figure>> {
    let mut out = Vec::new();
    out.extend(maps::failure_map(a)?);
    if !a.points.iter().any(|p| p.mfr().is_some()) {
        return Ok(out);
    }
    // An adaptive sweep's spaces are its batches, each the runs so far: one histogram, of them all.
    let skip = if a.design.is_adaptive() { a.spaces.len().saturating_sub(1) } else { 0 };
    for (k, s) in a.spaces.iter().enumerate().skip(skip) {
        out.push(plots::histogram(a, k, &s.members)?);
    }
    if !a.spaces.is_empty() {
        out.push(plots::statistics(a)?);
    }
    out.push(plots::scatter(a)?);
    let mfr = |p: &PointRow| p.mfr();
    let label = format!("{} (–)", a.answer_name());
    out.extend(maps::pair_maps(
        a,
        &maps::MapSpec { stem: a.answer_key(), label: &label, value: &mfr, cells: maps::CellValue::Points },
    )?);
    let covered = |p: &PointRow| p.done().and_then(|(r, _)| r.layer.map(|l| l.covered_fraction));
    out.extend(maps::pair_maps(
        a,
        &maps::MapSpec {
            stem: "covered",
            label: "covered fraction (–)",
            value: &covered,
            cells: maps::CellValue::Points,
        },
    )?);
    // A layout that measures no v_x (a layers sweep) gets no empty profile panels.
    if a.points.iter().any(|p| p.done().is_some_and(|(r, _)| r.vx.iter().any(Option::is_some))) {
        out.push(plots::profiles(a)?);
        out.extend(plots::lattice_panels(a)?);
    }
    out.extend(passes::draw(a)?);
    Ok(out)
}
