//! The layers layout's own `[scene]` keys: its passes, its bed, its blade and its plate.

use serde::{Deserialize, Serialize};

use crate::scene::own_settings::{LayoutSettings, OwnSettings};
use crate::scene::settings::SceneSettings;
use crate::scenes::BadSetting;

use super::{
    fused, geometry, Bed, MAX_BLADE_RADIUS_MM, MAX_CLEARANCE_MM, MAX_FREEZE_DEPTH_DIAMETERS, MAX_LAYERS,
    MAX_PLATE_DIAMETERS, MIN_FREEZE_DEPTH_DIAMETERS, MIN_STEADY_PASSES,
};

/// Passes by default; enough for the steady layer of every case measured (docs/study/layers.md).
pub const DEFAULT_LAYERS: usize = 10;
/// A fused bed's search passes by default (docs/study/layers.md: Ti-6Al-4V's depth came within
/// 3 % of its steady value in six).
pub const DEFAULT_SEARCH_PASSES: usize = 6;
/// A round blade's radius by default, mm (Gaboriault et al. 2025's blade).
pub const DEFAULT_BLADE_RADIUS_MM: f64 = 2.5;
/// Segments of a roller's whole circle: the round blade's angle a segment (its 48 over 0.75 of a
/// half circle); docs/study/roller.md "The roller's numerics" halves and doubles it.
pub const DEFAULT_ROLLER_SEGMENTS: usize = 128;
/// The build plate's length by default, in diameters.
pub const DEFAULT_PLATE_DIAMETERS: f64 = 40.0;

/// The layers layout's own `[scene]` keys (no fidelity changes them).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct LayersSettings {
    /// Passes of the blade, each onto the layers before it: the most a point runs.
    pub layers: usize,
    /// `"loose"` (default: the layers before stay powder and are sheared again, as in a
    /// spreading test or binder jetting) or `"fused"` (each layer consolidates to a solid of its
    /// packing times its height before the next, as in laser or electron-beam fusion).
    pub bed: String,
    /// A fused bed: the first passes search for the steady depth of powder under the blade
    /// instead of building it up layer by layer — after each, the solid is set so that the next
    /// pass meets its own depth times the layer thickness over its deposit; 0: every pass is a
    /// layer on the one before, from the bare plate. Not set: a fused bed searches for
    /// [`DEFAULT_SEARCH_PASSES`] passes (at most `layers` less six), a loose bed never.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search_passes: Option<usize>,
    /// The fewest passes before a point may stop on its steady layer; it runs pass by pass until
    /// the steady rule holds or it reaches `layers`, the most. Not set: the search's passes and
    /// [`super::STOP_KEPT_PASSES`] laid ones after them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub least_layers: Option<usize>,
    /// The blade's profile, `"flat"` (default: a box, the thesis's), `"round"` (a cylinder of
    /// `blade_radius_mm`, its lowest line the tip) or `"roller"` (that cylinder turning).
    pub blade_profile: String,
    /// Radius of a round blade or a roller, mm.
    pub blade_radius_mm: f64,
    /// Height of the blade's tip above the machine's top surface (the level the dose is fed at
    /// and the platform drops from), mm; 0: the blade grazes it.
    pub blade_clearance_mm: f64,
    /// A roller: segments of its circle's mesh (a numerical knob: the roller's resolution; the
    /// round blade's angle a segment by default).
    pub roller_segments: usize,
    /// Length of the build plate along the travel, in diameters.
    pub plate_diameters: f64,
    /// A loose bed: the bed deeper than this many diameters under the machine's top surface, at
    /// rest and beyond the blade's reach, stops moving and its particles are not searched
    /// against each other (0: the whole bed moves).
    pub freeze_depth_diameters: f64,
    /// In a sweep: start a point from the steady state of its nearest finished neighbour (a
    /// fused bed's steady depth, skipping the search); a point with none searches as it would.
    pub warm_start: bool,
    /// Lay every dose from the third pass on as pass 2's came to rest in front of the blade
    /// (a copy, a layer higher a pass, nudged; a round blade starts where its arc clears it),
    /// instead of dropping a fresh one that falls and settles during and after every pass. Off
    /// by default: about 1.5 times less CPU a pass and the same steady layer within 2 SE at 0.1
    /// m/s, but at 0.2 m/s a bed 5–8 SE deeper and less packed (docs/layers.md "Laid doses").
    pub laid_dose: bool,
}

