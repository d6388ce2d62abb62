//! The catalogue of scene parameters: names, units, defaults and physical domains.
//!
//! A sweep file may sweep or fix any of these; anything it does not name takes the default.
//! Units are fixed per parameter (mm for lengths a user thinks of in mm, SI otherwise) so a
//! sweep file can never mix mm and m: a `unit` written in the file must match.

/// What one parameter is.
#[derive(Debug, Clone, Copy)]
pub struct ParamInfo {
    pub name: &'static str,
    pub unit: &'static str,
    pub default: f64,
    /// Open or closed lower bound of the physical domain.
    pub min: Bound,
    pub max: Bound,
    pub description: &'static str,
}

#[derive(Debug, Clone, Copy)]
pub enum Bound {
    Open(f64),
    Closed(f64),
    None,
}

impl ParamInfo {
    pub fn accepts(&self, v: f64) -> bool {
        let lo = match self.min {
            Bound::Open(m) => v > m,
            Bound::Closed(m) => v >= m,
            Bound::None => true,
        };
        let hi = match self.max {
            Bound::Open(m) => v < m,
            Bound::Closed(m) => v <= m,
            Bound::None => true,
        };
        lo && hi
    }

    /// The domain in interval notation, for error messages.
    pub fn domain(&self) -> String {
        let lo = match self.min {
            Bound::Open(m) => format!("({m}"),
            Bound::Closed(m) => format!("[{m}"),
            Bound::None => "(-inf".into(),
        };
        let hi = match self.max {
            Bound::Open(m) => format!("{m})"),
            Bound::Closed(m) => format!("{m}]"),
            Bound::None => "inf)".into(),
        };
        format!("the domain of {} {lo}, {hi}", self.name)
    }
}

/// Every parameter the spreading scene understands. Defaults are thesis Table 3.1 mid-values.
pub const CATALOGUE: &[ParamInfo] = &[
    ParamInfo {
        name: "friction",
        unit: "-",
        default: 0.2,
        min: Bound::Closed(0.0),
        max: Bound::None,
        description: "sliding friction coefficient, particle-particle and particle-wall",
    },
    ParamInfo {
        name: "rolling_friction",
        unit: "-",
        // Rolling resistance keeps a heap of spheres at its angle of repose; spreading studies
        // use 0.01–0.3 (docs/scene.md). 0 is the thesis's setting and switches it off.
        default: 0.1,
        min: Bound::Closed(0.0),
        max: Bound::None,
        description: "rolling friction coefficient (EPSD2 model); 0 switches it off",
    },
    ParamInfo {
        name: "restitution",
        unit: "-",
        default: 0.5,
        // LIGGGHTS refuses e <= 0.05 (global_properties.cpp).
        min: Bound::Open(0.05),
        max: Bound::Closed(1.0),
        description: "coefficient of restitution",
    },
    ParamInfo {
        name: "diameter",
        unit: "mm",
        default: 2.0,
        min: Bound::Open(0.0),
        max: Bound::None,
        description: "particle diameter (the nominal one with a size distribution)",
    },
    ParamInfo {
        name: "gap",
        unit: "mm",
        default: 3.0,
        min: Bound::Open(0.0),
        max: Bound::None,
        description: "height of the blade tip above the plate",
    },
    ParamInfo {
        name: "heap_height",
        unit: "mm",
        // 10 D at the thesis's centre diameter, 2 mm: the heap every earlier result was measured
        // with at that point.
        default: 20.0,
        min: Bound::Open(0.0),
        max: Bound::None,
        description: "height of the heap held in front of the blade above its tip (conveyor layout)",
    },
    ParamInfo {
        name: "layer_thickness",
        unit: "mm",
        // 1.5 D at the default diameter, as machines print 1–3 D50 layers.
        default: 3.0,
        min: Bound::Open(0.0),
        max: Bound::None,
        description:
            "how far the platform drops between passes: the machine's layer thickness (layers layout)",
    },
    ParamInfo {
        name: "blade_speed",
        unit: "m/s",
        default: 1.4,
        min: Bound::Open(0.0),
        max: Bound::None,
        description: "blade speed in +x",
    },
    ParamInfo {
        name: "roller_speed_ratio",
        unit: "-",
        // 0: a roller that does not turn — and no roller at all elsewhere ([`ONLY_WHERE_READ`]).
        default: 0.0,
        min: Bound::None,
        max: Bound::None,
        description: "a roller's surface speed about its axis over its travel speed; counter-rotation \
                      positive, forward rolling −1 (layers layout, blade_profile = \"roller\")",
    },
    ParamInfo {
        name: "density",
        unit: "kg/m3",
        default: 7980.0,
        min: Bound::Open(0.0),
        max: Bound::None,
        description: "particle (solid) density",
    },
    ParamInfo {
        name: "youngs_modulus",
        unit: "MPa",
        default: 21.0,
        // LIGGGHTS refuses 5e6 > Y > 1e9 Pa without hard_particles (global_properties.cpp).
        min: Bound::Closed(5.0),
        max: Bound::Closed(1000.0),
        description: "Young's modulus (the thesis's reduced value is 21 MPa)",
    },
    ParamInfo {
        name: "poisson",
        unit: "-",
        default: 0.3,
        min: Bound::Closed(0.0),
        max: Bound::Closed(0.5),
        description: "Poisson's ratio",
    },
    ParamInfo {
        name: "surface_energy",
        unit: "J/m2",
        // Non-cohesive, as every scene before it. Ti-6Al-4V: about 1e-4 (docs/powders.md).
        default: 0.0,
        min: Bound::Closed(0.0),
        max: Bound::None,
        description: "surface energy per surface (JKR); the deck's SJKR cohesion (docs/powders.md); 0: none",
    },
    ParamInfo {
        name: "weibull_shape",
        unit: "-",
        default: 4.0,
        min: Bound::Open(0.0),
        max: Bound::None,
        description: "Weibull shape k of the diameter distribution (size_distribution = weibull)",
    },
    ParamInfo {
        name: "weibull_scale",
        unit: "mm",
        default: 2.0,
        min: Bound::Open(0.0),
        max: Bound::None,
        description: "Weibull scale λ of the diameter distribution (size_distribution = weibull)",
    },
];

/// Parameters a layout reads only in some of its setups (the roller's speed ratio, only with
/// `blade_profile = "roller"`). Where a point does not read one it is refused when set away from
/// its default, not only when swept — a speed ratio given for a blade would otherwise be dropped
/// without a word — and it is left out of the point's deck header and results.csv, so that the
/// points that never read it are written as before it existed.
pub const ONLY_WHERE_READ: &[&str] = &["roller_speed_ratio"];

pub fn lookup(name: &str) -> Option<&'static ParamInfo> {
    CATALOGUE.iter().find(|p| p.name == name)
}
