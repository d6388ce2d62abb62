//! Plausibility: is a point inside what the scene is built for, or is it a unit slip?
//!
//! Lengths are in mm and a value written in metres (0.002 for 2 mm) passes every domain check
//! but gives a point no one meant: a 37-million-particle pile, or a gap no sphere fits under.
//! A point far outside the bounds below is refused before anything is written, with one line
//! naming the value, its unit and the likely slip; `--force` runs it anyway. Not responsible for
//! the physical domains of the parameters (that is [`crate::scene::params`]) nor for the
//! measured stability bound of the timestep ([`crate::scene::check_rayleigh_fraction`]).

use std::collections::BTreeMap;

use crate::scene::settings::{SceneSettings, SizeDistributionSpec};
use crate::scene::Scene;

/// Most particles (the dose; the substrate is not counted) the scene is built for: 40× the
/// largest point of the shipped sweeps (4,950 at D 1 mm, gap 5 mm, reference fidelity; 2,304 at
/// the fast one, a point of about 7 CPU s).
pub const MAX_PARTICLES: usize = 200_000;
/// Smallest mean diameter, mm (10 µm): below it cohesion, which the scene leaves out, dominates.
pub const MIN_DIAMETER_MM: f64 = 0.01;
/// Largest mean diameter, mm: a recoater spreads powder, not gravel.
pub const MAX_DIAMETER_MM: f64 = 20.0;
/// Smallest gap, in mean diameters: below it not even a sphere resting in a pocket fits under
/// the blade (that starts at 0.55 D), so such a point is a sure zero or a slip.
pub const MIN_GAP_DIAMETERS: f64 = 0.1;
/// Blade speeds the scene is built for, m/s: recoaters run at 10–500 mm/s, the thesis at
/// 1.2–1.6 m/s; above 10 m/s is a speed written in mm/s, below 1 mm/s a run that never ends.
pub const BLADE_SPEED_M_S: (f64, f64) = (0.001, 10.0);
/// Particle densities the scene is built for, kg/m³: polymers (≈ 1,000) to tungsten
/// (19,300); outside is a density written in g/cm³ (7.98 for steel) or a slip of exponent.
pub const DENSITY_KG_M3: (f64, f64) = (100.0, 25_000.0);
/// Smallest timestep, as a fraction of the Rayleigh time: 10× finer than the reference fidelity.
pub const MIN_RAYLEIGH_FRACTION: f64 = 0.01;

/// What a refusal says after it: the way past it.
const FORCE: &str = "(--force runs it anyway)";

