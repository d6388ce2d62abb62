//! A timestep ladder through the reference solver and LIGGGHTS ([`check::run_cases`]): where
//! the two part from each other, and where each parts from the closed form.
//!
//! The timestep is a fraction of the elastic Hertz contact time t_c (dt = t_c/n). Per case and
//! level the same impact runs both ways from the same initial numbers; the difference is the
//! largest relative difference of any compared quantity or trajectory state (the
//! `contact-check` table), and each side is also compared with the case's closed form.

use std::path::Path;

use serde::Serialize;

use super::{scene_case, CLOSED_FORM_TOLERANCE, SCENE_DENSITY, STEEL};
use crate::bench::cell;
use crate::contact::analysis::Outcome;
use crate::contact::check::{self, TOLERANCE};
use crate::contact::{Case, ContactError, Target};

/// What a case is compared with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ClosedForm {
    /// e = 1, head-on: contact time and maximum overlap of Hertz theory, restitution 1.
    Elastic,
    /// Head-on, damped: the nominal restitution (relative error).
    Restitution(f64),
    /// Rigid-body sliding throughout (e = 1, fixed normal, lever arm r): tangential
    /// restitution −1 + 3.5 μ(1+e) vn/vt (absolute error) and rebound spin
    /// 2.5 μ(1+e) vn/r (relative error).
    Sliding,
}

impl ClosedForm {
    /// The largest error of `o` against this closed form for `case`.
    pub fn error(&self, case: &Case, o: &Outcome) -> f64 {
        let pair = case.pair();
        match *self {
            ClosedForm::Elastic => [
                o.contact_time / pair.hertz_time(case.vn) - 1.0,
                o.max_overlap / pair.hertz_max_overlap(case.vn) - 1.0,
                o.restitution_n - 1.0,
            ]
            .iter()
            .fold(0.0, |m: f64, v| m.max(v.abs())),
            ClosedForm::Restitution(e) => (o.restitution_n / e - 1.0).abs(),
            ClosedForm::Sliding => {
                let impulse = case.friction * (1.0 + case.restitution) * case.vn;
                let e_t = -1.0 + 3.5 * impulse / case.vt;
                let omega = 2.5 * impulse / case.radius;
                let e_t_err = o.restitution_t.map_or(f64::INFINITY, |v| (v - e_t).abs());
                e_t_err.max((o.omega_out / omega - 1.0).abs()).max((o.restitution_n - 1.0).abs())
            }
        }
    }
}

/// The ladder's cases: the scene's D 2 mm particle head-on on a same-material wall (elastic and
/// e = 0.5) and on a second particle (elastic: the pair code path of LIGGGHTS), and a steel
/// sphere sliding on a steel wall (μ 0.2, vt/vn = 5, past the stick threshold 3.5 μ(1+e) = 1.4).
pub fn default_cases() -> Vec<(&'static str, Case, ClosedForm)> {
    let base = scene_case();
    let sphere = Target::Sphere { radius: base.radius, density: SCENE_DENSITY };
    vec![
        ("wall-elastic", base, ClosedForm::Elastic),
        ("wall-damped", Case { restitution: 0.5, ..base }, ClosedForm::Restitution(0.5)),
        ("pair-elastic", Case { target: sphere, ..base }, ClosedForm::Elastic),
        (
            "wall-slide-steel",
            Case { material: STEEL, target: Target::Wall(STEEL), friction: 0.2, vt: 5.0, ..base },
            ClosedForm::Sliding,
        ),
    ]
}

/// Steps per Hertz contact time, finest first: from 10× the default to a step of two contact
/// times (the rebound is then 36 times the approach: nothing is left to learn beyond).
pub const DEFAULT_LADDER: [f64; 12] =
    [10000.0, 1000.0, 100.0, 50.0, 20.0, 10.0, 5.0, 3.0, 2.0, 1.5, 1.0, 0.5];

/// One case at one timestep, both ways.
#[derive(Debug, Clone, Serialize)]
pub struct LadderRow {
    pub case: String,
    /// Hertz contact time / dt.
    pub steps_per_contact: f64,
    pub dt_s: f64,
    /// dt over the particle's Rayleigh time (the unit of the scene's timestep).
    pub dt_over_rayleigh: f64,
    pub solver_restitution_n: Option<f64>,
    pub liggghts_restitution_n: Option<f64>,
    pub solver_contact_time_s: Option<f64>,
    pub liggghts_contact_time_s: Option<f64>,
    pub solver_restitution_t: Option<f64>,
    pub liggghts_restitution_t: Option<f64>,
    pub solver_omega_out: Option<f64>,
    pub liggghts_omega_out: Option<f64>,
    /// Largest relative difference solver–LIGGGHTS over the `contact-check` quantities and the
    /// trajectory.
    pub engine_diff: Option<f64>,
    pub solver_closed_form_error: Option<f64>,
    pub liggghts_closed_form_error: Option<f64>,
    /// Why a side failed, if it did.
    pub error: String,
}

