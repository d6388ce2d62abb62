//! The scenes a point can be: each layout is one folder implementing [`Layout`], registered
//! once in [`LAYOUTS`]. Nothing outside this folder asks which layout a point is: the sweep file
//! names it (`[scene] layout`), [`lookup`] finds it, and the point, the report and the CLI ask
//! the layout itself for its template, geometry, measurement and what to show.
//!
//! A trait rather than an enum: a new scene is a new folder and one line in [`LAYOUTS`], with no
//! `match` to extend elsewhere.

pub mod conveyor;
pub mod figures;
mod keys;
pub mod layers;
pub mod moving_blade;
pub mod pour;
pub mod quantity;
mod results;
pub mod settings;
pub mod stand_in;
#[cfg(test)]
mod template_keys;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::engine::EngineRun;
use crate::outcome::{AnswerKind, FailureClass, RunResult};
use crate::scene::own_settings::OwnSettings;
use crate::scene::settings::SceneSettings;
use crate::scene::{params, plausible, Base, Scene, SceneError};
pub use conveyor::warm::Warm;
pub use keys::{readers, reads, unread, UnreadSetting};

/// Why a point starts cold instead of from a finished neighbour's state ([`Layout::warm_start`]).
#[derive(Debug, thiserror::Error)]
pub enum ColdStart {
    /// A layout with no steady state to carry.
    #[error("the {layout} layout starts every point cold")]
    NoWarmStart { layout: &'static str },
    /// The neighbour's state dump cannot be read.
    #[error(transparent)]
    Dump(#[from] crate::engine::dump::DumpError),
    #[error("the state dump is empty")]
    EmptyDump,
    /// The neighbour's powder is not this point's scaled.
    #[error("another size distribution")]
    OtherSizes,
    #[error("nothing of its heap fits this point")]
    NothingFits,
    /// A loose bed's state is every layer's particles.
    #[error("a loose bed starts cold")]
    LooseBed,
    #[error("it has no steady layer to start from")]
    NoSteadyLayer,
}

/// Every layout, in the order `scene.layout`'s error lists them.
pub const LAYOUTS: &[&dyn Layout] =
    &[&moving_blade::GATED, &moving_blade::THESIS, &conveyor::Conveyor, &pour::Pour, &layers::Layers];

/// The layout named `name`.
pub fn lookup(name: &str) -> Option<&'static dyn Layout> {
    LAYOUTS.iter().copied().find(|l| l.name() == name)
}

/// The layouts' names, in registration order.
pub fn names() -> Vec<&'static str> {
    LAYOUTS.iter().map(|l| l.name()).collect()
}

/// Why a one-layer layout (moving blade, conveyor) ignores `layer_thickness` ([`Layout::ignores`]).
pub const ONE_LAYER: &str = "spreads one layer at `gap`; only the layers layout drops a platform";

/// Why the parameter or `[scene]` key `name` (`scene.…`) plays no part in a point of
/// `settings`, if it plays none: the layout does not read it, or the size distribution takes its
/// sizes elsewhere.
pub fn ignored(settings: &SceneSettings, name: &str) -> Option<String> {
    if let Some(why) = settings.size_distribution.ignores(name) {
        return Some(why.to_string());
    }
    let layout = lookup(&settings.layout)?;
    if let Some(key) = name.strip_prefix("scene.") {
        return (!reads(settings, key)).then(|| {
            let readers = keys::the_layouts(&readers(key));
            format!("the {} layout does not read it; it is read only by {readers}", layout.name())
        });
    }
    layout.ignores(settings, name).map(|why| format!("the {} layout {why}", layout.name()))
}

/// Why a point of `settings` refuses the parameter `name` set to `value`: one read only in some
/// setups ([`params::ONLY_WHERE_READ`]), set away from its default where it is not read.
pub fn set_but_unread(settings: &SceneSettings, name: &str, value: f64) -> Option<String> {
    let info = params::lookup(name)?;
    // Exactly the default: a value nobody set (the catalogue's own number), not a measurement.
    if !params::ONLY_WHERE_READ.contains(&name) || value == info.default {
        return None;
    }
    ignored(settings, name)
}

