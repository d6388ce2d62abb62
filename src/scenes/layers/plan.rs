//! The plan of a layers point: every number its deck and its measure need — the well, the
//! dose, the blade's passes and their steps — derived from the point's common part and the
//! layout's settings, and the deck of one pass of a point run by the pass.

use serde::{Deserialize, Serialize};

use super::settings::own;
use super::{
    dose_factor, fused, least_passes, search_passes, DOSE_FRACTION, DOSE_REST_SHARE, EXTEND_ROOM,
    FEED_OVER_PLATE, MAX_DOSE_SPEED, PIT_DIAMETERS, RAMP_DIAMETERS, ROUND_ARC_SHARE, SEARCH_MAX_DEPTH_LAYERS,
    SEARCH_MAX_GROWTH, SETTLE_CHECKS,
};
use crate::scene::blade::Blade;
use crate::scene::own::LayoutData;
use crate::scene::settings::SceneSettings;
use crate::scene::{
    prime_seed, Base, Feed, FeedClass, Scene, GRAVITY, LAYER_FRACTION_MAX, MIN_INSERT_VOLUME,
};
use crate::scenes::moving_blade::{self, Dose};

fn default_roller_segments() -> usize {
    super::settings::DEFAULT_ROLLER_SEGMENTS
}

/// One pass of the blade, as the deck runs it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pass {
    /// From 1.
    pub k: usize,
    /// Height of the machine's top surface — the feed platform and the wall — over the plate, m.
    pub top: f64,
    /// Height of the blade's tip over the plate, m.
    pub tip: f64,
    /// Prime seed of this pass's dose.
    pub seed: u64,
}