impl LadderRow {
    /// The row of case `case` at `steps_per_contact`, its timestep `dt_s` (`dt_over_rayleigh`
    /// Rayleigh times), before either side has run: nothing measured, no error.
    fn new(case: &str, steps_per_contact: f64, dt_s: f64, dt_over_rayleigh: f64) -> LadderRow {
        LadderRow {
            case: case.to_string(),
            steps_per_contact,
            dt_s,
            dt_over_rayleigh,
            solver_restitution_n: None,
            liggghts_restitution_n: None,
            solver_contact_time_s: None,
            liggghts_contact_time_s: None,
            solver_restitution_t: None,
            liggghts_restitution_t: None,
            solver_omega_out: None,
            liggghts_omega_out: None,
            engine_diff: None,
            solver_closed_form_error: None,
            liggghts_closed_form_error: None,
            error: String::new(),
        }
    }
}

/// Runs every case at every `ladder` entry through the solver and `engine`. The cases of one
/// level run at once (a LIGGGHTS start is mostly waiting), levels one after another.
pub fn run(
    cases: &[(&str, Case, ClosedForm)],
    ladder: &[f64],
    engine: &Path,
) -> Result<Vec<LadderRow>, ContactError> {
    for (_, case, _) in cases {
        case.validate()?;
    }
    let mut rows = Vec::new();
    for &n in ladder {
        let level: Vec<LadderRow> = std::thread::scope(|scope| {
            let handles: Vec<_> = cases
                .iter()
                .map(|(name, case, cf)| scope.spawn(move || row(name, case, *cf, n, engine)))
                .collect();
            handles.into_iter().map(|h| h.join().expect("a ladder thread panicked")).collect()
        });
        rows.extend(level);
    }
    Ok(rows)
}

fn row(name: &str, case: &Case, closed: ClosedForm, n: f64, engine: &Path) -> LadderRow {
    let dt = case.pair().hertz_time(case.vn) / n;
    let case = Case { dt: Some(dt), ..*case };
    let rayleigh =
        crate::scene::rayleigh_time(case.radius, case.density, case.material.youngs, case.material.poisson);
    let mut r = LadderRow::new(name, n, dt, dt / rayleigh);
    let solver = crate::contact::run(&case);
    if let Ok(o) = &solver {
        r.solver_restitution_n = Some(o.restitution_n);
        r.solver_contact_time_s = Some(o.contact_time);
        r.solver_restitution_t = o.restitution_t;
        r.solver_omega_out = Some(o.omega_out);
        r.solver_closed_form_error = Some(closed.error(&case, o));
    }
    match check::run_cases(&[(name.to_string(), case)], engine, None) {
        Ok(report) => {
            let c = &report.cases[0];
            let o = &c.liggghts;
            r.liggghts_restitution_n = Some(o.restitution_n);
            r.liggghts_contact_time_s = Some(o.contact_time);
            r.liggghts_restitution_t = o.restitution_t;
            r.liggghts_omega_out = Some(o.omega_out);
            r.liggghts_closed_form_error = Some(closed.error(&case, o));
            let regime_differs = c.reference.regime != c.liggghts.regime;
            r.engine_diff = Some(if regime_differs {
                f64::INFINITY
            } else {
                c.quantities.iter().map(|q| q.rel_diff).fold(0.0, f64::max)
            });
        }
        Err(e) => r.error = e.to_string(),
    }
    if let Err(e) = solver {
        r.error = format!("solver: {e}");
    }
    r
}

/// Per case: the coarsest level up to which (from the finest) a measure stays within its
/// tolerance, and the first level beyond it.
#[derive(Debug, Clone, PartialEq)]
pub struct Divergence {
    pub case: String,
    /// Solver against LIGGGHTS within [`TOLERANCE`]: (last level within, first level beyond),
    /// as steps per contact.
    pub engines: (Option<f64>, Option<f64>),
    /// The solver against its closed form within [`CLOSED_FORM_TOLERANCE`].
    pub solver_closed_form: (Option<f64>, Option<f64>),
    /// LIGGGHTS against the closed form within [`CLOSED_FORM_TOLERANCE`].
    pub liggghts_closed_form: (Option<f64>, Option<f64>),
}

/// The divergence points of each case, from rows in ladder order (finest first).
pub fn divergence(rows: &[LadderRow]) -> Vec<Divergence> {
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.case.as_str()) {
            names.push(&r.case);
        }
    }
    names
        .into_iter()
        .map(|name| {
            let mine: Vec<&LadderRow> = rows.iter().filter(|r| r.case == name).collect();
            let edge = |within: &dyn Fn(&LadderRow) -> bool| {
                let first_out = mine.iter().position(|r| !within(r));
                let last_in = match first_out {
                    Some(0) => None,
                    Some(k) => Some(mine[k - 1].steps_per_contact),
                    None => mine.last().map(|r| r.steps_per_contact),
                };
                (last_in, first_out.map(|k| mine[k].steps_per_contact))
            };
            let ok = |v: Option<f64>, tol: f64| v.is_some_and(|v| v <= tol);
            Divergence {
                case: name.to_string(),
                engines: edge(&|r| ok(r.engine_diff, TOLERANCE)),
                solver_closed_form: edge(&|r| ok(r.solver_closed_form_error, CLOSED_FORM_TOLERANCE)),
                liggghts_closed_form: edge(&|r| ok(r.liggghts_closed_form_error, CLOSED_FORM_TOLERANCE)),
            }
        })
        .collect()
}

