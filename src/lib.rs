//! demsweep: parameter sweeps of LIGGGHTS powder-spreading simulations.
//!
//! The pipeline (DESIGN §2), one module per stage, data flowing one way:
//! sweep file → [`sweep`] → [`space`] + [`design`] → [`scene`] → deck → engine → dump → metrics.

pub mod atomic;
pub mod cluster;
pub mod contact;
pub mod convergence;
pub mod deck;
pub mod design;
pub mod dump;
pub mod engine;
pub mod error;
pub mod fidelity;
pub mod metrics;
pub mod outcome;
pub mod point;
pub mod pool;
pub mod process;
pub mod progress;
pub mod quality;
pub mod report;
pub mod scene;
pub mod screen;
pub mod sensitivity;
pub mod space;
pub mod stability;
pub mod standin;
pub mod stats;
pub mod store;
pub mod sweep;
pub mod sweeprun;
pub mod weights;

pub use error::{Error, Result};
