//! Time integration of one contact, step by step as LIGGGHTS 3.8 does it.
//!
//! Each step (LIGGGHTS `verlet.cpp` with `fix nve/sphere`, `src/fix_nve_sphere.cpp`):
//! half kick of v and ω (I = 0.4 m r²), drift of x, contact force from the new positions and
//! the half-step velocities, half kick. The force follows `surface_model_default.h` (relative
//! velocities), `normal_model_hertz.h` (normal force) and `tangential_model_history.h` (shear
//! history, Coulomb limit, torque); the wall contact follows `fix_wall_gran.cpp`
//! (`post_force_primitive`). This module integrates and records states; [`super::analysis`]
//! turns the record into an outcome.

use super::{Case, ContactError, Target};

/// A 3-vector in SI units.
pub type V3 = [f64; 3];

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(s: f64, a: V3) -> V3 {
    [s * a[0], s * a[1], s * a[2]]
}
/// a · b.
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// a × b.
pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
/// |a|.
pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// The kinematic state of the bodies at the end of a step. For a wall, body 2 stays at rest
/// at the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time since the start in s.
    pub t: f64,
    pub x1: V3,
    pub v1: V3,
    pub w1: V3,
    pub x2: V3,
    pub v2: V3,
    pub w2: V3,
}

/// The recorded run: the initial state, then one sample per step.
#[derive(Debug, Clone)]
pub struct Trajectory {
    pub samples: Vec<Sample>,
    /// Steps integrated.
    pub steps: usize,
}

#[derive(Debug, Clone, Copy)]
struct Body {
    x: V3,
    v: V3,
    w: V3,
    f: V3,
    torque: V3,
    radius: f64,
    mass: f64,
}

/// `fix_nve_sphere.cpp`: INERTIA = 0.4, I = 0.4 m r².
const INERTIA: f64 = 0.4;

impl Body {
    /// `FixNVESphere::initial_integrate`: v += dt/2 f/m; x += dt v; ω += dt/2 τ/I.
    fn initial_integrate(&mut self, dtf: f64, dtv: f64) {
        let dtfm = dtf / self.mass;
        self.v = add(self.v, scale(dtfm, self.f));
        self.x = add(self.x, scale(dtv, self.v));
        let dtirotate = dtf / INERTIA / (self.radius * self.radius * self.mass);
        self.w = add(self.w, scale(dtirotate, self.torque));
    }

    /// `FixNVESphere::final_integrate`: v += dt/2 f/m; ω += dt/2 τ/I.
    fn final_integrate(&mut self, dtf: f64) {
        let dtfm = dtf / self.mass;
        self.v = add(self.v, scale(dtfm, self.f));
        let dtirotate = dtf / INERTIA / (self.radius * self.radius * self.mass);
        self.w = add(self.w, scale(dtirotate, self.torque));
    }
}

/// The surfaces start this many (normal) steps apart, so contact begins within the first few
/// steps at a fraction of a step that depends on dt (no artificial alignment with the grid).
pub const GAP_STEPS: f64 = 2.5;

/// Initial state of sphere 1 and (for sphere–sphere) sphere 2 at timestep `dt`: sphere 1
/// above, surfaces [`GAP_STEPS`]·vn·dt apart; sphere–sphere in the centre-of-mass frame.
/// Returned as a [`Sample`] at t = 0 (the LIGGGHTS deck starts from the same numbers).
pub fn initial_state(case: &Case, dt: f64) -> Sample {
    let gap = GAP_STEPS * case.vn * dt;
    let vrel = [case.vt, 0.0, -case.vn];
    let w1 = [0.0, case.spin, 0.0];
    match case.sphere2() {
        None => Sample {
            t: 0.0,
            x1: [0.0, 0.0, case.radius + gap],
            v1: vrel,
            w1,
            x2: [0.0; 3],
            v2: [0.0; 3],
            w2: [0.0; 3],
        },
        Some((r2, m2)) => {
            let m1 = case.mass();
            Sample {
                t: 0.0,
                x1: [0.0, 0.0, case.radius + r2 + gap],
                v1: scale(m2 / (m1 + m2), vrel),
                w1,
                x2: [0.0; 3],
                v2: scale(-m1 / (m1 + m2), vrel),
                w2: [0.0; 3],
            }
        }
    }
}