/// The layers layout's own numbers (`scene.own`). Lengths in m.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub fused: bool,
    pub layer_thickness: f64,
    /// Fused bed: the first passes that search for the steady depth (not layers on the one
    /// before), and the deepest powder under the tip they may ask for.
    #[serde(default)]
    pub search_passes: usize,
    #[serde(default)]
    pub search_max_depth: f64,
    /// Least deposit a search pass counts (a pass that left almost nothing multiplies the depth
    /// by at most [`SEARCH_MAX_GROWTH`]).
    #[serde(default)]
    pub search_least_deposit: f64,
    /// The blade's tip over the plate's k drops (the first layer is a drop and this deep).
    pub clearance: f64,
    /// The blade's tip over the feed platform and the wall: the clearance, but a round blade's
    /// at least the largest diameter ([`platform_gap`]).
    #[serde(default)]
    pub platform_gap: f64,
    pub plate_x0: f64,
    pub plate_x1: f64,
    /// Plate area (length × depth), m².
    pub plate_area: f64,
    /// The feed platform's back end (its top runs from here to `plate_x0`).
    pub feed_x0: f64,
    /// How far the feed platform's and the wall's faces reach below their top: past the plate
    /// at the last pass.
    pub block_depth: f64,
    /// The round blade's or the roller's radius (0: flat).
    pub blade_radius: f64,
    /// The blade is a roller: a whole cylinder, turned about its axis as it travels.
    #[serde(default)]
    pub roller: bool,
    /// The roller's surface speed about its axis over its travel speed (counter-rotation
    /// positive: its lowest line runs ahead of its axis), and its angular velocity about +y per
    /// unit travel speed, −ratio / radius (rad/m); 0 for a blade.
    #[serde(default)]
    pub roller_speed_ratio: f64,
    #[serde(default)]
    pub roller_spin: f64,
    /// Segments of the roller's circle (`scene.roller_segments`).
    #[serde(default = "default_roller_segments")]
    pub roller_segments: usize,
    /// A round blade's arc (not a roller's): how high over its lowest line it reaches and how
    /// far ahead of it there (0 for a flat blade or a roller). A laid dose's pass starts the blade
    /// where the arc clears the dose's top (`laid_dose`).
    #[serde(default)]
    pub arc_height: f64,
    #[serde(default)]
    pub arc_ahead: f64,
    /// x of the blade's lowest line at the start (flat: its rear face), and its travel in a pass.
    pub tip_x0: f64,
    pub travel: f64,
    /// The dose's insertion region above the top surface.
    pub dose_x0: f64,
    pub dose_x1: f64,
    pub dose_lift: f64,
    pub dose_height: f64,
    /// The first dose's region height: it fills the clearance too.
    pub first_dose_height: f64,
    pub dose_fraction: f64,
    /// Downward speed the dose is inserted at, m/s (0 unless it is sparse).
    pub dose_speed: f64,
    pub dose_particles: usize,
    /// Most steps of the first dose's fall before the first pass.
    pub fall_steps: u64,
    /// Steps of a pass until the blade has cleared the feed platform (the next dose goes in).
    pub clear_steps: u64,
    /// Steps of the blade's whole pass, the rest after it, and the most wait for the rest of the
    /// next dose's fall before the next pass.
    pub pass_steps: u64,
    pub rest_steps: u64,
    pub wait_steps: u64,
    /// The blade starts once the dose and the bed are at rest: their rms speeds under
    /// `rest_speed` (m/s), checked every `settle_check_steps`, at most `fall_checks` times before
    /// the first pass and `wait_checks` before each later one (the fall and the wait above).
    #[serde(default)]
    pub rest_speed: f64,
    #[serde(default)]
    pub settle_check_steps: u64,
    #[serde(default)]
    pub fall_checks: u64,
    #[serde(default)]
    pub wait_checks: u64,
    /// Every pass the machine is built for: its box and its faces reach the last of them, so
    /// that `sweep extend` can add passes up to it ([`EXTEND_ROOM`] times the most).
    pub passes: Vec<Pass>,
    /// The most passes a point runs (`scene.layers`); 0 in a plan read from an older result: all.
    #[serde(default)]
    pub most_passes: usize,
    /// The passes this deck runs, from 1: every pass in the deck `sweep render` writes, one in
    /// a point's run by the pass.
    #[serde(default = "first")]
    pub first_pass: usize,
    #[serde(default)]
    pub last_pass: usize,
    /// A deck of a point's run by the pass: each pass readies the next one's dose and lift,
    /// whether or not the point runs it.
    #[serde(default)]
    pub by_pass: bool,
    /// The state the deck's first pass goes on from, if it is not the first.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resume: Option<Resume>,
    /// The fewest passes before the point may stop on its steady layer (the most: `passes`).
    #[serde(default)]
    pub least_passes: usize,
    /// A fused bed warm-started from a finished neighbour: the solid's top under the first pass
    /// (its depth of powder the neighbour's steady one), m; cold, the plate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_floor: Option<f64>,
    /// Loose bed: the bed deeper than this under a pass's top surface is held still and not
    /// searched against itself, m (0: none).
    #[serde(default)]
    pub freeze_depth: f64,
    /// Loose bed held still: the bed deeper than this under a pass's top surface is removed at
    /// the pass's end, its mass counted on the plate by the measure, m (0: none). It lies
    /// [`BURY_SKIN_DIAMETERS`] largest diameters under the held bed's top, out of reach of every
    /// particle that moves.
    #[serde(default)]
    pub bury_depth: f64,
    /// From the third pass on, every dose is pass 2's as it lay at rest, laid again (read from
    /// [`super::laid::LAID_DOSE`]) instead of inserted to fall.
    #[serde(default)]
    pub laid_dose: bool,
    pub feed: Vec<FeedClass>,
    pub volume_limit: f64,
    pub distribution_seed: u64,
}

fn first() -> usize {
    1
}

/// Where a pass goes on from: the restart the last pass wrote, and on a fused bed the solid's
/// top it left (m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Resume {
    pub restart: String,
    pub solid: f64,
}

impl Plan {
    /// Most steps of the whole run: the first dose's fall, then each pass with its rest and wait.
    pub fn total_steps(&self) -> u64 {
        let n = self.most() as u64;
        self.fall_steps + n * (self.pass_steps + self.rest_steps) + n.saturating_sub(1) * self.wait_steps
    }

    /// The most passes a point runs.
    pub fn most(&self) -> usize {
        if self.most_passes == 0 {
            self.passes.len()
        } else {
            self.most_passes
        }
    }

    /// The last pass this deck runs (a plan read from an older result runs every pass).
    pub fn reached(&self) -> usize {
        if self.last_pass == 0 {
            self.most()
        } else {
            self.last_pass
        }
    }

    /// The largest diameter of the powder it doses.
    pub fn max_diameter(&self) -> f64 {
        self.feed.iter().map(|c| c.diameter).fold(0.0, f64::max)
    }

