//! A bed of the powder: the layer a machine's blade spreads onto, a random packing of the
//! powder's own sizes, fixed, with its mean surface at z = 0 (the gap is measured from it).
//!
//! Built by sequential deposition in a box periodic in x and y: each sphere, drawn by number
//! from the size distribution, is dropped at 32 random spots and kept where it comes to rest
//! lowest (its first contact on the way down, with the floor or a sphere already there), until
//! the spheres' volume fills the wanted thickness at a packing of 0.55. Keeping the lowest of
//! many drops fills the pockets first: equal spheres pack at about 0.43 below the mean surface,
//! the packing of a spread layer (0.4–0.55, Meier et al. 2019), which is what the bed is; a
//! single drop would leave a loose, tall deposit, and settling under gravity in the engine would
//! cost a run per point.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::scene::psd::SizeClass;

/// Drops tried per sphere.
const DROPS: usize = 32;
/// Solid fraction the bed's volume is filled to, over its thickness.
const FILL: f64 = 0.55;
/// Grid cells per smallest diameter for the surface and the open depth.
const CELLS_PER_D: f64 = 4.0;

/// The fixed spheres of a bed: `[x, y, z, diameter]`, m, the mean surface at z = 0.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Bed {
    pub spheres: Vec<[f64; 4]>,
    /// Height of the plate under the bed (the floor the spheres were dropped on), m.
    pub floor: f64,
    pub length: f64,
    pub width: f64,
}

impl Bed {
    /// A bed `thickness` deep (of solid at a packing of 0.55) of spheres of `classes` over a
    /// periodic `length` × `width`, seeded.
    pub fn deposit(classes: &[SizeClass], length: f64, width: f64, thickness: f64, seed: u64) -> Bed {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let d_max = classes.iter().map(|c| c.diameter).fold(0.0, f64::max);
        let mut bed = Bed { spheres: Vec::new(), floor: 0.0, length, width };
        let mut grid = Columns::new(length, width, d_max);
        let target = FILL * length * width * thickness;
        let mut volume = 0.0;
        while volume < target {
            let d = draw(classes, rng.gen());
            let spot = (0..DROPS)
                .map(|_| {
                    let (x, y) = (rng.gen::<f64>() * length, rng.gen::<f64>() * width);
                    (x, y, bed.landing(&grid, x, y, 0.5 * d))
                })
                .min_by(|a, b| a.2.total_cmp(&b.2))
                .expect("DROPS > 0");
            grid.add(spot.0, spot.1, bed.spheres.len());
            bed.spheres.push([spot.0, spot.1, spot.2, d]);
            volume += std::f64::consts::PI / 6.0 * d.powi(3);
        }
        let mean = bed.surface(bed.cell(classes)).iter().sum::<f64>() / bed.cells(bed.cell(classes)) as f64;
        for s in &mut bed.spheres {
            s[2] -= mean;
        }
        bed.floor = -mean;
        bed
    }

    /// The grid cell for the surface and the open depth: a quarter of the smallest diameter.
    fn cell(&self, classes: &[SizeClass]) -> f64 {
        classes.iter().map(|c| c.diameter).fold(f64::INFINITY, f64::min) / CELLS_PER_D
    }

    fn grid_n(&self, cell: f64) -> (usize, usize) {
        (((self.length / cell).round() as usize).max(1), ((self.width / cell).round() as usize).max(1))
    }

    fn cells(&self, cell: f64) -> usize {
        let (nx, ny) = self.grid_n(cell);
        nx * ny
    }

    /// The bed's spheres in columns wide enough for a sphere of `probe` diameter to touch only
    /// its own and the neighbouring ones.
    fn columns(&self, probe: f64) -> Columns {
        let d_max = self.spheres.iter().map(|s| s[3]).fold(probe, f64::max);
        let mut grid = Columns::new(self.length, self.width, d_max);
        for (i, s) in self.spheres.iter().enumerate() {
            grid.add(s[0], s[1], i);
        }
        grid
    }

