//! Measuring a run: its dump frames, the flux counts and v_x profile of a moving blade's window,
//! the steady state of a held heap, the spread layer's quality, the v_x profile's quality class,
//! and the plausibility checks of what the engine wrote. Building blocks the scenes use.

pub mod frame;
pub mod layer;
pub mod metrics;
pub mod plausible;
pub mod quality;
pub mod steady;
