//! What one run produced: a result, a classified failure, or a cancellation.
//!
//! These are the records the pool, the store and the reports exchange. A failure is never turned
//! into a number: it carries its class (which decides the retry policy) and a one-line reason.

pub mod answer;
pub mod layer;
pub mod own_result;
pub mod steady;

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

pub use answer::{AnswerKind, PointAnswer};
pub use own_result::OwnResult;

/// Version of `result.json` / `failure.json`.
pub const RESULT_FORMAT: u32 = 1;
/// The file a finished run writes its [`RunResult`] to, in its run directory.
pub const RESULT_FILE: &str = "result.json";

/// Number of v_x layers in front of the blade (thesis Appendix A).
pub const VX_LAYERS: usize = 12;

/// The result of a completed run: `result.json`.
///
/// Read through [`RunResult`]'s own `Deserialize`, which reads an older answer written as `mfr`
/// as the quantity the layout's own result says it is (a layers run's steady layer).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(remote = "Self")]
pub struct RunResult {
    pub format: u32,
    /// Content hash of the run (deck, mesh, engine identity).
    pub hash: String,
    /// Every scene parameter, swept and fixed, in the sweep file's units.
    pub parameters: BTreeMap<String, f64>,
    /// The point's answer ([`answer`]), under its own keys: a flow's mass flow ratio from the
    /// deposited layer (`mfr`, docs/scene.md "Metrics", thesis Eq. 15–17, dimensionless; its
    /// standard error `mfr_se`, of the conveyor layout: batch means over the steady window), a
    /// layers point's steady layer (`relative_density` or `steady_packing`). NaN, and absent from
    /// the file, where the scene measures none (a pour).
    #[serde(flatten)]
    pub answer: PointAnswer,
    /// The same from the flux of particles past the blade's front face (cross-check).
    #[serde(default = "not_measured", skip_serializing_if = "is_not_measured")]
    pub mfr_flux: f64,
    /// Particles counted in the answer (a flow's crossings of its window, a layers point's
    /// deposits over all its passes): its counting noise is about 1/√n relative. Written as
    /// `mfr_particles` before December 2026, and read under that name too.
    #[serde(alias = "mfr_particles")]
    pub answer_particles: usize,
    /// The steady-state measurement: block series, transient, batches, trend, heap, stop.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steady_state: Option<Box<crate::outcome::steady::SteadyState>>,
    /// The answer over consecutive parts of the measurement: a flow's MFR over sub-windows of
    /// its window (four), a layers point's relative density or packing pass by pass, none for
    /// a pour. Written as `mfr_windows` before December 2026, and read under that name too.
    #[serde(alias = "mfr_windows")]
    pub answer_windows: Vec<f64>,
    /// False when the measurement had not reached a steady state (a flow's sub-windows, a
    /// layers point's passes).
    pub steady: bool,
    /// Two-sided p-value of the steadiness test (the window's halves, counting noise); NaN and
    /// absent where nothing flows.
    #[serde(default = "not_measured", skip_serializing_if = "is_not_measured")]
    pub steady_p: f64,
    /// Mean v_x (m/s) per layer k = 1..12 at z = gap + k·D/2; `None` for an empty layer.
    pub vx: Vec<Option<f64>>,
    /// Standard error of each v_x layer over the steady window's snapshots (conveyor layout).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub vx_se: Vec<Option<f64>>,
    /// Particles in the pile.
    pub particles: usize,
    /// The spread layer's quality behind the blade at the window's end (absent in results
    /// written before it was measured, and from engines that give none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer: Option<crate::outcome::layer::Layer>,
    /// The layer's thickness, m: the gap plus the open depth of the substrate's pockets that the
    /// powder reaches below the tops (docs/scene.md "Layer packing"); absent in older results.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_thickness: Option<f64>,
    /// The deposit's packing over that thickness: MFR × gap / layer_thickness. Bounded by the
    /// packing of spheres, as MFR is not at thin gaps on a rough substrate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_packing: Option<f64>,
    /// Its standard error (MFR's, scaled alike).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_packing_se: Option<f64>,
    /// What only the run's layout measures, under its own key ([`own_result`]): a layers
    /// run's passes and steady layer (`layers`), a pour's heap (`heap`); nothing elsewhere.
    #[serde(flatten)]
    pub own: OwnResult,
    /// The powder's sizes, for a size distribution (absent for one size).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sizes: Option<SizeSummary>,
    /// Timesteps of the settle (until at rest, or the fixed settle of the thesis layout).
    pub settle_steps: u64,
    /// Timesteps run in all: settle and spread.
    pub steps: u64,
    /// Simulated time, s.
    pub simulated_time: f64,
    /// Wall-clock time of the LIGGGHTS process, s.
    pub wall_time: f64,
    /// CPU time of the LIGGGHTS process, s (absent in results written before it was measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_time: Option<f64>,
    pub engine_version: String,
    pub warnings: Vec<String>,
    /// The finished point this run started from (absent: it started cold).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warm_start: Option<WarmStart>,
    /// The SE target of MFR the sweep chose for this run (absent: the scene's own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mfr_se_target: Option<f64>,
    /// The parts that continued the run's window after its first (`sweep extend`), each in
    /// `extension-N/` of its run directory; its times are every part's (absent: none).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub extensions: u32,
}

