//! The conveyor layout's own `[scene]` keys: its deposit series, the precision it runs to and
//! its warm start.

use serde::{Deserialize, Serialize};

use crate::scene::own_settings::{LayoutSettings, OwnSettings};
use crate::scene::settings::SceneSettings;

/// The default warm-up in gravity times of the held heap, √(H/g) with H = gap + `heap_height`
/// (docs/study/warmup-um.md): long runs at D 1–3 mm and 24–35 µm settle within it.
pub const WARMUP_HEAP_FALLS: f64 = 6.5;

/// The conveyor layout's own `[scene]` keys.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ConveyorSettings {
    /// substrate travel per block of the deposit series, in diameters.
    pub block_diameters: f64,
    /// simulated time before the precision target is first checked, s (at
    /// least 10 D of travel). Unset (the default): [`WARMUP_HEAP_FALLS`] × √(H/g), H = gap +
    /// `heap_height`, the held heap's height ([`ConveyorSettings::warmup_for`]). The start-up
    /// transient is a time, not a travel, and that time is the heap's: run long, MFR settles
    /// within 3–6 √(H/g) at D 1–3 mm, heaps of 8–40 mm and 0.1–1.4 m/s (docs/study/recoater)
    /// and at D 24–35 µm, heaps of 0.3–1 mm and 0.02–0.2 m/s, cohesive or not
    /// (docs/study/warmup-um.md); 0.3 s at the thesis's heap, 0.04–0.07 s at a real powder's.
    /// A set value wins. The blocks after it are judged by the stop rule's MSER truncation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warmup_s: Option<f64>,
    /// the most travel after the warm-up, in diameters (the window's precision
    /// is a number of blocks): where it ends the run before the precision target is met, the
    /// point says so (`stop = "cap"`). The warm-up is never cut short by it.
    pub window_cap_diameters: f64,
    /// the window runs until the standard error of MFR is at most this
    /// fraction of MFR ...
    pub mfr_rel_se: f64,
    /// ... or at most this absolute value (MFR near zero), whichever is reached first.
    pub mfr_abs_se: f64,
    /// the least number of blocks after the warm-up before the target can stop
    /// the run.
    pub min_window_blocks: usize,
    /// In a sweep: start a point from the steady state a finished point near it
    /// left (its heap mapped to this point's size, speed and gap), so that the transient it must
    /// outlive is the difference between neighbours, not a heap starting from rest. A point with
    /// no such neighbour starts cold. The run's hash does not depend on it.
    pub warm_start: bool,
    /// the least warm-up of a warm-started point, s (at least one block); its
    /// warm-up is the cold one's times the neighbour's distance over 0.5, never less than 0.6 of
    /// the cold one nor than this.
    pub warm_warmup_s: f64,
    /// In a sweep: `"sweep"` — once the first batch has finished, every later
    /// point runs until the SE of its MFR is a tenth of the spread of MFR over that batch (what
    /// the sweep's statistics need; `mfr_rel_se`/`mfr_abs_se` until then); `"fixed"` — always
    /// `mfr_rel_se`/`mfr_abs_se` (the default when the file writes either).
    pub precision: String,
}

impl Default for ConveyorSettings {
    /// The fast preset's.
    fn default() -> Self {
        ConveyorSettings {
            block_diameters: 5.0,
            warmup_s: None,
            window_cap_diameters: 600.0,
            mfr_rel_se: 0.05,
            mfr_abs_se: 0.005,
            min_window_blocks: 8,
            // Opt-in: at machine speeds a warm start left points 3–5 SE above long runs that
            // a start from rest got right (BENCHMARKS.md "Warm start at machine speeds").
            warm_start: false,
            warm_warmup_s: 0.03,
            precision: "sweep".into(),
        }
    }
}

impl LayoutSettings for ConveyorSettings {
    fn knobs(&self) -> &'static [&'static str] {
        &[
            "block_diameters",
            "warmup_s",
            "window_cap_diameters",
            "mfr_rel_se",
            "mfr_abs_se",
            "min_window_blocks",
            "warm_start",
            "warm_warmup_s",
            "precision",
        ]
    }

    fn warm_start(&self) -> bool {
        self.warm_start
    }

    fn sweep_precision(&self) -> bool {
        self.precision == "sweep"
    }
}

impl ConveyorSettings {
    /// The keys of fidelity `fidelity` (a name of [`crate::scene::settings::FIDELITIES`]):
    /// every point to its own target at `reference` and `thesis`, where errors are measured.
    pub fn preset(fidelity: &str) -> ConveyorSettings {
        match fidelity {
            "fast" => ConveyorSettings::default(),
            _ => ConveyorSettings { precision: "fixed".into(), ..ConveyorSettings::default() },
        }
    }

    /// `written` over the preset of `fidelity`; a target written without a precision is the
    /// one the points run to.
    pub fn read(fidelity: &str, written: &toml::Table) -> Result<ConveyorSettings, toml::de::Error> {
        let mut table =
            toml::Table::try_from(ConveyorSettings::preset(fidelity)).map_err(serde::de::Error::custom)?;
        table.extend(written.clone());
        let mut keys: ConveyorSettings = table.try_into()?;
        let target_written = written.contains_key("mfr_rel_se") || written.contains_key("mfr_abs_se");
        if target_written && !written.contains_key("precision") {
            keys.precision = "fixed".into();
        }
        Ok(keys)
    }

    /// The warm-up, s, for a held heap `heap_height` tall (m, gap included): the set
    /// `warmup_s`, or [`WARMUP_HEAP_FALLS`] × √(H/g).
    pub fn warmup_for(&self, heap_height: f64) -> f64 {
        self.warmup_s.unwrap_or_else(|| WARMUP_HEAP_FALLS * (heap_height / crate::scene::GRAVITY).sqrt())
    }

    /// The settings of a conveyor sweep with these keys, every other key the fast preset's.
    pub fn settings(self) -> SceneSettings {
        SceneSettings { layout: super::NAME.into(), own: OwnSettings::new(self), ..SceneSettings::default() }
    }
}

/// A conveyor point's own keys.
pub fn own(s: &SceneSettings) -> &ConveyorSettings {
    s.own.get().expect("a conveyor point's settings hold the conveyor layout's keys")
}
