//! demsweep: parameter sweeps of LIGGGHTS powder-spreading simulations.
//!
//! The pipeline (DESIGN §2), one module per stage, data flowing one way:
//! sweep file → [`sweep`] → [`space`] + [`design`] → [`scene`] → deck → engine → dump → metrics.

pub mod analysis;
pub mod bench;
pub mod contact;
pub mod design;
pub mod engine;
pub mod error;
pub mod outcome;
pub mod point;
pub mod report;
pub mod run;
pub mod scene;
pub mod store;
pub mod sweep;
pub mod sys;

pub use error::{Error, Result};
