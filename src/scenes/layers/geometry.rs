//! The layers layout's wall meshes, as ASCII STL at their first position: each pass's deck
//! re-creates them moved up to its heights (`fix mesh/surface ... move`).
//!
//! - `blade.stl`: the blade with its lowest line at z = 0 — a box one diameter thick (flat) or
//!   the lowest [`ROUND_ARC_SHARE`] of a cylinder's half circle about a y axis with vertical
//!   faces above (round), or a whole cylinder (roller: it turns, so every side of it comes
//!   down to the powder);
//! - `feed.stl`: the feed platform, top at z = 0, from the box's back to the plate;
//! - `wall.stl`: the wall after the plate, one diameter thick, top at z = 0;
//! - `plate.stl`: the build plate, top at z = 0;
//! - `pit.stl`: the pit's wall under the plate's end (still);
//! - `over.stl` (a roller's only): a plane over the whole scene at z = 0, raised each pass to the
//!   roller's top line, through which the deck counts the powder sent over the roller — not a
//!   wall: nothing touches it.
//!
//! Every mesh spans the periodic depth inset from its faces (a mesh must lie inside the box) and
//! has no faces normal to y (LIGGGHTS 3.8's mesh build fails on faces that face each other across
//! the periodic boundary; [`crate::scene::mesh`]).

use std::fmt::Write;

use super::settings::{own, DEFAULT_ROLLER_SEGMENTS};
use super::{Plan, ROUND_ARC_SHARE};
use crate::scene::mesh::box_stl;
use crate::scene::settings::SceneSettings;
use crate::scene::Scene;
use crate::scenes::BadSetting;

/// The range of `scene.roller_segments`: from a polygon whose flats a particle feels to one whose
/// mesh is still built in seconds.
pub const ROLLER_SEGMENTS: (usize, usize) = (16, 4096);

/// `scene.roller_segments`: within [`ROLLER_SEGMENTS`], and set only for a roller.
pub fn check(s: &SceneSettings) -> Result<(), BadSetting> {
    let n = own(s).roller_segments;
    let (least, most) = ROLLER_SEGMENTS;
    if n != DEFAULT_ROLLER_SEGMENTS && own(s).blade_profile != "roller" {
        let why = format!("{n}: only a roller's circle is cut in segments; expected it only with blade_profile = \"roller\"");
        return Err(BadSetting { key: "scene.roller_segments", why });
    }
    if !(least..=most).contains(&n) {
        let why = format!("{n}: expected a whole number of segments from {least} to {most}");
        return Err(BadSetting { key: "scene.roller_segments", why });
    }
    Ok(())
}

/// Segments of a round blade's arc.
const ARC_SEGMENTS: usize = 48;

pub fn blade_stl(s: &Scene, plan: &Plan) -> String {
    let blade = &super::part(s).blade;
    let (y0, y1) = inset(s);
    if plan.blade_radius <= 0.0 {
        let x0 = plan.tip_x0;
        return box_stl(
            "blade",
            [x0, y0, 0.0],
            [x0 + blade.blade_thickness, y1, blade.blade_top],
            false,
            s.mesh_cell,
        );
    }
    let r = plan.blade_radius;
    let (xc, zc) = (plan.tip_x0, r);
    // Angle a from the lowest line (0), counter-clockwise seen from −y.
    let point = |a: f64| [xc + r * a.sin(), zc - r * a.cos()];
    let mut profile: Vec<[f64; 2]> = Vec::new();
    if plan.roller {
        // The whole circle, from its top down the back, under it and up the front.
        let pi = std::f64::consts::PI;
        let n = plan.roller_segments;
        for i in 0..n {
            profile.push(point(-pi + 2.0 * pi * i as f64 / n as f64));
        }
        profile.push(profile[0]);
    } else {
        // The arc from angle −φ to +φ about the lowest line, φ = share × 90°, then vertical faces
        // from its ends up to the blade's top, and a lid.
        let phi = 0.5 * ROUND_ARC_SHARE * std::f64::consts::PI;
        let top = blade.blade_top.max(point(phi)[1] + s.diameter);
        profile.push([point(-phi)[0], top]);
        for i in 0..=ARC_SEGMENTS {
            profile.push(point(-phi + 2.0 * phi * i as f64 / ARC_SEGMENTS as f64));
        }
        profile.push([point(phi)[0], top]);
        profile.push(profile[0]);
    }
    let mut out = String::from("solid blade\n");
    // Each segment of the profile extruded across the depth, in cells no larger than the mesh
    // cell along both (LIGGGHTS 3.8's mesh build fails on elements large against the depth).
    let h = s.mesh_cell;
    let cells = ((y1 - y0) / h).ceil().max(1.0) as usize;
    for seg in profile.windows(2) {
        let ([xa, za], [xb, zb]) = (seg[0], seg[1]);
        let (dx, dz) = (xb - xa, zb - za);
        let len = (dx * dx + dz * dz).sqrt();
        if len == 0.0 {
            continue;
        }
        // The profile runs counter-clockwise in the x–z plane (down the back, along the arc, up
        // the front, back over the lid): the outward normal is (dz, −dx)/len, and the triangles
        // are wound counter-clockwise seen from outside.
        let n = [dz / len, 0.0, -dx / len];
        let pieces = (len / h).ceil().max(1.0) as usize;
        for i in 0..pieces {
            let (u0, u1) = (i as f64 / pieces as f64, (i + 1) as f64 / pieces as f64);
            let (xa, za, xb, zb) = (xa + u0 * dx, za + u0 * dz, xa + u1 * dx, za + u1 * dz);
            for j in 0..cells {
                let ya = y0 + (y1 - y0) * j as f64 / cells as f64;
                let yb = y0 + (y1 - y0) * (j + 1) as f64 / cells as f64;
                let (p00, p10, p11, p01) = ([xa, ya, za], [xb, ya, zb], [xb, yb, zb], [xa, yb, za]);
                for tri in [[p00, p01, p11], [p00, p11, p10]] {
                    facet(&mut out, n, tri);
                }
            }
        }
    }
    out.push_str("endsolid blade\n");
    out
}

