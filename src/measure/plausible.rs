//! What is physically possible: the checks every number passes before it counts, on what the
//! engine hands the metrics (each dump frame) and on every result, fresh or read back.
//!
//! An engine that exits 0 can still write garbage (a negative mass, a velocity of 1e300), and a
//! result file can be edited or damaged; none of it may become a number in results.csv. Not
//! responsible for whether a result belongs to its run directory or point (the store checks
//! that).

use crate::measure::frame::Frame;
use crate::outcome::RunResult;

/// Highest possible packing of a layer: the densest packing of equal spheres, π/√18 ≈ 0.7405
/// (Kepler; random close packing is ≈ 0.64). The layer's packing is bounded by it; MFR (the
/// deposit over the gap alone) is bounded by it times layer_thickness / gap, since on a rough
/// substrate the deposit also fills the pockets below the tops.
pub const PACKING_MAX: f64 = 0.74;

/// Highest possible |v_x| of a particle, in multiples of the blade speed. The blade pushes the
/// heap at its own speed; grains thrown ahead of it move at a few times that at most, and a run
/// whose energy explodes is stopped by the engine's log watch long before 10×.
pub const VX_MAX_BLADE_SPEEDS: f64 = 10.0;

/// The overlap, as a fraction of the radius, whose Hertz energy bounds what a jam released at
/// the blade's tip can give one sphere. At a slow blade that, not the blade, is what throws
/// spheres fastest: a 35 µm powder at 0.02 m/s (5 MPa) threw six spheres forward at once from
/// just above the gap, the fastest at 0.22 m/s (11 blade speeds, and above what a fall from the
/// heap's top gives, 0.12 m/s), in a run with nothing else wrong; that sphere's speed is the
/// energy of an overlap of 4.5 % of the radius. 10 % is beyond what the contact model is meant
/// for.
pub const RELEASED_OVERLAP: f64 = 0.1;

/// The speed one sphere gains from the Hertz energy of an overlap of [`RELEASED_OVERLAP`] of
/// its radius with an equal sphere: U = (8/15)·E*·√R*·δ^(5/2), E* = E/(2(1 − ν²)), R* = R/2,
/// all of U to the sphere's mass (4/3)πR³ρ. R cancels: v² = (4/(5π))·(1/√2)·0.1^(5/2)·E*/ρ.
pub fn released_jam_speed(youngs_modulus: f64, poisson: f64, density: f64) -> f64 {
    let e_star = youngs_modulus / (2.0 * (1.0 - poisson * poisson));
    let v2 =
        4.0 / (5.0 * std::f64::consts::PI) / std::f64::consts::SQRT_2 * RELEASED_OVERLAP.powf(2.5) * e_star
            / density;
    v2.sqrt()
}

/// What moves one sphere besides the blade: a fall from the top of the box and a jam released.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereSpeeds {
    pub blade: f64,
    /// The box's height: the highest fall a sphere can make.
    pub fall_height: f64,
    /// [`released_jam_speed`] of the powder.
    pub released: f64,
}

impl SphereSpeeds {
    /// The speeds a scene with a blade of `blade_speed` allows its spheres.
    pub fn of(scene: &crate::scene::Scene, blade_speed: f64) -> SphereSpeeds {
        SphereSpeeds {
            blade: blade_speed,
            fall_height: scene.z_hi - scene.z_lo,
            released: released_jam_speed(
                scene.material.youngs_modulus,
                scene.material.poisson,
                scene.material.density,
            ),
        }
    }

    /// The highest |v_x| a single sphere can reach: [`VX_MAX_BLADE_SPEEDS`] blade speeds, the
    /// speed of a fall of the box's height and the released jam's speed, added.
    pub fn vx_limit(&self) -> f64 {
        vx_limit(self.blade)
            + (2.0 * crate::scene::GRAVITY * self.fall_height.max(0.0)).sqrt()
            + self.released
    }
}

