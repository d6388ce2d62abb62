//! Which layouts read which `[scene]` keys: each layout lists the keys it reads of those some
//! layout does not ([`Layout::own_settings`](super::Layout::own_settings)), and a key set away
//! from its preset's value where its layout does not read it is refused, naming the layouts that
//! do ([`unread`]), rather than run as if it had not been written.

use super::LAYOUTS;
use crate::scene::settings::SceneSettings;

/// The layouts that list the `[scene]` key `key` as theirs
/// ([`Layout::own_settings`](super::Layout::own_settings)), in registration order; empty for a
/// key every layout reads.
pub fn readers(key: &str) -> Vec<&'static str> {
    LAYOUTS.iter().filter(|l| l.own_settings().contains(&key)).map(|l| l.name()).collect()
}

/// Whether the layout of `settings` reads the `[scene]` key `key`.
pub fn reads(settings: &SceneSettings, key: &str) -> bool {
    let readers = readers(key);
    readers.is_empty() || readers.contains(&settings.layout.as_str())
}

/// A `[scene]` key set where its layout does not read it ([`unread`]).
#[derive(Debug, Clone, PartialEq)]
pub struct UnreadSetting {
    /// The key, without `scene.`.
    pub key: String,
    /// Its value, as TOML writes it.
    pub value: String,
    /// The layout in use.
    pub layout: String,
    /// The layouts that read it.
    pub readers: Vec<&'static str>,
}

impl std::fmt::Display for UnreadSetting {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} is read only by {}; this sweep's layout is {} (remove the key, or change the layout)",
            self.value,
            the_layouts(&self.readers),
            self.layout
        )
    }
}

/// The first `[scene]` key of `settings` (in the order of its fields) whose layout does not read
/// it but another does, set away from the value its fidelity preset gives it: a setting that
/// would change nothing, refused rather than run without a word. A key at the preset's value is
/// no setting (as a catalogue parameter at its default is none, [`super::set_but_unread`]): a
/// resolved `DIR/sweep.toml` writes every key, and is read as a sweep file too.
pub fn unread(settings: &SceneSettings) -> Option<UnreadSetting> {
    let preset = SceneSettings::common_preset(&settings.fidelity)?;
    let (Ok(mine), Ok(preset)) = (toml::Table::try_from(settings), toml::Table::try_from(&preset)) else {
        return None;
    };
    // The layout's own keys were judged as they were read (`super::settings::parse`).
    let own = settings.own.table();
    mine.iter()
        .filter(|(key, _)| !own.contains_key(*key) && !reads(settings, key))
        .find(|(key, value)| preset.get(*key) != Some(*value))
        .map(|(key, value)| UnreadSetting {
            key: key.clone(),
            value: value.to_string(),
            layout: settings.layout.clone(),
            readers: readers(key),
        })
}

