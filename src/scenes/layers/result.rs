//! Layer after layer: a layers run's own result, `result.json`'s `layers` record
//! (docs/layers.md defines each measure; [`super::measure`] measures them).

use serde::{Deserialize, Serialize};

use crate::outcome::own_result::LayoutResult;
use crate::outcome::{AnswerKind, PointAnswer, RunResult};

/// What one pass of the blade left on the build plate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassRecord {
    /// The pass, from 1.
    pub k: usize,
    /// A fused bed's search pass: the solid under it was set to search for the steady depth, not
    /// laid by the pass before (its deposit is measured all the same).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub search: bool,
    /// Solid volume the pass added to the plate over the plate's area, m: the deposit as a
    /// height of solid.
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub deposit_m: f64,
    /// The deposit over the platform's drop before the pass (Gaboriault et al. 2025's layer
    /// relative density; the first pass's drop includes the blade's clearance).
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub relative_density: f64,
    /// The powder's depth under the blade's tip: the tip's height over the bed's mean top
    /// surface before the pass (loose) or over the solid's top (fused), m.
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub effective_thickness_m: f64,
    /// The deposit over that depth: the packing of the layer the blade left.
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub packing: f64,
    /// Share of the plate's area under this pass's own particles.
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub covered_fraction: f64,
    /// RMS of the bed's top surface about its mean after the pass, in D.
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub roughness_d: f64,
    /// Solid volume on the plate over its area and the height of everything laid so far (loose:
    /// the bed's relative density; fused: the solid, 1 by construction, not stored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bed_relative_density: Option<f64>,
    /// Particles on the plate after the pass that it brought.
    pub particles: usize,
    /// What turning and pushing the roller took over the pass (a roller's pass only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roller: Option<RollerLoad>,
}

/// What a roller took over a pass's move, per metre of its width (the scene is a periodic slice
/// of it): means over the steps it moved, approach and run-out included.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RollerLoad {
    /// The torque the motor applies about the axis in the counter-rotating sense, N·m per m
    /// (negative: the powder turns it that way).
    pub torque_nm_per_m: f64,
    /// The power turning it takes: its torque times its rate of turn, W per m (0 when it does
    /// not turn).
    pub turning_power_w_per_m: f64,
    /// The force pushing it along its travel takes, N per m, and that force times its speed, W
    /// per m.
    pub push_n_per_m: f64,
    pub pushing_power_w_per_m: f64,
    /// The powder it sent over its top in the pass — thrown higher than its highest line or
    /// carried over it, out of the gap it spreads through — kg per m (docs/layers.md "The
    /// roller"): `None` in a result written before it was measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ejected_kg_per_m: Option<f64>,
}

/// A roller's steady load: each measure's mean over the steady passes and its SE.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RollerSteady {
    pub mean: RollerLoad,
    pub se: RollerLoad,
}

/// Every pass and the steady layer: the answer of a layers run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayerSeries {
    /// `"loose"` or `"fused"`.
    pub bed: String,
    /// The platform's drop per pass, m.
    pub layer_thickness_m: f64,
    pub passes: Vec<PassRecord>,
    /// The first pass of the steady layers (from 1): from it on, passes agree within their
    /// scatter (MSER truncation of the measure the point answers with, no trend after it).
    pub steady_from: usize,
    /// Whether the passes from `steady_from` on show no trend (a least-squares slope within
    /// [`crate::scenes::layers::measure::trend_limit`] of its SE) and at least three of them are
    /// left.
    pub steady: bool,
    /// The steady layer's means and standard errors over the steady passes.
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub packing: f64,
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub packing_se: f64,
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub relative_density: f64,
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub relative_density_se: f64,
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub effective_thickness_m: f64,
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub effective_thickness_se_m: f64,
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub covered_fraction: f64,
    #[serde(deserialize_with = "crate::outcome::nan_if_null")]
    pub roughness_d: f64,
    /// How far the scene's numerical choices may move the steady layer, beside its SE (not in
    /// it): `None` in a result written before it was stated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub numerical_error: Option<NumericalError>,
    /// A roller's load over the steady passes (a roller only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roller: Option<RollerSteady>,
}

