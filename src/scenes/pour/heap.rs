//! The heap's angle of repose and packing from the particles at rest.
//!
//! The surface profile: in each of [`SECTORS`] azimuthal sectors around the axis, the highest
//! particle top in each ring one mean diameter wide. The angle of a sector is the slope of a
//! least-squares line through its profile between the rings where it falls below 80 % and below
//! 20 % of the heap's height (the rounded top and the toe left out); the heap's angle is the
//! sectors' mean, with their standard error. The packing is the solid fraction of a cylinder
//! around the axis under the surface, from the particles whose centres lie in it (unbiased for
//! a random packing away from walls, so the cylinder starts one diameter above the plate).

use super::result::Heap;
use crate::scenes::quantity::Quantity;

/// What a calibration can fit a pour to: the heap's angle of repose, its packing, and the
/// apparent density they make.
pub const CALIBRATION_TARGETS: &[Quantity] = &[
    Quantity {
        name: "angle_of_repose",
        unit: "°",
        read: |r| super::result::heap(r).map(|h| (h.angle_deg, Some(h.angle_se_deg).filter(|s| *s > 0.0))),
        repeats: 2,
        possible: (0.0, 90.0),
        lo_possible: false,
    },
    Quantity {
        name: "bulk_packing",
        unit: "-",
        read: |r| super::result::heap(r).map(|h| (h.packing, None)),
        repeats: 2,
        // Spheres pack no denser than π/√18 (face-centred cubic).
        possible: (0.0, 0.7405),
        lo_possible: false,
    },
    // ASTM B212's apparent density (a Hall funnel's free-poured fill of a cup) as the heap's
    // packing times the material's density: both a free-poured, unconsolidated packing.
    Quantity {
        name: "apparent_density",
        unit: "g/cm³",
        read: |r| {
            let density = r.parameters.get("density")?;
            super::result::heap(r).map(|h| (h.packing * density / 1000.0, None))
        },
        repeats: 2,
        // The heap's packing (at most 0.7405) times the densest material (25,000 kg/m³).
        possible: (0.0, 20.0),
        lo_possible: false,
    },
];

/// Azimuthal sectors of the profile.
pub const SECTORS: usize = 8;
/// The profile's band fitted by a line, as fractions of the heap's height.
const FIT_TOP: f64 = 0.8;
const FIT_FOOT: f64 = 0.2;
/// Radius of the packing's cylinder, as a fraction of the foot's radius: at most this, and at
/// most where the surface is [`CORE_MIN_TOP`] diameters above the plate (the cylinder then
/// spans 2 diameters between 1 above the plate and 1 under the surface); at least
/// [`CORE_MIN_RADIUS`] diameters.
const CORE_FRACTION: f64 = 0.4;
const CORE_MIN_TOP: f64 = 4.0;
const CORE_MIN_RADIUS: f64 = 2.0;

/// A particle at rest: centre (m) and radius (m).
#[derive(Debug, Clone, Copy)]
pub struct Grain {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub r: f64,
}

/// Why a heap cannot be measured: too low, or a sector without a slope to fit. Heights in m.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HeapError {
    #[error("the heap is {:.2} mm tall, under 5 diameters: nothing to fit", .height * 1e3)]
    Low { height: f64 },
    /// A sector whose slope spans fewer than 3 rings.
    #[error("sector {sector} of {SECTORS}: its slope spans {rings} rings of one diameter, under the 3 a line needs")]
    ShortSlope { sector: usize, rings: usize },
    #[error("sector {sector} of {SECTORS}: the surface does not fall away from the axis")]
    NoSlope { sector: usize },
    /// A core narrower than [`CORE_MIN_RADIUS`] diameters where it is [`CORE_MIN_TOP`] tall.
    #[error(
        "the heap stands {:.2} mm tall: its core is under 2 diameters wide where it is {CORE_MIN_TOP} \
         diameters tall, no packing to measure",
        .height * 1e3
    )]
    NarrowCore { height: f64 },
}

