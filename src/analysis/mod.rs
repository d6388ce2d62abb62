//! Analysis: what the MFR values of a sweep say. Statistics with bootstrap intervals, the
//! convergence rule over nested spaces, and sensitivity indices.
//!
//! Pure functions of numbers and settings: nothing here runs a point, drives a sweep or touches
//! a sweep directory.

pub mod adapt;
pub mod calibration;
pub mod convergence;
pub mod emulator;
pub mod noise;
pub mod sensitivity;
pub mod simplex;
pub mod stats;
pub mod weights;