/// Whether a point of `settings` lists the parameter `name` in its deck's header and
/// results.csv: every parameter but one read only in some setups where it is not read.
pub fn shown(settings: &SceneSettings, name: &str) -> bool {
    !params::ONLY_WHERE_READ.contains(&name) || ignored(settings, name).is_none()
}

/// Why a layout without a roller ignores `roller_speed_ratio` ([`Layout::ignores`]).
pub const NO_ROLLER: &str = "has no roller; only the layers layout turns one (blade_profile = \"roller\")";

/// A built-in deck template.
#[derive(Debug, Clone, Copy)]
pub struct BuiltinTemplate {
    pub name: &'static str,
    pub source: &'static str,
}

/// A `[scene]` setting a layout refuses: the key (`scene.…`) and what was expected.
#[derive(Debug, Clone, PartialEq)]
pub struct BadSetting {
    pub key: &'static str,
    pub why: String,
}

/// What a finished engine run left, for the layout to measure.
pub struct Finished<'a> {
    pub scene: &'a Scene,
    /// Every catalogue parameter of the point, in catalogue units.
    pub parameters: &'a BTreeMap<String, f64>,
    pub hash: &'a str,
    pub run_dir: &'a Path,
    pub run: &'a EngineRun,
    pub engine_version: &'a str,
    /// The run directories of the run's earlier parts, oldest first, when this one continued
    /// them (`sweep extend`); empty for a run from rest.
    pub earlier: &'a [PathBuf],
}

impl Finished<'_> {
    /// What every layout's result says of the run itself: the sizes inserted, its steps and
    /// simulated time, the engine's clocks, version and warnings; the rest at its default.
    pub fn record(&self, steps: u64) -> RunResult {
        RunResult {
            sizes: self.scene.sizes_of_a_distribution(),
            steps,
            simulated_time: steps as f64 * self.scene.timestep,
            wall_time: self.run.wall_time,
            cpu_time: self.run.cpu_time,
            engine_version: self.engine_version.to_string(),
            warnings: self.run.warnings.clone(),
            ..RunResult::default()
        }
    }
}

/// Why a finished run gives no result; `measured` keeps its numbers where they were measured
/// (an unsteady or implausible flow), for the record, never for the statistics.
#[derive(Debug)]
pub struct Rejected {
    pub class: FailureClass,
    pub reason: String,
    pub measured: Option<Box<RunResult>>,
}

impl Rejected {
    pub fn new(class: FailureClass, reason: impl Into<String>) -> Rejected {
        Rejected { class, reason: reason.into(), measured: None }
    }

    pub fn measured(class: FailureClass, reason: impl Into<String>, result: RunResult) -> Rejected {
        Rejected { class, reason: reason.into(), measured: Some(Box::new(result)) }
    }
}

/// The held heap of a layout that keeps one in front of the blade, at the centre of a sweep's
/// space (for the report's setup and summary.json).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HeldHeap {
    pub heap_particles: usize,
    pub heap_height_mm: f64,
    pub block_travel_mm: f64,
    pub warmup_blocks: u64,
    pub min_window_blocks: u64,
    pub cap_travel_mm: f64,
}

/// A layout's rows of the report's setup table: `head` after the layout and substrate, `tail`
/// after the common numerical knobs.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SetupRows {
    pub head: Vec<(&'static str, String)>,
    pub tail: Vec<(&'static str, String)>,
}

/// The files of a warm start in a run directory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WarmFiles {
    /// The end-of-run state a finished point leaves for its neighbours to start from.
    pub state: &'static str,
    /// The mapped particles a warm-started deck reads.
    pub data: &'static str,
}