    /// The centre height where a sphere of radius `r` dropped at (x, y) first touches the floor
    /// or a sphere of the bed.
    fn landing(&self, grid: &Columns, x: f64, y: f64, r: f64) -> f64 {
        let mut z = self.floor + r;
        for i in grid.near(x, y) {
            let [sx, sy, sz, sd] = self.spheres[i];
            let (dx, dy) = (wrap(x - sx, self.length), wrap(y - sy, self.width));
            let reach = r + 0.5 * sd;
            let rho2 = dx * dx + dy * dy;
            if rho2 < reach * reach {
                z = z.max(sz + (reach * reach - rho2).sqrt());
            }
        }
        z
    }

    /// The bed's top over each cell of a grid of `cell` (row-major in x), m.
    fn surface(&self, cell: f64) -> Vec<f64> {
        self.over_grid(cell, |x, y, grid| {
            let mut top = self.floor;
            for i in grid.near(x, y) {
                let [sx, sy, sz, sd] = self.spheres[i];
                let (dx, dy) = (wrap(x - sx, self.length), wrap(y - sy, self.width));
                let r2 = 0.25 * sd * sd - dx * dx - dy * dy;
                if r2 > 0.0 {
                    top = top.max(sz + r2.sqrt());
                }
            }
            top
        })
    }

    fn over_grid(&self, cell: f64, f: impl Fn(f64, f64, &Columns) -> f64) -> Vec<f64> {
        let grid = self.columns(0.0);
        let (nx, ny) = self.grid_n(cell);
        let (hx, hy) = (self.length / nx as f64, self.width / ny as f64);
        let mut out = Vec::with_capacity(nx * ny);
        for i in 0..nx {
            for j in 0..ny {
                out.push(f((i as f64 + 0.5) * hx, (j as f64 + 0.5) * hy, &grid));
            }
        }
        out
    }

    /// Open depth below the mean surface that spheres of `powder_diameter` reach from above, m
    /// (as [`crate::scene::pockets`] for a lattice): the mean over the bed of the column from the
    /// lowest point such a sphere's body reaches (or the bed's top there) up to z = 0.
    pub fn open_depth(&self, powder_diameter: f64) -> f64 {
        let r = 0.5 * powder_diameter;
        let cell = powder_diameter / CELLS_PER_D;
        let grid = self.columns(powder_diameter);
        let centres = self.over_grid(cell, |x, y, _| self.landing(&grid, x, y, r));
        let tops = self.surface(cell);
        let (nx, ny) = self.grid_n(cell);
        crate::scene::pockets::reachable_depth(&centres, &tops, nx, ny, self.length / nx as f64, r)
    }

    /// Height of the top of a sphere of `powder_diameter` resting as low as it can on the bed, m.
    pub fn lowest_top(&self, powder_diameter: f64) -> f64 {
        let r = 0.5 * powder_diameter;
        let grid = self.columns(powder_diameter);
        self.over_grid(powder_diameter / CELLS_PER_D, |x, y, _| self.landing(&grid, x, y, r))
            .into_iter()
            .fold(f64::INFINITY, f64::min)
            + r
    }
}

/// The diameter of the class where the cumulative number fraction passes `u` in [0, 1).
fn draw(classes: &[SizeClass], u: f64) -> f64 {
    let mut below = 0.0;
    for c in classes {
        below += c.fraction;
        if u < below {
            return c.diameter;
        }
    }
    classes.last().map(|c| c.diameter).unwrap_or(0.0)
}

/// The shortest periodic image of a separation over a period.
fn wrap(d: f64, period: f64) -> f64 {
    d - period * (d / period).round()
}

/// Spheres binned into columns at least the largest diameter wide, periodic: everything a
/// sphere dropped at a point can touch is in its column or the eight around it.
struct Columns {
    nx: usize,
    ny: usize,
    hx: f64,
    hy: f64,
    members: Vec<Vec<usize>>,
}

impl Columns {
    fn new(length: f64, width: f64, d_max: f64) -> Columns {
        let nx = ((length / d_max).floor() as usize).max(1);
        let ny = ((width / d_max).floor() as usize).max(1);
        Columns { nx, ny, hx: length / nx as f64, hy: width / ny as f64, members: vec![Vec::new(); nx * ny] }
    }

