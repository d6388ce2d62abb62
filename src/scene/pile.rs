//! The initial pile as a LIGGGHTS data file: a jittered simple-cubic block of spheres.
//!
//! Deterministic for a given scene (seeded ChaCha8), exact in count, and free of overlaps: each
//! sphere sits in its own lattice cell and is jittered by at most half the clearance between the
//! largest sphere and the cell. Diameters are assigned so the class counts match the number
//! fractions as closely as integers allow (largest remainder), then shuffled over the cells.

use std::fmt::Write;

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use serde::Serialize;

use super::Scene;

/// Data file name in the run directory.
pub const PILE_DATA: &str = "pile.data";

/// The dose as it starts (the moving blade's): a jittered simple-cubic block nx × ny × nz of
/// this spacing, from `pile_x0` on the plate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PileBlock {
    pub pile_x0: f64,
    pub pile_x1: f64,
    pub pile_z1: f64,
    pub pile_spacing: f64,
    pub pile_n: [usize; 3],
}

/// Number of particles of each class: floor of n·fraction, the remainder to the largest
/// fractional parts.
pub fn class_counts(fractions: &[f64], n: usize) -> Vec<usize> {
    let exact: Vec<f64> = fractions.iter().map(|f| f * n as f64).collect();
    let mut counts: Vec<usize> = exact.iter().map(|e| e.floor() as usize).collect();
    let mut order: Vec<usize> = (0..fractions.len()).collect();
    order.sort_by(|&a, &b| (exact[b] - exact[b].floor()).total_cmp(&(exact[a] - exact[a].floor())));
    let missing = n - counts.iter().sum::<usize>();
    for &i in order.iter().cycle().take(missing) {
        counts[i] += 1;
    }
    counts
}

/// The seeded draw of a pile's spheres: the diameters of the scene's `particles`, class by class
/// in the counts of their number fractions ([`class_counts`]) and shuffled, the generator
/// that goes on to jitter their positions, and the jitter's bound (0.45 of the clearance
/// between the largest sphere and its cell).
pub struct Draw {
    pub rng: ChaCha8Rng,
    pub diameters: Vec<f64>,
    pub jitter: f64,
}

impl Draw {
    /// The draw of `s`'s particles for cells of `spacing`.
    pub fn of(s: &Scene, spacing: f64) -> Draw {
        let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
        let fractions: Vec<f64> = s.size_classes.iter().map(|c| c.fraction).collect();
        let mut diameters: Vec<f64> = class_counts(&fractions, s.particles)
            .iter()
            .zip(&s.size_classes)
            .flat_map(|(&n, c)| std::iter::repeat_n(c.diameter, n))
            .collect();
        diameters.shuffle(&mut rng);
        let d_max = s.size_classes.iter().map(|c| c.diameter).fold(0.0, f64::max);
        Draw { rng, diameters, jitter: 0.45 * (spacing - d_max) }
    }
}

impl Draw {
    /// `p` moved by the jitter, each coordinate in turn.
    pub fn jittered(&mut self, p: [f64; 3]) -> [f64; 3] {
        let jitter = self.jitter;
        p.map(|x| x + self.rng.gen_range(-jitter..=jitter))
    }
}

/// One sphere's line of a LIGGGHTS data file in atom style granular: id type diameter density
/// x y z (positions to ten significant digits).
pub fn atom_line(out: &mut String, id: usize, kind: u8, diameter: f64, density: f64, [x, y, z]: [f64; 3]) {
    let _ = writeln!(out, "{id} {kind} {diameter} {density} {x:.9e} {y:.9e} {z:.9e}");
}

/// The LIGGGHTS data file (atom style granular: id type diameter density x y z) of the pile,
/// with the simulation box. Atom type 1; type 2 is the walls'; type 3 the fixed spheres of a
/// rough substrate, numbered after the pile.
pub fn pile_data(s: &Scene) -> String {
    let mut out = String::with_capacity(64 * s.particles + 256);
    let _ = write!(
        out,
        "LIGGGHTS data file: demsweep initial pile\n\n{} atoms\n3 atom types\n\n\
         0.0 {} xlo xhi\n0.0 {} ylo yhi\n{} {} zlo zhi\n\nAtoms\n\n",
        s.atoms(),
        s.x_hi,
        s.depth,
        s.z_lo,
        s.z_hi
    );
    let mut id = 0;
    if let Some(p) = s.pile() {
        let mut draw = Draw::of(s, p.pile_spacing);
        let [nx, ny, nz] = p.pile_n;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let c = draw.jittered([
                        p.pile_x0 + (i as f64 + 0.5) * p.pile_spacing,
                        (j as f64 + 0.5) * p.pile_spacing,
                        (k as f64 + 0.5) * p.pile_spacing,
                    ]);
                    atom_line(&mut out, id + 1, 1, draw.diameters[id], s.material.density, c);
                    id += 1;
                }
            }
        }
    }
    let Some(sub) = s.substrate() else { return out };
    if let Some(bed) = &sub.substrate_bed {
        for &[x, y, z, d] in &bed.spheres {
            id += 1;
            atom_line(&mut out, id, 3, d, s.material.density, [x, y, z]);
        }
    }
    let [sx, sy] = sub.substrate_n;
    let h = sub.substrate_spacing;
    for i in 0..sx {
        for j in 0..sy {
            id += 1;
            let c = [(i as f64 + 0.5) * h, (j as f64 + 0.5) * h, -0.5 * sub.substrate_diameter];
            atom_line(&mut out, id, 3, sub.substrate_diameter, s.material.density, c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn class_counts_sum_to_n_and_follow_the_fractions() {
        let c = class_counts(&[0.0444, 0.2276, 0.4078, 0.2691, 0.0511], 1000);
        assert_eq!(c.iter().sum::<usize>(), 1000);
        assert_eq!(c, vec![44, 228, 408, 269, 51]);
        assert_eq!(class_counts(&[1.0], 7), vec![7]);
    }
}
