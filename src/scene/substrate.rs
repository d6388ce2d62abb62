//! What the powder is spread onto besides the plate: fixed spheres on a square lattice (a rough
//! substrate, tops at z = 0) or a bed of the powder ([`Bed`]), or nothing (a smooth plate). A
//! group of the layouts that spread onto one ([`super::own::LayoutData::substrate`]); its
//! fields are the deck's keys (`scene.substrate_particles`, …).

use serde::Serialize;

use super::bed::Bed;
use super::pockets;

/// The substrate under the blade.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Substrate {
    /// Its spheres (none: a smooth plate).
    pub substrate_particles: usize,
    pub substrate_diameter: f64,
    pub substrate_spacing: f64,
    pub substrate_n: [usize; 2],
    /// A bed of the powder in place of the lattice (conveyor, `substrate = "powder"`).
    #[serde(skip)]
    pub substrate_bed: Option<Bed>,
}

impl Substrate {
    /// A smooth plate: no spheres.
    pub fn smooth() -> Substrate {
        Substrate {
            substrate_particles: 0,
            substrate_diameter: 0.0,
            substrate_spacing: 0.0,
            substrate_n: [0, 0],
            substrate_bed: None,
        }
    }

    /// Open depth of the pockets below the substrate's tops that a sphere of `d_min` reaches, m
    /// ([`pockets`]); 0 on a smooth plate.
    pub fn open_depth(&self, d_min: f64) -> f64 {
        if self.substrate_particles == 0 {
            return 0.0;
        }
        if let Some(bed) = &self.substrate_bed {
            return bed.open_depth(d_min);
        }
        pockets::open_depth(self.substrate_spacing, self.substrate_diameter, d_min)
    }
}
