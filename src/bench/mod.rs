//! Benchmarks behind `sweep bench`: run time against error of the fidelity presets
//! ([`fidelity`]), the scene's stability edge ([`stability`]), and the contact reference
//! solver's own stability ([`contact`]).
//!
//! The top of the pipeline beside the command line: a bench may use every stage below it.

pub mod contact;
pub mod fidelity;
pub mod stability;