/// "the layers layout", "the gated and conveyor layouts".
pub(super) fn the_layouts(names: &[&str]) -> String {
    match names {
        [one] => format!("the {one} layout"),
        [init @ .., last] => format!("the {} and {last} layouts", init.join(", ")),
        [] => "no layout".into(),
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::scene::Base;
    use crate::scenes::settings::{parse, SettingError};
    use crate::scenes::Layout;

    /// Each key some layout lists, set away from its default (valid where it is read).
    const CHANGED: &[(&str, &str)] = &[
        ("substrate", "\"smooth\""),
        ("supply_factor", "1.5"),
        ("settle_max_s", "2.0"),
        ("settle_min_falls", "3.0"),
        ("rest_speed", "0.02"),
        ("window_start_diameters", "40.0"),
        ("window_diameters", "60.0"),
        ("full_dump_every_s", "0.05"),
        ("run_to_end", "true"),
        ("vx_band_diameters", "0.5"),
        ("thesis_band", "true"),
        ("mesh_cells_across", "3"),
        ("depth_diameters", "8.0"),
        ("block_diameters", "7.0"),
        ("warmup_s", "0.5"),
        ("window_cap_diameters", "800.0"),
        ("mfr_rel_se", "0.03"),
        ("mfr_abs_se", "0.003"),
        ("min_window_blocks", "10"),
        ("warm_start", "true"),
        ("warm_warmup_s", "0.05"),
        ("precision", "\"fixed\""),
        ("layers", "12"),
        ("bed", "\"fused\""),
        ("search_passes", "2"),
        ("least_layers", "8"),
        ("blade_profile", "\"round\""),
        ("blade_radius_mm", "3.0"),
        ("roller_segments", "64"),
        ("blade_clearance_mm", "0.1"),
        ("plate_diameters", "50.0"),
        ("freeze_depth_diameters", "5.0"),
        ("laid_dose", "true"),
    ];

    /// The keys a layout reads when it runs, not when it derives its scene: the precision a
    /// sweep's points run to (`crate::run::precision`), the layers' warm start between points
    /// (`crate::point::passes`), and the layers' settings that act only beside another (a
    /// search needs a fused bed, a radius a round blade).
    const READ_AT_RUN: &[(&str, &str)] = &[
        ("conveyor", "precision"),
        ("layers", "warm_start"),
        ("layers", "search_passes"),
        ("layers", "blade_radius_mm"),
    ];

    /// The layout's settings with `change` written, or why they cannot be read.
    fn read(layout: &dyn Layout, change: Option<(&str, &str)>) -> Result<SceneSettings, SettingError> {
        let mut table = toml::Table::new();
        table.insert("layout".into(), layout.name().into());
        if let Some((key, value)) = change {
            table.extend(toml::from_str::<toml::Table>(&format!("{key} = {value}")).unwrap());
        }
        parse(&table)
    }

    fn settings(layout: &dyn Layout, change: Option<(&str, &str)>) -> SceneSettings {
        read(layout, change).unwrap()
    }

    /// The layout's scene with `change` written; `None` where the key is another layout's own,
    /// which its settings cannot hold (refused as it is read).
    fn derived(layout: &dyn Layout, change: Option<(&str, &str)>) -> Option<serde_json::Value> {
        let s = match read(layout, change) {
            Err(SettingError::Unread(_)) => return None,
            s => s.unwrap(),
        };
        Some(serde_json::to_value(layout.derive(Base::new(&BTreeMap::new(), &s).unwrap(), &s)).unwrap())
    }

    #[test]
    fn every_key_a_layout_lists_is_a_setting_with_a_changed_value_here() {
        for layout in LAYOUTS {
            for key in layout.own_settings() {
                assert!(
                    CHANGED.iter().any(|(k, _)| *k == key),
                    "{}: {key} has no changed value here",
                    layout.name()
                );
            }
        }
        for (key, _) in CHANGED {
            assert!(!readers(key).is_empty(), "{key}: no layout lists it");
        }
    }

    /// What a refusal rests on: a key a layout does not list changes nothing of its scene (and
    /// so of its deck, its meshes and what its measurement reads from the scene).
    #[test]
    fn a_layout_derives_the_same_scene_whatever_a_key_it_does_not_list_is_set_to() {
        let mut bad = Vec::new();
        for layout in LAYOUTS {
            let plain = derived(*layout, None).unwrap();
            for &(key, value) in CHANGED.iter().filter(|(k, _)| !layout.own_settings().contains(k)) {
                let Some(other) = derived(*layout, Some((key, value))) else { continue };
                let fields: Vec<String> = plain
                    .as_object()
                    .unwrap()
                    .iter()
                    .filter(|(f, v)| other.get(f.as_str()) != Some(v))
                    .map(|(f, _)| f.clone())
                    .collect();
                if !fields.is_empty() {
                    bad.push(format!("{}: {key} = {value}: {fields:?}", layout.name()));
                }
            }
        }
        assert!(bad.is_empty(), "{}", bad.join("\n"));
    }

    /// No layout lists a key it does not read: each changes its scene, but those read only as
    /// it runs, which change none (so that list holds no more than it must).
    #[test]
    fn a_layout_reads_every_key_it_lists() {
        let mut bad = Vec::new();
        for layout in LAYOUTS {
            let plain = derived(*layout, None);
            for &(key, value) in CHANGED.iter().filter(|(k, _)| layout.own_settings().contains(k)) {
                let changed = derived(*layout, Some((key, value))).unwrap() != plain.clone().unwrap();
                if changed == READ_AT_RUN.contains(&(layout.name(), key)) {
                    bad.push(format!("{}: {key} = {value} changes its scene: {changed}", layout.name()));
                }
            }
        }
        assert!(bad.is_empty(), "{}", bad.join("\n"));
    }

    #[test]
    fn a_key_is_refused_where_its_layout_does_not_read_it_and_only_away_from_its_preset_value() {
        let conveyor = crate::scenes::lookup("conveyor").unwrap();
        // Another layout's own key is refused as it is read ...
        let Err(SettingError::Unread(u)) = read(conveyor, Some(("bed", "\"fused\""))) else {
            panic!("a conveyor takes a fused bed")
        };
        assert_eq!((u.key.as_str(), u.value.as_str(), &u.readers), ("bed", "\"fused\"", &vec!["layers"]));
        assert_eq!(
            u.to_string(),
            "\"fused\" is read only by the layers layout; this sweep's layout is conveyor (remove the key, or change the layout)"
        );
        // ... but at its default, as a resolved sweep.toml writes every key, it is no setting.
        assert_eq!(settings(conveyor, Some(("bed", "\"loose\""))), SceneSettings::default());
        // A key every layout's settings hold is refused by `unread`, where the layout does not
        // read it.
        assert_eq!(unread(&settings(conveyor, Some(("block_diameters", "7.0")))), None);
        // A knob at the value of the file's preset is none either, at another it is.
        let layers = crate::scenes::lookup("layers").unwrap();
        let mut reference = SceneSettings::common_preset("reference").unwrap();
        reference.layout = "layers".into();
        assert_eq!(unread(&reference), None);
        reference.rest_speed = 0.01;
        let u = unread(&reference).unwrap();
        assert_eq!((u.key.as_str(), u.readers), ("rest_speed", vec!["gated", "pour"]));
        assert!(matches!(
            read(layers, Some(("window_cap_diameters", "800.0"))),
            Err(SettingError::Unread(_))
        ));
    }
}