impl LayoutResult for LayerSeries {
    fn key(&self) -> &'static str {
        KEY
    }

    fn answer_kind(&self) -> Option<AnswerKind> {
        Some(LayerSeries::answer_kind(self))
    }
}

/// The key of [`LayerSeries`] in `result.json`.
pub const KEY: &str = "layers";

/// A layers run's passes and steady layer (`None` for a run of another layout).
pub fn series(r: &RunResult) -> Option<&LayerSeries> {
    r.own.get()
}

impl LayerSeries {
    /// What the point answers with: the steady layer's relative density on a loose bed, its
    /// packing on a fused one (whose relative density is the whole drop by construction).
    pub fn answer_kind(&self) -> AnswerKind {
        if self.bed == "fused" {
            AnswerKind::SteadyPacking
        } else {
            AnswerKind::RelativeDensity
        }
    }

    /// The steady layer's answer with its standard error.
    pub fn answer(&self) -> PointAnswer {
        let (value, se) = match self.answer_kind() {
            AnswerKind::SteadyPacking => (self.packing, self.packing_se),
            _ => (self.relative_density, self.relative_density_se),
        };
        PointAnswer { kind: self.answer_kind(), value, se: Some(se) }
    }
}

/// The numerical error of a steady layer: each numerical choice's measured move
/// (`crate::scenes::layers::numerics`) and their root sum of squares.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NumericalError {
    /// Of the packing (and the relative density), absolute.
    pub packing: f64,
    /// Of the depth under the blade, as a fraction of it.
    pub depth_fraction: f64,
    /// Of the covered fraction, absolute.
    pub covered_fraction: f64,
    pub terms: Vec<NumericalTerm>,
    /// The choices whose move at this scene's value was not measured.
    pub unmeasured: Vec<String>,
}

/// One numerical choice's measured move of the steady layer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NumericalTerm {
    pub choice: String,
    pub packing: f64,
    pub depth_fraction: f64,
    pub covered_fraction: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::outcome::layer::Layer;

    #[test]
    fn a_measure_a_pass_could_not_take_is_read_back_as_not_measured() {
        // serde_json writes NaN as null; a failed layers point's failure.json holds such
        // passes, and the report must read it (it once left every unsteady point out).
        let pass = PassRecord {
            k: 1,
            search: false,
            deposit_m: 0.0,
            relative_density: 0.0,
            effective_thickness_m: 1e-4,
            packing: f64::NAN,
            covered_fraction: 0.0,
            roughness_d: f64::NAN,
            bed_relative_density: None,
            particles: 0,
            roller: None,
        };
        let back: PassRecord = serde_json::from_str(&serde_json::to_string(&pass).unwrap()).unwrap();
        assert!(back.packing.is_nan() && back.roughness_d.is_nan());
        assert_eq!(back.effective_thickness_m, 1e-4);
        let layer = Layer {
            layer_cv: f64::NAN,
            layer_cv_noise: f64::NAN,
            covered_fraction: 0.5,
            roughness_d: 0.4,
            height_d: 2.0,
            particles: 10,
        };
        let json = serde_json::to_string(&layer).unwrap();
        assert!(!json.contains("layer_cv"), "{json}");
        let back: Layer = serde_json::from_str(&json).unwrap();
        assert!(back.layer_cv.is_nan() && back.covered_fraction == 0.5);
        // As earlier versions wrote it.
        let old = r#"{"layer_cv": null, "layer_cv_noise": null, "covered_fraction": 0.5,
            "roughness_d": 0.4, "height_d": 2.0, "particles": 10}"#;
        let back: Layer = serde_json::from_str(old).unwrap();
        assert!(back.layer_cv.is_nan() && back.layer_cv_noise.is_nan());
    }
}