/// Why a number the engine wrote, or a result holds, is not possible: the number, named.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Implausible {
    /// A number of a result: `mfr = 3: expected a finite number in [0, 0.74]`.
    #[error("{what} = {}: expected {expected}", shown(*.value))]
    Value { what: String, value: f64, expected: String },
    /// A window that counted more particles than the pile holds.
    #[error("answer_particles = {counted}: more than the {particles} particles of the pile")]
    Counted { counted: usize, particles: usize },
    /// A particle of a dump frame, where it was: `step 100, particle 7 at x = 10 mm, z = 2 mm:
    /// mass = 0: expected a finite mass > 0`.
    #[error("step {step}, particle {id} at x = {} mm, z = {} mm: {what} = {value}: expected {expected}", mm(*.x), mm(*.z))]
    Particle { step: u64, id: u64, x: f64, z: f64, what: &'static str, value: f64, expected: String },
    /// A deposit under a gap no resting sphere passes ([`check_squeezed`]); the gap and the
    /// sphere's top in diameters.
    #[error(
        "MFR = {mfr:.4} at a gap of {gap_d:.2} D, below the {top_d:.2} D a resting sphere stands: particles were pressed \
         under the tip with overlaps beyond the contact model's range, so MFR is not a flow"
    )]
    Squeezed { mfr: f64, gap_d: f64, top_d: f64 },
}

/// Shortest form that is still the value: 1e300 as "1e300", not 301 digits.
fn shown(v: f64) -> String {
    if v.is_finite() && v != 0.0 && !(1e-5..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A position in millimetres, to four digits.
fn mm(metres: f64) -> String {
    crate::scene::plausible::round_to(metres * 1e3, 4)
}

/// Why a number is not possible, naming it.
fn bad(what: &str, v: f64, expected: &str) -> Implausible {
    Implausible::Value { what: what.to_string(), value: v, expected: expected.to_string() }
}

fn check_within(what: &str, v: f64, hi: f64) -> Result<(), Implausible> {
    if v.is_finite() && (0.0..=hi).contains(&v) {
        Ok(())
    } else {
        Err(bad(what, v, &format!("a finite number in [0, {}]", crate::scene::plausible::round_to(hi, 4))))
    }
}

fn vx_limit(blade_speed: f64) -> f64 {
    VX_MAX_BLADE_SPEEDS * blade_speed.abs()
}

/// What a layout's result measures, for [`check_result`]: each layout says it of its own
/// result ([`crate::scenes::Layout::check_result`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measures {
    /// Whether it holds a flow's answer (`mfr`): a pour's heap does not.
    pub flow: bool,
    /// Whether it holds the flux past the blade (`mfr_flux`) and the window's steadiness p-value
    /// (`steady_p`): layer after layer has neither (its passes are its test).
    pub flux: bool,
    /// How many times the packing bound the answer and its windows may reach over
    /// layer_thickness / gap: the deepest powder under the blade over the platform's drop, layer
    /// after layer (a pass may deposit more than the drop); 1 for one layer.
    pub depth: f64,
}

impl Measures {
    /// A flow under a blade: MFR, its flux and its steadiness, over one layer.
    pub const FLOW: Measures = Measures { flow: true, flux: true, depth: 1.0 };
}

/// Every number of a result finite and possible: the layer's packing at most [`PACKING_MAX`],
/// 0 ≤ MFR ≤ [`PACKING_MAX`] × layer_thickness / gap × `depth` (the flux and window MFRs, net
/// counts, within ± that), each v_x within [`VX_MAX_BLADE_SPEEDS`] blade speeds,
/// the p-value in [0, 1], counts and times consistent; of the flow, flux and depth `measures`
/// says the result holds.
pub fn check_result(r: &RunResult, measures: Measures) -> Result<(), Implausible> {
    let gap = r.parameters.get("gap").map(|g| g * 1e-3);
    let thicker = match (r.layer_thickness, gap) {
        (Some(t), Some(g)) if t.is_finite() && g > 0.0 && t >= g => t / g,
        _ => 1.0,
    };
    if let Some(p) = r.layer_packing {
        check_within("layer_packing", p, PACKING_MAX)?;
    }
    let Measures { flow, flux, depth } = measures;
    let mfr_max = PACKING_MAX * thicker * depth;
    let within = format!("within ±{}", crate::scene::plausible::round_to(mfr_max, 4));
    if flow {
        check_within(r.answer.kind.key(), r.answer.value, mfr_max)?;
    }
    if flux {
        check_within("mfr_flux", r.mfr_flux.abs(), mfr_max)
            .map_err(|_| bad("mfr_flux", r.mfr_flux, &within))?;
    }
    for (i, w) in r.answer_windows.iter().enumerate() {
        check_within(&format!("answer_windows[{i}]"), w.abs(), mfr_max)
            .map_err(|_| bad(&format!("answer_windows[{i}]"), *w, &within))?;
    }
    if flux && !(r.steady_p.is_finite() && (0.0..=1.0).contains(&r.steady_p)) {
        return Err(bad("steady_p", r.steady_p, "a p-value in [0, 1]"));
    }
    let speed = r.parameters.get("blade_speed").copied();
    if let Some(s) = speed {
        if !(s.is_finite() && s > 0.0) {
            return Err(bad("parameters.blade_speed", s, "a positive speed"));
        }
    }
    for (k, v) in r.vx.iter().enumerate() {
        let Some(v) = *v else { continue };
        let ok = v.is_finite() && speed.is_none_or(|s| v.abs() <= vx_limit(s));
        if !ok {
            let limit = speed.map_or("a finite speed".to_string(), |s| {
                format!("|v_x| ≤ {VX_MAX_BLADE_SPEEDS} blade speeds ({} m/s)", vx_limit(s))
            });
            return Err(bad(&format!("v_x of layer {}", k + 1), v, &limit));
        }
    }
    if let Some(se) = r.answer.se.filter(|se| !(se.is_finite() && *se >= 0.0)) {
        return Err(bad(r.answer.kind.se_key(), se, "a finite standard error ≥ 0"));
    }
    // A held heap (steady_state) is topped up as it deposits, so its window can count more
    // particles than the heap holds at once; a pile of its own cannot.
    if r.steady_state.is_none() && r.answer_particles > r.particles {
        return Err(Implausible::Counted { counted: r.answer_particles, particles: r.particles });
    }
    for (what, v) in [("simulated_time", r.simulated_time), ("wall_time", r.wall_time)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(bad(what, v, "a finite time ≥ 0"));
        }
    }
    if let Some(c) = r.cpu_time.filter(|c| !(c.is_finite() && *c >= 0.0)) {
        return Err(bad("cpu_time", c, "a finite time ≥ 0"));
    }
    Ok(())
}

