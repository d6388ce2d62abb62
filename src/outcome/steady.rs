//! The steady-state record of a held-heap run as result.json stores it (`steady_state`;
//! [`crate::measure::steady`] computes it).

use serde::{Deserialize, Serialize};

/// What a conveyor run measured, beyond MFR itself (result.json `steady_state`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SteadyState {
    /// MFR of every block, the transient included.
    pub block_mfr: Vec<f64>,
    /// Blocks dropped by MSER truncation.
    pub transient_blocks: usize,
    pub window_blocks: usize,
    /// Substrate travel per block, in diameters.
    pub block_diameters: f64,
    /// Blocks per batch of the SE, and the lag-1 autocorrelation of the batch means (over every
    /// block after the warm-up, from which the SE is taken).
    pub batch_blocks: usize,
    pub batch_acf1: f64,
    /// Lag-1 autocorrelation of the window's blocks.
    pub block_acf1: f64,
    /// OLS slope of the window's batch means (`measure::steady::window_trend`) over its SE, and the limit
    /// |trend_z| must stay within for the window to count as steady (absent in older results,
    /// whose trend was over single blocks within 3).
    pub trend_z: f64,
    #[serde(default = "old_trend_limit")]
    pub trend_limit: f64,
    /// (last quarter − first quarter) / MFR over the window.
    pub drift: f64,
    /// The heap's count at the window's start and end, and its target.
    pub heap_start: u64,
    pub heap_end: u64,
    pub heap_target: u64,
    /// The heap's mean mass over the window per width of blade, kg/m (= g/mm): the same at
    /// every D for one `heap_height` (absent in older results).
    #[serde(default)]
    pub heap_mass_per_width: f64,
    /// `"target"`: the precision target ended the run; `"cap"`: the window cap did.
    pub stop: String,
}

/// The trend limit of results written before it was recorded.
fn old_trend_limit() -> f64 {
    3.0
}