pub fn feed_stl(s: &Scene, plan: &Plan) -> String {
    let (y0, y1) = inset(s);
    box_stl("feed", [plan.feed_x0, y0, -plan.block_depth], [plan.plate_x0, y1, 0.0], false, coarse(s))
}

pub fn wall_stl(s: &Scene, plan: &Plan) -> String {
    let (y0, y1) = inset(s);
    box_stl(
        "wall",
        [plan.plate_x1, y0, -plan.block_depth],
        [plan.plate_x1 + s.diameter, y1, 0.0],
        false,
        coarse(s),
    )
}

/// The pit's wall under the plate's end, from just above the pit's floor (a mesh must lie inside
/// the box) to just under the plate: what falls
/// into the pit cannot roll under the plate. It never moves (the wall above it rises with the
/// top surface, its bottom always below this one's top).
pub fn pit_stl(s: &Scene, plan: &Plan) -> String {
    let (y0, y1) = inset(s);
    box_stl(
        "pit",
        [plan.plate_x1, y0, s.z_lo + 0.1 * s.diameter],
        [plan.plate_x1 + s.diameter, y1, -s.diameter],
        false,
        coarse(s),
    )
}

/// The plane the deck counts the powder sent over a roller through: over the whole box along the
/// travel (inset by half a diameter: a mesh must lie inside it), at z = 0, facing up.
pub fn over_stl(s: &Scene, plan: &Plan) -> String {
    let (y0, y1) = inset(s);
    let (x0, x1) = (plan.feed_x0, s.x_hi - 0.5 * s.diameter);
    let h = coarse(s);
    let (nx, ny) = (((x1 - x0) / h).ceil().max(1.0) as usize, ((y1 - y0) / h).ceil().max(1.0) as usize);
    let mut out = String::from("solid over\n");
    for i in 0..nx {
        let (xa, xb) = (x0 + (x1 - x0) * i as f64 / nx as f64, x0 + (x1 - x0) * (i + 1) as f64 / nx as f64);
        for j in 0..ny {
            let (ya, yb) =
                (y0 + (y1 - y0) * j as f64 / ny as f64, y0 + (y1 - y0) * (j + 1) as f64 / ny as f64);
            let (p00, p10, p11, p01) = ([xa, ya, 0.0], [xb, ya, 0.0], [xb, yb, 0.0], [xa, yb, 0.0]);
            for tri in [[p00, p10, p11], [p00, p11, p01]] {
                facet(&mut out, [0.0, 0.0, 1.0], tri);
            }
        }
    }
    out.push_str("endsolid over\n");
    out
}

pub fn plate_stl(s: &Scene, plan: &Plan) -> String {
    let (y0, y1) = inset(s);
    box_stl("plate", [plan.plate_x0, y0, -s.diameter], [plan.plate_x1, y1, 0.0], false, coarse(s))
}

/// The meshes' span across the periodic depth: inset from its faces as the blade is.
fn inset(s: &Scene) -> (f64, f64) {
    let inset = super::part(s).blade.blade_y_inset;
    (inset, s.depth - inset)
}

/// Cells of the still walls: a few diameters (a mesh's cost grows with its faces).
fn coarse(s: &Scene) -> f64 {
    (4.0 * s.diameter).max(s.mesh_cell)
}

fn facet(out: &mut String, n: [f64; 3], tri: [[f64; 3]; 3]) {
    let _ = writeln!(out, "  facet normal {} {} {}\n    outer loop", n[0], n[1], n[2]);
    for p in tri {
        let _ = writeln!(out, "      vertex {:.9e} {:.9e} {:.9e}", p[0], p[1], p[2]);
    }
    out.push_str("    endloop\n  endfacet\n");
}
