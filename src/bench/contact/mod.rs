//! The reference solver's own stability (`sweep bench contact`; BENCHMARKS.md "Reference solver stability").
//!
//! Three studies, each a list of rows with a CSV and a table rendering:
//! - [`drift`]: kinetic-energy drift at e = 1 over many consecutive contacts, against the closed
//!   form (energy is conserved without friction; with friction the box sheds exactly the
//!   tangential energy);
//! - [`stiffness`]: particle against wall moduli over six decades, against Hertz theory, and
//!   where the contact stops making sense;
//! - [`timestep`]: a timestep ladder through the solver and LIGGGHTS, where the two part from
//!   each other and each from the closed form.
//!
//! Not here: the integrator and the contact law ([`super::solver`]), the LIGGGHTS deck
//! ([`super::check`]).

pub mod drift;
pub mod stiffness;
pub mod timestep;

use crate::contact::{Case, ContactError, Material, Target};

/// The spreading scene's particle (thesis Table 3.1): E 21 MPa, ν 0.3.
pub const SCENE_MATERIAL: Material = Material { youngs: 21e6, poisson: 0.3 };
/// Real steel, stiff enough that the lever arm r − δ/2 is r to 0.1 % (closed-form oblique cases).
pub const STEEL: Material = Material { youngs: 200e9, poisson: 0.3 };
/// The scene's particle density, kg/m³.
pub const SCENE_DENSITY: f64 = 7980.0;

/// A relative error below this counts as agreeing with the closed form (1 %: a tenth of the
/// seed-to-seed MFR noise the scene studies measured, BENCHMARKS.md "Scene convergence").
pub const CLOSED_FORM_TOLERANCE: f64 = 1e-2;

/// The base case of the studies: a D 2 mm scene particle on a same-material wall at 1 m/s,
/// elastic and frictionless, at the default timestep.
pub fn scene_case() -> Case {
    Case {
        target: Target::Wall(SCENE_MATERIAL),
        radius: 1e-3,
        density: SCENE_DENSITY,
        material: SCENE_MATERIAL,
        restitution: 1.0,
        friction: 0.0,
        vn: 1.0,
        vt: 0.0,
        spin: 0.0,
        dt: None,
    }
}

/// Rows as CSV, header from the field names (`None` → an empty cell).
pub fn to_csv<T: serde::Serialize>(rows: &[T]) -> Result<String, ContactError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(std::io::Error::from)?;
    }
    let bytes = w.into_inner().map_err(|e| std::io::Error::other(e.to_string()))?;
    String::from_utf8(bytes).map_err(|e| ContactError::Io(std::io::Error::other(e)))
}
