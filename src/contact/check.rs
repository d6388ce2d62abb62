//! `sweep contact-check`: the same impacts through LIGGGHTS and the reference solver.
//!
//! Each case is rendered from `templates/contact.liggghts.tera` (two spheres, or one sphere and
//! a primitive `zplane` wall of atom type 2; gravity off; `fix print` writes the state of every
//! step), run in its own directory with `-echo none -screen none -log`, read back, analysed by
//! [`super::analysis`] exactly as the solver's own trajectory is, and compared quantity by
//! quantity. Not here: mesh walls, many particles, the spreading scene.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::analysis::{analyse, Outcome};
use super::solver::{initial_state, simulate, Sample};
use super::{Case, ContactError, Material, Target};

const TEMPLATE: &str = include_str!("../../templates/contact.liggghts.tera");

/// Relative tolerance on every compared quantity. The solver does LIGGGHTS' arithmetic in
/// LIGGGHTS' order from the same initial numbers, so the two agree to rounding (measured
/// ≤ 2e-13 over the built-in cases, docs/contact.md); 1e-9 leaves room for another compiler's
/// rounding and still catches any change of formula, coefficient or integration order.
pub const TOLERANCE: f64 = 1e-9;

/// The deck writes this file (one line per step).
const TRAJECTORY: &str = "trajectory.txt";

/// Steps LIGGGHTS runs beyond the solver's: the bodies must be apart at the end.
fn liggghts_steps(solver_steps: usize) -> usize {
    solver_steps + solver_steps / 10 + 10
}

/// The built-in cases: the spreading scene's materials (thesis Table 3.1: E = 21 MPa,
/// ν = 0.3, ρ = 7980 kg/m³, D 1–3 mm, e 0.4–0.6, μ 0.1–0.3) at 0.1–2 m/s, sphere–sphere and
/// sphere–wall (a same-material wall, and a 200 GPa plate as its own wall type), normal,
/// oblique (stick and slide) and spinning, at t_c/1000 and once at a coarse t_c/50.
pub fn default_cases() -> Vec<(String, Case)> {
    let steel = Material { youngs: 21e6, poisson: 0.3 };
    let case = |target, d: f64, e, mu, vn, vt, spin| Case {
        target,
        radius: d / 2.0,
        density: 7980.0,
        material: steel,
        restitution: e,
        friction: mu,
        vn,
        vt,
        spin,
        dt: None,
    };
    let wall = Target::Wall(steel);
    // A hard plate (real steel) as a wall type of its own: Y* from both types.
    let plate = Target::Wall(Material { youngs: 200e9, poisson: 0.3 });
    let sphere = |d: f64| Target::Sphere { radius: d / 2.0, density: 7980.0 };
    // At a production-like timestep (t_c/50), where the first and last contact steps weigh most.
    let mut coarse = case(sphere(1.5e-3), 1.5e-3, 0.4, 0.2, 1.0, 1.0, 100.0);
    coarse.dt = Some(coarse.pair().hertz_time(coarse.vn) / 50.0);
    vec![
        ("wall-normal-D1-e0.4".into(), case(wall, 1e-3, 0.4, 0.1, 0.1, 0.0, 0.0)),
        ("wall-normal-D3-e0.6".into(), case(wall, 3e-3, 0.6, 0.3, 2.0, 0.0, 0.0)),
        ("wall-oblique-slide".into(), case(wall, 2e-3, 0.5, 0.1, 1.0, 2.0, 0.0)),
        ("wall-oblique-stick".into(), case(wall, 2e-3, 0.5, 0.3, 1.0, 0.5, 0.0)),
        ("plate-oblique".into(), case(plate, 2e-3, 0.45, 0.15, 0.3, 0.6, 0.0)),
        ("wall-spin".into(), case(wall, 1.5e-3, 0.55, 0.2, 0.5, 0.0, 400.0)),
        ("pair-normal-D1-D3".into(), case(sphere(3e-3), 1e-3, 0.45, 0.2, 1.5, 0.0, 0.0)),
        ("pair-oblique-slide".into(), case(sphere(2e-3), 2e-3, 0.5, 0.1, 0.5, 1.5, 0.0)),
        ("pair-oblique-stick".into(), case(sphere(1e-3), 2.5e-3, 0.6, 0.3, 2.0, 0.8, -200.0)),
        ("pair-coarse-dt".into(), coarse),
    ]
}

