//! The blade mesh: an ASCII STL box generated from the scene, written beside the deck.

use std::fmt::Write;

use super::Scene;

/// Version of the mesh generator; part of a run's identity (a change re-runs every point).
pub const MESH_VERSION: u32 = 2;

/// The blade as a box open at its two y ends (8 triangles, outward normals): x from the rear
/// face to the front face, y across the whole periodic depth (inset from the periodic faces, as
/// a mesh must lie inside the box), z from the tip (gap) to the top.
///
/// The y ends are left out on purpose: no particle can reach them (the blade spans the periodic
/// depth), and LIGGGHTS 3.8 fails with "assertion failed (region_neighbor_list_I.h:165)" for
/// some depths when two end faces face each other across the periodic boundary.
pub fn blade_stl(s: &Scene) -> String {
    let (x0, x1) = (s.blade_x0, s.blade_x0 + s.blade_thickness);
    let (y0, y1) = (s.blade_y_inset, s.depth - s.blade_y_inset);
    let (z0, z1) = (s.gap, s.blade_top);
    box_stl("blade", [x0, y0, z0], [x1, y1, z1], false)
}

/// An axis-aligned box [lo, hi] as ASCII STL, triangles wound counter-clockwise seen from
/// outside; `y_ends` includes the two faces normal to y.
fn box_stl(name: &str, lo: [f64; 3], hi: [f64; 3], y_ends: bool) -> String {
    let corner = |i: usize, j: usize, k: usize| [[lo[0], hi[0]][i], [lo[1], hi[1]][j], [lo[2], hi[2]][k]];
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
        for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            let _ = writeln!(out, "  facet normal {} {} {}\n    outer loop", n[0], n[1], n[2]);
            for [i, j, k] in tri {
                let p = corner(i, j, k);
                let _ = writeln!(out, "      vertex {:.9e} {:.9e} {:.9e}", p[0], p[1], p[2]);
            }
            out.push_str("    endloop\n  endfacet\n");
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
        let stl = box_stl("b", [0.0, 0.0, 0.0], [1.0, 2.0, 3.0], true);
        let tris = parse_triangles(&stl);
        assert_eq!(tris.len(), 12);
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
        let open = parse_triangles(&box_stl("b", [0.0; 3], [1.0, 2.0, 3.0], false));
        assert_eq!(open.len(), 8);
        assert!(open.iter().all(|(n, _)| n[1] == 0.0));
    }
}
