//! Designs: where in the unit cube the sweep puts its points.
//!
//! - [`lattice`]: n values per dimension, inclusive of both ends, n^d points in a stable order.
//! - [`halton`]: the Halton sequence, plain or scrambled (Braaten–Weller or seeded random
//!   digit permutations); every prefix of the sequence is itself a design, which is what lets an
//!   LDS sweep stop early and extend later.
//! - [`discrepancy`]: the centred L2 discrepancy of a point set, to compare designs.
//!
//! Points are in unit coordinates; [`crate::sweep::space`] scales them onto parameter ranges.

pub mod discrepancy;
pub mod halton;
pub mod lattice;

/// A design: points in unit coordinates, one `Vec` of length `dim` per point.
pub type Points = Vec<Vec<f64>>;

/// The most points a design may have: far beyond any DEM sweep (the thesis's largest is
/// 10,000), small enough that a mistyped level count is an error instead of exhausting memory.
pub const MAX_POINTS: usize = 1_000_000;

/// Why a design of the size asked for cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DesignError {
    #[error("expected at least 2 values per dimension")]
    TooFewLevels,
    /// A lattice of `levels^dim` points, more than [`MAX_POINTS`].
    #[error("{levels}^{dim} points: expected at most {MAX_POINTS}")]
    LargeLattice { levels: usize, dim: usize },
    #[error("expected a positive number of points")]
    NoPoints,
    #[error("expected at most {MAX_POINTS} points")]
    TooManyPoints,
}

/// The number of points of the lattice with `levels` values per dimension in `dim`
/// dimensions, or why it cannot be built (fewer than 2 levels, more than [`MAX_POINTS`]).
pub fn lattice_size(dim: usize, levels: usize) -> Result<usize, DesignError> {
    if levels < 2 {
        return Err(DesignError::TooFewLevels);
    }
    match levels.checked_pow(dim as u32) {
        Some(n) if n <= MAX_POINTS => Ok(n),
        _ => Err(DesignError::LargeLattice { levels, dim }),
    }
}

/// Check a Halton design size: at least 1 and at most [`MAX_POINTS`] points.
pub fn lds_size(n: usize) -> Result<usize, DesignError> {
    if n == 0 {
        Err(DesignError::NoPoints)
    } else if n > MAX_POINTS {
        Err(DesignError::TooManyPoints)
    } else {
        Ok(n)
    }
}
