//! From a recorded impact (states per step) to the verification quantities.
//!
//! The same code reads the reference solver's trajectory and the LIGGGHTS one, so the two are
//! compared on identical definitions. It does not integrate anything.
//!
//! Definitions (u = relative velocity of the contact points, sphere 1 minus body 2; n = +z):
//! - `contact_time`: between the zero crossings of the overlap δ = r1 + r2 − |x1 − x2|
//!   (wall: r1 − z1), each linearly interpolated between the two samples around it.
//! - `max_overlap`: the vertex of the parabola through the largest sample and its neighbours.
//! - `restitution_n` = −u_n,out / u_n,in.
//! - `restitution_t` = −u_t,out · t̂ / |u_t,in| (Foerster et al. 1994, Am. J. Phys. 62, 76),
//!   t̂ = u_t,in/|u_t,in|, u_t = v_t + n × (cr1 ω1 + cr2 ω2), cr = r − δ/2 in contact (as
//!   LIGGGHTS) and r apart. −1 for a frictionless contact, 0 when the slip is just arrested.
//!   `None` when there is no initial slip.
//! - `regime`: `normal` without initial slip; `slide` when the slip keeps its initial direction
//!   in every sample in contact (rigid-body theory's "sliding throughout"); `stick` otherwise.
//! - "in" is the first sample, "out" the first sample after separation.
//! - `omega_out`: sphere 1's ω_y after the impact (`omega2_out` sphere 2's).

use serde::Serialize;

use super::solver::{cross, dot, norm, Sample, V3};
use super::{Case, ContactError};

/// Slip or no slip over the contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Regime {
    /// No tangential slip velocity at impact.
    Normal,
    /// The slip was arrested (or reversed) during the contact.
    Stick,
    /// The contact slid throughout.
    Slide,
}

impl Regime {
    pub fn as_str(self) -> &'static str {
        match self {
            Regime::Normal => "normal",
            Regime::Stick => "stick",
            Regime::Slide => "slide",
        }
    }
}

/// The outcome of one impact, SI units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Outcome {
    /// Contact duration in s.
    pub contact_time: f64,
    /// Maximum normal overlap in m.
    pub max_overlap: f64,
    /// Achieved normal restitution (dimensionless).
    pub restitution_n: f64,
    /// Tangential restitution of the contact-point slip; `None` without initial slip.
    pub restitution_t: Option<f64>,
    /// Sphere 1's angular velocity about +y after the impact, rad/s.
    pub omega_out: f64,
    /// Sphere 2's angular velocity about +y after the impact, rad/s (sphere–sphere only).
    pub omega2_out: Option<f64>,
    pub regime: Regime,
    /// Integration steps used.
    pub steps: usize,
    /// Timestep in s.
    pub dt: f64,
}

/// A slip smaller than this fraction of the approach speed counts as none.
const NO_SLIP: f64 = 1e-12;

struct Contact {
    overlap: f64,
    /// Relative normal velocity u_n (negative approaching).
    un: f64,
    /// Tangential slip velocity u_t of the contact points.
    ut: V3,
}

fn contact(case: &Case, s: &Sample) -> Contact {
    let r2 = case.sphere2().map_or(0.0, |(r2, _)| r2);
    let delta = match case.sphere2() {
        None => [0.0, 0.0, s.x1[2]],
        Some(_) => [s.x1[0] - s.x2[0], s.x1[1] - s.x2[1], s.x1[2] - s.x2[2]],
    };
    let r = norm(delta);
    let overlap = case.radius + r2 - r;
    let normal = [delta[0] / r, delta[1] / r, delta[2] / r];
    let half = 0.5 * overlap.max(0.0);
    let (cr1, cr2) = (case.radius - half, r2 - half);
    let vr = [s.v1[0] - s.v2[0], s.v1[1] - s.v2[1], s.v1[2] - s.v2[2]];
    let un = dot(vr, normal);
    let spin = [cr1 * s.w1[0] + cr2 * s.w2[0], cr1 * s.w1[1] + cr2 * s.w2[1], cr1 * s.w1[2] + cr2 * s.w2[2]];
    let rot = cross(normal, spin);
    let ut =
        [vr[0] - un * normal[0] + rot[0], vr[1] - un * normal[1] + rot[1], vr[2] - un * normal[2] + rot[2]];
    Contact { overlap, un, ut }
}

