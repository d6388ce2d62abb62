//! Designs: where in the unit cube the sweep puts its points.
//!
//! - [`lattice`]: n values per dimension, inclusive of both ends, n^d points in a stable order.
//! - [`halton`]: the Halton sequence, plain or scrambled (Braaten–Weller or seeded random
//!   digit permutations); every prefix of the sequence is itself a design, which is what lets an
//!   LDS sweep stop early and extend later.
//! - [`discrepancy`]: the centred L2 discrepancy of a point set, to compare designs.
//!
//! Points are in unit coordinates; [`crate::space`] scales them onto parameter ranges.

pub mod discrepancy;
pub mod halton;
pub mod lattice;

/// A design: points in unit coordinates, one `Vec` of length `dim` per point.
pub type Points = Vec<Vec<f64>>;