/// A point far outside what the scene is built for: the value in its unit, the bound, and what
/// was probably meant. Lengths in mm, as written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OutOfBounds {
    /// The mean diameter (set by `name`, written as `value`) below [`MIN_DIAMETER_MM`].
    #[error(
        "{name} {} mm: below the {} µm the scene is built for; values are in mm — did you mean {}? {FORCE}",
        show(*.value),
        show(MIN_DIAMETER_MM * 1e3),
        show(*.value * 1e3)
    )]
    SmallDiameter { name: &'static str, value: f64 },
    /// The mean diameter above [`MAX_DIAMETER_MM`].
    #[error(
        "{name} {} mm: above the {} mm the scene is built for; values are in mm — did you mean {}? {FORCE}",
        show(*.value),
        show(MAX_DIAMETER_MM),
        show(*.value / 1e3)
    )]
    LargeDiameter { name: &'static str, value: f64 },
    /// A gap below [`MIN_GAP_DIAMETERS`] of the mean diameter `d`.
    #[error(
        "gap {} mm: below {} D (D = {} mm), where nothing passes under the blade; values are in \
         mm — did you mean {}? {FORCE}",
        show(*.gap),
        show(MIN_GAP_DIAMETERS),
        show(*.d),
        show(*.gap * 1e3)
    )]
    Gap { gap: f64, d: f64 },
    /// More than [`MAX_PARTICLES`] in the dose (or the held heap of height `heap` above the
    /// gap), at the diameter written as `value` of `name`.
    #[error(
        "{} particles at gap {} mm{} and {name} {} mm (gap = {} D): more than the {MAX_PARTICLES} the \
         scene is built for; values are in mm — lower the {} or raise the diameter {FORCE}",
        count(.particles),
        show(*.gap),
        heap_of(.heap),
        show(*.value),
        show(ratio(.gap, .d)),
        lower(.heap)
    )]
    Particles { particles: usize, gap: f64, d: f64, heap: Option<f64>, name: &'static str, value: f64 },
    /// A timestep below [`MIN_RAYLEIGH_FRACTION`] of the Rayleigh time; `steps` the run would take.
    #[error(
        "timestep {timestep:.3e} s: {} of the Rayleigh time ({rayleigh_time:.3e} s), below the {} the scene is built \
         for (a run would take {steps:.1e} steps); scene.timestep_s is in seconds {FORCE}",
        show(*.fraction),
        show(MIN_RAYLEIGH_FRACTION)
    )]
    Timestep { timestep: f64, fraction: f64, rayleigh_time: f64, steps: f64 },
    /// A blade speed or density outside its range `lo`–`hi`, with the value it would be in the
    /// unit it was probably written in, if that is inside.
    #[error(
        "{name} {} {unit}: outside the {}–{} {unit} the scene is built for; values are in \
         {unit}{} {FORCE}",
        show(*.value),
        show(*.lo),
        show(*.hi),
        did_you_mean(.meant)
    )]
    Range {
        name: &'static str,
        unit: &'static str,
        value: f64,
        lo: f64,
        hi: f64,
        meant: Option<(f64, &'static str)>,
    },
}

/// A particle count; a count that saturated is past anything countable.
fn count(particles: &usize) -> String {
    if *particles == usize::MAX {
        "more than 1e19".to_string()
    } else {
        particles.to_string()
    }
}

/// `", a heap of H mm"` for a held heap, or nothing.
fn heap_of(heap: &Option<f64>) -> String {
    heap.map(|h| format!(", a heap of {} mm", show(h))).unwrap_or_default()
}

fn ratio(a: &f64, b: &f64) -> f64 {
    a / b
}

/// What to lower for fewer particles: the held heap's height, or the gap.
fn lower(heap: &Option<f64>) -> &'static str {
    if heap.is_some() {
        "heap_height"
    } else {
        "gap"
    }
}