/// How a layout's point runs pass by pass ([`Layout::by_pass`]): the fewest passes before it
/// may stop, and the most.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ByPass {
    pub least: usize,
    pub most: usize,
}

/// One scene layout: everything that differs from one scene to another.
pub trait Layout: Sync {
    /// Its name in `[scene] layout`.
    fn name(&self) -> &'static str;

    /// The deck it renders unless the sweep file names its own template.
    fn template(&self) -> BuiltinTemplate;

    /// Refuse the `[scene]` settings this layout cannot run with.
    fn check_settings(&self, settings: &SceneSettings) -> Result<(), BadSetting>;

    /// The `[scene]` keys this layout reads of those some layout does not ([`unread`]): a key
    /// no layout lists is read by every layout; one that others list and this one does not is
    /// refused in its sweep files.
    fn own_settings(&self) -> Vec<&'static str>;

    /// Every number the deck and the measurement need, from the point's common part.
    fn derive(&self, base: Base, settings: &SceneSettings) -> Scene;

    /// Its own `[scene]` keys as its type (`scene::own_settings::LayoutSettings`): the keys of
    /// `own_settings()` that not every layout reads, `written` over the fidelity's preset;
    /// default none (a layout that reads only keys every layout has).
    fn own_keys(&self, _fidelity: &str, written: &toml::Table) -> Result<OwnSettings, toml::de::Error> {
        match written.keys().next() {
            None => Ok(OwnSettings::none()),
            Some(key) => Err(serde::de::Error::custom(format!("unknown field `{key}`"))),
        }
    }

    /// The atoms the engine's log must keep to the end (None: the count varies by design).
    fn atoms_kept(&self, scene: &Scene) -> Option<u64>;

    /// The run's result from what the engine left.
    fn measure(&self, run: &Finished) -> Result<RunResult, Rejected>;

    /// A few words on what a run of `scene` simulates (`sweep run`, `sweep render`).
    fn what_runs(&self, scene: &Scene) -> String;

    /// The report's setup rows of this layout's own settings.
    fn setup_rows(&self, settings: &SceneSettings) -> SetupRows;