impl Default for LayersSettings {
    fn default() -> Self {
        LayersSettings {
            layers: DEFAULT_LAYERS,
            bed: "loose".into(),
            search_passes: None,
            least_layers: None,
            blade_profile: "flat".into(),
            blade_radius_mm: DEFAULT_BLADE_RADIUS_MM,
            blade_clearance_mm: 0.0,
            roller_segments: DEFAULT_ROLLER_SEGMENTS,
            plate_diameters: DEFAULT_PLATE_DIAMETERS,
            freeze_depth_diameters: 0.0,
            warm_start: false,
            laid_dose: false,
        }
    }
}

impl LayoutSettings for LayersSettings {
    fn knobs(&self) -> &'static [&'static str] {
        &["roller_segments", "warm_start"]
    }

    fn warm_start(&self) -> bool {
        self.warm_start
    }
}

impl LayersSettings {
    /// The settings of a layers sweep with these keys, every other key the fast preset's.
    pub fn settings(self) -> SceneSettings {
        SceneSettings { layout: super::NAME.into(), own: OwnSettings::new(self), ..SceneSettings::default() }
    }

    /// `written` over the defaults (the same at every fidelity).
    pub fn read(written: &toml::Table) -> Result<LayersSettings, toml::de::Error> {
        written.clone().try_into()
    }
}

/// The layers settings it cannot run with, named by their key.
pub fn check(s: &SceneSettings) -> Result<(), BadSetting> {
    if !(1..=MAX_LAYERS).contains(&own(s).layers) {
        return Err(BadSetting {
            key: "scene.layers",
            why: format!("{}: expected a whole number of passes from 1 to {MAX_LAYERS}", own(s).layers),
        });
    }
    if Bed::parse(&own(s).bed).is_none() {
        return Err(BadSetting {
            key: "scene.bed",
            why: format!("\"{}\": expected \"loose\" or \"fused\"", own(s).bed),
        });
    }
    let asked = own(s).search_passes.unwrap_or(0);
    if asked > 0 && !fused(s) {
        return Err(BadSetting {
            key: "scene.search_passes",
            why: format!(
                "{asked}: a search for the steady depth needs bed = \"fused\" (a loose bed's depth is the powder it keeps); expected 0"
            ),
        });
    }
    if asked > 0 && asked + MIN_STEADY_PASSES > own(s).layers {
        return Err(BadSetting {
            key: "scene.search_passes",
            why: format!(
                "{asked}: expected at most scene.layers − {MIN_STEADY_PASSES} = {} (the steady layer needs {MIN_STEADY_PASSES} passes after the search)",
                own(s).layers.saturating_sub(MIN_STEADY_PASSES)
            ),
        });
    }
    if let Some(least) = own(s).least_layers {
        if !(1..=own(s).layers).contains(&least) {
            return Err(BadSetting {
                key: "scene.least_layers",
                why: format!(
                    "{least}: expected a whole number of passes from 1 to scene.layers = {} (the most a point runs)",
                    own(s).layers
                ),
            });
        }
    }
    if !matches!(own(s).blade_profile.as_str(), "flat" | "round" | "roller") {
        return Err(BadSetting {
            key: "scene.blade_profile",
            why: format!("\"{}\": expected \"flat\", \"round\" or \"roller\"", own(s).blade_profile),
        });
    }
    // Bounded above too: a radius of 1e155 mm overflowed the blade's mesh, 1e10 took minutes
    // to mesh. A machine's blade or roller is millimetres to centimetres.
    for (key, v, least, most) in [
        ("scene.blade_radius_mm", own(s).blade_radius_mm, 0.0, MAX_BLADE_RADIUS_MM),
        ("scene.blade_clearance_mm", own(s).blade_clearance_mm, 0.0, MAX_CLEARANCE_MM),
        ("scene.plate_diameters", own(s).plate_diameters, 10.0, MAX_PLATE_DIAMETERS),
        ("scene.supply_factor", s.supply_factor, 0.5, 100.0),
        ("scene.freeze_depth_diameters", own(s).freeze_depth_diameters, 0.0, MAX_FREEZE_DEPTH_DIAMETERS),
    ] {
        let radius = key == "scene.blade_radius_mm";
        let ok = v.is_finite() && v <= most && if radius { v > least } else { v >= least };
        if !ok {
            let lower = if radius { format!("above {least}") } else { format!("from {least}") };
            return Err(BadSetting { key, why: format!("{v}: expected a number {lower} to {most}") });
        }
    }
    geometry::check(s)?;
    if own(s).blade_profile == "flat" && own(s).blade_radius_mm != DEFAULT_BLADE_RADIUS_MM {
        return Err(BadSetting {
            key: "scene.blade_radius_mm",
            why: format!(
                "{}: a flat blade has no radius; expected it only with blade_profile = \"round\" or \"roller\"",
                own(s).blade_radius_mm
            ),
        });
    }
    if own(s).freeze_depth_diameters > 0.0 && fused(s) {
        return Err(BadSetting {
            key: "scene.freeze_depth_diameters",
            why: format!(
                "{}: a fused bed keeps no powder under its layers to hold still; expected it only with bed = \"loose\"",
                own(s).freeze_depth_diameters
            ),
        });
    }
    if own(s).freeze_depth_diameters > 0.0 && own(s).freeze_depth_diameters < MIN_FREEZE_DEPTH_DIAMETERS {
        return Err(BadSetting {
            key: "scene.freeze_depth_diameters",
            why: format!(
                "{}: expected 0 (off) or at least {MIN_FREEZE_DEPTH_DIAMETERS} diameters, below the blade's reach",
                own(s).freeze_depth_diameters
            ),
        });
    }
    if s.substrate == "powder" {
        return Err(BadSetting {
            key: "scene.substrate",
            why: "\"powder\": the layers layout spreads its own bed of the powder (scene.bed); expected \"smooth\" or \"rough\", which it ignores".into(),
        });
    }
    Ok(())
}

