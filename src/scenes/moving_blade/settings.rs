//! The moving-blade layouts' own `[scene]` keys: the window the blade's flow is measured over,
//! what the run dumps, and the gated dose's settle and release.

use serde::{Deserialize, Serialize};

use crate::scene::own_settings::LayoutSettings;
use crate::scene::settings::SceneSettings;

/// The moving-blade layouts' own `[scene]` keys (the thesis's pile reads no gate's).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SpreadSettings {
    /// Length of the MFR measurement window (blade travel), in diameters.
    pub window_diameters: f64,
    /// Interval of a dump of every per-particle column over the whole run, s (0: none; only the
    /// window's snapshots of the columns the metrics read are written).
    pub full_dump_every_s: f64,
    /// Keep the blade going after the window to the end of the domain (the thesis's full
    /// traverse) instead of stopping once the window is measured.
    pub run_to_end: bool,
    /// Gated layout: the least settle before the rest criterion is first checked, in free-fall
    /// times of the dose block (a lattice block is still for an instant before it collapses).
    pub settle_min_falls: f64,
    /// Gated layout: blade travel past the opened gate before the window starts, in diameters.
    pub window_start_diameters: f64,
}

impl Default for SpreadSettings {
    /// The fast preset's. 40 D of window: measured 2.8× less seed-to-seed spread than 20 D for
    /// 1.6× the CPU (BENCHMARKS.md "MFR noise").
    fn default() -> Self {
        SpreadSettings {
            window_diameters: 40.0,
            full_dump_every_s: 0.0,
            run_to_end: false,
            settle_min_falls: 2.0,
            window_start_diameters: 30.0,
        }
    }
}

impl LayoutSettings for SpreadSettings {
    fn knobs(&self) -> &'static [&'static str] {
        &["window_diameters", "settle_min_falls", "full_dump_every_s", "run_to_end"]
    }
}

impl SpreadSettings {
    /// The keys of fidelity `fidelity`: a window twice as long at `reference`; the thesis's
    /// every column dumped every 0.02 s (Appendix A) and its blade driven to the end of the
    /// domain at `thesis`.
    pub fn preset(fidelity: &str) -> SpreadSettings {
        let fast = SpreadSettings::default();
        match fidelity {
            "reference" => SpreadSettings { window_diameters: 80.0, ..fast },
            "thesis" => SpreadSettings { full_dump_every_s: 0.02, run_to_end: true, ..fast },
            _ => fast,
        }
    }

    /// `written` over the preset of `fidelity`.
    pub fn read(fidelity: &str, written: &toml::Table) -> Result<SpreadSettings, toml::de::Error> {
        let mut table =
            toml::Table::try_from(SpreadSettings::preset(fidelity)).map_err(serde::de::Error::custom)?;
        table.extend(written.clone());
        table.try_into()
    }

    /// The settings it cannot run with, named by their key.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        for (k, v) in [
            ("scene.window_start_diameters", self.window_start_diameters),
            ("scene.window_diameters", self.window_diameters),
            ("scene.settle_min_falls", self.settle_min_falls),
        ] {
            if !v.is_finite() || v <= 0.0 {
                return Err((k, format!("{v}: expected a finite number > 0")));
            }
        }
        let v = self.full_dump_every_s;
        if !v.is_finite() || v < 0.0 {
            return Err(("scene.full_dump_every_s", format!("{v}: expected a finite number ≥ 0 (0: off)")));
        }
        Ok(())
    }
}

/// A moving-blade point's own keys.
pub fn own(s: &SceneSettings) -> &SpreadSettings {
    s.own.get().expect("a moving-blade point's settings hold the moving-blade layouts' keys")
}
