//! The sweep file's schema: the tables and keys a user writes, with their defaults.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::analysis::convergence::ConvergenceSettings;
use crate::design::halton::Scrambling;
use crate::scene::settings::SceneSettings;

/// Version of the resolved sweep format written to `DIR/sweep.toml`.
pub const SWEEP_FORMAT: u32 = 1;

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Name of the sweep; the default output directory is `runs/<name>`.
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Files whose `[parameters]` this sweep takes, in order, for every parameter it does not
    /// set itself (e.g. the powder `sweep calibrate` wrote: `include = ["calibrated.toml"]`).
    /// Paths are relative to the sweep file; the resolved sweep (`DIR/sweep.toml`) holds the
    /// parameters themselves and no include.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub include: Vec<PathBuf>,
    /// Every parameter of the scene that the sweep sets: a range (swept) or a value (fixed).
    /// Parameters not named take the scene's defaults.
    pub parameters: toml::Table,
    #[serde(default)]
    pub design: DesignSettings,
    #[serde(default)]
    pub convergence: ConvergenceSettings,
    /// `[scene]`: the keys every layout reads and the layout's own, each from the fidelity's
    /// preset where the file does not write it (read by the layouts,
    /// [`crate::scenes::settings::parse`]).
    #[serde(default, deserialize_with = "crate::scenes::settings::deserialize")]
    pub scene: SceneSettings,
    #[serde(default)]
    pub run: RunSettings,
    #[serde(default, skip_serializing_if = "ClusterSettings::is_default")]
    pub cluster: ClusterSettings,
}

/// `[cluster]`: how the scripts of `sweep submit` start `sweep` on a node.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ClusterSettings {
    /// The command that runs `sweep` on a node, e.g. `"sweep"` (found on the node's PATH) or
    /// `"/opt/demsweep/bin/sweep"`; default: the executable that submits.
    pub command: Option<String>,
    /// Lines each script runs first, e.g. `["module load liggghts/3.8", "module load demsweep"]`.
    pub prologue: Vec<String>,
}

impl ClusterSettings {
    fn is_default(&self) -> bool {
        *self == ClusterSettings::default()
    }
}

/// One entry of `[parameters]` as written: either `{ lo, hi, [unit], [scale] }` or `{ value,
/// [unit] }` or a bare number.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(super) struct ParamEntry {
    pub(super) lo: Option<f64>,
    pub(super) hi: Option<f64>,
    pub(super) value: Option<f64>,
    pub(super) unit: Option<String>,
    #[serde(default)]
    pub(super) scale: Scale,
}

#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Scale {
    #[default]
    Linear,
    /// Uniform in log(x); only for positive ranges.
    Log,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct DesignSettings {
    /// Lattice levels: n values per dimension, run in order (`sweep lattice`).
    pub lattice_levels: Vec<usize>,
    pub lds: LdsSettings,
    pub adapt: AdaptSettings,
}

impl Default for DesignSettings {
    fn default() -> Self {
        DesignSettings {
            lattice_levels: vec![5, 6, 7, 9, 10],
            lds: LdsSettings::default(),
            adapt: AdaptSettings::default(),
        }
    }
}

/// `[design.adapt]`: the sequential design of `sweep adapt` (docs/statistics.md "Adaptive
/// design").
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct AdaptSettings {
    /// Points of the first batch, scrambled Halton; 0 means 10 per swept parameter (the
    /// "10·d" starting design of Loeppky, Sacks & Welch 2009).
    pub first: usize,
    /// Points of every later batch; 0 means the job slots (`--jobs`).
    pub batch: usize,
    /// Most points to run. 480 by default: on the replayed thesis sweep, at an adaptive sweep's
    /// precision, the rule held at 300–420 runs (docs/statistics.md "When the rule waits on the
    /// skewness").
    pub max: usize,
    /// Seed of the first batch's scrambling, of the candidates and of the emulator's draws.
    pub seed: u64,
}

impl Default for AdaptSettings {
    fn default() -> Self {
        AdaptSettings { first: 0, batch: 0, max: 480, seed: DEFAULT_SEED }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct LdsSettings {
    /// Points per batch; each prefix of the sequence at a multiple of `step` is one space.
    pub step: usize,
    /// Most points to run.
    pub max: usize,
    pub scrambling: Scrambling,
    /// Seed for `scrambling = "random"`. The default, 14, was chosen by measurement
    /// (`docs/study/statistics/bench_discrepancy.py`, BENCHMARKS.md "Design discrepancy"): of
    /// seeds 0–39 it has the smallest worst-case ratio of its centred discrepancy to the average of
    /// scipy's scrambled Halton in 4-D and 6-D (N = 400, 800, 2400) and 8-D (N = 100), and is
    /// below that average in every case.
    pub seed: u64,
}

impl Default for LdsSettings {
    fn default() -> Self {
        LdsSettings { step: 400, max: 2400, scrambling: Scrambling::default(), seed: DEFAULT_SEED }
    }
}

/// The default `design.lds.seed` (see [`LdsSettings::seed`]).
pub const DEFAULT_SEED: u64 = 14;

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RunSettings {
    /// LIGGGHTS executable (default: `liggghts` on PATH).
    pub engine: Option<PathBuf>,
    /// Wall-clock limit of one run, seconds.
    pub timeout_s: f64,
    /// Retries of transient failures (could not start, killed by a signal, timed out).
    pub retries: u32,
    /// Skip the points where nothing can pass under the blade ([`crate::scene::passage`]),
    /// counting them as MFR = 0, once a seeded sample of them has run and given MFR = 0
    /// ([`crate::run::screen`]).
    pub screen: bool,
    /// Fraction of the closed points run anyway to verify the screen (seeded by
    /// `design.lds.seed`).
    pub screen_sample: f64,
    /// ... and at least this many (every closed point when fewer).
    pub screen_sample_min: usize,
}

impl Default for RunSettings {
    fn default() -> Self {
        RunSettings {
            engine: None,
            timeout_s: 600.0,
            retries: 1,
            screen: true,
            // A tenth: on a 2,400-point sweep of the thesis space about 12 of ~120 closed points.
            screen_sample: 0.1,
            screen_sample_min: 3,
        }
    }
}