/// `" — did you mean V (written in UNIT)?"` for a value that is in range in another unit.
fn did_you_mean(meant: &Option<(f64, &'static str)>) -> String {
    meant.map(|(v, slip)| format!(" — did you mean {} (written in {slip})?", show(v))).unwrap_or_default()
}

/// Refuse a point outside the bounds above, saying which value, in which unit, and what was
/// probably meant. `values` are the catalogue parameters in catalogue units; `held_heap` is the
/// particles and height (m) of a heap the layout holds in front of the blade, if it holds one.
pub fn check(
    scene: &Scene,
    held_heap: Option<(usize, f64)>,
    values: &BTreeMap<String, f64>,
    settings: &SceneSettings,
) -> Result<(), OutOfBounds> {
    let mm = |m: f64| m * 1e3;
    let d = mm(scene.diameter);
    // The parameter that sets the mean diameter.
    let d_name = match settings.size_distribution {
        SizeDistributionSpec::Weibull { .. } => "weibull_scale",
        SizeDistributionSpec::Lognormal { relative: false, .. }
        | SizeDistributionSpec::Classes { relative: false, .. } => "the size distribution's mean",
        _ => "diameter",
    };
    let d_value = values.get(d_name).copied().unwrap_or(d);
    if d < MIN_DIAMETER_MM {
        return Err(OutOfBounds::SmallDiameter { name: d_name, value: d_value });
    }
    if d > MAX_DIAMETER_MM {
        return Err(OutOfBounds::LargeDiameter { name: d_name, value: d_value });
    }
    check_speed_and_density(values)?;
    // A scene without a blade has no gap to close.
    let blade_gap = scene.blade().map_or(f64::INFINITY, |b| b.gap);
    let gap = mm(blade_gap);
    if gap < MIN_GAP_DIAMETERS * d {
        return Err(OutOfBounds::Gap { gap, d });
    }
    // A layout that holds its heap at a count instead of placing a dose: then the heap sets it.
    let (particles, heap) = match held_heap {
        Some((n, height)) if n > scene.particles => (n, Some(mm(height - blade_gap))),
        _ => (scene.particles, None),
    };
    if particles > MAX_PARTICLES {
        return Err(OutOfBounds::Particles { particles, gap, d, heap, name: d_name, value: d_value });
    }
    let fraction = scene.timestep / scene.rayleigh_time;
    if fraction < MIN_RAYLEIGH_FRACTION {
        return Err(OutOfBounds::Timestep {
            timestep: scene.timestep,
            fraction,
            rayleigh_time: scene.rayleigh_time,
            steps: scene.run_steps() as f64,
        });
    }
    Ok(())
}

/// Blade speed and density within [`BLADE_SPEED_M_S`] and [`DENSITY_KG_M3`], naming the slip.
fn check_speed_and_density(values: &BTreeMap<String, f64>) -> Result<(), OutOfBounds> {
    let checks = [
        ("blade_speed", "m/s", BLADE_SPEED_M_S, "mm/s", 1e-3),
        ("density", "kg/m3", DENSITY_KG_M3, "g/cm³", 1e3),
    ];
    for (name, unit, (lo, hi), slip, factor) in checks {
        let Some(&value) = values.get(name) else { continue };
        let meant = Some((value * factor, slip)).filter(|(m, _)| (lo..=hi).contains(m));
        if value < lo || value > hi {
            return Err(OutOfBounds::Range { name, unit, value, lo, hi, meant });
        }
    }
    Ok(())
}

/// A number for people: at most 6 significant digits, no trailing zeros, no float noise
/// (0.30000000000000004 → 0.3). Files keep full precision.
pub fn show(v: f64) -> String {
    round_to(v, 6)
}

/// `v` to three decimals without trailing zeros: the report's tables and axes.
pub fn short(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if matches!(s, "" | "-" | "0" | "-0") {
        // A value under a thousandth is not 0: a surface energy of 1e-4 J/m² must read so.
        if v != 0.0 && v.is_finite() {
            return round_to(v, 3);
        }
        "0".into()
    } else {
        s.to_string()
    }
}

/// `v` with at most `digits` significant digits, printed without trailing zeros.
pub fn round_to(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let magnitude = v.abs().log10().floor() as i32;
    let decimals = (digits - 1 - magnitude).max(0) as usize;
    let text = format!("{v:.decimals$}");
    let text = if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.') } else { &text };
    // Very small or large magnitudes: scientific notation says it shorter.
    if !(-5..=9).contains(&magnitude) {
        let e = format!("{:.*e}", (digits - 1) as usize, v);
        let (m, x) = e.split_once('e').unwrap_or((&e, "0"));
        let m = if m.contains('.') { m.trim_end_matches('0').trim_end_matches('.') } else { m };
        return format!("{m}e{x}");
    }
    text.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_without_float_noise() {
        assert_eq!(show(0.30000000000000004), "0.3");
        assert_eq!(show(2.0), "2");
        assert_eq!(show(0.002 * 1e3), "2");
        assert_eq!(show(1.23456789), "1.23457");
        assert_eq!(show(-0.5), "-0.5");
        assert_eq!(show(37057656.0), "37057656");
        assert_eq!(show(1.5e-6), "1.5e-6");
        assert_eq!(round_to(1.2345678901234567, 12), "1.23456789012");
    }

    #[test]
    fn a_short_number_under_a_thousandth_is_not_shown_as_zero() {
        assert_eq!(short(1e-4), "0.0001");
        assert_eq!(short(-4.667e-4), "-0.000467");
        assert_eq!((short(0.0), short(-0.0), short(0.1234)), ("0".into(), "0".into(), "0.123".into()));
    }
}
