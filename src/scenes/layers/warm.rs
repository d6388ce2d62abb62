//! A fused bed's warm start from a finished neighbour of the same sweep (`[scene] warm_start =
//! true`): the point's first pass lies on a solid set at the neighbour's steady depth of powder
//! under the blade, in layer thicknesses, and its search for its own depth starts there, so it
//! needs [`WARM_SEARCH_PASSES`] search passes instead of the cold bed's six. A loose bed starts
//! cold: its state is every layer's particles, not a number. Opt-in: on deep beds (five layers
//! of powder under the blade and more) a warm answer's depth stood 3–9 SE from the cold one's
//! (docs/study/layers.md "Warm start").

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::plan::{plan_of, with_plan};
use crate::outcome::{RunResult, RESULT_FILE};
use crate::scene::Scene;
use crate::scenes::{ColdStart, Warm};

/// What a warm-started point keeps in its run directory of the state it started from, so that it
/// resumes from the same.
pub const WARM_DATA: &str = "warm-start.json";

/// Search passes of a warm-started fused bed (the search multiplies the depth by the layer
/// thickness over the pass's deposit): with 2, two of five warm points of the study stood 6 and
/// 9 SE from their cold depth; with 4, 5 and 3 SE, the other three within 1 SE either way.
pub const WARM_SEARCH_PASSES: usize = 4;

/// The depth a warm start sets under the first pass's tip, m.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WarmDepth {
    pub depth_m: f64,
}

/// `to` started from the steady layer the finished point in `from_dir` left.
pub fn start(from_dir: &Path, to: &Scene) -> Result<Warm, ColdStart> {
    let plan = plan_of(to);
    if !plan.fused {
        return Err(ColdStart::LooseBed);
    }
    let from: RunResult = std::fs::read_to_string(from_dir.join(RESULT_FILE))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .ok_or(ColdStart::NoSteadyLayer)?;
    let l = super::result::series(&from).filter(|l| l.steady).ok_or(ColdStart::NoSteadyLayer)?;
    let ratio = l.effective_thickness_m / l.layer_thickness_m;
    if !ratio.is_finite() || ratio <= 0.0 {
        return Err(ColdStart::NoSteadyLayer);
    }
    // In this point's layer thicknesses, within what its search may ask for.
    let t = plan.layer_thickness;
    let deepest =
        if plan.search_max_depth > 0.0 { plan.search_max_depth } else { super::SEARCH_MAX_DEPTH_LAYERS * t };
    let depth = WarmDepth { depth_m: (ratio * t).clamp(t, deepest) };
    Ok(Warm {
        scene: with_depth(to, depth),
        data: serde_json::to_string(&depth).expect("a depth serialises"),
        data_file: WARM_DATA,
        particles: 0,
    })
}

/// `to` started again from the depth it recorded (`data`, [`WARM_DATA`]'s).
pub fn again(to: &Scene, data: &str) -> Result<Scene, String> {
    let depth: WarmDepth =
        serde_json::from_str(data).map_err(|e| format!("{WARM_DATA}: not a layers warm start: {e}"))?;
    Ok(with_depth(to, depth))
}

/// `to` with its first pass on a solid `depth` under its tip, and fewer search passes.
fn with_depth(to: &Scene, depth: WarmDepth) -> Scene {
    let mut plan = plan_of(to);
    let cold = plan.search_passes;
    plan.search_passes = cold.min(WARM_SEARCH_PASSES);
    plan.least_passes = plan.least_passes.saturating_sub(cold - plan.search_passes).max(1);
    plan.first_floor = Some(plan.passes[0].tip - depth.depth_m);
    with_plan(to, plan)
}