    /// The platform's drop before pass `k` (from 1): the first includes the clearance.
    pub fn drop_before(&self, k: usize) -> f64 {
        if k == 1 {
            self.layer_thickness + self.clearance
        } else {
            self.layer_thickness
        }
    }
}

/// The blade's tip over the feed platform and the wall. A round blade's arc closes on a flat
/// face in a wedge: with less than the largest diameter under its tip it grinds the powder on the
/// feed platform into the face, and a soft powder is pressed through it (measured at
/// Ti-6Al-4V 15–45 µm with no clearance: 29 particles inside the platform after the first pass,
/// 65 after the second, thrown out at up to 10 m/s, and the neighbour lists rebuilt every 10
/// steps for 1.7 × the crossing's CPU; docs/study/layers.md "The platform gap"). So it rides at
/// least that high over both; a flat blade meets the powder with its vertical face and keeps the
/// clearance.
pub fn platform_gap(blade_radius: f64, clearance: f64, d_max: f64) -> f64 {
    if blade_radius > 0.0 {
        clearance.max(d_max)
    } else {
        clearance
    }
}

/// The layers layout's part of the scene: its blade and its plan (`own`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Passes {
    #[serde(flatten)]
    pub blade: Blade,
    /// The deck's `scene.own.*`.
    #[serde(rename = "own")]
    pub plan: Plan,
}

impl LayoutData for Passes {
    fn steps(&self) -> u64 {
        self.plan.total_steps()
    }
    fn blade(&self) -> Option<&Blade> {
        Some(&self.blade)
    }
}

/// Largest diameters of held bed kept under the moving powder when the bed below is removed:
/// a contact reaches at most one, and the second keeps a particle that settles into the held
/// bed's top off the removed bed.
pub const BURY_SKIN_DIAMETERS: f64 = 2.0;

/// The part of a layers scene.
pub fn part(scene: &Scene) -> &Passes {
    scene.own().expect("a layers scene carries its passes")
}

/// `scene` carrying `plan`.
pub(super) fn with_plan(scene: &Scene, plan: Plan) -> Scene {
    let mut s = scene.clone();
    s.own_mut::<Passes>().expect("a layers scene carries its passes").plan = plan;
    s
}

/// The plan a scene of this layout carries.
pub fn plan_of(scene: &Scene) -> Plan {
    part(scene).plan.clone()
}