/// One quantity of one case, both ways.
#[derive(Debug, Clone)]
pub struct Compared {
    pub quantity: &'static str,
    pub reference: Option<f64>,
    pub liggghts: Option<f64>,
    /// |reference − liggghts| / max(|reference|, floor); infinite when only one is defined.
    pub rel_diff: f64,
    pub tolerance: f64,
}

impl Compared {
    fn new(quantity: &'static str, reference: Option<f64>, liggghts: Option<f64>, floor: f64) -> Self {
        let rel_diff = match (reference, liggghts) {
            (Some(a), Some(b)) => (a - b).abs() / a.abs().max(floor).max(f64::MIN_POSITIVE),
            (None, None) => 0.0,
            _ => f64::INFINITY,
        };
        Compared { quantity, reference, liggghts, rel_diff, tolerance: TOLERANCE }
    }

    pub fn passed(&self) -> bool {
        self.rel_diff <= self.tolerance
    }
}

/// The comparison of one case.
#[derive(Debug, Clone)]
pub struct CaseReport {
    pub name: String,
    pub reference: Outcome,
    pub liggghts: Outcome,
    pub quantities: Vec<Compared>,
}

impl CaseReport {
    pub fn passed(&self) -> bool {
        self.reference.regime == self.liggghts.regime && self.quantities.iter().all(Compared::passed)
    }
}

/// The comparison of all cases.
#[derive(Debug, Clone)]
pub struct Report {
    pub cases: Vec<CaseReport>,
}

impl Report {
    pub fn passed(&self) -> bool {
        self.cases.iter().all(CaseReport::passed)
    }

    /// A fixed-width table: one row per case and quantity, then the verdict.
    pub fn table(&self) -> String {
        let fmt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.9e}"));
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{:<22} {:<14} {:>16} {:>16} {:>10} {:>8}  ok",
            "case", "quantity", "reference", "liggghts", "rel.diff", "tol"
        );
        for c in &self.cases {
            for q in &c.quantities {
                let _ = writeln!(
                    out,
                    "{:<22} {:<14} {:>16} {:>16} {:>10.2e} {:>8.0e}  {}",
                    c.name,
                    q.quantity,
                    fmt(q.reference),
                    fmt(q.liggghts),
                    q.rel_diff,
                    q.tolerance,
                    if q.passed() { "yes" } else { "NO" }
                );
            }
            let same = c.reference.regime == c.liggghts.regime;
            let _ = writeln!(
                out,
                "{:<22} {:<14} {:>16} {:>16} {:>10} {:>8}  {}",
                c.name,
                "regime",
                c.reference.regime.as_str(),
                c.liggghts.regime.as_str(),
                "",
                "",
                if same { "yes" } else { "NO" }
            );
        }
        let failed = self.cases.iter().filter(|c| !c.passed()).count();
        let _ = writeln!(out, "{} case(s), {} failed", self.cases.len(), failed);
        out
    }
}

/// Runs every case through the solver and LIGGGHTS (`engine`), one directory per case under
/// `keep` (kept) or under the system temporary directory (removed afterwards).
pub fn run_cases(
    cases: &[(String, Case)],
    engine: &Path,
    keep: Option<&Path>,
) -> Result<Report, ContactError> {
    for (_, case) in cases {
        case.validate()?;
    }
    // A LIGGGHTS start-up is mostly waiting (~0.5 s, little CPU), so the cases run at once.
    let results: Vec<Result<CaseReport, ContactError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = cases
            .iter()
            .map(|(name, case)| {
                scope.spawn(move || {
                    let dir = match keep {
                        Some(k) => k.join(name),
                        None => scratch_dir(name),
                    };
                    std::fs::create_dir_all(&dir)?;
                    let result = compare(name, case, engine, &dir);
                    if keep.is_none() {
                        let _ = std::fs::remove_dir_all(&dir);
                    }
                    result
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("a contact-check thread panicked")).collect()
    });
    Ok(Report { cases: results.into_iter().collect::<Result<_, _>>()? })
}

/// A fresh directory under the system temporary directory.
fn scratch_dir(name: &str) -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("demsweep-contact-{}-{n}-{name}", std::process::id()))
}