/// A layers point's own keys.
pub fn own(s: &SceneSettings) -> &LayersSettings {
    s.own.get().expect("a layers point's settings hold the layers layout's keys")
}

/// `s` with its layers keys as `change` leaves them.
pub fn with_own(mut s: SceneSettings, change: impl FnOnce(&mut LayersSettings)) -> SceneSettings {
    change(s.own.get_mut().expect("a layers point's settings hold the layers layout's keys"));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> SceneSettings {
        LayersSettings {
            layers: 4,
            plate_diameters: 20.0,
            blade_clearance_mm: 0.05,
            ..LayersSettings::default()
        }
        .settings()
    }

    #[test]
    fn a_bad_layer_count_bed_or_profile_is_refused_naming_its_key() {
        let fused = |layers: usize, search_passes: usize| {
            with_own(settings(), |l| {
                l.bed = "fused".into();
                l.layers = layers;
                l.search_passes = Some(search_passes);
            })
        };
        let cases: [(SceneSettings, &str); 7] = [
            // A loose bed keeps its powder: there is no depth to search for.
            (with_own(settings(), |l| l.search_passes = Some(1)), "scene.search_passes"),
            // The steady layer needs three passes after the search.
            (fused(6, 4), "scene.search_passes"),
            (with_own(settings(), |l| l.layers = 0), "scene.layers"),
            (with_own(settings(), |l| l.layers = 1000), "scene.layers"),
            (with_own(settings(), |l| l.bed = "sintered".into()), "scene.bed"),
            (with_own(settings(), |l| l.blade_profile = "wavy".into()), "scene.blade_profile"),
            (with_own(settings(), |l| l.blade_clearance_mm = -0.1), "scene.blade_clearance_mm"),
        ];
        for (s, key) in cases {
            let err = check(&s).unwrap_err();
            assert_eq!(err.key, key);
            assert!(!err.why.contains('\n'));
        }
        assert!(check(&settings()).is_ok());
        assert!(check(&fused(7, 4)).is_ok());
        let v = [("diameter", 0.065), ("layer_thickness", -0.05)].map(|(k, v)| (k.to_string(), v)).into();
        let err = crate::scenes::build(&v, &settings()).unwrap_err().to_string();
        assert!(err.contains("layer_thickness") && err.contains("domain"), "{err}");
    }
}
