//! Reading a `[scene]` table: the keys every layout reads into [`SceneSettings`], the layout's
//! own keys into its type ([`Layout::own_keys`]), each key the file does not write from the
//! fidelity's preset. A key only other layouts read is taken at their preset's value (a
//! resolved `DIR/sweep.toml` of an earlier version writes every key) and refused otherwise,
//! naming them; a key no layout reads is refused with what was meant.

use crate::error::hint;
use crate::scene::settings::{quoted, KnobError, SceneSettings, KNOBS};

use super::{lookup, names, readers, Layout, UnreadSetting, LAYOUTS};

/// Why a `[scene]` table cannot be read.
#[derive(Debug, Clone, PartialEq)]
pub enum SettingError {
    /// A key no layout reads: serde's words (`unknown field `bedd``) and what was meant.
    Unknown { key: String, why: String },
    /// A key with a value it cannot take.
    Value { key: String, why: String },
    /// `layout` or `fidelity` naming none.
    Choice { key: String, why: String },
    /// A key only other layouts read, set away from their preset's value.
    Unread(UnreadSetting),
}

impl SettingError {
    /// The key, as `scene.…`.
    pub fn key(&self) -> String {
        match self {
            SettingError::Unknown { key, .. }
            | SettingError::Value { key, .. }
            | SettingError::Choice { key, .. }
                if key.is_empty() =>
            {
                "scene".into()
            }
            SettingError::Unknown { key, .. }
            | SettingError::Value { key, .. }
            | SettingError::Choice { key, .. } => {
                format!("scene.{key}")
            }
            SettingError::Unread(u) => format!("scene.{}", u.key),
        }
    }

    /// What is wrong with it.
    pub fn why(&self) -> String {
        match self {
            SettingError::Unknown { why, .. }
            | SettingError::Value { why, .. }
            | SettingError::Choice { why, .. } => why.clone(),
            SettingError::Unread(u) => u.to_string(),
        }
    }
}

impl std::fmt::Display for SettingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.key(), self.why())
    }
}

/// The settings a `[scene]` table `written` says (see the module's doc).
pub fn parse(written: &toml::Table) -> Result<SceneSettings, SettingError> {
    let text = |key: &str, default: &'static str| match written.get(key) {
        None => Ok(default.to_string()),
        Some(toml::Value::String(s)) => Ok(s.clone()),
        Some(v) => Err(SettingError::Value { key: key.into(), why: format!("{v}: expected a string") }),
    };
    let name = text("layout", "conveyor")?;
    let layout = lookup(&name).ok_or_else(|| SettingError::Choice {
        key: "layout".into(),
        why: format!("\"{name}\": expected one of {}", quoted(&names())),
    })?;
    let fidelity = text("fidelity", "fast")?;
    let preset = SceneSettings::common_preset(&fidelity).ok_or_else(|| SettingError::Choice {
        key: "fidelity".into(),
        why: KnobError::UnknownFidelity { fidelity: fidelity.clone() }.to_string(),
    })?;
    let mut common = toml::Table::try_from(&preset).expect("the preset is TOML");
    let mut own = toml::Table::new();
    for (key, value) in written {
        if is_common(key) {
            common.insert(key.clone(), value.clone());
        } else if layout.own_settings().contains(&key.as_str()) {
            own.insert(key.clone(), value.clone());
        } else if readers(key).is_empty() {
            let known = known_keys();
            let why = format!("unknown field `{key}`{}", hint(key, known.iter().map(String::as_str)));
            return Err(SettingError::Unknown { key: key.clone(), why });
        } else if let Some(value) = away_from_others_preset(layout, &fidelity, key, value) {
            return Err(SettingError::Unread(UnreadSetting {
                key: key.clone(),
                value: value.to_string(),
                layout: name.clone(),
                readers: readers(key),
            }));
        }
    }
    let mut settings: SceneSettings = read(&common, written)?;
    settings.own = layout
        .own_keys(&fidelity, &own)
        .map_err(|e| value_error(e, &own, |t| layout.own_keys(&fidelity, t)))?;
    Ok(settings)
}

/// `[scene]` of a sweep file read by serde (`SweepFile::scene`): [`parse`], its error in one
/// line (`Sweep::parse` reads the table again for the error's key and line).
pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<SceneSettings, D::Error> {
    let table = <toml::Table as serde::Deserialize>::deserialize(d)?;
    parse(&table).map_err(serde::de::Error::custom)
}