/// The scene of a layers point: the moving blade's common numbers, then the well, the dose and
/// the passes.
pub(super) fn derive(base: Base, settings: &SceneSettings) -> Scene {
    let t = base.layer_thickness;
    let clearance = own(settings).blade_clearance_mm * 1e-3;
    let mut s = moving_blade::derive(base.clone(), settings, Dose::Free);
    let mut blade = moving_blade::spread(&s).spreader.blade.clone();
    let Base { psd, d, speed: v, timestep: dt, .. } = base;
    let fused = fused(settings);
    let layers = own(settings).layers.max(1);
    let plate_len = own(settings).plate_diameters.max(10.0) * d;
    let feed_len = FEED_OVER_PLATE * plate_len;
    let roller = own(settings).blade_profile == "roller";
    let radius = if roller || own(settings).blade_profile == "round" {
        own(settings).blade_radius_mm * 1e-3
    } else {
        0.0
    };
    let roller_speed_ratio = if roller { base.roller_speed_ratio } else { 0.0 };
    // The blade's x extent about its lowest line: behind and ahead of it.
    let (behind, ahead) = if roller {
        (radius, radius)
    } else if radius > 0.0 {
        let half = radius * (0.5 * ROUND_ARC_SHARE * std::f64::consts::PI).sin();
        (half, half)
    } else {
        (0.0, d)
    };
    let d_max = psd.max_diameter();
    let freeze_depth = if fused { 0.0 } else { own(settings).freeze_depth_diameters * d };
    let platform_gap = platform_gap(radius, clearance, d_max);
    let tip_x0 = 0.5 * d + behind + d;
    let front0 = tip_x0 + ahead;
    let dose_x0 = front0 + 0.5 * d;
    let plate_x0 = dose_x0 + feed_len + d;
    let plate_x1 = plate_x0 + plate_len;
    // The tip runs past the plate's end by two diameters: everything ahead of it is in the pit.
    // A roller runs on until all of it is past the plate: a turning roller carries cohesive
    // powder up its front and over its top, which fell onto the plate when it was taken away
    // over it (measured at Ti-6Al-4V 15–45 µm, ratio 4: 8–14 particles 4.7–6.1 mm over a 0.5 mm
    // plate, the layer's roughness 60 D; docs/study/roller.md). Now that powder falls in the pit.
    let past = if roller { behind } else { 0.0 };
    let travel = plate_x1 + 2.0 * d + past - tip_x0;
    let x_hi = plate_x1 + 2.0 * d + past + ahead + PIT_DIAMETERS * d;

    let dose_x1 = plate_x0 - d;
    // Every dose is dose_factor layers of the drop; the first fills the drop and the clearance.
    // LIGGGHTS refuses to insert into a region under its floor once shrunk by the largest
    // diameter (MIN_INSERT_VOLUME): a fine powder in thin layers gets its dose inserted sparser
    // in a taller region at the same depth, not a wider box (which would multiply the particles
    // of every layer).
    let w = s.depth;
    let dose_for = |drop: f64| {
        dose_factor(settings) * settings.supply_factor * plate_len * drop * LAYER_FRACTION_MAX * w
    };
    let dose_len = dose_x1 - dose_x0;
    let (dose_solid, first_solid) = (dose_for(t), dose_for(t + clearance));
    let shrunk_area = (dose_len - d_max) * (w - d_max);
    let dose_fraction = DOSE_FRACTION.min(dose_solid / (dose_len * w) * shrunk_area / MIN_INSERT_VOLUME);
    let dose_particles = (dose_solid / psd.mean_volume()).ceil() as usize;
    let region_height = |solid: f64, fraction: f64| solid / (fraction * dose_len * w) + d_max;
    let (dose_height, first_dose_height) =
        (region_height(dose_solid, dose_fraction), region_height(first_solid, dose_fraction));
    let dose_lift = 0.5 * d;
    // The box and the machine's faces reach the last pass `sweep extend` may add.
    let room = EXTEND_ROOM * layers;
    let last_top = room as f64 * t;
    // A search may set the solid below the plate (the depth it asks for deeper than the layers so
    // far): the feed platform's and the wall's faces reach that far down too.
    let search_passes = search_passes(settings);
    let search_max_depth = if search_passes > 0 { SEARCH_MAX_DEPTH_LAYERS * t } else { 0.0 };
    let block_depth = last_top + clearance + 2.0 * d + search_max_depth;
    // The pit holds a pass's excess dose below the plate.
    let pit_depth = 10.0 * d + first_solid / (LAYER_FRACTION_MAX * PIT_DIAMETERS * d * w);
    // The blade stands above the first dose as it would lie at DOSE_FRACTION (a sparse dose
    // falls in front of it and settles lower).
    let blade_height = (dose_lift + region_height(first_solid, DOSE_FRACTION) + 2.0 * d).max(if roller {
        2.0 * radius + d
    } else {
        radius * (1.0 - (0.5 * ROUND_ARC_SHARE * std::f64::consts::PI).cos()) + 2.0 * d
    });
    let z_top = last_top + clearance + blade_height.max(dose_lift + first_dose_height) + 2.0 * d;

    let steps = |time: f64| ((time / dt).ceil() as u64).max(1);
    // The dose falls from the top of its region, and as long again to come down in a heap. The
    // first dose falls before the first pass; every later one is inserted as soon as the blade
    // has cleared the feed platform, and falls while the blade crosses the plate (what is left
    // of its fall is waited for before the next pass).
    // A sparse dose is thrown down so that it lands in about the time the dense one falls (at
    // most at MAX_DOSE_SPEED): its tall region would otherwise take longer to fall than a pass.
    let dense_height = dose_lift + region_height(dose_solid, DOSE_FRACTION);
    let dense_fall = (2.0 * dense_height / GRAVITY).sqrt();
    let dose_speed = ((dose_lift + dose_height - dense_height).max(0.0) / dense_fall).min(MAX_DOSE_SPEED);
    let fall = |height: f64| {
        let h = dose_lift + height;
        steps(2.0 * ((dose_speed * dose_speed + 2.0 * GRAVITY * h).sqrt() - dose_speed) / GRAVITY)
    };
    let (fall_steps, later_fall_steps) = (fall(first_dose_height), fall(dose_height));
    let ramp_time = 2.0 * RAMP_DIAMETERS * d / v;
    let ramp_steps = steps(ramp_time);
    let pass_steps = steps(travel / v + 0.5 * ramp_time);
    let clear_travel = (plate_x0 - (tip_x0 - behind)).min(travel);
    let clear_steps = steps(clear_travel / v + 0.5 * ramp_time).min(pass_steps);
    let rest_steps = steps((2.0 * 10.0 * d / GRAVITY).sqrt());
    let wait_steps = later_fall_steps.saturating_sub(pass_steps - clear_steps + rest_steps);
    // The fall and the wait above are the most: the blade starts as soon as the dose has landed
    // and it and the bed are at rest for the blade — their rms speeds a hundredth of its own
    // (DOSE_REST_SHARE) — checked SETTLE_CHECKS times a fall.
    let rest_speed = DOSE_REST_SHARE * v;
    let settle_check_steps = later_fall_steps.div_ceil(SETTLE_CHECKS);
    let (fall_checks, wait_checks) =
        (fall_steps.div_ceil(settle_check_steps), wait_steps.div_ceil(settle_check_steps));
    let cycle = pass_steps + rest_steps + wait_steps;
    let passes = (1..=room)
        .map(|k| {
            let tip = k as f64 * t + clearance;
            Pass { k, top: tip - platform_gap, tip, seed: prime_seed(settings.seed, 100 + k) }
        })
        .collect();
    let Feed { classes: feed, volume_limit } = Feed::of(&psd, settings.seed);
    let plan = Plan {
        fused,
        layer_thickness: t,
        search_passes,
        search_max_depth,
        search_least_deposit: t / SEARCH_MAX_GROWTH,
        clearance,
        platform_gap,
        plate_x0,
        plate_x1,
        plate_area: plate_len * w,
        feed_x0: 0.5 * d,
        block_depth,
        blade_radius: radius,
        roller,
        roller_speed_ratio,
        roller_spin: if roller { -roller_speed_ratio / radius } else { 0.0 },
        roller_segments: own(settings).roller_segments,
        arc_height: if radius > 0.0 && !roller {
            radius * (1.0 - (0.5 * ROUND_ARC_SHARE * std::f64::consts::PI).cos())
        } else {
            0.0
        },
        arc_ahead: if radius > 0.0 && !roller { ahead } else { 0.0 },
        tip_x0,
        travel,
        dose_x0,
        dose_x1,
        dose_lift,
        dose_height,
        first_dose_height,
        dose_fraction,
        dose_speed,
        dose_particles,
        fall_steps,
        clear_steps,
        pass_steps,
        rest_steps,
        wait_steps,
        rest_speed,
        settle_check_steps,
        fall_checks,
        wait_checks,
        first_pass: 1,
        most_passes: layers,
        last_pass: layers,
        by_pass: false,
        resume: None,
        least_passes: least_passes(settings),
        first_floor: None,
        freeze_depth,
        bury_depth: if freeze_depth > 0.0 { freeze_depth + BURY_SKIN_DIAMETERS * d_max } else { 0.0 },
        passes,
        laid_dose: own(settings).laid_dose,
        feed,
        volume_limit,
        distribution_seed: prime_seed(settings.seed, 0),
    };

    let mass = (first_solid / psd.mean_volume() + dose_particles as f64 * layers as f64)
        * s.material.density
        * psd.mean_volume();
    // A turning roller's surface runs at |ratio| × v about its axis: what it throws may be that fast.
    let v_ref = v.max((1.0 + roller_speed_ratio.abs()) * v).max((2.0 * GRAVITY * z_top).sqrt());
    blade.gap = t + clearance;
    s.particles = dose_particles * layers;
    blade.blade_x0 = tip_x0;
    blade.blade_thickness = if radius > 0.0 { 0.0 } else { d };
    blade.blade_top = blade_height;
    s.x_hi = x_hi;
    // The feed platform's and the wall's faces reach block_depth under their top, which stands
    // lower than the plate's drops where the platform gap exceeds the clearance.
    s.z_lo = -(block_depth.max(pit_depth) + d + (platform_gap - clearance));
    s.z_hi = z_top + v * v / GRAVITY;
    blade.ramp_steps = ramp_steps;
    s.thermo_every = (cycle / 20).clamp(1, 1000);
    s.ke_limit = 0.5 * mass * (10.0 * v_ref).powi(2);
    s.set_own(Passes { blade, plan });
    s
}
