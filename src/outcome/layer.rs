//! The spread layer's quality measures as result.json stores them (docs/layer.md defines them;
//! [`crate::measure::layer`] measures them).

use serde::{Deserialize, Serialize};

/// The layer measures of one run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    /// Coefficient of variation of the deposited mass per bin (–); NaN, and absent from the
    /// file, where the layout measures none (layers).
    #[serde(
        default = "super::not_measured",
        deserialize_with = "super::nan_if_null",
        skip_serializing_if = "super::is_not_measured"
    )]
    pub layer_cv: f64,
    /// The same for independently placed particles: its counting noise (–).
    #[serde(
        default = "super::not_measured",
        deserialize_with = "super::nan_if_null",
        skip_serializing_if = "super::is_not_measured"
    )]
    pub layer_cv_noise: f64,
    /// Share of the strip's area under the deposit (–).
    pub covered_fraction: f64,
    /// RMS of the top surface's height about its mean, in D.
    pub roughness_d: f64,
    /// Mean top-surface height over the strip, in D.
    pub height_d: f64,
    /// Particles in the deposit.
    pub particles: usize,
}
