//! The numerical error a steady layer carries beside its SE: how far the scene's numerical
//! choices — the plate's length, the periodic depth, the timestep — moved the answer when each
//! was varied at the Ti-6Al-4V machine point (15–45 µm, 50 µm layers, 0.1 m/s, fused bed, round
//! blade; docs/study/layers.md "The machine point's numerical choices" and "The plate's length,
//! bounded"). The SE says how well the passes pin the answer of this scene; this says how far the
//! scene's choices may stand from the answer of a longer plate, a wider domain, a finer step.
//! Measured at one point: elsewhere it is the same choices' size, not a bound.

use super::result::{NumericalError, NumericalTerm};
use crate::scene::Scene;

use super::Plan;

/// A scene whose choice is under this share of a move's `applies_below` carries the move: the box
/// rounds its depth to whole lattice spacings, so a 12 D domain may be 11.9 D.
const SHORT_OF: f64 = 0.9;

/// One choice's measured move: what it is, the value of the choice up to which a scene carries it
/// (the next value measured: a scene short of it by more than [`SHORT_OF`] carries the move), and
/// the move of the packing, of the depth under the blade (a fraction of it) and of the cover.
struct Measured {
    choice: &'static str,
    applies_below: f64,
    packing: f64,
    depth_fraction: f64,
    covered: f64,
}

/// The plate's length, in mean diameters. 40 and 80 D each against 160 D, on one deck, one seed
/// each (`cuts.sh now machine machine-plate80 machine-plate160`): 40 D moved the packing by
/// +0.005 (1.3 combined SE), the depth by −1.0 µm of 137 (0.8 SE), the cover by +0.004 (0.3 SE);
/// 80 D by −0.003, −0.9 µm and −0.022 (all within 1.2 SE). Each term is the move or, where
/// larger, the combined SE it was measured with (the least move the pair could have told): 40 D
/// 0.005, 1.0 % (SE 1.35 µm), 0.015 (SE); 80 D 0.007 (SE), 1.6 % (SE 2.2 µm), 0.022. The plate
/// below 40 D carries 20 → 40 D's move, measured on the deck before the blade was taken away at
/// a pass's end (a 20 D plate put 15 % more powder under the blade). Beyond 160 D: not measured.
const PLATE: [Measured; 3] = [
    Measured {
        choice: "plate length 20 → 40 D",
        applies_below: 40.0,
        packing: 0.020,
        depth_fraction: 0.15,
        covered: 0.04,
    },
    Measured {
        choice: "plate length 40 D against 160 D",
        applies_below: 80.0,
        packing: 0.005,
        depth_fraction: 0.010,
        covered: 0.015,
    },
    Measured {
        choice: "plate length 80 D against 160 D",
        applies_below: 160.0,
        packing: 0.007,
        depth_fraction: 0.016,
        covered: 0.022,
    },
];
/// The periodic depth, in mean diameters: 6 → 12 D moved the packing by 0.007 and the depth by
/// 2.5 %. The cover's term is measured again on the cover counted whole (`cuts.sh err-depth12
/// machine` against `arcj`, laid doses, one seed each): +0.014 ± 0.006 (the packing +0.010 ±
/// 0.010, the depth −2.8 ± 2.0 µm there).
const DEPTH: Measured = Measured {
    choice: "periodic depth 6 → 12 D",
    applies_below: 12.0,
    packing: 0.007,
    depth_fraction: 0.025,
    covered: 0.014,
};
/// The timestep, in Rayleigh times: 0.33 → 0.165 moved the packing by 0.001 and the depth by
/// 0.4 % (converged in both). The cover's term is measured again on the cover counted whole
/// (`cuts.sh err-dt0.165 machine` against `arcj`, laid doses, one seed each): +0.007, its
/// combined SE 0.007 (the packing +0.002 ± 0.010, the depth −0.4 ± 2.0 µm there).
const TIMESTEP: Measured = Measured {
    choice: "timestep 0.33 → 0.165 Rayleigh times",
    applies_below: f64::INFINITY,
    packing: 0.001,
    depth_fraction: 0.004,
    covered: 0.007,
};

/// What a loose bed's error leaves out: its terms are the fused machine point's. At Gaboriault et
/// al.'s PS1 (a loose bed, docs/study/layers.md) the plate 24 → 48 D, the depth 6 → 12 D, the
/// timestep halved and the bed held 4 D moved the relative density by −0.013 ± 0.026, +0.003 ±
/// 0.033, −0.006 ± 0.056 and −0.032 ± 0.019: none resolved.
const LOOSE_BED: &str =
    "a loose bed's own moves (these are a fused bed's; at a loose one each moved the relative density by less than its 0.02–0.06 SE)";

