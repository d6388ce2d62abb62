//! The parameter space of a sweep: maps unit-cube design points onto parameter values.
//!
//! Thesis §3.3: a point x in [0, 1) scales to A + x·(B − A). A log-scaled parameter is uniform
//! in ln(value) instead. The end points are exact: x = 0 gives lo and x = 1 gives hi bit for bit,
//! so a lattice contains both ends of every range.

use crate::sweep::{ParamKind, Scale, Sweep};

/// The unit coordinate of `v` on [lo, hi] (the inverse of [`scale`]; not clamped, so a value
/// outside the range lands outside [0, 1]).
pub fn unscale(v: f64, lo: f64, hi: f64, scale: Scale) -> f64 {
    match scale {
        Scale::Linear => (v - lo) / (hi - lo),
        Scale::Log => (v.ln() - lo.ln()) / (hi.ln() - lo.ln()),
    }
}

/// A point of swept values in unit coordinates (the inverse of [`scale_point`]).
pub fn unit_point(sweep: &Sweep, values: &[f64]) -> Vec<f64> {
    sweep
        .swept
        .iter()
        .zip(values)
        .map(|(p, &v)| match p.kind {
            ParamKind::Swept { lo, hi, scale: s } if hi != lo => unscale(v, lo, hi, s),
            _ => 0.5,
        })
        .collect()
}

/// Scale one coordinate in [0, 1] onto [lo, hi].
pub fn scale(x: f64, lo: f64, hi: f64, scale: Scale) -> f64 {
    if x <= 0.0 {
        return lo;
    }
    if x >= 1.0 {
        return hi;
    }
    match scale {
        Scale::Linear => lo + x * (hi - lo),
        Scale::Log => (lo.ln() + x * (hi.ln() - lo.ln())).exp(),
    }
}

/// Scale a unit-cube point onto the swept parameters of `sweep`, in their file order.
pub fn scale_point(sweep: &Sweep, unit: &[f64]) -> Vec<f64> {
    debug_assert_eq!(unit.len(), sweep.dim());
    sweep
        .swept
        .iter()
        .zip(unit)
        .map(|(p, &x)| match p.kind {
            ParamKind::Swept { lo, hi, scale: s } => scale(x, lo, hi, s),
            ParamKind::Fixed(v) => v,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_scaling_is_thesis_formula_with_exact_ends() {
        assert_eq!(scale(0.0, 0.1, 0.3, Scale::Linear), 0.1);
        assert_eq!(scale(1.0, 0.1, 0.3, Scale::Linear), 0.3);
        assert!((scale(0.25, 1.0, 5.0, Scale::Linear) - 2.0).abs() < 1e-15);
    }

    #[test]
    fn log_scaling_is_uniform_in_log() {
        // Midpoint of [1, 100] in log scale is 10.
        assert!((scale(0.5, 1.0, 100.0, Scale::Log) - 10.0).abs() < 1e-12);
        assert_eq!(scale(1.0, 1.0, 100.0, Scale::Log), 100.0);
    }
}