/// Every particle of a dump frame possible: positions and velocities finite, masses finite and
/// positive, |v_x| within [`SphereSpeeds::vx_limit`]. The error names the particle and where it
/// was.
pub fn check_frame(f: &Frame, speeds: &SphereSpeeds) -> Result<(), Implausible> {
    let limit = speeds.vx_limit();
    for i in 0..f.len() {
        let at = |what, value, expected: String| Implausible::Particle {
            step: f.step,
            id: f.id[i],
            x: f.x[i],
            z: f.z[i],
            what,
            value,
            expected,
        };
        let m = f.mass[i];
        if !(m.is_finite() && m > 0.0) {
            return Err(at("mass", m, "a finite mass > 0".into()));
        }
        for (what, v) in [("x", f.x[i]), ("z", f.z[i])] {
            if !v.is_finite() {
                return Err(at(what, v, "a finite position".into()));
            }
        }
        let v = f.vx[i];
        if !(v.is_finite() && v.abs() <= limit) {
            let expected = format!(
                "|v_x| ≤ {} m/s ({VX_MAX_BLADE_SPEEDS} blade speeds, a fall of {} mm and a jam released)",
                crate::scene::plausible::round_to(limit, 3),
                mm(speeds.fall_height)
            );
            return Err(at("vx", v, expected));
        }
    }
    Ok(())
}