/// These settings with `key = value` (TOML syntax) set, for a knob only.
pub fn with_knob(settings: &SceneSettings, key: &str, value: &str) -> Result<SceneSettings, KnobError> {
    let (key, value) = (key.to_string(), value.to_string());
    let knobs = knobs(settings);
    if !knobs.contains(&key.as_str()) {
        return Err(KnobError::NotAKnob { key, knobs });
    }
    let Ok(parsed) = toml::from_str::<toml::Table>(&format!("{key} = {value}")) else {
        return Err(KnobError::NotToml { key, value });
    };
    let mut table = toml::Table::try_from(settings)?;
    table.extend(parsed);
    let mut s = parse(&table).map_err(|e| KnobError::Value { key, value, why: e.why() })?;
    s.force_bounds = settings.force_bounds;
    s.vtk = settings.vtk;
    Ok(s)
}

/// The settings of `layout` at the fidelity preset `fidelity`, if it names one.
pub fn preset(layout: &dyn Layout, fidelity: &str) -> Option<SceneSettings> {
    let written: toml::Table = [("layout", layout.name()), ("fidelity", fidelity)]
        .into_iter()
        .map(|(k, v)| (k.to_string(), toml::Value::from(v)))
        .collect();
    parse(&written).ok()
}

/// The numerical knobs of `settings`: [`KNOBS`] and its layout's own.
pub fn knobs(settings: &SceneSettings) -> Vec<&'static str> {
    KNOBS.iter().chain(settings.own.keys().knobs()).copied().collect()
}

/// These settings with every knob ([`knobs`]) and the fidelity's name taken from the preset
/// `fidelity` of their layout: the same point computed another way.
pub fn with_knobs_of(settings: &SceneSettings, fidelity: &str) -> Result<SceneSettings, KnobError> {
    let unknown = || KnobError::UnknownFidelity { fidelity: fidelity.to_string() };
    let layout = lookup(&settings.layout).ok_or_else(unknown)?;
    let preset = toml::Table::try_from(preset(layout, fidelity).ok_or_else(unknown)?)?;
    let mut table = toml::Table::try_from(settings)?;
    for key in knobs(settings).iter().chain(&["fidelity"]) {
        match preset.get(*key) {
            Some(v) => table.insert(key.to_string(), v.clone()),
            None => table.remove(*key),
        };
    }
    let mut s =
        parse(&table).map_err(|e| KnobError::Value { key: e.key(), value: String::new(), why: e.why() })?;
    s.force_bounds = settings.force_bounds;
    s.vtk = settings.vtk;
    Ok(s)
}

impl Default for SceneSettings {
    /// The settings of a sweep file that writes no `[scene]`: the fast preset on the conveyor.
    fn default() -> SceneSettings {
        parse(&toml::Table::new()).expect("the defaults are settings")
    }
}

/// Whether every layout reads `key` ([`SceneSettings`]' own field).
fn is_common(key: &str) -> bool {
    let probe: toml::Table = [(key.to_string(), toml::Value::Boolean(false))].into_iter().collect();
    match probe.try_into::<SceneSettings>() {
        Ok(_) => true,
        Err(e) => !e.message().starts_with("unknown field"),
    }
}

/// Every key some layout reads, for the "did you mean" of an unknown one.
fn known_keys() -> Vec<String> {
    let mut keys: Vec<String> =
        toml::Table::try_from(SceneSettings::common_preset("fast").expect("the fast preset"))
            .map(|t| t.keys().cloned().collect())
            .unwrap_or_default();
    keys.extend(KNOBS.iter().map(|k| k.to_string()));
    keys.extend(LAYOUTS.iter().flat_map(|l| l.own_settings()).map(String::from));
    keys.sort();
    keys.dedup();
    keys
}

/// `value` as the layouts that read `key` hold it, unless it is what the fidelity's preset gives
/// it in one of them (`5` is `5.0` where the key is a number).
fn away_from_others_preset(
    me: &dyn Layout,
    fidelity: &str,
    key: &str,
    value: &toml::Value,
) -> Option<toml::Value> {
    let one: toml::Table = [(key.to_string(), value.clone())].into_iter().collect();
    let mut held = None;
    for l in LAYOUTS.iter().filter(|l| l.name() != me.name() && l.own_settings().contains(&key)) {
        let (Ok(preset), Ok(typed)) = (l.own_keys(fidelity, &toml::Table::new()), l.own_keys(fidelity, &one))
        else {
            continue;
        };
        let typed = typed.table().get(key).cloned();
        if typed.is_some() && typed == preset.table().get(key).cloned() {
            return None;
        }
        held = held.or(typed);
    }
    Some(held.unwrap_or_else(|| value.clone()))
}

