//! `sweep contact` and `sweep contact-check`: single-contact cases on the reference solver,
//! and through LIGGGHTS against it.

use std::path::PathBuf;

use super::error::CliError;
use clap::Args;
use demsweep::error::Error;

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum ContactCase {
    SphereWall,
    SphereSphere,
}

/// One impact (SI units). The contact normal is +z, tangential velocity +x, spin about +y.
/// `--case`, `--radius`, `--density`, `--youngs`, `--poisson`, `--restitution`, `--friction`
/// and `--vn` are required (checked by [`CaseArgs::case`], so that `contact-check` can take
/// the same flags optionally).
#[derive(Args)]
pub(super) struct CaseArgs {
    #[arg(long, value_enum)]
    case: Option<ContactCase>,
    /// Radius of sphere 1, m.
    #[arg(long)]
    radius: Option<f64>,
    /// Radius of sphere 2, m (sphere-sphere; default: --radius).
    #[arg(long)]
    radius2: Option<f64>,
    /// Density, kg/m^3.
    #[arg(long)]
    density: Option<f64>,
    /// Density of sphere 2, kg/m^3 (sphere-sphere; default: --density).
    #[arg(long)]
    density2: Option<f64>,
    /// Young's modulus, Pa.
    #[arg(long)]
    youngs: Option<f64>,
    /// Poisson's ratio.
    #[arg(long)]
    poisson: Option<f64>,
    /// Wall Young's modulus, Pa (sphere-wall; default: --youngs, a same-material wall as a
    /// LIGGGHTS wall type; `inf` for a rigid plane).
    #[arg(long)]
    wall_youngs: Option<f64>,
    /// Wall Poisson's ratio (sphere-wall; default: --poisson).
    #[arg(long)]
    wall_poisson: Option<f64>,
    /// Nominal restitution coefficient, 0.05 < e <= 1.
    #[arg(long)]
    restitution: Option<f64>,
    /// Coulomb friction coefficient.
    #[arg(long)]
    friction: Option<f64>,
    /// Normal approach speed, m/s (sphere-sphere: relative).
    #[arg(long)]
    vn: Option<f64>,
    /// Tangential speed, m/s (sphere-sphere: relative).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    vt: f64,
    /// Initial angular velocity of sphere 1 about +y, rad/s.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    spin: f64,
    /// Timestep, s (default: the Hertz contact time / 1000).
    #[arg(long)]
    dt: Option<f64>,
}

impl CaseArgs {
    /// Whether any flag that defines a case was given.
    fn given(&self) -> bool {
        self.case.is_some()
            || [
                self.radius,
                self.radius2,
                self.density,
                self.density2,
                self.youngs,
                self.poisson,
                self.wall_youngs,
                self.wall_poisson,
                self.restitution,
                self.friction,
                self.vn,
                self.dt,
            ]
            .iter()
            .any(Option::is_some)
            || self.vt != 0.0
            || self.spin != 0.0
    }

    fn case(&self) -> Result<demsweep::contact::Case, Error> {
        use demsweep::contact::{Case, Material, Target};
        fn need<T: Copy>(v: Option<T>, flag: &str, what: &str) -> Result<T, Error> {
            v.ok_or_else(|| super::error::flag(flag, format!("required, expected {what}")))
        }
        let radius = need(self.radius, "--radius", "a radius in m")?;
        let density = need(self.density, "--density", "a density in kg/m^3")?;
        let material = Material {
            youngs: need(self.youngs, "--youngs", "a Young's modulus in Pa")?,
            poisson: need(self.poisson, "--poisson", "a Poisson's ratio")?,
        };
        let target = match need(self.case, "--case", "sphere-wall or sphere-sphere")? {
            ContactCase::SphereWall => Target::Wall(Material {
                youngs: self.wall_youngs.unwrap_or(material.youngs),
                poisson: self.wall_poisson.unwrap_or(material.poisson),
            }),
            ContactCase::SphereSphere => Target::Sphere {
                radius: self.radius2.unwrap_or(radius),
                density: self.density2.unwrap_or(density),
            },
        };
        Ok(Case {
            target,
            radius,
            density,
            material,
            restitution: need(self.restitution, "--restitution", "0.05 < e <= 1")?,
            friction: need(self.friction, "--friction", "a friction coefficient")?,
            vn: need(self.vn, "--vn", "an approach speed in m/s")?,
            vt: self.vt,
            spin: self.spin,
            dt: self.dt,
        })
    }
}

#[derive(Args)]
pub(super) struct ContactArgs {
    #[command(flatten)]
    case: CaseArgs,
}

#[derive(Args)]
pub(super) struct ContactCheckArgs {
    /// Check this one case instead of the built-in set spanning the spreading scene's materials.
    #[command(flatten)]
    case: CaseArgs,
    /// The LIGGGHTS executable.
    #[arg(long, default_value = "liggghts")]
    engine: PathBuf,
    /// Keep each case's deck and output under this directory (default: temporary, removed).
    #[arg(long)]
    keep: Option<PathBuf>,
}

pub(super) fn contact(a: ContactArgs) -> Result<(), Error> {
    let outcome = demsweep::contact::run(&a.case.case()?)?;
    let json = serde_json::to_string_pretty(&outcome).map_err(CliError::Json)?;
    println!("{json}");
    Ok(())
}

pub(super) fn contact_check(a: ContactCheckArgs) -> Result<(), Error> {
    use demsweep::contact::check;
    let cases =
        if a.case.given() { vec![("cli".to_string(), a.case.case()?)] } else { check::default_cases() };
    let report = check::run_cases(&cases, &a.engine, a.keep.as_deref())?;
    print!("{}", report.table());
    let failed = report.cases.iter().filter(|c| !c.passed()).count();
    match failed {
        0 => Ok(()),
        failed => Err(Error::RunsFailed { failed, total: report.cases.len() }),
    }
}