/// A fixed-width table of the rows, then one line per case with its divergence points.
pub fn table(rows: &[LadderRow]) -> String {
    let mut out = format!(
        "{:<17} {:>7} {:>10} {:>7} {:>12} {:>12} {:>9} {:>9} {:>9}  error\n",
        "case", "t_c/dt", "dt s", "dt/T_R", "e_n solver", "e_n liggghts", "diff", "cf solver", "cf liggg."
    );
    let num = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.8}"));
    for r in rows {
        out += &format!(
            "{:<17} {:>7} {:>10.3e} {:>7.4} {:>12} {:>12} {:>9} {:>9} {:>9}  {}\n",
            r.case,
            r.steps_per_contact,
            r.dt_s,
            r.dt_over_rayleigh,
            num(r.solver_restitution_n),
            num(r.liggghts_restitution_n),
            cell(r.engine_diff),
            cell(r.solver_closed_form_error),
            cell(r.liggghts_closed_form_error),
            r.error
        );
    }
    let show = |(within, beyond): (Option<f64>, Option<f64>)| {
        let w = within.map_or("none".to_string(), |n| format!("t_c/{n}"));
        let b = beyond.map_or("never on the ladder".to_string(), |n| format!("parts at t_c/{n}"));
        format!("within down to {w}, {b}")
    };
    for d in divergence(rows) {
        out += &format!(
            "{}: solver vs LIGGGHTS (tol {TOLERANCE:e}) {}; solver vs closed form (tol {CLOSED_FORM_TOLERANCE}) {}; \
             LIGGGHTS vs closed form {}\n",
            d.case,
            show(d.engines),
            show(d.solver_closed_form),
            show(d.liggghts_closed_form)
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ladder_row(case: &str, n: f64, diff: Option<f64>, cf: Option<f64>) -> LadderRow {
        LadderRow {
            solver_restitution_n: Some(0.5),
            liggghts_restitution_n: diff.map(|_| 0.5),
            engine_diff: diff,
            solver_closed_form_error: cf,
            liggghts_closed_form_error: cf,
            ..LadderRow::new(case, n, 1e-6, 0.1)
        }
    }

    #[test]
    fn divergence_is_the_first_level_beyond_the_tolerance_from_the_finest() {
        let rows = vec![
            ladder_row("a", 1000.0, Some(1e-14), Some(1e-4)),
            ladder_row("b", 1000.0, Some(1e-14), Some(0.5)),
            ladder_row("a", 10.0, Some(1e-12), Some(2e-2)),
            ladder_row("b", 10.0, None, Some(0.5)),
            // Back within after a failure does not count: the edge is the first failure.
            ladder_row("a", 1.0, Some(1e-6), Some(1e-3)),
            ladder_row("b", 1.0, Some(1e-14), Some(0.5)),
        ];
        let d = divergence(&rows);
        assert_eq!(d[0].case, "a");
        assert_eq!(d[0].engines, (Some(10.0), Some(1.0)));
        assert_eq!(d[0].solver_closed_form, (Some(1000.0), Some(10.0)));
        assert_eq!(d[1].engines, (Some(1000.0), Some(10.0)));
        assert_eq!(d[1].liggghts_closed_form, (None, Some(1000.0)));
        let text = table(&rows);
        assert!(
            text.contains("a: solver vs LIGGGHTS (tol 1e-9) within down to t_c/10, parts at t_c/1"),
            "{text}"
        );
    }

    #[test]
    fn sliding_closed_form_is_rigid_body_theory() {
        let (_, case, cf) = default_cases().remove(3);
        assert_eq!(cf, ClosedForm::Sliding);
        // μ 0.2, e 1, vn 1, vt 5, r 1 mm: e_t = −1 + 3.5·0.4/5 = −0.72, ω = 2.5·0.4/1e-3 = 1000.
        let exact = Outcome {
            contact_time: 1e-6,
            max_overlap: 1e-7,
            restitution_n: 1.0,
            restitution_t: Some(-0.72),
            omega_out: 1000.0,
            omega2_out: None,
            regime: crate::contact::Regime::Slide,
            steps: 1,
            dt: 1e-9,
        };
        assert!(cf.error(&case, &exact) < 1e-12);
        let off = Outcome { omega_out: 1010.0, ..exact };
        assert!((cf.error(&case, &off) - 0.01).abs() < 1e-12);
    }
}