/// The settings of the keys every layout reads, the written ones over the preset's.
fn read(common: &toml::Table, written: &toml::Table) -> Result<SceneSettings, SettingError> {
    common.clone().try_into().map_err(|e| {
        let probe = |t: &toml::Table| t.clone().try_into::<SceneSettings>().map(drop);
        value_error(e, written, probe)
    })
}

/// A value error of a table's read, named by the first of `written`'s keys that alone fails it.
fn value_error<T>(
    e: toml::de::Error,
    written: &toml::Table,
    read: impl Fn(&toml::Table) -> Result<T, toml::de::Error>,
) -> SettingError {
    let why = |e: &toml::de::Error| e.message().trim().replace('\n', " ");
    for (key, value) in written {
        let one: toml::Table = [(key.clone(), value.clone())].into_iter().collect();
        if let Err(e) = read(&one) {
            if !e.message().starts_with("unknown field") {
                return SettingError::Value { key: key.clone(), why: why(&e) };
            }
        }
    }
    SettingError::Value { key: "".into(), why: why(&e) }
}

/// The settings of a sweep file that writes only `layout = "<name>"`.
pub fn defaults(layout: &dyn Layout) -> SceneSettings {
    let written: toml::Table =
        [("layout".to_string(), toml::Value::from(layout.name()))].into_iter().collect();
    parse(&written).expect("a layout's defaults are settings")
}

impl SceneSettings {
    /// The defaults on the gated layout (the unit tests of that scene and its deck).
    #[cfg(test)]
    pub(crate) fn gated() -> SceneSettings {
        defaults(lookup("gated").expect("the gated layout"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A key of a layout's own type that no layout of that type lists could never be set:
    /// `parse` gives a layout only the keys it lists (and `keys`' tests set every listed key).
    /// The gated and thesis layouts share one type, the thesis reading none of the gate's keys.
    #[test]
    fn every_key_of_a_layouts_own_type_is_one_its_layouts_list_and_none_every_layout_holds() {
        for layout in LAYOUTS {
            for fidelity in crate::scene::settings::FIDELITIES {
                let own = layout.own_keys(fidelity, &toml::Table::new()).unwrap();
                let family: Vec<_> = LAYOUTS
                    .iter()
                    .filter(|l| l.own_keys(fidelity, &toml::Table::new()).unwrap().same_type(&own))
                    .collect();
                for key in own.table().keys() {
                    let listed = family.iter().any(|l| l.own_settings().contains(&key.as_str()));
                    assert!(listed, "{}: {key} is not listed", layout.name());
                    assert!(!is_common(key), "{}: {key} is in both", layout.name());
                }
            }
        }
    }

    /// A fidelity changes how finely a point is computed, never what it is: each layout's
    /// presets differ from its fast one only in its knobs.
    #[test]
    fn a_layouts_presets_differ_only_in_its_knobs() {
        for layout in LAYOUTS {
            let fast = toml::Table::try_from(preset(*layout, "fast").unwrap()).unwrap();
            for fidelity in crate::scene::settings::FIDELITIES {
                let other = preset(*layout, fidelity).unwrap();
                let knobs = knobs(&other);
                for (key, value) in toml::Table::try_from(&other).unwrap() {
                    let same = fast.get(&key) == Some(&value);
                    assert!(
                        same || key == "fidelity" || knobs.contains(&key.as_str()),
                        "{}: {key}",
                        layout.name()
                    );
                }
            }
        }
        let gated = SceneSettings::gated();
        assert!(with_knob(&gated, "window_diameters", "60").is_ok(), "a layout's own knob");
        let e = with_knob(&SceneSettings::default(), "window_diameters", "60").unwrap_err().to_string();
        assert!(e.contains("not a numerical knob") && e.contains("block_diameters"), "{e}");
    }

    #[test]
    fn a_written_number_is_compared_with_another_layouts_preset_as_that_layout_holds_it() {
        let read = |text: &str| parse(&toml::from_str(text).unwrap());
        // `5` is the conveyor's 5.0: at its preset, no setting on the layers.
        assert!(read("layout = \"layers\"\nblock_diameters = 5").is_ok());
        let Err(SettingError::Unread(u)) = read("layout = \"layers\"\nblock_diameters = 7") else { panic!() };
        assert_eq!((u.value.as_str(), u.readers), ("7.0", vec!["conveyor"]));
        let Err(SettingError::Unknown { why, .. }) = read("layout = \"layers\"\nlayres = 3") else {
            panic!()
        };
        assert!(why.contains("unknown field `layres`") && why.contains("did you mean `layers`"), "{why}");
    }
}
