//! The number a point answers with — what a sweep's statistics, emulator, report and
//! prediction read — under its own name: a flow's MFR (`mfr`), a layers point's steady-layer
//! relative density (`relative_density`) or, on a fused bed, its packing (`steady_packing`).
//!
//! In memory it is [`PointAnswer`]: which quantity, its value and its standard error. In
//! `result.json` (and wherever a point's answer is written beside other keys) it is two keys
//! named for the quantity: `mfr` and `mfr_se`, `relative_density` and `relative_density_se`,
//! `steady_packing` and `steady_packing_se`; a value not measured (NaN: a pour's heap) and an
//! SE not stated are left out.

use serde::de::{self, IgnoredAny, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Which quantity a point answers with: its key in `result.json`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum AnswerKind {
    /// Mass flow ratio of the deposited layer (docs/scene.md "Metrics").
    #[default]
    Mfr,
    /// The steady layer's relative density: deposit over the platform's drop (a loose bed).
    RelativeDensity,
    /// The steady layer's packing: deposit over the powder under the blade (a fused bed).
    SteadyPacking,
}

impl AnswerKind {
    /// Every kind, in the order a reader looks for them.
    pub const ALL: [AnswerKind; 3] =
        [AnswerKind::Mfr, AnswerKind::RelativeDensity, AnswerKind::SteadyPacking];

    /// Its key in `result.json`, results.csv's layout columns and summary.json.
    pub fn key(self) -> &'static str {
        match self {
            AnswerKind::Mfr => "mfr",
            AnswerKind::RelativeDensity => "relative_density",
            AnswerKind::SteadyPacking => "steady_packing",
        }
    }

    /// The key of its standard error.
    pub fn se_key(self) -> &'static str {
        match self {
            AnswerKind::Mfr => "mfr_se",
            AnswerKind::RelativeDensity => "relative_density_se",
            AnswerKind::SteadyPacking => "steady_packing_se",
        }
    }

    /// In words, as the terminal and the report name it.
    pub fn words(self) -> &'static str {
        match self {
            AnswerKind::Mfr => "MFR",
            AnswerKind::RelativeDensity => "steady-layer relative density",
            AnswerKind::SteadyPacking => "steady-layer packing",
        }
    }
}

/// A point's answer: the quantity, its value (NaN where the run measures none) and its
/// standard error where the run states one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointAnswer {
    pub kind: AnswerKind,
    pub value: f64,
    pub se: Option<f64>,
}

impl PointAnswer {
    /// An MFR, without an SE.
    pub fn mfr(value: f64) -> PointAnswer {
        PointAnswer { kind: AnswerKind::Mfr, value, se: None }
    }

    /// Nothing measured (a pour's heap): an MFR of NaN, written as no key at all.
    pub fn none() -> PointAnswer {
        PointAnswer::mfr(f64::NAN)
    }

    /// The same value and SE as another quantity (an older file's layers answer, written as
    /// `mfr`).
    pub fn as_kind(self, kind: AnswerKind) -> PointAnswer {
        PointAnswer { kind, ..self }
    }
}

impl Default for PointAnswer {
    fn default() -> PointAnswer {
        PointAnswer::mfr(0.0)
    }
}

/// Written as its keys, to be flattened into the record that holds it.
impl Serialize for PointAnswer {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(None)?;
        if !self.value.is_nan() {
            map.serialize_entry(self.kind.key(), &self.value)?;
        }
        if let Some(se) = self.se {
            map.serialize_entry(self.kind.se_key(), &se)?;
        }
        map.end()
    }
}

/// Read from whichever kind's keys the record holds (an MFR of NaN when none), ignoring every
/// other key; a record with two kinds' keys is refused.
impl<'de> Deserialize<'de> for PointAnswer {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<PointAnswer, D::Error> {
        struct Keys;
        impl<'de> Visitor<'de> for Keys {
            type Value = PointAnswer;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a point's answer (mfr, relative_density or steady_packing, and its _se)")
            }

            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<PointAnswer, A::Error> {
                let mut kind: Option<AnswerKind> = None;
                let (mut value, mut se) = (None, None);
                while let Some(key) = map.next_key::<String>()? {
                    let Some((k, is_se)) = AnswerKind::ALL.iter().find_map(|k| {
                        (key == k.key()).then_some((*k, false)).or((key == k.se_key()).then_some((*k, true)))
                    }) else {
                        map.next_value::<IgnoredAny>()?;
                        continue;
                    };
                    if kind.is_some_and(|seen| seen != k) {
                        return Err(de::Error::custom(format!(
                            "two answers: {} and {}",
                            kind.map_or("", |s| s.key()),
                            k.key()
                        )));
                    }
                    kind = Some(k);
                    if is_se {
                        se = map.next_value::<Option<f64>>()?;
                    } else {
                        value = Some(map.next_value::<f64>()?);
                    }
                }
                Ok(PointAnswer { kind: kind.unwrap_or_default(), value: value.unwrap_or(f64::NAN), se })
            }
        }
        d.deserialize_map(Keys)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Holder {
        n: u32,
        #[serde(flatten)]
        answer: PointAnswer,
    }

    #[test]
    fn an_answer_is_written_and_read_back_under_its_own_keys() {
        let cases = [
            (PointAnswer::mfr(0.4), r#"{"n":1,"mfr":0.4}"#),
            (
                PointAnswer { kind: AnswerKind::RelativeDensity, value: 0.57, se: Some(0.01) },
                r#"{"n":1,"relative_density":0.57,"relative_density_se":0.01}"#,
            ),
            (
                PointAnswer { kind: AnswerKind::SteadyPacking, value: 0.5, se: Some(0.02) },
                r#"{"n":1,"steady_packing":0.5,"steady_packing_se":0.02}"#,
            ),
        ];
        for (answer, json) in cases {
            let h = Holder { n: 1, answer };
            assert_eq!(serde_json::to_string(&h).unwrap(), json);
            assert_eq!(serde_json::from_str::<Holder>(json).unwrap(), h);
        }
        // Nothing measured: no key, and read back as such.
        let none = Holder { n: 1, answer: PointAnswer::none() };
        assert_eq!(serde_json::to_string(&none).unwrap(), r#"{"n":1}"#);
        let back: Holder = serde_json::from_str(r#"{"n":1,"other":[1,2]}"#).unwrap();
        assert!(
            back.answer.value.is_nan() && back.answer.kind == AnswerKind::Mfr && back.answer.se.is_none()
        );
        // A whole number is a number.
        assert_eq!(serde_json::from_str::<Holder>(r#"{"n":1,"mfr":0}"#).unwrap().answer.value, 0.0);
    }

    #[test]
    fn a_record_with_two_answers_is_refused() {
        let e = serde_json::from_str::<Holder>(r#"{"n":1,"mfr":0.4,"relative_density":0.5}"#).unwrap_err();
        assert!(e.to_string().contains("two answers"), "{e}");
    }
}
