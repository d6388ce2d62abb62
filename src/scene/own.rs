//! A layout's part of its [`Scene`](super::Scene): a type of the layout's (the moving blade's
//! spread, the conveyor's held heap, the pour's column, the layers' plan) beside the common
//! fields, built of the groups it shares with other layouts ([`Blade`], [`Window`],
//! [`Substrate`], [`PileBlock`], [`super::blade::Settle`]) and the numbers only it has. The scene
//! knows no layout, so it holds the part behind a trait object: the layout reads it back as its
//! type ([`super::Scene::own`]; a read as another type is `None`, not a misparse), and the
//! levels below the layouts ask it for the groups they read ([`LayoutData::blade`], …).
//!
//! Not a bag: the part is a struct the compiler checks; the deck's context is built from it by
//! serde when the deck is rendered, its fields flattened beside the common ones (the groups'
//! fields are `scene.gap`, `scene.substrate_particles`, …; a layout keeps the numbers only it
//! has in a field serialised as `own`, the deck's `scene.own.*`). A key a template reads and the
//! part lacks fails the render (Tera refuses an undefined variable), and the deck tests render
//! every layout.

use std::any::Any;
use std::fmt;

use serde::Serialize;

use super::blade::{Blade, Spreader, Window};
use super::pile::PileBlock;
use super::substrate::Substrate;

/// A layout's part of its scene: its type says which of the shared groups it has (none by
/// default) and how many steps its run takes.
pub trait LayoutData: Any + fmt::Debug + Send + Sync + PartMechanics {
    /// The steps a run takes after its settle, at most (the spread, the lift and the heap's
    /// settle, every pass): what the plausibility bounds count the timestep's cost in.
    fn steps(&self) -> u64;
    /// Its blade, the window and the substrate, for a layout that has all three; one that has
    /// only some gives each by its own method below.
    fn spreader(&self) -> Option<&Spreader> {
        None
    }
    /// The blade it moves (or holds still over a moving substrate).
    fn blade(&self) -> Option<&Blade> {
        self.spreader().map(|s| &s.blade)
    }
    /// The window of the blade's travel its flow is measured over.
    fn window(&self) -> Option<&Window> {
        self.spreader().map(|s| &s.window)
    }
    /// The substrate it spreads onto.
    fn substrate(&self) -> Option<&Substrate> {
        self.spreader().map(|s| &s.substrate)
    }
    /// The block of spheres its dose starts as.
    fn pile(&self) -> Option<&PileBlock> {
        None
    }
}

/// What the scene does with any part: clone it, read it back as its type, serialise it (a
/// blanket impl: nothing to implement).
pub trait PartMechanics {
    fn clone_data(&self) -> OwnData;
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
    /// The numbers as the deck's template reads them.
    fn to_context(&self) -> serde_json::Result<serde_json::Value>;
}

impl<T: LayoutData + Clone + Serialize> PartMechanics for T {
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

    /// The layout's type itself, for the groups it has.
    pub fn data(&self) -> &dyn LayoutData {
        &*self.0
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

    impl LayoutData for Held {
        fn steps(&self) -> u64 {
            1
        }
    }

    #[test]
    fn a_layouts_numbers_read_back_as_their_type_serialise_as_their_fields_and_clone() {
        let none = OwnData::new(Held { heap_particles: 0 });
        assert!(none.data().blade().is_none() && none.data().substrate().is_none(), "no group by default");
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