fn compare(name: &str, case: &Case, engine: &Path, dir: &Path) -> Result<CaseReport, ContactError> {
    let dt = case.timestep();
    let trajectory = simulate(case, dt)?;
    let reference = analyse(case, &trajectory.samples, trajectory.steps)?;
    let steps = liggghts_steps(trajectory.steps);
    let deck =
        render(name, case, dt, steps, reach(&trajectory.samples, (steps - trajectory.steps) as f64 * dt))?;
    std::fs::write(dir.join("in.contact"), deck)?;
    run_liggghts(engine, dir)?;
    let samples = read_trajectory(&dir.join(TRAJECTORY), case, dt)?;
    let liggghts = analyse(case, &samples, steps)?;
    let spin_scale = case.vn / case.radius;
    let quantities = vec![
        Compared::new("contact_time", Some(reference.contact_time), Some(liggghts.contact_time), 0.0),
        Compared::new("max_overlap", Some(reference.max_overlap), Some(liggghts.max_overlap), 0.0),
        Compared::new("restitution_n", Some(reference.restitution_n), Some(liggghts.restitution_n), 0.0),
        // Tangential restitution runs through 0 between stick and slide: relative to 1.
        Compared::new("restitution_t", reference.restitution_t, liggghts.restitution_t, 1.0),
        // Spin relative to the natural scale vn/r (it is 0 in a normal impact).
        Compared::new("omega_out", Some(reference.omega_out), Some(liggghts.omega_out), spin_scale),
        Compared::new("omega2_out", reference.omega2_out, liggghts.omega2_out, spin_scale),
        Compared {
            quantity: "trajectory",
            reference: None,
            liggghts: None,
            rel_diff: trajectory_deviation(case, &trajectory.samples, &samples),
            tolerance: TOLERANCE,
        },
    ];
    Ok(CaseReport { name: name.to_string(), reference, liggghts, quantities })
}

