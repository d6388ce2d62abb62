//! Reading a layout's own result back from `result.json`: the one place that knows which
//! layout writes which key ([`OwnResult`]'s `Deserialize`; a result holds its layout's part
//! behind a trait object and cannot name the types). A layout with a result of its own adds its
//! key here; a key no layout writes is left to the common fields (or ignored, as any unknown
//! key of a result is).

use serde::de::{IgnoredAny, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};

use crate::outcome::OwnResult;

use super::{layers, pour};

/// The layout's own result under `key`, read as that layout's type, or `None` if no layout
/// writes that key.
fn read<'de, A: MapAccess<'de>>(key: &str, map: &mut A) -> Result<Option<OwnResult>, A::Error> {
    Ok(match key {
        layers::result::KEY => map.next_value::<Option<layers::result::LayerSeries>>()?.map(OwnResult::new),
        pour::result::KEY => map.next_value::<Option<pour::result::Heap>>()?.map(OwnResult::new),
        _ => {
            map.next_value::<IgnoredAny>()?;
            None
        }
    })
}

impl<'de> Deserialize<'de> for OwnResult {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<OwnResult, D::Error> {
        struct Own;
        impl<'de> Visitor<'de> for Own {
            type Value = OwnResult;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a run's result")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<OwnResult, A::Error> {
                let mut own = OwnResult::none();
                while let Some(key) = map.next_key::<String>()? {
                    if let Some(found) = read(&key, &mut map)? {
                        if own.result().is_some() {
                            return Err(serde::de::Error::custom(format!(
                                "`{key}` beside another layout's result: a run has one layout"
                            )));
                        }
                        own = found;
                    }
                }
                Ok(own)
            }
        }
        d.deserialize_map(Own)
    }
}

#[cfg(test)]
mod tests {
    use crate::outcome::{AnswerKind, PointAnswer, RunResult};

    use super::*;

    #[test]
    fn each_layouts_result_reads_back_as_its_type_and_writes_the_same_bytes() {
        let pour = r#"{"format":1,"hash":"h","parameters":{},"answer_particles":0,"answer_windows":[],
            "steady":true,"vx":[],"particles":5,
            "heap":{"angle_deg":31.5,"angle_se_deg":0.4,"sector_angles_deg":[31.0,32.0],"height_mm":2.0,
            "base_radius_mm":3.0,"packing":0.58,"particles_in_heap":5,"particles_run_out":0},
            "settle_steps":1,"steps":2,"simulated_time":0.1,"wall_time":1.0,"engine_version":"v","warnings":[]}"#;
        let r: RunResult = serde_json::from_str(pour).unwrap();
        let heap = pour::result::heap(&r).expect("a pour's heap");
        assert_eq!((heap.angle_deg, heap.packing), (31.5, 0.58));
        assert!(layers::result::series(&r).is_none(), "another layout's type is not a misparse");
        let compact: String = pour.split_whitespace().collect();
        assert_eq!(serde_json::to_string(&r).unwrap(), compact, "the same keys in the same order");
        let back: RunResult = serde_json::from_str(&compact).unwrap();
        assert_eq!(back.own, r.own);

        let none = pour.replace(r#""heap":{"#, r#""other":{"#);
        let r: RunResult = serde_json::from_str(&none).unwrap();
        assert!(r.own.result().is_none(), "a key no layout writes is no layout's result");
        let both = pour.replace(r#""particles":5,"#, r#""particles":5,"layers":null,"#);
        assert!(pour::result::heap(&serde_json::from_str(&both).unwrap()).is_some(), "null is none");
    }

    #[test]
    fn a_recorded_layers_result_with_mfr_keys_reads_its_passes_and_count_under_their_own_names() {
        // A real result.json, as the layers layout wrote it on 7 December 2026 before its
        // quantities had their own names (docs/study/layers/record/machine-lattice/a2900f7b…/
        // result.json at commit ce70714d, copied whole): a fused bed's steady packing as `mfr`,
        // its per-pass packings as `mfr_windows`, the particles of its 11 passes as
        // `mfr_particles`.
        let text = include_str!("../../tests/data/layers-result-before-answer-names.json");
        let old: serde_json::Value = serde_json::from_str(text).unwrap();
        assert!(
            old.get("mfr_windows").is_some() && old.get("answer_windows").is_none(),
            "not the old format"
        );
        let r: RunResult = serde_json::from_str(text).unwrap();
        assert_eq!(
            r.answer,
            PointAnswer {
                kind: AnswerKind::SteadyPacking,
                value: 0.17737717229934943,
                se: Some(0.0036150069293106424)
            }
        );
        let passes = &layers::result::series(&r).expect("its passes").passes;
        assert_eq!(r.answer_windows, passes.iter().map(|p| p.packing).collect::<Vec<_>>());
        assert_eq!((r.answer_windows.len(), r.answer_windows[0]), (11, 0.13696732712213172));
        assert_eq!(r.answer_particles, 1968);
        assert_eq!(r.answer_particles, passes.iter().map(|p| p.particles).sum::<usize>());
        // Written again under the new names only, and read back the same.
        let json = serde_json::to_value(&r).unwrap();
        for gone in ["mfr", "mfr_se", "mfr_windows", "mfr_particles"] {
            assert!(json.get(gone).is_none(), "{gone} written again");
        }
        assert_eq!(json["answer_windows"], old["mfr_windows"]);
        assert_eq!(json["answer_particles"], old["mfr_particles"]);
        // (Compared as written: its NaNs, the flux and the p-value it does not measure, are
        // equal to nothing.)
        let again = serde_json::from_value::<RunResult>(json.clone()).unwrap();
        assert_eq!(
            (again.answer, &again.answer_windows, again.answer_particles),
            (r.answer, &r.answer_windows, 1968)
        );
        assert_eq!(serde_json::to_value(&again).unwrap(), json);
    }
}
