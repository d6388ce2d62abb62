//! A layout's own `[scene]` keys: a type of the layout's (the layers' passes, bed and blade),
//! kept in [`SceneSettings::own`](super::settings::SceneSettings::own) beside the keys every
//! layout reads. The settings know no layout, so they hold the type behind a trait object, as
//! the scene holds its layout's part ([`super::own`]): the layout reads it back as its type
//! ([`OwnSettings::get`]; a read as another type is `None`), and it is written flattened into
//! `[scene]`, where the sweep file keeps its keys. A `[scene]` table is read with
//! `crate::scenes::settings::parse`, which knows the layouts and gives each its own keys.

use std::any::{Any, TypeId};
use std::fmt;

use serde::Serialize;

/// A layout's own `[scene]` keys, of its own type (serialised as its keys, deserialised by its
/// layout, every key with its default).
pub trait LayoutSettings: Any + fmt::Debug + Send + Sync + SettingsMechanics {
    /// Its keys that are numerical knobs: how finely a point is computed, not what it is (a
    /// fidelity preset may set them; `sweep bench fidelity --variant` may vary them).
    fn knobs(&self) -> &'static [&'static str] {
        &[]
    }

    /// Whether a point of a sweep starts from the state a finished neighbour left
    /// (`warm_start`); default no.
    fn warm_start(&self) -> bool {
        false
    }

    /// Whether a point of a sweep runs to the SE of its answer that the sweep's first batch
    /// sets (`precision = "sweep"`); default no.
    fn sweep_precision(&self) -> bool {
        false
    }
}

/// What the settings do with any layout's keys: clone them, read them back as their type, write
/// them as a TOML table (a blanket impl: nothing to implement).
pub trait SettingsMechanics {
    fn clone_settings(&self) -> OwnSettings;
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
    /// The keys as the sweep file writes them.
    fn to_table(&self) -> Result<toml::Table, toml::ser::Error>;
}

impl<T: LayoutSettings + Clone + Serialize> SettingsMechanics for T {
    fn clone_settings(&self) -> OwnSettings {
        OwnSettings(Box::new(self.clone()))
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
    fn to_table(&self) -> Result<toml::Table, toml::ser::Error> {
        toml::Table::try_from(self)
    }
}

/// The keys of a layout that reads none but the common ones.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct NoOwnKeys {}

impl LayoutSettings for NoOwnKeys {}

/// A layout's own `[scene]` keys, of its own type (see the module's doc).
pub struct OwnSettings(Box<dyn LayoutSettings>);

impl OwnSettings {
    pub fn new<T: LayoutSettings>(keys: T) -> OwnSettings {
        OwnSettings(Box::new(keys))
    }

    /// The settings of a layout with no keys of its own.
    pub fn none() -> OwnSettings {
        OwnSettings::new(NoOwnKeys {})
    }

    /// The keys as `T`, if they are of that type.
    pub fn get<T: Any>(&self) -> Option<&T> {
        self.0.as_any().downcast_ref()
    }

    pub fn get_mut<T: Any>(&mut self) -> Option<&mut T> {
        self.0.as_any_mut().downcast_mut()
    }

    /// The layout's type itself, for what the levels outside the layout ask of any.
    pub fn keys(&self) -> &dyn LayoutSettings {
        &*self.0
    }

    /// The keys as the sweep file writes them (empty if they cannot be written: a broken
    /// invariant the serialisation of the whole settings reports).
    pub fn table(&self) -> toml::Table {
        self.0.to_table().unwrap_or_default()
    }
}

impl fmt::Debug for OwnSettings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl Clone for OwnSettings {
    fn clone(&self) -> OwnSettings {
        self.0.clone_settings()
    }
}

impl PartialEq for OwnSettings {
    fn eq(&self, other: &OwnSettings) -> bool {
        self.same_type(other) && self.table() == other.table()
    }
}

impl Default for OwnSettings {
    fn default() -> OwnSettings {
        OwnSettings::none()
    }
}

impl Serialize for OwnSettings {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.to_table().map_err(serde::ser::Error::custom)?.serialize(s)
    }
}

impl OwnSettings {
    /// Whether these keys and `other` are of one type (one layout's, or one family's).
    pub fn same_type(&self, other: &OwnSettings) -> bool {
        self.0.as_any().type_id() == other.0.as_any().type_id()
    }

    /// Whether these are keys of type `T`.
    pub fn is<T: Any>(&self) -> bool {
        self.0.as_any().type_id() == TypeId::of::<T>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Clone, PartialEq, Serialize)]
    struct Passes {
        layers: usize,
    }

    impl LayoutSettings for Passes {}

    #[test]
    fn a_layouts_keys_read_back_as_their_type_compare_and_write_as_their_keys() {
        let mut own = OwnSettings::new(Passes { layers: 7 });
        assert_eq!(own.get::<Passes>(), Some(&Passes { layers: 7 }));
        assert!(own.get::<NoOwnKeys>().is_none() && own.is::<Passes>(), "another type is not a misparse");
        let copy = own.clone();
        own.get_mut::<Passes>().unwrap().layers = 8;
        assert_eq!(copy.get::<Passes>().unwrap().layers, 7);
        assert_ne!(own, copy);
        assert_eq!(copy, OwnSettings::new(Passes { layers: 7 }));
        assert_ne!(OwnSettings::none(), OwnSettings::new(Passes { layers: 0 }), "the type counts");
        assert_eq!(toml::to_string(&copy).unwrap().trim(), "layers = 7");
        assert!(OwnSettings::none().table().is_empty());
    }
}
