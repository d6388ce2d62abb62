//! The blade a layout moves over the plate (or holds still over a moving substrate), and the
//! window of its travel over which a flow under it is measured: groups of numbers that the
//! blade layouts share, each a part of the layouts' own types that has it
//! ([`super::own::LayoutData::blade`], [`super::own::LayoutData::window`]), not of every scene.
//!
//! Their fields are the deck's keys (`scene.gap`, `scene.blade_x0`, …: the layout's type
//! flattens them into its context). The measurement ([`crate::measure`]), the passage screen and
//! the blade mesh read them here; which layout a scene is, they do not know. Lengths in metres.

use serde::Serialize;

use super::substrate::Substrate;

/// A blade spreading over its substrate: the blade, the window of its travel its flow is
/// measured over, and the substrate under it (the moving-blade layouts' and the conveyor's, whose
/// blade stands still over a moving substrate: [`super::own::LayoutData::spreader`]). The
/// layout's type flattens it, so its fields keep their keys (`scene.gap`,
/// `scene.window_length_steps`, `scene.substrate_particles`, …).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spreader {
    #[serde(flatten)]
    pub blade: Blade,
    #[serde(flatten)]
    pub window: Window,
    #[serde(flatten)]
    pub substrate: Substrate,
}

/// A blade: where it stands, how fast it travels and how it starts.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Blade {
    /// Height of its tip over the plate (or the substrate's top), m.
    pub gap: f64,
    pub blade_speed: f64,
    pub blade_thickness: f64,
    /// x of the blade's rear face at the start; the front face is at + thickness.
    pub blade_x0: f64,
    pub blade_top: f64,
    /// Inset of the blade mesh from the periodic y faces (it must lie inside the box).
    pub blade_y_inset: f64,
    /// The blade stands still (the substrate moves under it) instead of travelling.
    pub blade_fixed: bool,
    /// Steps over which the blade accelerates linearly from rest to full speed.
    pub ramp_steps: u64,
}

impl Blade {
    /// Timestep at which the blade starts moving: the spread's steps count from it (the deck
    /// resets the step counter once the pile has settled).
    pub fn start_step(&self) -> u64 {
        0
    }

    /// x of the blade's rear face at timestep `step` of a run of `timestep` seconds a step: at
    /// rest until the blade starts, then a linear velocity ramp over `ramp_steps` (travel
    /// v·t²/(2 t_r)), then full speed.
    pub fn rear_at(&self, timestep: f64, step: u64) -> f64 {
        if self.blade_fixed {
            return self.blade_x0;
        }
        let k = step.saturating_sub(self.start_step()) as f64;
        let r = self.ramp_steps as f64;
        let travel_steps = if k <= r { k * k / (2.0 * r) } else { k - 0.5 * r };
        self.blade_x0 + self.blade_speed * timestep * travel_steps
    }

    /// x of the blade's front face at timestep `step`.
    pub fn front_at(&self, timestep: f64, step: u64) -> f64 {
        self.rear_at(timestep, step) + self.blade_thickness
    }
}

/// The window of the blade's travel over which the flow under it is measured, and the v_x
/// layers in front of it (thesis Appendix A).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Window {
    /// Steps from the blade's start (step 0 of the spread) to the window's start.
    pub approach_steps: u64,
    /// Steps of the measurement window.
    pub window_length_steps: u64,
    /// Steps between snapshots; the window is SUB_WINDOWS × SNAPSHOTS_PER_SUB_WINDOW of them.
    pub dump_every: u64,
    /// Diameter that sets the v_x layers: D for one size, D85 for a distribution (thesis §3.2).
    pub profile_diameter: f64,
    /// Half-height of a v_x layer, m.
    pub vx_band: f64,
    /// Length of the v_x region in front of the blade (6 D, thesis Appendix A), m.
    pub vx_length: f64,
}

impl Window {
    /// Timestep of the window's start (t1) and end (t2).
    pub fn steps(&self) -> (u64, u64) {
        let t1 = self.approach_steps;
        (t1, t1 + self.window_length_steps)
    }

    /// Steps of the spread, from the blade's start to the window's end.
    pub fn spread_steps(&self) -> u64 {
        self.steps().1
    }

    /// Centre height of v_x layer k = 1..12 over a blade at `gap`: z = gap + k·D/2 (thesis
    /// Appendix A).
    pub fn layer_height(&self, gap: f64, k: usize) -> f64 {
        gap + k as f64 * self.profile_diameter / 2.0
    }
}

/// The fixed-time settle of a dose, or its settle until it is at rest (the gated layout's dose,
/// the pour's column and heap): the deck's `scene.settle_steps`, `scene.rest_ke`, ….
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Settle {
    /// Steps of the fixed-time settle; with a rest criterion, the least settle before it is
    /// checked.
    pub settle_steps: u64,
    /// Translational kinetic energy of the powder below which it is at rest, J (0: fixed-time
    /// settle).
    pub rest_ke: f64,
    /// The rms speed that `rest_ke` stands for, m/s.
    pub rest_speed: f64,
    /// Steps between rest checks, and the most checks before the run fails.
    pub settle_check_steps: u64,
    pub settle_max_checks: u64,
}