/// A point whose gap is below the top of the smallest particle resting as low as it can (in a
/// substrate pocket, [`crate::scene::Scene::lowest_top`]) can deposit only by pressing particles
/// under the tip with overlaps far beyond the contact model's range: the blade and the substrate
/// are kinematic, so a soft sphere caught between them is squeezed through however small the
/// gap (seen at machine blade speeds, where no impact throws it out of its pocket first). Such a
/// deposit is an artefact, not a flow.
pub fn check_squeezed(scene: &crate::scene::Scene, gap: f64, mfr: f64) -> Result<(), Implausible> {
    let top = scene.lowest_top();
    if mfr > 0.0 && gap < top {
        return Err(Implausible::Squeezed { mfr, gap_d: gap / scene.diameter, top_d: top / scene.diameter });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::outcome::PointAnswer;

    fn frame(mass: f64, vx: f64) -> Frame {
        Frame {
            step: 100,
            id: vec![7],
            x: vec![0.01],
            y: None,
            z: vec![0.002],
            vx: vec![vx],
            mass: vec![mass],
        }
    }

    /// The bound of a blade at `blade` m/s alone: no fall, no jam.
    fn blade_only(blade: f64) -> SphereSpeeds {
        SphereSpeeds { blade, fall_height: 0.0, released: 0.0 }
    }

    #[test]
    fn a_frame_with_a_negative_or_zero_mass_is_refused_naming_the_particle() {
        for m in [-4.4e-6, 0.0, f64::NAN] {
            let e = check_frame(&frame(m, 0.5), &blade_only(1.4)).unwrap_err().to_string();
            assert!(e.contains("particle 7 at x = 10 mm, z = 2 mm") && e.contains("mass"), "{e}");
        }
        assert!(check_frame(&frame(4.4e-6, 0.5), &blade_only(1.4)).is_ok());
    }

    #[test]
    fn a_frame_with_vx_beyond_the_stated_multiple_of_the_blade_speed_is_refused() {
        assert!(check_frame(&frame(4.4e-6, 13.9), &blade_only(1.4)).is_ok());
        for v in [14.1, -14.1, 1e300, f64::INFINITY] {
            assert!(
                check_frame(&frame(4.4e-6, v), &blade_only(1.4)).unwrap_err().to_string().contains("vx"),
                "{v}"
            );
        }
    }

    #[test]
    fn the_released_jam_speed_is_the_hertz_energy_of_a_tenth_of_the_radius_given_to_one_sphere() {
        // Worked for R = 17.5 µm, E = 5 MPa, ν = 0.3, ρ = 4430 (sweeps/ti64-machine.toml):
        // E* = 5e6 / (2 × 0.91) = 2.7473e6 Pa, R* = R/2, δ = 1.75 µm;
        // U = (8/15) E* √R* δ^2.5 = 8/15 × 2.7473e6 × 2.958e-3 × 4.0514e-15 = 1.7558e-11 J;
        // m = 4/3 π R³ ρ = 9.9489e-11 kg; v = √(2U/m) = 0.5941 m/s.
        let (r, e, nu, rho) = (17.5e-6f64, 5e6, 0.3, 4430.0);
        let e_star = e / (2.0 * (1.0 - nu * nu));
        let u = 8.0 / 15.0 * e_star * (r / 2.0).sqrt() * (0.1 * r).powf(2.5);
        let m = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) * rho;
        let v = (2.0 * u / m).sqrt();
        assert!((v - 0.5941).abs() < 5e-4, "{v}");
        assert!((released_jam_speed(e, nu, rho) - v).abs() < 1e-12 * v);
    }

    #[test]
    fn at_a_slow_blade_a_sphere_may_move_at_a_fall_and_a_released_jam_beyond_ten_blade_speeds() {
        // The 35 µm powder at 0.02 m/s: a 2.255 mm box, a fall from its top 0.2104 m/s, a jam
        // 0.5941 m/s; the sphere seen at 0.2215 m/s (11 blade speeds) passes, 1.1 m/s does not.
        let speeds = SphereSpeeds {
            blade: 0.02,
            fall_height: 2.2553e-3,
            released: released_jam_speed(5e6, 0.3, 4430.0),
        };
        assert!((speeds.vx_limit() - (0.2 + 0.2104 + 0.5941)).abs() < 1e-3, "{}", speeds.vx_limit());
        assert!(check_frame(&frame(9.9e-11, 0.2215), &speeds).is_ok());
        assert!(check_frame(&frame(9.9e-11, -0.99), &speeds).is_ok());
        let e = check_frame(&frame(9.9e-11, 1.1), &speeds).unwrap_err().to_string();
        assert!(e.contains("|v_x| ≤ 1 m/s") && e.contains("a fall of 2.255 mm"), "{e}");
    }

    #[test]
    fn a_result_is_checked_on_what_it_measures_and_not_on_the_flux_it_does_not() {
        let r = |mfr: f64| RunResult {
            parameters: [("blade_speed".to_string(), 0.1)].into_iter().collect(),
            answer: PointAnswer::mfr(mfr),
            mfr_flux: f64::NAN,
            steady_p: f64::NAN,
            answer_windows: vec![0.4, 1.14],
            ..RunResult::default()
        };
        let passes = Measures { flow: true, flux: false, depth: 2.14 };
        // A pass may deposit more than the drop at the packing bound when the powder under the
        // blade is 2.14 drops deep.
        assert!(check_result(&r(1.0), passes).is_ok(), "{:?}", check_result(&r(1.0), passes));
        assert!(check_result(&r(f64::NAN), passes).is_err());
        assert!(check_result(&r(0.74 * 2.2), passes).is_err(), "beyond the packing bound over the depth");
        // Nothing flows: its NaN answer is not checked.
        let heap = Measures { flow: false, flux: false, depth: 1.0 };
        assert!(check_result(&RunResult { answer_windows: Vec::new(), ..r(f64::NAN) }, heap).is_ok());
        // A flow's result still needs its flux.
        let flow = RunResult { answer: PointAnswer::mfr(0.3), mfr_flux: f64::NAN, ..RunResult::default() };
        assert!(check_result(&flow, Measures::FLOW).unwrap_err().to_string().contains("mfr_flux"));
    }
}
