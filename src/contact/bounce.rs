//! Many consecutive impacts: a sphere bouncing between two parallel walls, no gravity.
//!
//! The box is the sphere's diameter plus a clearance of 2 × [`GAP_STEPS`] approach steps high,
//! so the sphere starts in its middle (as [`initial_state`] places it) and flies
//! [`GAP_STEPS`] steps each way between contacts. The integrator knows one wall, at z = 0; the
//! top wall is reached through the box's symmetry: right after each separation the state is
//! turned by π about the x axis through the box's mid-height, which maps the top wall onto the
//! bottom one. That is exact (the bodies are apart, so no force or history is involved) and
//! keeps one contact law and one integrator, [`Integrator`].
//!
//! This module drives the impacts and records the kinetic energy after each; it does not judge
//! them (`super::stability` does).

use super::analysis::centres_crossed;
use super::solver::{dot, initial_state, max_steps_per_impact, Integrator, Sample, GAP_STEPS};
use super::{Case, ContactError, Target};

/// The kinetic energy after each of `contacts` consecutive impacts (J), and the state after the
/// last one.
#[derive(Debug, Clone)]
pub struct Bounces {
    /// Kinetic energy (translation and rotation) before the first impact, J.
    pub initial_energy: f64,
    /// Kinetic energy after impact k (k = 0..contacts), J.
    pub energy: Vec<f64>,
    /// The state one step after the last separation (in the frame of the wall last hit).
    pub last: Sample,
    /// Integration steps over all impacts.
    pub steps: usize,
}

/// Translational plus rotational kinetic energy of sphere 1 (I = 0.4 m r²), J.
pub fn kinetic_energy(case: &Case, s: &Sample) -> f64 {
    let m = case.mass();
    0.5 * m * dot(s.v1, s.v1) + 0.5 * 0.4 * m * case.radius * case.radius * dot(s.w1, s.w1)
}

/// Runs `contacts` consecutive impacts of a sphere–wall `case` at timestep `dt` in the box
/// described above.
pub fn bounce(case: &Case, dt: f64, contacts: usize) -> Result<Bounces, ContactError> {
    case.validate()?;
    if !matches!(case.target, Target::Wall(_)) {
        return Err(ContactError::Unsupported("repeated impacts need a sphere-wall case"));
    }
    let s0 = initial_state(case, dt);
    // The box: walls at z = 0 and z = 2 r + 2 GAP_STEPS vn dt; mid-height h.
    let mid = case.radius + GAP_STEPS * case.vn * dt;
    let max_steps = max_steps_per_impact(case, dt);
    let mut integrator = Integrator::new(case, dt);
    let mut energy = Vec::with_capacity(contacts);
    for _ in 0..contacts {
        let start = integrator.steps();
        let mut touched = false;
        loop {
            let in_contact = integrator.step();
            touched |= in_contact;
            if touched && !in_contact {
                break;
            }
            if integrator.steps() - start >= max_steps {
                return Err(ContactError::NoSeparation { steps: max_steps, dt });
            }
        }
        let s = integrator.sample();
        if centres_crossed(case, &s) {
            return Err(case.passed_through());
        }
        energy.push(kinetic_energy(case, &s));
        integrator.set_state(&turn_over(&s, mid));
    }
    Ok(Bounces {
        initial_energy: kinetic_energy(case, &s0),
        energy,
        last: integrator.sample(),
        steps: integrator.steps(),
    })
}

/// Rotation by π about the x axis through (0, 0, `mid`): (x, y, z) → (x, −y, 2 mid − z) for the
/// position; (a, b, c) → (a, −b, −c) for velocity and spin (a proper rotation, so the spin
/// pseudovector turns like a vector).
fn turn_over(s: &Sample, mid: f64) -> Sample {
    let turn = |v: [f64; 3]| [v[0], -v[1], -v[2]];
    Sample { x1: [s.x1[0], -s.x1[1], 2.0 * mid - s.x1[2]], v1: turn(s.v1), w1: turn(s.w1), ..*s }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::Material;

    fn case(friction: f64, vt: f64, spin: f64) -> Case {
        let m = Material { youngs: 21e6, poisson: 0.3 };
        Case {
            target: Target::Wall(m),
            radius: 1e-3,
            density: 7980.0,
            material: m,
            restitution: 1.0,
            friction,
            vn: 1.0,
            vt,
            spin,
            dt: None,
        }
    }

    #[test]
    fn turning_over_twice_is_the_identity_and_keeps_the_energy() {
        let c = case(0.0, 0.3, 50.0);
        let s = Sample {
            x1: [0.1, 0.2, 1.3e-3],
            v1: [0.3, 0.1, 0.9],
            w1: [1.0, 50.0, -2.0],
            ..initial_state(&c, 1e-7)
        };
        let once = turn_over(&s, 1.1e-3);
        assert_eq!(once.v1[2], -0.9);
        assert!((once.x1[2] - 0.9e-3).abs() < 1e-15);
        assert_eq!(kinetic_energy(&c, &once), kinetic_energy(&c, &s));
        let twice = turn_over(&once, 1.1e-3);
        assert_eq!((twice.v1, twice.w1, twice.x1[..2].to_vec()), (s.v1, s.w1, s.x1[..2].to_vec()));
        assert!((twice.x1[2] - s.x1[2]).abs() < 1e-18);
    }

    #[test]
    fn each_impact_comes_back_to_the_wall_with_the_approach_speed() {
        // Frictionless: vt and spin never change; vn comes back downward every time.
        let c = case(0.0, 0.4, 120.0);
        let dt = c.timestep();
        let b = bounce(&c, dt, 5).unwrap();
        assert_eq!(b.energy.len(), 5);
        assert!(b.last.v1[2] < 0.0 && (b.last.v1[2] + 1.0).abs() < 1e-6, "{:?}", b.last);
        assert_eq!(b.last.v1[0], 0.4);
        // Five contacts of ~1000 steps each and five steps of flight between them.
        assert!((5000..5600).contains(&b.steps), "{}", b.steps);
    }

    #[test]
    fn a_sphere_pair_is_refused() {
        let c = Case { target: Target::Sphere { radius: 1e-3, density: 7980.0 }, ..case(0.0, 0.0, 0.0) };
        assert!(matches!(bounce(&c, 1e-7, 1), Err(ContactError::Unsupported(_))));
    }
}
