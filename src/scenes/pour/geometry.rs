//! The pour's deck files: the powder column on a jittered lattice inside the cylinder
//! (`pile.data`) and the cylinder as an open tube of triangles (`blade.stl`, the deck's one
//! moving mesh).

use std::f64::consts::PI;
use std::fmt::Write;

use crate::scene::pile::{atom_line, Draw};
use crate::scene::Scene;

/// Flat faces around the tube: the inscribed polygon's flats lie within 0.2 % of the radius.
const TUBE_SEGMENTS: usize = 48;

/// The cylinder's axis in the box: its centre.
pub fn axis(s: &Scene) -> [f64; 2] {
    [0.5 * s.x_hi, 0.5 * s.depth]
}

/// The cylinder's inner radius.
pub fn cylinder_radius(s: &Scene) -> f64 {
    let c = super::column(s);
    0.5 * (c.cylinder_x1 - c.cylinder_x0)
}

/// The lattice sites of one layer of the column, relative to the axis: a square grid of
/// `spacing` whose cells lie wholly inside a circle of `radius`.
pub fn layer_sites(radius: f64, spacing: f64) -> Vec<[f64; 2]> {
    let n = (radius / spacing).ceil() as i64 + 1;
    let mut sites = Vec::new();
    for i in -n..=n {
        for j in -n..=n {
            let (x, y) = ((i as f64 + 0.5) * spacing, (j as f64 + 0.5) * spacing);
            // The cell's far corner inside the circle: the sphere and its jitter are too.
            if (x.abs() + 0.5 * spacing).hypot(y.abs() + 0.5 * spacing) <= radius {
                sites.push([x, y]);
            }
        }
    }
    sites
}

/// The LIGGGHTS data file of the column (atom style granular: id type diameter density x y z):
/// the lattice's layers of [`layer_sites`], the first `particles` sites from the bottom filled,
/// each sphere jittered by at most 0.45 of the clearance to its cell, the diameters assigned by
/// the size classes' number fractions and shuffled (seeded, reproducible).
pub fn column_data(s: &Scene) -> String {
    let column = super::column(s);
    let spacing = column.lattice_spacing;
    let mut draw = Draw::of(s, spacing);
    let sites = layer_sites(cylinder_radius(s), spacing);
    let [cx, cy] = axis(s);

    let mut out = String::with_capacity(64 * s.particles + 256);
    let _ = write!(
        out,
        "LIGGGHTS data file: demsweep pour column\n\n{} atoms\n2 atom types\n\n\
         0.0 {} xlo xhi\n0.0 {} ylo yhi\n{} {} zlo zhi\n\nAtoms\n\n",
        s.particles, s.x_hi, s.depth, s.z_lo, s.z_hi
    );
    let positions = (0..column.lattice_layers)
        .flat_map(|k| sites.iter().map(move |&[x, y]| [x, y, (k as f64 + 0.5) * spacing]));
    for (id, p) in positions.take(s.particles).enumerate() {
        let c = draw.jittered(p);
        atom_line(&mut out, id + 1, 1, draw.diameters[id], s.material.density, [cx + c[0], cy + c[1], c[2]]);
    }
    out
}

/// The cylinder as ASCII STL: an open tube of [`TUBE_SEGMENTS`] flat faces from the plate to
/// the tube's height, each face cut into rings no taller than its width (LIGGGHTS bins mesh elements
/// by their bounding radius), two triangles per cell. The faces lie at the cylinder's radius (the
/// corners just outside it), where the smooth wall the column settled against stood.
pub fn tube_stl(s: &Scene) -> String {
    let r = cylinder_radius(s) / (PI / TUBE_SEGMENTS as f64).cos();
    let [cx, cy] = axis(s);
    let width = 2.0 * r * (PI / TUBE_SEGMENTS as f64).sin();
    let height = super::column(s).tube_height;
    let rings = (height / width).ceil().max(1.0) as usize;
    let at = |i: usize, j: usize| {
        let phi = 2.0 * PI * i as f64 / TUBE_SEGMENTS as f64;
        [cx + r * phi.cos(), cy + r * phi.sin(), height * j as f64 / rings as f64]
    };
    let mut out = String::from("solid cylinder\n");
    for i in 0..TUBE_SEGMENTS {
        let mid = 2.0 * PI * (i as f64 + 0.5) / TUBE_SEGMENTS as f64;
        // Normals point into the tube, towards the powder.
        let n = [-mid.cos(), -mid.sin(), 0.0];
        for j in 0..rings {
            let (p00, p10, p11, p01) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            for tri in [[p00, p01, p11], [p00, p11, p10]] {
                let _ = writeln!(out, "  facet normal {} {} {}\n    outer loop", n[0], n[1], n[2]);
                for p in tri {
                    let _ = writeln!(out, "      vertex {:.9e} {:.9e} {:.9e}", p[0], p[1], p[2]);
                }
                let _ = writeln!(out, "    endloop\n  endfacet");
            }
        }
    }
    out.push_str("endsolid cylinder\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_site_keeps_its_cell_inside_the_circle_and_the_grid_is_full() {
        let (r, h) = (6.0, 1.05);
        let sites = layer_sites(r, h);
        for [x, y] in &sites {
            assert!((x.abs() + h / 2.0).hypot(y.abs() + h / 2.0) <= r + 1e-12);
        }
        // Nearly the circle's area in cells: every cell whose far corner is inside, i.e. the
        // cells of a circle of radius r - h/√2 at least.
        let inner = PI * (r - h * std::f64::consts::SQRT_2).powi(2) / (h * h);
        assert!(
            sites.len() as f64 >= inner && (sites.len() as f64) < PI * r * r / (h * h),
            "{}",
            sites.len()
        );
        // Symmetric about the axis.
        let sum: [f64; 2] = sites.iter().fold([0.0, 0.0], |a, s| [a[0] + s[0], a[1] + s[1]]);
        assert!(sum[0].abs() < 1e-9 && sum[1].abs() < 1e-9);
    }
}