/// The bodies, the shear history and the contact coefficients of one case, advanced one
/// velocity-Verlet step at a time. [`simulate`] drives it through one impact; a driver of many
/// impacts (`super::bounce`) steps it the same way, so there is one integrator.
#[derive(Debug, Clone)]
pub struct Integrator {
    pair: super::model::Pair,
    dt: f64,
    wall: bool,
    b1: Body,
    b2: Option<Body>,
    shear: V3,
    steps: usize,
}

impl Integrator {
    /// The bodies of `case` at [`initial_state`], at rest from forces, for timestep `dt`.
    pub fn new(case: &Case, dt: f64) -> Self {
        let s0 = initial_state(case, dt);
        let body = |x, v, w, radius, mass| Body { x, v, w, f: [0.0; 3], torque: [0.0; 3], radius, mass };
        Integrator {
            pair: case.pair(),
            dt,
            wall: matches!(case.target, Target::Wall(_)),
            b1: body(s0.x1, s0.v1, s0.w1, case.radius, case.mass()),
            b2: case.sphere2().map(|(radius, mass)| body(s0.x2, s0.v2, s0.w2, radius, mass)),
            shear: [0.0; 3],
            steps: 0,
        }
    }

    /// One step: half kick, drift, contact force, half kick. Returns whether the bodies touch.
    pub fn step(&mut self) -> bool {
        let (dtf, dtv) = (0.5 * self.dt, self.dt);
        self.b1.initial_integrate(dtf, dtv);
        if let Some(b2) = self.b2.as_mut() {
            b2.initial_integrate(dtf, dtv);
        }
        let in_contact =
            contact_force(&self.pair, self.dt, self.wall, &mut self.b1, self.b2.as_mut(), &mut self.shear);
        self.b1.final_integrate(dtf);
        if let Some(b2) = self.b2.as_mut() {
            b2.final_integrate(dtf);
        }
        self.steps += 1;
        in_contact
    }

    /// The state after the last step (t = steps·dt).
    pub fn sample(&self) -> Sample {
        let b1 = &self.b1;
        let (x2, v2, w2) = self.b2.map_or(([0.0; 3], [0.0; 3], [0.0; 3]), |b| (b.x, b.v, b.w));
        Sample { t: self.steps as f64 * self.dt, x1: b1.x, v1: b1.v, w1: b1.w, x2, v2, w2 }
    }

    /// Steps taken so far.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Replaces positions, velocities and spins by those of `s` (its time is ignored). Only
    /// valid while the bodies are apart: the forces of the last step are kept, and apart they
    /// are zero, so the next half kick is the one the new state would have had.
    pub fn set_state(&mut self, s: &Sample) {
        debug_assert!(self.b1.f == [0.0; 3] && self.b1.torque == [0.0; 3], "set_state in contact");
        (self.b1.x, self.b1.v, self.b1.w) = (s.x1, s.v1, s.w1);
        if let Some(b2) = self.b2.as_mut() {
            (b2.x, b2.v, b2.w) = (s.x2, s.v2, s.w2);
        }
    }
}

/// Integrates `case` at timestep `dt` from [`initial_state`] until the bodies have separated
/// after contact (one sample past separation).
pub fn simulate(case: &Case, dt: f64) -> Result<Trajectory, ContactError> {
    let mut integrator = Integrator::new(case, dt);
    let mut samples = vec![integrator.sample()];
    let mut touched = false;
    // Free flight to contact plus a contact (the elastic Hertz time is the longest) with room.
    let max_steps = max_steps_per_impact(case, dt);
    for step in 1..=max_steps {
        let in_contact = integrator.step();
        samples.push(integrator.sample());
        touched |= in_contact;
        if touched && !in_contact {
            return Ok(Trajectory { samples, steps: step });
        }
    }
    Err(ContactError::NoSeparation { steps: max_steps, dt })
}