/// Whether sphere 1's centre is at or past the wall plane, or below sphere 2's centre (sphere 1
/// starts straight above it): in contact, the contact normal has turned over.
pub fn centres_crossed(case: &Case, s: &Sample) -> bool {
    match case.sphere2() {
        None => s.x1[2] <= 0.0,
        Some(_) => s.x1[2] - s.x2[2] <= 0.0,
    }
}

/// Time where the overlap crosses zero between samples a and b (linear interpolation).
fn crossing(a: (&Sample, f64), b: (&Sample, f64)) -> f64 {
    let (sa, da) = a;
    let (sb, db) = b;
    sa.t + (sb.t - sa.t) * (-da) / (db - da)
}

/// The outcome of the impact recorded in `samples` (first = before contact, last = after).
pub fn analyse(case: &Case, samples: &[Sample], steps: usize) -> Result<Outcome, ContactError> {
    let fail = |message: &str| ContactError::Analysis(message.to_string());
    let contacts: Vec<Contact> = samples.iter().map(|s| contact(case, s)).collect();
    // Only in contact: after a glancing impact two spheres may fly on past each other.
    if samples.iter().zip(&contacts).any(|(s, c)| c.overlap > 0.0 && centres_crossed(case, s)) {
        return Err(case.passed_through());
    }
    let first =
        contacts.iter().position(|c| c.overlap > 0.0).ok_or_else(|| fail("the bodies never touched"))?;
    if first == 0 {
        return Err(fail("the bodies touch in the first sample"));
    }
    let last = first
        + contacts[first..]
            .iter()
            .position(|c| c.overlap <= 0.0)
            .ok_or_else(|| fail("the bodies did not separate"))?
        - 1;
    let t_start = crossing(
        (&samples[first - 1], contacts[first - 1].overlap),
        (&samples[first], contacts[first].overlap),
    );
    let t_end =
        crossing((&samples[last], contacts[last].overlap), (&samples[last + 1], contacts[last + 1].overlap));

    let (k, _) = contacts[first..=last]
        .iter()
        .enumerate()
        .map(|(i, c)| (first + i, c.overlap))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("at least one sample in contact");
    let max_overlap = parabola_vertex(contacts[k - 1].overlap, contacts[k].overlap, contacts[k + 1].overlap);

    // "Out" is the first sample after separation: later the normal of two spheres that slid
    // past each other is no longer the contact normal.
    let (c_in, c_out) = (&contacts[0], &contacts[last + 1]);
    let s_out = &samples[last + 1];
    let restitution_n = -c_out.un / c_in.un;
    let slip_in = norm(c_in.ut);
    let (restitution_t, regime) = if slip_in <= NO_SLIP * c_in.un.abs() {
        (None, Regime::Normal)
    } else {
        let dir = [c_in.ut[0] / slip_in, c_in.ut[1] / slip_in, c_in.ut[2] / slip_in];
        let slid = contacts[first..=last].iter().all(|c| dot(c.ut, dir) > 0.0);
        (Some(-dot(c_out.ut, dir) / slip_in), if slid { Regime::Slide } else { Regime::Stick })
    };
    Ok(Outcome {
        contact_time: t_end - t_start,
        max_overlap,
        restitution_n,
        restitution_t,
        omega_out: s_out.w1[1],
        omega2_out: case.sphere2().map(|_| s_out.w2[1]),
        regime,
        steps,
        dt: samples[1].t - samples[0].t,
    })
}

/// The maximum of the parabola through (−1, a), (0, b), (1, c), with b ≥ a, c.
fn parabola_vertex(a: f64, b: f64, c: f64) -> f64 {
    let curvature = a - 2.0 * b + c;
    if curvature >= 0.0 {
        return b;
    }
    b - (c - a) * (c - a) / (8.0 * curvature)
}

#[cfg(test)]
mod tests {
    use super::parabola_vertex;

    #[test]
    fn parabola_vertex_recovers_an_exact_parabola() {
        // y = 5 − 2 (x − 0.3)² sampled at −1, 0, 1.
        let f = |x: f64| 5.0 - 2.0 * (x - 0.3) * (x - 0.3);
        let v = parabola_vertex(f(-1.0), f(0.0), f(1.0));
        assert!((v - 5.0).abs() < 1e-12, "{v}");
    }
}
