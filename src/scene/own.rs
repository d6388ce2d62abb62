//! A layout's own numbers in its [`Scene`](super::Scene): a type of the layout's (the
//! conveyor's held heap, the layers' plan) beside the common fields, which the deck reads as
//! `scene.own.*` and the layout reads back as its type ([`super::Scene::own`]). The scene knows
//! no layout, so it holds the numbers behind a trait object: any `Clone + Serialize` type of the
//! layout's is one, and a read back as another type is `None`, not a misparse.
//!
//! Not a bag: what a layout keeps here is a struct the compiler checks; the deck's context is
//! built from it by serde when the deck is rendered.

use std::any::Any;
use std::fmt;

use serde::Serialize;

/// What a layout's own numbers are: any of its types that clones, serialises and is shared
/// between threads (a blanket impl: nothing to implement).
pub trait LayoutData: Any + fmt::Debug + Send + Sync {
    fn clone_data(&self) -> OwnData;
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
    /// The numbers as the deck's template reads them.
    fn to_context(&self) -> serde_json::Result<serde_json::Value>;
}

impl<T: Any + fmt::Debug + Clone + Serialize + Send + Sync> LayoutData for T {
    fn clone_data(&self) -> OwnData {
        OwnData(Box::new(self.clone()))
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
    fn to_context(&self) -> serde_json::Result<serde_json::Value> {
        serde_json::to_value(self)
    }
}

/// A layout's own numbers, of its own type (see the module's doc).
#[derive(Debug)]
pub struct OwnData(Box<dyn LayoutData>);

impl OwnData {
    pub fn new<T: LayoutData>(data: T) -> OwnData {
        OwnData(Box::new(data))
    }

    /// The numbers as `T`, if they are of that type.
    pub fn get<T: Any>(&self) -> Option<&T> {
        self.0.as_any().downcast_ref()
    }

    pub fn get_mut<T: Any>(&mut self) -> Option<&mut T> {
        self.0.as_any_mut().downcast_mut()
    }
}

impl Clone for OwnData {
    fn clone(&self) -> OwnData {
        self.0.clone_data()
    }
}

impl Serialize for OwnData {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.to_context().map_err(serde::ser::Error::custom)?.serialize(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Clone, PartialEq, Serialize)]
    struct Held {
        heap_particles: usize,
    }

    #[test]
    fn a_layouts_numbers_read_back_as_their_type_serialise_as_their_fields_and_clone() {
        let mut own = OwnData::new(Held { heap_particles: 7 });
        assert_eq!(own.get::<Held>(), Some(&Held { heap_particles: 7 }));
        assert_eq!(own.get::<String>(), None, "another type is not a misparse");
        own.get_mut::<Held>().unwrap().heap_particles = 8;
        let copy = own.clone();
        own.get_mut::<Held>().unwrap().heap_particles = 9;
        assert_eq!(copy.get::<Held>().unwrap().heap_particles, 8);
        assert_eq!(serde_json::to_string(&copy).unwrap(), r#"{"heap_particles":8}"#);
    }
}
