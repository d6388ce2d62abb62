//! A reference solver for ONE Hertz–Mindlin contact, and its check against LIGGGHTS.
//!
//! A sphere hits a flat wall, or two spheres collide, with LIGGGHTS 3.8's
//! `model hertz tangential history` (Hertz normal spring with viscous damping from the
//! restitution coefficient, Mindlin tangential spring with history and the Coulomb limit,
//! rotation) integrated by velocity Verlet as `fix nve/sphere` does. [`run`] reports the
//! quantities a contact model is verified with: contact duration, maximum overlap, normal and
//! tangential restitution, rebound spin, stick or slide. [`check`] runs the same cases through
//! the installed LIGGGHTS and compares them quantity by quantity.
//!
//! Geometry: the impact plane is x–z; the contact normal is +z (sphere 1 above the wall at
//! z = 0, or above sphere 2); tangential velocity is along +x and spin about +y. No gravity.
//!
//! Not here: many-body contacts, rolling friction, cohesion, `limitForce on`, moving walls,
//! mesh walls. All quantities are SI.

pub mod analysis;
pub mod bounce;
pub mod check;
pub mod model;
pub mod solver;

pub use analysis::{Outcome, Regime};
pub use model::Material;

/// Errors of the contact solver and of its LIGGGHTS check.
#[derive(Debug, thiserror::Error)]
pub enum ContactError {
    /// A case parameter is out of range.
    #[error("--{name} {value}: expected {expected}")]
    Input { name: &'static str, value: f64, expected: &'static str },
    /// The bodies were still in contact after the step limit (should not happen for e > 0.05).
    #[error("the bodies did not separate within {steps} steps of {dt:e} s")]
    NoSeparation { steps: usize, dt: f64 },
    /// The centres passed through each other (a wall: sphere 1's centre crossed the wall
    /// plane), where the contact normal flips and the contact law means nothing. Hertz's
    /// elastic estimate of the maximum overlap says how far out of range the case is.
    #[error(
        "the bodies passed through each other: the Hertz overlap {hertz_overlap:.3e} m reaches \
         {reach:.3e} m (the centre crosses); stiffen --youngs/--wall-youngs or lower --vn"
    )]
    PassedThrough { hertz_overlap: f64, reach: f64 },
    /// The operation does not apply to this kind of case.
    #[error("{0}")]
    Unsupported(&'static str),
    /// LIGGGHTS could not be started or failed on a case.
    #[error("{0}")]
    Engine(String),
    /// The LIGGGHTS output of a case could not be read.
    #[error("{path}:{line}: {message}")]
    Output { path: String, line: usize, message: String },
    /// A recorded trajectory does not show one complete impact.
    #[error("the trajectory cannot be analysed: {0}")]
    Analysis(String),
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// Bad case parameters are input errors (exit 2); LIGGGHTS failures are engine errors (3).
impl From<ContactError> for crate::Error {
    fn from(e: ContactError) -> Self {
        use ContactError as C;
        match e {
            C::Input { .. } | C::PassedThrough { .. } => crate::Error::Input(Box::new(e)),
            C::Engine(_) | C::Output { .. } => crate::Error::Engine(Box::new(e)),
            C::NoSeparation { .. } | C::Analysis(_) | C::Unsupported(_) | C::Io(_) => {
                crate::Error::Internal(Box::new(e))
            }
        }
    }
}

/// What sphere 1 hits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// A flat wall at z = 0 with its own elastic constants (LIGGGHTS: the wall's atom type).
    Wall(Material),
    /// A second sphere of this radius (m) and density (kg/m³), of sphere 1's material.
    Sphere { radius: f64, density: f64 },
}

/// One impact. For sphere–sphere, `vn`, `vt` are relative velocities (sphere 1 minus sphere 2)
/// and the spheres start in their centre-of-mass frame; `spin` is sphere 1's only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Case {
    pub target: Target,
    /// Sphere 1 radius in m.
    pub radius: f64,
    /// Sphere 1 density in kg/m³.
    pub density: f64,
    /// Sphere 1 (and sphere 2) material.
    pub material: Material,
    /// Nominal restitution coefficient e, 0.05 < e ≤ 1 (LIGGGHTS' range).
    pub restitution: f64,
    /// Coulomb friction coefficient μ ≥ 0.
    pub friction: f64,
    /// Normal approach speed in m/s, > 0.
    pub vn: f64,
    /// Tangential velocity in m/s (+x).
    pub vt: f64,
    /// Initial angular velocity of sphere 1 about +y, rad/s.
    pub spin: f64,
    /// Timestep in s; `None` for [`DEFAULT_STEPS_PER_CONTACT`] steps per Hertz contact time.
    pub dt: Option<f64>,
}

/// The default timestep is the elastic Hertz contact time divided by this: fine enough that
/// the outcome is converged to ~1e-5 (docs/contact.md), cheap enough for a few ms per case.
pub const DEFAULT_STEPS_PER_CONTACT: f64 = 1000.0;