    fn index(&self, x: f64, y: f64) -> (usize, usize) {
        let i = ((x / self.hx).floor() as isize).rem_euclid(self.nx as isize) as usize;
        let j = ((y / self.hy).floor() as isize).rem_euclid(self.ny as isize) as usize;
        (i, j)
    }

    fn add(&mut self, x: f64, y: f64, sphere: usize) {
        let (i, j) = self.index(x, y);
        self.members[i * self.ny + j].push(sphere);
    }

    /// The spheres in the column of (x, y) and its neighbours, each column once.
    fn near(&self, x: f64, y: f64) -> impl Iterator<Item = usize> + '_ {
        let (i, j) = self.index(x, y);
        let wrap = |k: usize, di: isize, n: usize| (k as isize + di).rem_euclid(n as isize) as usize;
        let mut columns: Vec<usize> = Vec::with_capacity(9);
        for di in -1..=1 {
            for dj in -1..=1 {
                let c = wrap(i, di, self.nx) * self.ny + wrap(j, dj, self.ny);
                if !columns.contains(&c) {
                    columns.push(c);
                }
            }
        }
        columns.into_iter().flat_map(move |c| self.members[c].iter().copied())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mono(d: f64) -> Vec<SizeClass> {
        vec![SizeClass { diameter: d, fraction: 1.0 }]
    }

    #[test]
    fn no_two_spheres_of_the_bed_overlap_and_none_sinks_through_the_floor() {
        let classes =
            vec![SizeClass { diameter: 1.0, fraction: 0.5 }, SizeClass { diameter: 1.6, fraction: 0.5 }];
        let bed = Bed::deposit(&classes, 12.0, 6.0, 2.0, 7);
        let s = &bed.spheres;
        for i in 0..s.len() {
            assert!(s[i][2] - 0.5 * s[i][3] >= bed.floor - 1e-9);
            for j in 0..i {
                let dx = wrap(s[i][0] - s[j][0], 12.0);
                let dy = wrap(s[i][1] - s[j][1], 6.0);
                let dz = s[i][2] - s[j][2];
                let gap = (dx * dx + dy * dy + dz * dz).sqrt() - 0.5 * (s[i][3] + s[j][3]);
                assert!(gap > -1e-9, "spheres {i} and {j} overlap by {}", -gap);
            }
        }
    }

    #[test]
    fn a_bed_of_equal_spheres_packs_like_a_spread_layer() {
        // The solid under the mean surface over the depth from the floor: a spread layer's
        // 0.4–0.55 (Meier et al. 2019), below random close packing.
        let bed = Bed::deposit(&mono(1.0), 16.0, 8.0, 4.0, 3);
        let depth = -bed.floor;
        let solid: f64 = bed
            .spheres
            .iter()
            .map(|s| {
                // Volume of each sphere below z = 0 (a spherical cap when it pokes through).
                let (r, z) = (0.5 * s[3], s[2]);
                let h = (r - z).clamp(0.0, 2.0 * r);
                std::f64::consts::PI * h * h * (3.0 * r - h) / 3.0
            })
            .sum();
        let packing = solid / (16.0 * 8.0 * depth);
        assert!((0.40..0.55).contains(&packing), "{packing}");
    }

    #[test]
    fn powder_rests_in_the_bed_s_pockets_at_its_mean_surface() {
        // The mean surface averages the pockets in: a sphere of the bed's size resting as low as
        // it can has its bottom near it and its top about a diameter above; smaller spheres
        // reach at least as deep below it.
        let bed = Bed::deposit(&mono(1.0), 12.0, 6.0, 2.0, 11);
        let (d1, d05) = (bed.open_depth(1.0), bed.open_depth(0.5));
        assert!((0.0..0.3).contains(&d1), "{d1}");
        assert!(d05 >= d1, "{d05} against {d1}");
        let top = bed.lowest_top(1.0);
        assert!(top > 0.5 && top < 1.2, "{top}");
    }
}