    /// Why a catalogue parameter plays no part in this layout's scene, if it plays none: a
    /// sweep of such a parameter is refused, and the report leaves it out of the setup every
    /// point shares. (Which `[scene]` keys it reads is [`Layout::own_settings`].)
    fn ignores(&self, _settings: &SceneSettings, _name: &str) -> Option<&'static str> {
        None
    }

    /// The heap it holds in front of the blade, if it holds one.
    fn held_heap(&self, _scene: &Scene) -> Option<HeldHeap> {
        None
    }

    /// The deck's wall mesh (`blade.stl`): the scene's blade, unless the layout moves another
    /// wall (a layout with neither overrides this).
    fn mesh(&self, scene: &Scene) -> String {
        scene.blade().map_or_else(String::new, |b| crate::scene::mesh::blade_stl(scene, b))
    }

    /// A warm start of `to` (whose particle file is `to_pile`) from the state a finished point
    /// `from`, `distance` away in the design's unit cube, left in `from_dir`: the scene to render
    /// and the particles it reads. `Err` says why the point starts cold; a layout with no steady
    /// state to carry starts every point cold.
    fn warm_start(
        &self,
        _from: &Scene,
        _from_dir: &Path,
        _to: &Scene,
        _to_pile: &str,
        _distance: f64,
    ) -> Result<Warm, ColdStart> {
        Err(ColdStart::NoWarmStart { layout: self.name() })
    }

    /// `scene` continued from the finished run whose parts' directories are `parts` (oldest
    /// first) by a new part in `part_dir`, where what it reads besides its deck is written;
    /// `warm_distance`: the run's first part was warm-started from a neighbour that far off.
    /// `Err` says why it cannot be.
    fn continuation(
        &self,
        _scene: &Scene,
        _warm_distance: Option<f64>,
        _parts: &[PathBuf],
        _part_dir: &Path,
    ) -> Result<Scene, String> {
        Err(format!("the {} layout does not run to a precision, so its runs are not extended", self.name()))
    }

    /// Shrink what a finished run leaves in `run_dir` to what is kept (`done`: it has a
    /// result).
    fn keep(&self, _run_dir: &Path, _done: bool) {}

    /// `scene` run until the SE of its MFR is at most `mfr_abs_se` (the sweep's choice), if
    /// this layout runs to a precision.
    fn with_precision(&self, _scene: &Scene, _mfr_abs_se: f64) -> Option<Scene> {
        None
    }

    /// Wall meshes the deck reads besides `blade.stl`: (file name, ASCII STL). Part of the run's
    /// identity.
    fn extra_meshes(&self, _scene: &Scene) -> Vec<(&'static str, String)> {
        Vec::new()
    }

    /// The deck's particle file (`pile.data`): the box, the dose and the substrate.
    fn pile(&self, scene: &Scene) -> String {
        crate::scene::pile::pile_data(scene)
    }

    /// Why a sweep (`sweep lds`, `sweep lattice`) of this layout is refused, if it is: the
    /// sweep's statistics, report and emulator read MFR.
    fn refuses_sweeps(&self) -> Option<&'static str> {
        None
    }

    /// What a point of this layout under `settings` answers with: the number a sweep's
    /// statistics, emulator, report and prediction read, named by its own key in result.json
    /// (MFR unless the layout measures another quantity).
    fn answer(&self, _settings: &SceneSettings) -> AnswerKind {
        AnswerKind::Mfr
    }

    /// [`Layout::answer`] in words.
    fn answer_name(&self, settings: &SceneSettings) -> &'static str {
        self.answer(settings).words()
    }

    /// What the report's recommendation says of a done point after its answer, if anything.
    fn answer_detail(&self, _r: &RunResult) -> Option<String> {
        None
    }

    /// The layout's own quantities in results.csv, by their own names, after the common
    /// columns (none: the common MFR, v_x and layer columns say it all).
    fn result_columns(&self) -> &'static [&'static str] {
        &[]
    }

    /// A result's values of [`Layout::result_columns`], one each (empty where not measured).
    fn result_values(&self, _r: &RunResult) -> Vec<String> {
        Vec::new()
    }

    /// What `sweep run` prints of a result above its particles, steps and times, if not MFR
    /// and v_x.
    fn result_lines(&self, _r: &RunResult) -> Option<Vec<String>> {
        None
    }

    /// The files a run of this layout under `settings` writes into its run directory besides
    /// the deck, the log and the result: an earlier attempt's are removed before a run, so that
    /// none is read as this one's.
    fn run_files(&self, _settings: &SceneSettings) -> Vec<String> {
        Vec::new()
    }

    /// The files of its warm starts, if it starts points from a finished neighbour's state.
    fn warm_start_files(&self) -> Option<WarmFiles> {
        None
    }

    /// The quantities of a result a calibration (`sweep calibrate --target NAME=…`) can fit
    /// this layout's runs to ([`quantity`]).
    fn calibration_targets(&self) -> &'static [quantity::Quantity] {
        std::slice::from_ref(&quantity::MFR)
    }

    /// How a point of `scene` runs pass by pass, if it does (`crate::point::passes`): one engine
    /// run a pass, each from the restart the pass before wrote, measured after each from the
    /// least on, until the measure says it is done.
    fn by_pass(&self, _scene: &Scene) -> Option<ByPass> {
        None
    }

    /// `scene`'s deck for pass `k` alone, going on from `before`: the restart and the log the
    /// pass before left (`None` for the first pass).
    fn pass_scene(&self, scene: &Scene, _k: usize, _before: Option<(&str, &str)>) -> Result<Scene, String> {
        Ok(scene.clone())
    }

    /// Ready `run_dir` for pass `k` of `scene`: files its deck reads that earlier passes' output
    /// makes. `Err` says what is missing.
    fn ready_pass(&self, _scene: &Scene, _k: usize, _run_dir: &std::path::Path) -> Result<(), String> {
        Ok(())
    }

    /// `to` started again from the warm start it recorded (`data`, the [`Warm`]'s), when a point
    /// run by the pass resumes.
    fn warm_again(&self, _to: &Scene, _data: &str) -> Result<Scene, String> {
        Err(format!("the {} layout does not resume a warm start", self.name()))
    }

    /// `scene` run to at most `most` passes (`sweep extend --passes`), if its machine is built
    /// for them; `Err` says why not.
    fn with_most_passes(&self, _scene: &Scene, _most: usize) -> Result<Scene, String> {
        Err(format!("the {} layout does not run pass by pass", self.name()))
    }

    /// `scene` as measured once passes 1 to `k` have run.
    fn measured_through(&self, scene: &Scene, _k: usize) -> Scene {
        scene.clone()
    }

    /// The files passes `from` to `to` write besides their deck, log and restart.
    fn pass_files(&self, _from: usize, _to: usize) -> Vec<String> {
        Vec::new()
    }

    /// Whether every number of a result of this layout is possible, as the stand-in makes it up
    /// and as it is read back ([`crate::store::counts`]): by default a flow's,
    /// [`plausible::check_result`](crate::measure::plausible::check_result) with
    /// [`Measures::FLOW`](crate::measure::plausible::Measures::FLOW).
    fn check_result(&self, r: &RunResult) -> Result<(), crate::measure::plausible::Implausible> {
        crate::measure::plausible::check_result(r, crate::measure::plausible::Measures::FLOW)
    }

    /// What the stand-in engine (`[run] engine = "stand-in"`) makes up for a point of this
    /// layout: the shape of its result from a closed form in the point's parameters, not its
    /// physics ([`stand_in`]), or why the point fails as a real run of it would. A result must
    /// pass the checks this layout's results pass when read back, or the point fails as
    /// implausible.
    fn stand_in(&self, point: &mut stand_in::StandInPoint) -> Result<RunResult, Rejected>;

    /// A done point's answer pass by pass, for the report, if it runs pass by pass.
    fn pass_series(&self, _r: &RunResult) -> Option<figures::PassSeries> {
        None
    }

    /// A top view of the layer the last pass of a done point of `scene` left, read from its run
    /// directory, for the report; `Err` says why it cannot be drawn.
    fn top_view(
        &self,
        _scene: &Scene,
        _run_dir: &Path,
        _r: &RunResult,
    ) -> Option<Result<figures::TopView, String>> {
        None
    }
}

/// The layout `settings` names; an unknown name is refused when the sweep file is read, so here
/// it is an internal error.
pub fn of(settings: &SceneSettings) -> Result<&'static dyn Layout, SceneError> {
    lookup(&settings.layout).ok_or_else(|| SceneError::Invalid {
        name: "layout".into(),
        value: f64::NAN,
        why: format!("\"{}\" is not one of {}", settings.layout, names().join(", ")),
    })
}

/// Build the scene of one point from every catalogue parameter (in catalogue units) and the
/// settings: the common part, the layout's geometry, then the plausibility bounds.
pub fn build(values: &BTreeMap<String, f64>, settings: &SceneSettings) -> Result<Scene, SceneError> {
    let layout = of(settings)?;
    for (name, &value) in values {
        if let Some(why) = set_but_unread(settings, name, value) {
            return Err(SceneError::Invalid { name: name.clone(), value, why });
        }
    }
    let scene = layout.derive(Base::new(values, settings)?, settings);
    if !settings.force_bounds {
        let held = layout.held_heap(&scene).map(|h| (h.heap_particles, h.heap_height_mm * 1e-3));
        plausible::check(&scene, held, values, settings)?;
    }
    Ok(scene)
}