impl Serialize for RunResult {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        RunResult::serialize(self, s)
    }
}

impl<'de> Deserialize<'de> for RunResult {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<RunResult, D::Error> {
        let mut r = RunResult::deserialize(d)?;
        // Before its answer had its own name, a layers result wrote it as `mfr` beside the
        // steady layer it came from.
        if let (AnswerKind::Mfr, Some(kind)) = (r.answer.kind, r.own.result().and_then(|o| o.answer_kind())) {
            r.answer = r.answer.as_kind(kind);
        }
        Ok(r)
    }
}

fn is_zero(n: &u32) -> bool {
    *n == 0
}

/// Where a warm-started run began: the point whose steady state it was mapped from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WarmStart {
    /// The run hash of that point.
    pub from: String,
    /// Its distance in the design's unit cube.
    pub distance: f64,
    /// The particles mapped from it.
    pub particles: usize,
}

impl Default for RunResult {
    /// A result of the current format that measured nothing: a base for the stand-in and test
    /// engines to fill (`RunResult { answer: PointAnswer::mfr(m), ..RunResult::default() }`).
    fn default() -> RunResult {
        RunResult {
            format: RESULT_FORMAT,
            hash: String::new(),
            parameters: BTreeMap::new(),
            answer: PointAnswer::default(),
            mfr_flux: 0.0,
            answer_particles: 0,
            steady_state: None,
            answer_windows: Vec::new(),
            steady: true,
            steady_p: 1.0,
            vx: Vec::new(),
            vx_se: Vec::new(),
            particles: 0,
            layer: None,
            layer_thickness: None,
            layer_packing: None,
            layer_packing_se: None,
            own: OwnResult::none(),
            sizes: None,
            settle_steps: 0,
            steps: 0,
            simulated_time: 0.0,
            wall_time: 0.0,
            cpu_time: None,
            engine_version: String::new(),
            warnings: Vec::new(),
            warm_start: None,
            mfr_se_target: None,
            extensions: 0,
        }
    }
}

/// A size distribution in a few numbers, m: what a datasheet states, of what the run used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SizeSummary {
    /// Number-mean diameter (the scene's unit of length).
    pub mean_diameter: f64,
    /// D10, D50 and D90 by volume, as laser diffraction reports them.
    pub d10: f64,
    pub d50: f64,
    pub d90: f64,
    /// (D90 − D10) / D50.
    pub span: f64,
    /// Size classes the engine inserts.
    pub classes: usize,
    /// The lognormal's largest relative miss of the datasheet's D10/D50/D90.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit_residual: Option<f64>,
}

/// Reads `null` — how serde_json writes NaN — back as NaN: a measure a pass could not take (a
/// pass that left nothing on the plate has no packing or roughness).
pub(crate) fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// A number the scene does not measure: NaN in memory, absent from `result.json`.
pub(crate) fn not_measured() -> f64 {
    f64::NAN
}

pub(crate) fn is_not_measured(v: &f64) -> bool {
    v.is_nan()
}

/// Why a run failed. The class decides whether the pool retries it.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum FailureClass {
    /// The engine could not be started.
    CouldNotStart,
    /// Killed by a signal we did not send.
    Signalled,
    /// Ran past its timeout.
    TimedOut,
    /// LIGGGHTS printed an ERROR or exited non-zero.
    EngineError,
    /// The atom count dropped where nothing is meant to remove atoms.
    LostAtoms,
    /// Non-finite or exploding kinetic energy.
    Unstable,
    /// The output (log or dump) could not be read.
    Unparsable,
    /// The dose was still moving when the settle's time cap ran out.
    NotSettled,
    /// The engine's output or the result holds a number that is not physically possible (a
    /// negative mass, a non-finite velocity, an MFR above the densest packing).
    Implausible,
    /// The flow through the gap was not steady over the window (its halves disagree beyond
    /// counting noise): the MFR is not a property of the point.
    Unsteady,
}

impl FailureClass {
    /// Transient failures may succeed on a retry; physics failures never will, nor a timeout:
    /// the same deck runs as many steps again (`--retry-failed` or a longer `timeout_s` does).
    pub fn is_transient(self) -> bool {
        matches!(self, FailureClass::CouldNotStart | FailureClass::Signalled)
    }

