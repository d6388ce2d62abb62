//! Benchmarks behind `sweep bench`: run time against error of the fidelity presets
//! ([`fidelity`]), the scene's stability edge ([`stability`]), the contact reference
//! solver's own stability ([`contact`]), and the designs against a known answer ([`designs`]).
//!
//! The top of the pipeline beside the command line: a bench may use every stage below it.

pub mod contact;
pub mod designs;
pub mod fidelity;
pub mod stability;

/// An optional number with `digits` decimals, or `absent` when there is none: the one formatter
/// of the benches' fixed-point cells.
pub fn opt_or(v: Option<f64>, digits: usize, absent: &str) -> String {
    v.map_or_else(|| absent.to_string(), |v| format!("{v:.digits$}"))
}

/// An optional number with `digits` decimals, empty when absent (a CSV cell).
pub fn opt(v: Option<f64>, digits: usize) -> String {
    opt_or(v, digits, "")
}

/// `v` in scientific notation for a table cell, or "-".
pub fn cell(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.2e}"))
}
