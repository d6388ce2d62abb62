//! What only one layout measures: a type of the layout's (the layers' passes and steady layer,
//! the pour's heap), kept in [`RunResult::own`](super::RunResult::own) beside what every run
//! reports. A result knows no layout, so it holds the type behind a trait object, as the scene
//! holds its layout's part (`crate::scene::own`): the layout reads it back as its type
//! ([`OwnResult::get`]; a read as another type is `None`), and `result.json` writes it under the
//! type's own key ([`LayoutResult::key`]: `layers`, `heap`) beside the common keys.
//!
//! It is read back by `crate::scenes::results`, which knows which layout writes which key (the
//! impl of `Deserialize` lives there: only the layouts know their types).

use std::any::Any;
use std::fmt;

use serde::ser::SerializeMap;
use serde::Serialize;

use super::AnswerKind;

/// A layout's own measurements of one run, of its own type.
pub trait LayoutResult: Any + fmt::Debug + Send + Sync + ResultMechanics + erased_serde::Serialize {
    /// Its key in `result.json`: one per layout, never a common key.
    fn key(&self) -> &'static str;

    /// The quantity the point answers with, if the layout's result decides it (a layers run's
    /// bed does): an older file's answer written as `mfr` is read as this one. Default: none.
    fn answer_kind(&self) -> Option<AnswerKind> {
        None
    }
}

/// What a result does with any layout's part: clone, compare, read back as its type, write (a
/// blanket impl: nothing to implement).
pub trait ResultMechanics {
    fn clone_result(&self) -> Box<dyn LayoutResult>;
    fn as_any(&self) -> &dyn Any;
    fn same_as(&self, other: &dyn Any) -> bool;
}

// Its fields as `result.json` writes them under the key, in the type's order.
erased_serde::serialize_trait_object!(LayoutResult);

impl<T: LayoutResult + Clone + PartialEq + Serialize> ResultMechanics for T {
    fn clone_result(&self) -> Box<dyn LayoutResult> {
        Box::new(self.clone())
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn same_as(&self, other: &dyn Any) -> bool {
        other.downcast_ref::<T>() == Some(self)
    }
}

/// A layout's own measurements of one run, if it has any (see the module's doc).
#[derive(Default)]
pub struct OwnResult(Option<Box<dyn LayoutResult>>);

impl OwnResult {
    pub fn new<T: LayoutResult>(result: T) -> OwnResult {
        OwnResult(Some(Box::new(result)))
    }

    /// A run whose layout measures nothing of its own (the moving blade, the conveyor).
    pub fn none() -> OwnResult {
        OwnResult(None)
    }

    /// The measurements as `T`, if they are of that type.
    pub fn get<T: Any>(&self) -> Option<&T> {
        self.0.as_ref()?.as_any().downcast_ref()
    }

    /// The layout's type itself, for what the levels outside the layout ask of any.
    pub fn result(&self) -> Option<&dyn LayoutResult> {
        self.0.as_deref()
    }
}

impl fmt::Debug for OwnResult {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            Some(r) => r.fmt(f),
            None => f.write_str("none"),
        }
    }
}

impl Clone for OwnResult {
    fn clone(&self) -> OwnResult {
        OwnResult(self.0.as_ref().map(|r| r.clone_result()))
    }
}

impl PartialEq for OwnResult {
    fn eq(&self, other: &OwnResult) -> bool {
        match (&self.0, &other.0) {
            (Some(a), Some(b)) => a.same_as(b.as_any()),
            (None, None) => true,
            _ => false,
        }
    }
}

/// Written flattened into the result: its one key, or nothing.
impl Serialize for OwnResult {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.is_some() as usize))?;
        if let Some(r) = &self.0 {
            map.serialize_entry(r.key(), r.as_ref())?;
        }
        map.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Clone, PartialEq, Serialize)]
    struct Cone {
        angle_deg: f64,
    }

    impl LayoutResult for Cone {
        fn key(&self) -> &'static str {
            "cone"
        }
    }

    #[derive(Debug, Clone, PartialEq, Serialize)]
    struct Ring {
        outer: f64,
        inner: f64,
    }

    impl LayoutResult for Ring {
        fn key(&self) -> &'static str {
            "ring"
        }
    }

    #[test]
    fn a_layouts_result_reads_back_as_its_type_compares_and_writes_under_its_key() {
        let own = OwnResult::new(Cone { angle_deg: 31.0 });
        assert_eq!(own.get::<Cone>(), Some(&Cone { angle_deg: 31.0 }));
        assert_eq!(own.get::<String>(), None, "another type is not a misparse");
        let copy = own.clone();
        assert_eq!(copy, own);
        assert_ne!(copy, OwnResult::new(Cone { angle_deg: 32.0 }));
        assert_ne!(copy, OwnResult::none());
        assert_eq!(OwnResult::none(), OwnResult::none());
        assert_eq!(serde_json::to_string(&copy).unwrap(), r#"{"cone":{"angle_deg":31.0}}"#);
        let two = OwnResult::new(Ring { outer: 2.0, inner: 1.0 });
        assert_eq!(
            serde_json::to_string(&two).unwrap(),
            r#"{"ring":{"outer":2.0,"inner":1.0}}"#,
            "in the type's order"
        );
        assert_eq!(serde_json::to_string(&OwnResult::none()).unwrap(), "{}");
    }
}