/// The heap of `grains` around the vertical axis at `axis`, on the plate z = 0, profiled in
/// rings `ring` wide; an error says why the heap cannot be measured.
pub fn measure(grains: &[Grain], axis: [f64; 2], ring: f64) -> Result<Heap, HeapError> {
    let polar = |g: &Grain| {
        let (dx, dy) = (g.x - axis[0], g.y - axis[1]);
        (dx.hypot(dy), dy.atan2(dx).rem_euclid(std::f64::consts::TAU))
    };
    let height = grains.iter().map(|g| g.z + g.r).fold(0.0, f64::max);
    if height < 5.0 * ring {
        return Err(HeapError::Low { height });
    }
    let rings = grains.iter().map(|g| (polar(g).0 / ring) as usize + 1).max().unwrap_or(0);
    let mut profile = vec![vec![0.0f64; rings]; SECTORS];
    for g in grains {
        let (rho, phi) = polar(g);
        let s = ((phi / std::f64::consts::TAU * SECTORS as f64) as usize).min(SECTORS - 1);
        let top = &mut profile[s][(rho / ring) as usize];
        *top = top.max(g.z + g.r);
    }
    let mut angles = Vec::with_capacity(SECTORS);
    let mut feet = Vec::with_capacity(SECTORS);
    let mut lines = Vec::with_capacity(SECTORS);
    for (s, p) in profile.iter().enumerate() {
        // Outward from the sector's highest ring (the rings at the axis are small and may be
        // empty): the first ring under 80 % of the height, then the first under 20 %.
        let top = p.iter().enumerate().fold(0, |best, (k, &h)| if h > p[best] { k } else { best });
        let first_under = |from: usize, f: f64| {
            p[from..].iter().position(|&h| h < f * height).map_or(p.len(), |k| from + k)
        };
        let a = first_under(top, FIT_TOP);
        let b = first_under(a, FIT_FOOT);
        let points: Vec<(f64, f64)> = (a..b).map(|k| ((k as f64 + 0.5) * ring, p[k])).collect();
        if points.len() < 3 {
            return Err(HeapError::ShortSlope { sector: s, rings: points.len() });
        }
        let (intercept, slope) = fit_line(&points);
        if slope >= 0.0 {
            return Err(HeapError::NoSlope { sector: s });
        }
        angles.push((-slope).atan().to_degrees());
        feet.push(-intercept / slope);
        lines.push((intercept, slope));
    }
    let n = SECTORS as f64;
    let angle = angles.iter().sum::<f64>() / n;
    let sd = (angles.iter().map(|a| (a - angle).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let foot = feet.iter().sum::<f64>() / n;
    // The packing's cylinder: under the lowest sector line at its rim, a diameter below it, and
    // at least 2 diameters tall; a low heap's is narrower than CORE_FRACTION of the foot.
    let tall_enough = lines.iter().map(|(a, b)| (a - CORE_MIN_TOP * ring) / -b).fold(f64::INFINITY, f64::min);
    let core = (CORE_FRACTION * foot).min(tall_enough);
    if core < CORE_MIN_RADIUS * ring {
        return Err(HeapError::NarrowCore { height });
    }
    let z_top = lines.iter().map(|(a, b)| a + b * core).fold(height, f64::min) - ring;
    let (z_bottom, cylinder) = (ring, std::f64::consts::PI * core * core * (z_top - ring));
    let solid: f64 = grains
        .iter()
        .filter(|g| polar(g).0 < core && g.z >= z_bottom && g.z < z_top)
        .map(|g| 4.0 / 3.0 * std::f64::consts::PI * g.r.powi(3))
        .sum();
    let run_out = grains.iter().filter(|g| polar(g).0 > foot + 2.0 * ring).count();
    Ok(Heap {
        angle_deg: angle,
        angle_se_deg: sd / n.sqrt(),
        sector_angles_deg: angles,
        height_mm: height * 1e3,
        base_radius_mm: foot * 1e3,
        packing: solid / cylinder,
        particles_in_heap: grains.len() - run_out,
        particles_run_out: run_out,
    })
}

/// Least-squares line through `points`: (intercept, slope).
fn fit_line(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (mx, my) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    let slope = sxy / sxx;
    (my - slope * mx, slope)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cone of angle `deg` and height `h` filled with spheres of diameter `d` on a simple
    /// cubic lattice (packing π/6), tilted by `tilt_deg` towards +x (a skew heap).
    fn cone(deg: f64, h: f64, d: f64, tilt_deg: f64) -> Vec<Grain> {
        let foot = h / deg.to_radians().tan();
        let n = (foot / d).ceil() as i64 + 2;
        let mut g = Vec::new();
        for i in -n..=n {
            for j in -n..=n {
                for k in 0..=((h / d) as i64) {
                    let (x, y, z) = (i as f64 * d, j as f64 * d, (k as f64 + 0.5) * d);
                    let rho = x.hypot(y);
                    let surface = h - rho * deg.to_radians().tan() + x * tilt_deg.to_radians().tan();
                    if z + 0.5 * d <= surface {
                        g.push(Grain { x: x + 0.1, y: y - 0.2, z, r: 0.5 * d });
                    }
                }
            }
        }
        g
    }

    #[test]
    fn a_lattice_cone_gives_back_its_angle_and_packing() {
        for deg in [20.0, 30.0, 40.0] {
            let d = 1e-3;
            let heap = measure(&cone(deg, 30e-3, d, 0.0), [0.1, -0.2], d).unwrap();
            // The profile steps by whole diameters, so the fit is within a degree or two.
            assert!((heap.angle_deg - deg).abs() < 2.0, "{deg}: {heap:?}");
            assert!(heap.angle_se_deg < 1.0, "{heap:?}");
            // The foot of a cone 30 mm tall, within two diameters.
            let foot = 30.0 / deg.to_radians().tan();
            assert!((heap.base_radius_mm - foot).abs() < 2.0, "{deg}: {heap:?}");
            // A simple cubic lattice packs π/6 = 0.524.
            assert!((heap.packing - std::f64::consts::PI / 6.0).abs() < 0.03, "{heap:?}");
            assert_eq!(heap.particles_run_out, 0);
        }
    }

    #[test]
    fn a_low_heap_measures_its_packing_in_a_narrower_core() {
        // 18° and 5.5 D tall: at 0.4 of the foot the surface is 3.3 D up, too low for a core
        // 2 D tall; the core narrows to where the surface is 4 D up.
        let d = 1e-3;
        let heap = measure(&cone(18.0, 5.5e-3, d, 0.0), [0.1, -0.2], d).unwrap();
        assert!((heap.angle_deg - 18.0).abs() < 3.0, "{heap:?}");
        // A core about 3 D across holds a few dozen lattice sites per layer, so counting
        // centres misses π/6 by up to ~0.1 on a lattice (a random packing has no such bias).
        assert!((heap.packing - std::f64::consts::PI / 6.0).abs() < 0.1, "{heap:?}");
    }

    #[test]
    fn a_skew_heap_shows_in_the_sectors_and_its_standard_error() {
        let d = 1e-3;
        let even = measure(&cone(30.0, 30e-3, d, 0.0), [0.1, -0.2], d).unwrap();
        let skew = measure(&cone(30.0, 30e-3, d, 5.0), [0.1, -0.2], d).unwrap();
        // Shallower towards +x (sector 0), steeper towards −x (sector 4).
        assert!(skew.sector_angles_deg[0] < skew.sector_angles_deg[4] - 5.0, "{skew:?}");
        assert!(skew.angle_se_deg > 3.0 * even.angle_se_deg.max(0.1), "{skew:?} {even:?}");
    }

    #[test]
    fn a_flat_spill_is_refused_with_its_reason() {
        let d = 1e-3;
        let flat: Vec<Grain> = (0..400)
            .map(|i| Grain { x: (i % 20) as f64 * d, y: (i / 20) as f64 * d, z: 0.5 * d, r: 0.5 * d })
            .collect();
        let e = measure(&flat, [0.01, 0.01], d).unwrap_err().to_string();
        assert!(e.contains("under 5 diameters"), "{e}");
    }

    #[test]
    fn the_line_fit_is_exact_on_a_line() {
        let (a, b) = fit_line(&[(1.0, 5.0), (2.0, 3.0), (4.0, -1.0)]);
        assert!((a - 7.0).abs() < 1e-12 && (b + 2.0).abs() < 1e-12);
    }
}