/// The numerical error of `scene`'s steady layer: each choice's measured move where the scene's
/// choice is one that was measured (its root sum of squares, the choices taken as independent),
/// and the choices whose move at this scene's value is not known.
pub fn of(scene: &Scene, plan: &Plan) -> NumericalError {
    let d = scene.diameter;
    let plate = (plan.plate_x1 - plan.plate_x0) / d;
    let depth = scene.depth / d;
    let timestep = scene.timestep / scene.rayleigh_time;
    let mut terms = Vec::new();
    let mut unmeasured = Vec::new();
    match PLATE.iter().find(|m| plate < m.applies_below * SHORT_OF) {
        Some(m) => terms.push(m),
        None => unmeasured.push(format!("plate length beyond {plate:.0} D")),
    }
    if depth < DEPTH.applies_below * SHORT_OF {
        terms.push(&DEPTH);
    } else {
        unmeasured.push(format!("periodic depth beyond {depth:.0} D"));
    }
    if timestep < 0.33 / SHORT_OF {
        terms.push(&TIMESTEP);
    } else {
        unmeasured.push(format!("timestep at {timestep:.2} Rayleigh times"));
    }
    if !plan.fused {
        unmeasured.push(LOOSE_BED.into());
    }
    let rss = |f: &dyn Fn(&Measured) -> f64| terms.iter().map(|m| f(m).powi(2)).sum::<f64>().sqrt();
    NumericalError {
        packing: rss(&|m| m.packing),
        depth_fraction: rss(&|m| m.depth_fraction),
        covered_fraction: rss(&|m| m.covered),
        terms: terms
            .iter()
            .map(|m| NumericalTerm {
                choice: m.choice.into(),
                packing: m.packing,
                depth_fraction: m.depth_fraction,
                covered_fraction: m.covered,
            })
            .collect(),
        unmeasured,
    }
}

/// `e` in a few words, its depth in µm of `depth_m`: "±0.011 packing, ±5.0 µm depth, ±0.07
/// cover".
pub fn summary(e: &NumericalError, depth_m: f64) -> String {
    format!(
        "±{:.3} packing, ±{:.1} µm depth, ±{:.2} cover",
        e.packing,
        e.depth_fraction * depth_m * 1e6,
        e.covered_fraction
    )
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::scene::settings::SceneSettings;
    use crate::scenes::layers::plan_of;
    use crate::scenes::layers::settings::{with_own, LayersSettings};

    fn error(plate: f64, depth: f64, fraction: f64) -> NumericalError {
        error_on("fused", plate, depth, fraction)
    }

    fn error_on(bed: &str, plate: f64, depth: f64, fraction: f64) -> NumericalError {
        let s = with_own(
            SceneSettings {
                layout: "layers".into(),
                depth_diameters: depth,
                rayleigh_fraction: fraction,
                ..LayersSettings::default().settings()
            },
            |l| {
                l.bed = bed.into();
                l.layers = 4;
                l.plate_diameters = plate;
            },
        );
        let v: BTreeMap<String, f64> =
            [("diameter", 0.065), ("layer_thickness", 0.1), ("blade_speed", 0.1), ("density", 4386.0)]
                .iter()
                .map(|(k, v)| (k.to_string(), *v))
                .collect();
        let scene = crate::scenes::build(&v, &s).unwrap();
        of(&scene, &plan_of(&scene))
    }

    #[test]
    fn a_scene_carries_the_moves_measured_at_its_choices_and_names_the_choices_never_measured() {
        // The default scene (40 D plate, 6 D deep, 0.33 Rayleigh times): all three moves, their
        // root sum of squares.
        let e = error(40.0, 6.0, 0.33);
        let names: Vec<&str> = e.terms.iter().map(|t| t.choice.as_str()).collect();
        assert_eq!(
            names,
            [
                "plate length 40 D against 160 D",
                "periodic depth 6 → 12 D",
                "timestep 0.33 → 0.165 Rayleigh times"
            ]
        );
        let rss = (0.005f64.powi(2) + 0.007f64.powi(2) + 0.001f64.powi(2)).sqrt();
        assert!((e.packing - rss).abs() < 1e-12 && e.unmeasured.is_empty());
        // A short plate carries the larger move measured below 40 D, an 80 D plate its own
        // against 160 D; a 160 D plate, a 12 D domain and a coarser step carry none, and say so.
        assert_eq!(error(24.0, 6.0, 0.33).terms[0].choice, "plate length 20 → 40 D");
        assert_eq!(error(80.0, 6.0, 0.33).terms[0].choice, "plate length 80 D against 160 D");
        let far = error(160.0, 12.0, 0.45);
        assert!(far.terms.is_empty() && far.packing == 0.0, "{far:?}");
        assert_eq!(far.unmeasured.len(), 3, "{:?}", far.unmeasured);
        assert!(far.unmeasured[0].contains("160 D"));
        // A loose bed carries the same terms and says they are a fused bed's.
        let loose = error_on("loose", 40.0, 6.0, 0.33);
        assert_eq!((loose.packing, loose.terms.len()), (e.packing, 3));
        assert_eq!(loose.unmeasured, [LOOSE_BED]);
    }
}
