//! The blade mesh: an ASCII STL box generated from the scene, written beside the deck.

use std::fmt::Write;

use super::blade::Blade;
use super::Scene;

/// Version of the mesh generator; part of a run's identity (a change re-runs every point).
pub const MESH_VERSION: u32 = 3;

/// The blade as a box open at its two y ends, outward normals: x from the rear face to the
/// front face, y across the whole periodic depth (inset from the periodic faces, as a mesh must
/// lie inside the box), z from the tip (gap) to the top. Faces are split into cells no larger
/// than the scene's `mesh_cell` (a whole fraction of the depth), two triangles each.
///
/// Both choices work around LIGGGHTS 3.8's mesh topology build (surface_mesh_I.h), which bins
/// the elements by their bounding radius over the whole box and fails with "assertion failed
/// (region_neighbor_list_I.h:165)" for some geometries when an element's bounding radius is
/// large against the box's depth, or when two end faces face each other across the periodic
/// boundary. The y ends are not needed: no particle can reach them.
pub fn blade_stl(s: &Scene, b: &Blade) -> String {
    let (x0, x1) = (b.blade_x0, b.blade_x0 + b.blade_thickness);
    let (y0, y1) = (b.blade_y_inset, s.depth - b.blade_y_inset);
    let (z0, z1) = (b.gap, b.blade_top);
    box_stl("blade", [x0, y0, z0], [x1, y1, z1], false, s.mesh_cell)
}

/// An axis-aligned box [lo, hi] as ASCII STL, each face split into a grid of cells no larger
/// than `h`, two triangles per cell, wound counter-clockwise seen from outside; `y_ends`
/// includes the two faces normal to y.
pub fn box_stl(name: &str, lo: [f64; 3], hi: [f64; 3], y_ends: bool, h: f64) -> String {
    let corner = |c: [usize; 3]| [[lo[0], hi[0]][c[0]], [lo[1], hi[1]][c[1]], [lo[2], hi[2]][c[2]]];
    // Each face: outward normal and its four corners counter-clockwise seen from outside.
    let faces: [([f64; 3], [[usize; 3]; 4]); 6] = [
        ([-1.0, 0.0, 0.0], [[0, 0, 0], [0, 0, 1], [0, 1, 1], [0, 1, 0]]),
        ([1.0, 0.0, 0.0], [[1, 0, 0], [1, 1, 0], [1, 1, 1], [1, 0, 1]]),
        ([0.0, -1.0, 0.0], [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]]),
        ([0.0, 1.0, 0.0], [[0, 1, 0], [0, 1, 1], [1, 1, 1], [1, 1, 0]]),
        ([0.0, 0.0, -1.0], [[0, 0, 0], [0, 1, 0], [1, 1, 0], [1, 0, 0]]),
        ([0.0, 0.0, 1.0], [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]),
    ];
    let mut out = format!("solid {name}\n");
    for (n, q) in faces {
        if n[1] != 0.0 && !y_ends {
            continue;
        }
        let (o, a, b) = (corner(q[0]), corner(q[1]), corner(q[3]));
        let du: [f64; 3] = std::array::from_fn(|k| a[k] - o[k]);
        let dv: [f64; 3] = std::array::from_fn(|k| b[k] - o[k]);
        let len = |d: [f64; 3]| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let (nu, nv) = ((len(du) / h).ceil().max(1.0) as usize, (len(dv) / h).ceil().max(1.0) as usize);
        let at = |i: usize, j: usize| -> [f64; 3] {
            let (u, v) = (i as f64 / nu as f64, j as f64 / nv as f64);
            std::array::from_fn(|k| o[k] + u * du[k] + v * dv[k])
        };
        for i in 0..nu {
            for j in 0..nv {
                let (p00, p10, p11, p01) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                for tri in [[p00, p10, p11], [p00, p11, p01]] {
                    let _ = writeln!(out, "  facet normal {} {} {}\n    outer loop", n[0], n[1], n[2]);
                    for p in tri {
                        let _ = writeln!(out, "      vertex {:.9e} {:.9e} {:.9e}", p[0], p[1], p[2]);
                    }
                    out.push_str("    endloop\n  endfacet\n");
                }
            }
        }
    }
    let _ = writeln!(out, "endsolid {name}");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_triangles(stl: &str) -> Vec<([f64; 3], [[f64; 3]; 3])> {
        let mut out = Vec::new();
        let mut normal = [0.0; 3];
        let mut verts = Vec::new();
        for line in stl.lines().map(str::trim) {
            let nums = |s: &str| -> Vec<f64> { s.split_whitespace().map(|t| t.parse().unwrap()).collect() };
            if let Some(rest) = line.strip_prefix("facet normal") {
                let v = nums(rest);
                normal = [v[0], v[1], v[2]];
            } else if let Some(rest) = line.strip_prefix("vertex") {
                let v = nums(rest);
                verts.push([v[0], v[1], v[2]]);
                if verts.len() == 3 {
                    out.push((normal, [verts[0], verts[1], verts[2]]));
                    verts.clear();
                }
            }
        }
        out
    }

    #[test]
    fn box_is_closed_with_outward_normals_matching_the_winding() {
        // Cells of at most 1: 2·(1·2 + 1·3 + 2·3) = 22 cells, 44 triangles.
        let stl = box_stl("b", [0.0, 0.0, 0.0], [1.0, 2.0, 3.0], true, 1.0);
        let tris = parse_triangles(&stl);
        assert_eq!(tris.len(), 44);
        let mut area = 0.0;
        for (n, [a, b, c]) in tris {
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let cross = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            let dot = cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2];
            assert!(dot > 0.0, "winding disagrees with normal {n:?}");
            area += dot / 2.0;
        }
        // Surface of a 1×2×3 box: 2(2 + 3 + 6) = 22.
        assert!((area - 22.0).abs() < 1e-12);
    }

    #[test]
    fn the_blade_has_no_y_end_faces() {
        let open = parse_triangles(&box_stl("b", [0.0; 3], [1.0, 2.0, 3.0], false, 10.0));
        assert_eq!(open.len(), 8);
        assert!(open.iter().all(|(n, _)| n[1] == 0.0));
    }
}
