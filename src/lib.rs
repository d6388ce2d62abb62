//! demsweep: parameter sweeps of LIGGGHTS powder-spreading simulations.
//!
//! One module per stage of the pipeline, and every import points down it (docs/architecture.md
//! has the order and what each may import): a sweep file ([`sweep`]) and a [`design`] give
//! points; each point is a [`scene`] rendered into a deck and run by LIGGGHTS ([`engine`]),
//! measured into a result ([`point`]); the drivers ([`run`]) run many points into a sweep
//! directory ([`store`]); [`analysis`] and [`report`] say what the results mean. [`contact`]
//! checks the contact model, [`bench`] measures speed against error, and [`sys`] holds the
//! operating-system plumbing beneath them all.

pub mod analysis;
pub mod bench;
pub mod contact;
pub mod design;
pub mod engine;
pub mod error;
pub mod measure;
pub mod outcome;
pub mod point;
pub mod report;
pub mod run;
pub mod scene;
pub mod scenes;
pub mod store;
pub mod sweep;
pub mod sys;

pub use error::{Error, Result};
