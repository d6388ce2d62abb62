//! The open volume of a rough substrate below its tops that spheres of the powder can reach.
//!
//! The gap is measured from the substrate's tops, but a deposit also fills the pockets between
//! them: a layer spread at a gap of 1.3 D on spheres of D holds a quarter of a diameter more than
//! the gap. So the layer's thickness is the gap plus this open depth, the volume per area below
//! z = 0 that a powder sphere's body can occupy without overlapping the substrate.
//!
//! The substrate is a square lattice (spacing s) of spheres of diameter D_s, tops at z = 0,
//! above a plate at z = −D_s. A powder sphere of radius r can put its centre anywhere at or above
//! the height field f(u, v) = −D_s/2 + √((D_s/2 + r)² − ρ²) (ρ the horizontal distance to the
//! nearest substrate centre; the plate's r above it where no sphere is in reach), since only the
//! spheres below it are in its way. The lowest point any such sphere reaches over a column
//! (x, y) is g(x, y) = min over ρ' ≤ r of f − √(r² − ρ'²): the bottom envelope of the sphere rolled
//! over f. The open depth is the mean over the cell of the column from max(g, the substrate's
//! top there) up to 0: the void reachable from above (a deposit fills from above; the void
//! under a substrate sphere's overhang is left out).

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// Grid cells per lattice spacing.
const CELLS: usize = 64;

/// The open depth, m, under a square lattice of spacing `spacing` of spheres of diameter
/// `substrate_diameter` (tops at z = 0, plate at −`substrate_diameter`) that spheres of diameter
/// `powder_diameter` can reach.
pub fn open_depth(spacing: f64, substrate_diameter: f64, powder_diameter: f64) -> f64 {
    if spacing <= 0.0 || substrate_diameter <= 0.0 {
        return 0.0;
    }
    // It depends only on the two ratios; a sweep's points share a few of them.
    static CACHE: OnceLock<Mutex<HashMap<(u64, u64), f64>>> = OnceLock::new();
    let key = (
        (spacing / substrate_diameter * 1e9).round() as u64,
        (powder_diameter / substrate_diameter * 1e9).round() as u64,
    );
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(&d) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return d * substrate_diameter;
    }
    let d = unit_open_depth(spacing / substrate_diameter, powder_diameter / substrate_diameter);
    cache.lock().unwrap_or_else(|e| e.into_inner()).insert(key, d);
    d * substrate_diameter
}

/// [`open_depth`] for a substrate diameter of 1.
fn unit_open_depth(s: f64, dp: f64) -> f64 {
    let big_r = 0.5;
    let r = 0.5 * dp;
    let n = CELLS;
    let h = s / n as f64;
    // Horizontal distance² from grid point (i, j) (cell-centred) to the nearest lattice centre
    // (the corners of the periodic cell).
    let rho2 = |i: isize, j: isize| {
        let wrap = |k: isize| {
            let x = (k.rem_euclid(n as isize) as f64 + 0.5) * h;
            x.min(s - x)
        };
        let (x, y) = (wrap(i), wrap(j));
        x * x + y * y
    };
    let plate = -2.0 * big_r;
    let reach = big_r + r;
    // f: the lowest centre height over each column.
    let mut f = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let p2 = rho2(i as isize, j as isize);
            f[i * n + j] = if p2 < reach * reach { -big_r + (reach * reach - p2).sqrt() } else { plate + r };
        }
    }
    let top: Vec<f64> = (0..n * n)
        .map(|k| {
            let p2 = rho2((k / n) as isize, (k % n) as isize);
            if p2 < big_r * big_r {
                -big_r + (big_r * big_r - p2).sqrt()
            } else {
                plate
            }
        })
        .collect();
    reachable_depth(&f, &top, n, n, h, r)
}

/// The open depth below z = 0 over a periodic grid of `nx` × `ny` square cells of side `h`
/// (row-major in x), given over each cell the lowest centre height `centres` a sphere of radius
/// `r` can reach and the substrate's top `tops`: the mean over the cells of the column from
/// max(lowest point of any such sphere's body over the cell, the top) up to 0.
pub fn reachable_depth(centres: &[f64], tops: &[f64], nx: usize, ny: usize, h: f64, r: f64) -> f64 {
    // The rolled sphere's stencil: offsets within r, and how far its bottom lies below its centre.
    let k = (r / h).ceil() as isize;
    let mut stencil = Vec::new();
    for di in -k..=k {
        for dj in -k..=k {
            let d2 = ((di * di + dj * dj) as f64) * h * h;
            if d2 <= r * r {
                stencil.push((di, dj, (r * r - d2).sqrt()));
            }
        }
    }
    let mut total = 0.0;
    for i in 0..nx as isize {
        for j in 0..ny as isize {
            let g = stencil
                .iter()
                .map(|&(di, dj, below)| {
                    let (u, v) = (
                        (i + di).rem_euclid(nx as isize) as usize,
                        (j + dj).rem_euclid(ny as isize) as usize,
                    );
                    centres[u * ny + v] - below
                })
                .fold(f64::INFINITY, f64::min);
            let top = tops[i as usize * ny + j as usize];
            total += (0.0 - g.max(top)).max(0.0);
        }
    }
    total / (nx * ny) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fine_powder_reaches_the_whole_void_seen_from_above() {
        // Spheres far smaller than the pockets reach every point not shadowed by a substrate
        // sphere: per area, D_s minus the sphere's shadow, its upper half-height over its disc
        // and its full lower part: D_s − (π/8 + π/12) D_s³ / s² (the under-overhang void is not
        // reachable from above, and a deposit fills from above).
        for s in [1.0, 1.2] {
            let want = 1.0 - (std::f64::consts::PI / 8.0 + std::f64::consts::PI / 12.0) / (s * s);
            let got = unit_open_depth(s, 0.01);
            assert!((got - want).abs() < 0.02, "s {s}: {got} against {want}");
        }
    }

    #[test]
    fn a_sphere_of_the_substrate_s_size_reaches_its_pocket_s_depth_and_no_further() {
        // Equal spheres on touching spheres: one resting in a pocket has its centre
        // √(D² − D²/2) above the substrate's centres, its bottom 0.2929 D below the tops; the
        // open depth is less than that (the pocket narrows), and more than nothing.
        let d = unit_open_depth(1.0, 1.0);
        assert!(d > 0.05 && d < 1.0 - 0.5f64.sqrt(), "{d}");
        // Larger powder reaches less, smaller more.
        assert!(unit_open_depth(1.0, 1.5) < d && unit_open_depth(1.0, 0.6) > d);
    }

    #[test]
    fn it_scales_with_the_substrate_diameter() {
        let a = open_depth(1.05e-3, 1e-3, 1e-3);
        let b = open_depth(2.1e-3, 2e-3, 2e-3);
        assert!((b / a - 2.0).abs() < 1e-9);
    }
}