    pub fn as_str(self) -> &'static str {
        match self {
            FailureClass::CouldNotStart => "could-not-start",
            FailureClass::Signalled => "signalled",
            FailureClass::TimedOut => "timed-out",
            FailureClass::EngineError => "engine-error",
            FailureClass::LostAtoms => "lost-atoms",
            FailureClass::Unstable => "unstable",
            FailureClass::Unparsable => "unparsable",
            FailureClass::NotSettled => "not-settled",
            FailureClass::Implausible => "implausible",
            FailureClass::Unsteady => "unsteady",
        }
    }
}

/// A failed run: `failure.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RunFailure {
    pub format: u32,
    pub hash: String,
    pub class: FailureClass,
    /// One line saying what went wrong.
    pub reason: String,
    /// The last lines of the LIGGGHTS log, for diagnosis.
    pub log_tail: String,
    pub wall_time: f64,
    /// What the run measured when it ran to the end but its answer is not valid (an unsteady
    /// flow): kept for diagnosis, never averaged into results.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured: Option<Box<RunResult>>,
}

impl RunFailure {
    /// The failure of the run `hash`, of the current format, that measured nothing.
    pub fn of(
        hash: &str,
        class: FailureClass,
        reason: String,
        log_tail: String,
        wall_time: f64,
    ) -> RunFailure {
        RunFailure {
            format: RESULT_FORMAT,
            hash: hash.to_string(),
            class,
            reason,
            log_tail,
            wall_time,
            measured: None,
        }
    }
}

/// How one attempt at a run ended.
#[derive(Debug, Clone, PartialEq)]
// One per run, moved once: boxing the result would buy nothing.
#[allow(clippy::large_enum_variant)]
pub enum RunOutcome {
    Done(RunResult),
    Failed(RunFailure),
    /// Stopped by Ctrl-C / SIGTERM; the run dir is incomplete and will be re-run on resume.
    Cancelled,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_older_layers_result_with_its_answer_as_mfr_reads_as_its_steady_layer() {
        // As a layers point wrote it before its answer had its own name (abridged: no passes).
        let old = |bed: &str, answer: f64| {
            format!(
                r#"{{"format": 1, "hash": "h", "parameters": {{"layer_thickness": 0.05}},
                "mfr": {answer}, "mfr_particles": 1200, "mfr_se": 0.011,
                "mfr_windows": [0.5, 0.57], "steady": true, "vx": [], "particles": 400,
                "layers": {{"bed": "{bed}", "layer_thickness_m": 5e-5, "passes": [], "steady_from": 2,
                  "steady": true, "packing": 0.52, "packing_se": 0.01, "relative_density": 0.57,
                  "relative_density_se": 0.011, "effective_thickness_m": 1e-4,
                  "effective_thickness_se_m": 1e-6, "covered_fraction": 0.9, "roughness_d": 0.4}},
                "settle_steps": 0, "steps": 10, "simulated_time": 0.1, "wall_time": 1.0,
                "engine_version": "x", "warnings": []}}"#
            )
        };
        let loose: RunResult = serde_json::from_str(&old("loose", 0.57)).unwrap();
        assert_eq!(
            loose.answer,
            PointAnswer { kind: AnswerKind::RelativeDensity, value: 0.57, se: Some(0.011) }
        );
        let fused: RunResult = serde_json::from_str(&old("fused", 0.52)).unwrap();
        assert_eq!(fused.answer.kind, AnswerKind::SteadyPacking);
        assert_eq!((loose.answer_windows.as_slice(), loose.answer_particles), ([0.5, 0.57].as_slice(), 1200));
        // Written again under its own name, and read back the same.
        let json = serde_json::to_value(&loose).unwrap();
        assert!(json.get("mfr").is_none() && json.get("mfr_se").is_none(), "{json}");
        assert_eq!(
            (json["relative_density"].as_f64(), json["relative_density_se"].as_f64()),
            (Some(0.57), Some(0.011))
        );
        let again = serde_json::from_value::<RunResult>(json.clone()).unwrap();
        assert_eq!(again.answer, loose.answer);
        assert_eq!(serde_json::to_value(&again).unwrap(), json);
        assert_eq!(serde_json::to_value(&fused).unwrap()["steady_packing"].as_f64(), Some(0.52));
    }

    #[test]
    fn a_flow_keeps_mfr_and_a_pour_writes_no_answer() {
        let flow = RunResult {
            answer: PointAnswer { se: Some(0.004), ..PointAnswer::mfr(0.41) },
            ..RunResult::default()
        };
        let json = serde_json::to_value(&flow).unwrap();
        assert_eq!((json["mfr"].as_f64(), json["mfr_se"].as_f64()), (Some(0.41), Some(0.004)));
        assert_eq!(serde_json::from_value::<RunResult>(json).unwrap(), flow);
        let pour = RunResult { answer: PointAnswer::none(), ..RunResult::default() };
        let json = serde_json::to_value(&pour).unwrap();
        assert!(json.get("mfr").is_none() && json.get("mfr_se").is_none(), "{json}");
        assert!(serde_json::from_value::<RunResult>(json).unwrap().answer.value.is_nan());
    }
}