/// The largest difference of state between two trajectories over their common steps, relative
/// to the natural scales: r1 for positions, vn for velocities, vn/r1 for spins.
fn trajectory_deviation(case: &Case, a: &[Sample], b: &[Sample]) -> f64 {
    let dev = |p: [f64; 3], q: [f64; 3], scale: f64| {
        (0..3).map(|k| (p[k] - q[k]).abs() / scale).fold(0.0, f64::max)
    };
    let (r, v, w) = (case.radius, case.vn, case.vn / case.radius);
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            [
                dev(p.x1, q.x1, r),
                dev(p.x2, q.x2, r),
                dev(p.v1, q.v1, v),
                dev(p.v2, q.v2, v),
                dev(p.w1, q.w1, w),
                dev(p.w2, q.w2, w),
            ]
            .into_iter()
            .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

/// How far from the origin the bodies of `samples` get, plus what their fastest speed covers in
/// `extra` more seconds, m: the box must hold the LIGGGHTS run however much energy a coarse
/// timestep adds (an atom that leaves it is lost).
pub fn reach(samples: &[Sample], extra: f64) -> f64 {
    let far = |x: [f64; 3]| x.iter().fold(0.0, |m: f64, c| m.max(c.abs()));
    let speed = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let (mut extent, mut fastest) = (0.0f64, 0.0f64);
    for s in samples {
        extent = extent.max(far(s.x1)).max(far(s.x2));
        fastest = fastest.max(speed(s.v1)).max(speed(s.v2));
    }
    extent + fastest * extra
}

/// The LIGGGHTS deck of `case` at timestep `dt`, running `steps` steps, in a box that holds
/// the bodies out to `reach` m from the origin ([`reach`]).
pub fn render(name: &str, case: &Case, dt: f64, steps: usize, reach: f64) -> Result<String, ContactError> {
    let s0 = initial_state(case, dt);
    let (wall, wall_material, r2, m2_density) = match case.target {
        Target::Wall(w) => (true, w, 0.0, case.density),
        Target::Sphere { radius, density } => (false, case.material, radius, density),
    };
    for (flag, youngs) in [("youngs", case.material.youngs), ("wall-youngs", wall_material.youngs)] {
        if !(5e6..=1e12).contains(&youngs) {
            return Err(ContactError::Input {
                name: flag,
                value: youngs,
                expected: "5e6 <= E <= 1e12 Pa for a LIGGGHTS deck (SI units)",
            });
        }
    }
    // LIGGGHTS refuses Y > 1e9 Pa unless told the particles are hard on purpose.
    let hard = case.material.youngs > 1e9 || wall_material.youngs > 1e9;
    let duration = steps as f64 * dt;
    let speed = case.vn.abs() + case.vt.abs() + case.spin.abs() * case.radius;
    let half = 4.0 * (case.radius + r2) + (2.0 * speed * duration).max(reach);
    let num = |v: f64| format!("{v:e}");
    let mut ctx = tera::Context::new();
    ctx.insert("name", name);
    ctx.insert("hard", &hard);
    ctx.insert("wall", &wall);
    ctx.insert("half", &num(half));
    ctx.insert("skin", &num(case.radius.min(if wall { case.radius } else { r2 })));
    ctx.insert("youngs", &num(case.material.youngs));
    ctx.insert("poisson", &num(case.material.poisson));
    ctx.insert("wall_youngs", &num(wall_material.youngs));
    ctx.insert("wall_poisson", &num(wall_material.poisson));
    ctx.insert("restitution", &num(case.restitution));
    ctx.insert("friction", &num(case.friction));
    ctx.insert("dt", &num(dt));
    ctx.insert("z1", &num(s0.x1[2]));
    ctx.insert("d1", &num(2.0 * case.radius));
    ctx.insert("density1", &num(case.density));
    ctx.insert("vx1", &num(s0.v1[0]));
    ctx.insert("vz1", &num(s0.v1[2]));
    ctx.insert("spin", &num(case.spin));
    ctx.insert("d2", &num(2.0 * r2));
    ctx.insert("density2", &num(m2_density));
    ctx.insert("vx2", &num(s0.v2[0]));
    ctx.insert("vz2", &num(s0.v2[2]));
    ctx.insert("atoms", &if wall { vec![1] } else { vec![1, 2] });
    ctx.insert("out", TRAJECTORY);
    ctx.insert("steps", &steps);
    tera::Tera::one_off(TEMPLATE, &ctx, false)
        .map_err(|e| ContactError::Engine(format!("failed to render contact.liggghts.tera: {e:?}")))
}

/// Longest a single-contact LIGGGHTS case may run (they take well under a second).
const CASE_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(120);

/// Runs `engine -in in.contact` in `dir`, output to files there, through the same runner as the
/// sweeps (`engine::command`, `process::run`): own process group, a timeout, the ERROR line kept.
fn run_liggghts(engine: &Path, dir: &Path) -> Result<(), ContactError> {
    use crate::sys::process::{self, CancelToken, ProcessOutcome};
    let cmd = crate::engine::command(engine, dir, "in.contact")
        .map_err(|e| ContactError::Engine(format!("failed to prepare {}: {e}", dir.display())))?;
    let (outcome, _) = process::run(cmd, CASE_TIMEOUT, &CancelToken::new());
    let why = match outcome {
        ProcessOutcome::Exited(0) => return Ok(()),
        ProcessOutcome::SpawnFailed(e) => {
            return Err(ContactError::Engine(format!("failed to start {}: {e}", engine.display())))
        }
        ProcessOutcome::TimedOut => format!("timed out after {} s", CASE_TIMEOUT.as_secs()),
        other => crate::engine::first_error_in(dir)
            .unwrap_or_else(|| format!("{other:?}, no ERROR line in the log")),
    };
    Err(ContactError::Engine(format!(
        "{} failed in {}: {why} (--keep DIR keeps the deck and log)",
        engine.display(),
        dir.display()
    )))
}

/// Reads the `fix print` file: per line the step, then per atom x y z vx vy vz ωx ωy ωz.
/// The initial state (LIGGGHTS prints from step 1) is the solver's, which the deck was given.
pub fn read_trajectory(path: &Path, case: &Case, dt: f64) -> Result<Vec<Sample>, ContactError> {
    let text = std::fs::read_to_string(path)?;
    let atoms = if case.sphere2().is_some() { 2 } else { 1 };
    let mut samples = vec![initial_state(case, dt)];
    for (i, line) in text.lines().enumerate() {
        let err =
            |message: String| ContactError::Output { path: path.display().to_string(), line: i + 1, message };
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        if fields.len() != 1 + 9 * atoms {
            return Err(err(format!("expected {} columns, found {}", 1 + 9 * atoms, fields.len())));
        }
        let step: usize =
            fields[0].parse().map_err(|_| err(format!("step `{}` is not an integer", fields[0])))?;
        let mut v = [0.0; 18];
        for (k, f) in fields[1..].iter().enumerate() {
            v[k] = f.parse().map_err(|_| err(format!("column {} `{f}` is not a number", k + 2)))?;
        }
        // LIGGGHTS evaluates x[i], vx[i], ... of an atom that left the box as 0; a body of a case
        // is never exactly at rest at the origin (sphere 1 starts above it, moving).
        if let Some(k) = (0..atoms).find(|k| v[9 * k..9 * k + 9].iter().all(|&x| x == 0.0)) {
            return Err(err(format!(
                "atom {} is gone at step {step} (LIGGGHTS prints 0 for a lost atom): it left the deck's box",
                k + 1
            )));
        }
        let three = |k: usize| [v[k], v[k + 1], v[k + 2]];
        samples.push(Sample {
            t: step as f64 * dt,
            x1: three(0),
            v1: three(3),
            w1: three(6),
            x2: three(9),
            v2: three(12),
            w2: three(15),
        });
    }
    Ok(samples)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::Regime;

    fn outcome(regime: Regime) -> Outcome {
        Outcome {
            contact_time: 1e-4,
            max_overlap: 1e-6,
            restitution_n: 0.5,
            restitution_t: None,
            omega_out: 0.0,
            omega2_out: None,
            regime,
            steps: 10,
            dt: 1e-5,
        }
    }

    #[test]
    fn a_difference_beyond_the_tolerance_fails() {
        assert!(Compared::new("q", Some(1.0), Some(1.0 + 0.5e-9), 0.0).passed());
        assert!(!Compared::new("q", Some(1.0), Some(1.0 + 2e-9), 0.0).passed());
        // Only one side defined (e.g. a slip LIGGGHTS did not see) fails.
        assert!(!Compared::new("q", Some(0.0), None, 1.0).passed());
        // Near zero, the floor sets the scale.
        assert!(Compared::new("q", Some(0.0), Some(1e-10), 1.0).passed());
    }

    #[test]
    fn a_different_regime_fails_the_case_and_the_report() {
        let case = CaseReport {
            name: "x".into(),
            reference: outcome(Regime::Stick),
            liggghts: outcome(Regime::Slide),
            quantities: vec![],
        };
        let report = Report { cases: vec![case] };
        assert!(!report.passed());
        assert!(report.table().contains("1 case(s), 1 failed"));
    }

    #[test]
    fn a_lost_atom_is_an_error_not_a_state_at_the_origin() {
        // wall-normal-D1-e0.4: one atom, 9 columns after the step.
        let (_, case) = default_cases().remove(0);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(TRAJECTORY);
        std::fs::write(&path, "1 0 0 5e-4 0 0 -0.1 0 0 0\n2 0 0 0 0 0 0 0 0 0\n").unwrap();
        let err = read_trajectory(&path, &case, 1e-7).unwrap_err().to_string();
        assert!(err.contains(":2: atom 1 is gone at step 2"), "{err}");
    }

    #[test]
    fn the_box_reaches_as_far_as_the_fastest_body_can_fly() {
        let (_, case) = default_cases().remove(7);
        let mut s = initial_state(&case, 1e-7);
        s.x1 = [0.0, 0.0, 3e-3];
        s.v1 = [0.0, 0.0, 4.0];
        // 3 mm out, then 4 m/s for 1 ms.
        assert!((reach(&[s], 1e-3) - 7e-3).abs() < 1e-15);
        let deck = render("pair", &case, 1e-7, 10, 1.0).unwrap();
        assert!(deck.contains("region box block -1.0"), "{deck}");
    }

    #[test]
    fn the_deck_renders_with_the_case_numbers() {
        // pair-oblique-slide.
        let (_, case) = default_cases().remove(7);
        let deck = render("pair", &case, 1e-7, 1234, 0.01).unwrap();
        assert!(deck.contains("pair_style gran model hertz tangential history"));
        assert!(!deck.contains("wall/gran"));
        assert!(deck.contains("run 1234"));
        assert!(deck.contains("${wz2}"), "{deck}");
        assert!(!deck.contains("{{") && !deck.contains("{%"));
    }
}