/// The most steps one impact may take: ten elastic Hertz times plus 1000 steps of approach.
pub fn max_steps_per_impact(case: &Case, dt: f64) -> usize {
    (10.0 * case.pair().hertz_time(case.vn) / dt) as usize + 1000
}

/// Sets the contact force and torques on the bodies (zero when apart) and updates the shear
/// history; returns whether they touch.
fn contact_force(
    pair: &super::model::Pair,
    dt: f64,
    wall: bool,
    b1: &mut Body,
    b2: Option<&mut Body>,
    shear: &mut V3,
) -> bool {
    // Wall (`fix_wall_gran.cpp`): delta runs from the wall's nearest point to the centre,
    // contact when the distance ≤ r. Pair (`pair_gran.cpp`): delta = xi − xj, contact when
    // |delta| < ri + rj.
    let (delta, radsum, v2, w2, r2) = match &b2 {
        None => ([0.0, 0.0, b1.x[2]], b1.radius, [0.0; 3], [0.0; 3], 0.0),
        Some(b2) => (sub(b1.x, b2.x), b1.radius + b2.radius, b2.v, b2.w, b2.radius),
    };
    let r = norm(delta);
    let touching = if wall { r <= radsum } else { r < radsum };
    b1.f = [0.0; 3];
    b1.torque = [0.0; 3];
    if !touching {
        // `tangential_model_history.h` surfacesClose: the history is reset on separation.
        *shear = [0.0; 3];
        if let Some(b2) = b2 {
            b2.f = [0.0; 3];
            b2.torque = [0.0; 3];
        }
        return false;
    }
    let rinv = 1.0 / r;
    let en = scale(rinv, delta);
    let deltan = radsum - r;

    // `surface_model_default.h`: relative velocity, its normal and tangential parts, and the
    // tangential velocity of the contact points including rotation, with lever arms
    // cr = r − δn/2: vtr = vt + delta × (cri ωi + crj ωj)/|delta|.
    let vr = sub(b1.v, v2);
    let vn = dot(vr, en);
    let vt = sub(vr, scale(vn, en));
    let cri = b1.radius - 0.5 * deltan;
    let crj = r2 - 0.5 * deltan;
    let wr = scale(rinv, add(scale(cri, b1.w), scale(crj, w2)));
    let vtr = add(vt, cross(delta, wr));

    // `normal_model_hertz.h`: Fn = kn δn − γn vn (vn < 0 approaching); limitForce off, so Fn
    // may turn slightly negative at the end of the contact.
    let k = pair.at(deltan);
    let fn_ = k.kn * deltan - k.gamma_n * vn;

    // `tangential_model_history.h`: integrate the shear, project out its normal part
    // (its magnitude is not preserved), Ft = −kt·shear with the current kt; above the Coulomb
    // limit μ|Fn| scale Ft to the limit and reset the shear to −Ft/kt without tangential
    // damping; below it add the damping −γt vtr (outside the Coulomb check).
    *shear = add(*shear, scale(dt, vtr));
    let rsht = dot(*shear, en);
    *shear = sub(*shear, scale(rsht, en));
    let shrmag = norm(*shear);
    let mut ft = scale(-k.kt, *shear);
    let ft_shear = k.kt * shrmag;
    let ft_friction = pair.friction * fn_.abs();
    if ft_shear > ft_friction {
        if shrmag != 0.0 {
            ft = scale(ft_friction / ft_shear, ft);
            *shear = scale(-1.0 / k.kt, ft);
        } else {
            ft = [0.0; 3];
        }
    } else {
        ft = sub(ft, scale(k.gamma_t, vtr));
    }

    // Torque on body i: −cri (en × Ft); on body j: −crj (en × Ft) (the force on j is −Ft at
    // lever arm +crj en).
    let tor = cross(en, ft);
    let f1 = add(scale(fn_, en), ft);
    b1.f = f1;
    b1.torque = scale(-cri, tor);
    if let Some(b2) = b2 {
        b2.f = scale(-1.0, f1);
        b2.torque = scale(-crj, tor);
    }
    true
}