impl Case {
    /// Checks every parameter; the error names the flag.
    pub fn validate(&self) -> Result<(), ContactError> {
        fn check(
            name: &'static str,
            value: f64,
            ok: bool,
            expected: &'static str,
        ) -> Result<(), ContactError> {
            if ok && !value.is_nan() {
                Ok(())
            } else {
                Err(ContactError::Input { name, value, expected })
            }
        }
        let positive = |v: f64| v > 0.0 && v.is_finite();
        check("radius", self.radius, positive(self.radius), "a positive radius in m")?;
        check("density", self.density, positive(self.density), "a positive density in kg/m^3")?;
        check(
            "youngs",
            self.material.youngs,
            positive(self.material.youngs),
            "a positive Young's modulus in Pa",
        )?;
        check(
            "poisson",
            self.material.poisson,
            (0.0..=0.5).contains(&self.material.poisson),
            "0 <= nu <= 0.5",
        )?;
        check(
            "restitution",
            self.restitution,
            self.restitution > 0.05 && self.restitution <= 1.0,
            "0.05 < e <= 1 (the range LIGGGHTS accepts)",
        )?;
        check(
            "friction",
            self.friction,
            self.friction >= 0.0 && self.friction.is_finite(),
            "a friction coefficient >= 0",
        )?;
        check("vn", self.vn, positive(self.vn), "a positive approach speed in m/s")?;
        check("vt", self.vt, self.vt.is_finite(), "a finite speed in m/s")?;
        check("spin", self.spin, self.spin.is_finite(), "a finite rate in rad/s")?;
        if let Some(dt) = self.dt {
            check("dt", dt, positive(dt), "a positive timestep in s")?;
        }
        match self.target {
            Target::Wall(w) => {
                check(
                    "wall-youngs",
                    w.youngs,
                    w.youngs > 0.0,
                    "a positive Young's modulus in Pa (inf: rigid)",
                )?;
                check("wall-poisson", w.poisson, (0.0..=0.5).contains(&w.poisson), "0 <= nu <= 0.5")?;
            }
            Target::Sphere { radius, density } => {
                check("radius2", radius, positive(radius), "a positive radius in m")?;
                check("density2", density, positive(density), "a positive density in kg/m^3")?;
            }
        }
        Ok(())
    }

    /// Sphere 1 mass in kg: 4/3 π r³ ρ (LIGGGHTS `set density` for a sphere).
    pub fn mass(&self) -> f64 {
        sphere_mass(self.radius, self.density)
    }

    /// The overlap at which the centres cross: sphere 1's radius against a wall (its centre
    /// reaches the wall plane), r1 + r2 for two spheres.
    pub fn crossing_overlap(&self) -> f64 {
        self.radius + self.sphere2().map_or(0.0, |(r2, _)| r2)
    }

    /// The error for a case whose bodies passed through each other.
    pub fn passed_through(&self) -> ContactError {
        ContactError::PassedThrough {
            hertz_overlap: self.pair().hertz_max_overlap(self.vn),
            reach: self.crossing_overlap(),
        }
    }

    /// Sphere 2 radius and mass, if there is a sphere 2.
    pub fn sphere2(&self) -> Option<(f64, f64)> {
        match self.target {
            Target::Wall(_) => None,
            Target::Sphere { radius, density } => Some((radius, sphere_mass(radius, density))),
        }
    }

    /// The pair coefficients of this case (`normal_model_hertz.h`: R* = ri against a wall,
    /// m* = mi against a wall).
    pub fn pair(&self) -> model::Pair {
        let m1 = self.mass();
        let (other, r_eff, m_eff) = match self.target {
            Target::Wall(w) => (w, self.radius, m1),
            Target::Sphere { radius, density } => {
                let m2 = sphere_mass(radius, density);
                (self.material, self.radius * radius / (self.radius + radius), m1 * m2 / (m1 + m2))
            }
        };
        model::Pair {
            y_eff: model::effective_youngs(self.material, other),
            g_eff: model::effective_shear(self.material, other),
            beta: model::beta(self.restitution),
            friction: self.friction,
            r_eff,
            m_eff,
        }
    }

    /// The timestep: the given one, or the Hertz contact time / [`DEFAULT_STEPS_PER_CONTACT`].
    pub fn timestep(&self) -> f64 {
        self.dt.unwrap_or_else(|| self.pair().hertz_time(self.vn) / DEFAULT_STEPS_PER_CONTACT)
    }
}

fn sphere_mass(radius: f64, density: f64) -> f64 {
    4.0 / 3.0 * std::f64::consts::PI * radius.powi(3) * density
}

/// Runs one case on the reference solver and reports its outcome.
pub fn run(case: &Case) -> Result<Outcome, ContactError> {
    case.validate()?;
    let trajectory = solver::simulate(case, case.timestep())?;
    analysis::analyse(case, &trajectory.samples, trajectory.steps)
}
