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

use super::Scene;

/// Data file name in the run directory.
pub const PILE_DATA: &str = "pile.data";

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
    pub fn of(s: &Scene) -> Draw {
        let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
        let fractions: Vec<f64> = s.size_classes.iter().map(|c| c.fraction).collect();
        let mut diameters: Vec<f64> = class_counts(&fractions, s.particles)
            .iter()
            .zip(&s.size_classes)
            .flat_map(|(&n, c)| std::iter::repeat_n(c.diameter, n))
            .collect();
        diameters.shuffle(&mut rng);
        let d_max = s.size_classes.iter().map(|c| c.diameter).fold(0.0, f64::max);
        Draw { rng, diameters, jitter: 0.45 * (s.pile_spacing - d_max) }
    }
}

/// The LIGGGHTS data file (atom style granular: id type diameter density x y z) of the pile,
/// with the simulation box. Atom type 1; type 2 is the walls'; type 3 the fixed spheres of a
/// rough substrate, numbered after the pile.
pub fn pile_data(s: &Scene) -> String {
    let Draw { mut rng, diameters, jitter } = Draw::of(s);
    let [nx, ny, nz] = s.pile_n;

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
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let mut c = [
                    s.pile_x0 + (i as f64 + 0.5) * s.pile_spacing,
                    (j as f64 + 0.5) * s.pile_spacing,
                    (k as f64 + 0.5) * s.pile_spacing,
                ];
                for x in &mut c {
                    *x += rng.gen_range(-jitter..=jitter);
                }
                let _ = writeln!(
                    out,
                    "{} 1 {} {} {:.9e} {:.9e} {:.9e}",
                    id + 1,
                    diameters[id],
                    s.material.density,
                    c[0],
                    c[1],
                    c[2]
                );
                id += 1;
            }
        }
    }
    if let Some(bed) = &s.substrate_bed {
        for &[x, y, z, d] in &bed.spheres {
            id += 1;
            let _ = writeln!(out, "{id} 3 {d} {} {x:.9e} {y:.9e} {z:.9e}", s.material.density);
        }
    }
    let [sx, sy] = s.substrate_n;
    let h = s.substrate_spacing;
    for i in 0..sx {
        for j in 0..sy {
            id += 1;
            let c = [(i as f64 + 0.5) * h, (j as f64 + 0.5) * h, -0.5 * s.substrate_diameter];
            let _ = writeln!(
                out,
                "{id} 3 {} {} {:.9e} {:.9e} {:.9e}",
                s.substrate_diameter, s.material.density, c[0], c[1], c[2]
            );
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
