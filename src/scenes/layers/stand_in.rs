//! The layers' stand-in model (`[run] engine = "stand-in"`): every pass and the steady layer
//! of a point, made up from a closed form in its layer thickness, blade speed, friction and
//! cohesion, shaped like the passes the real layout measures (docs/layers.md), not their
//! numbers.
//!
//! Each pass packs the powder under the blade's tip at a packing `P` (with the point's noise):
//! looser for a layer few diameters thick, a faster blade, more friction and more cohesion. The
//! depth under the tip then follows the bed: on a fused bed the tip rises by the drop and the
//! solid by the deposit, so the depth tends to drop / P and the relative density to 1 (a search
//! pass sets the next depth to the one its packing would fill with a whole drop); on a loose bed
//! the deposit fills `deposit / P` of the depth, so the depth tends to the drop and the relative
//! density to `P`. The first pass, on the bare plate, packs looser. The steady layer is the
//! passes from the first whose noiseless depth is within [`STEADY_WITHIN`] of its limit; a point
//! with fewer than [`MIN_STEADY_PASSES`] of them is not steady, as a real run would not be.

use super::result::{LayerSeries, PassRecord};
use super::{plan_of, Plan, MIN_STEADY_PASSES};
use crate::outcome::layer::Layer;
use crate::outcome::{FailureClass, RunResult, VX_LAYERS};
use crate::scenes::stand_in::StandInPoint;
use crate::scenes::Rejected;

/// How close to its limit the noiseless depth must be for a pass to count as steady.
pub const STEADY_WITHIN: f64 = 0.02;
/// Relative SD of a pass's packing about the point's.
pub const PACKING_NOISE: f64 = 0.03;
/// The first pass's packing over the point's: the bare plate orders the powder less.
const FIRST_PASS: f64 = 0.8;

/// The parameters the layers model reads (sweep units: mm, m/s, J/m²).
#[derive(Debug, Clone, Copy)]
pub struct LayersPoint {
    pub layer_thickness: f64,
    pub diameter: f64,
    pub blade_speed: f64,
    pub friction: f64,
    pub rolling_friction: f64,
    pub surface_energy: f64,
}

impl LayersPoint {
    /// The noiseless packing of a pass: 0.6 at most, less for a layer of few diameters, a fast
    /// blade, friction and cohesion (Ti-6Al-4V 15–45 µm at 50 µm and 0.1 m/s: 0.33).
    pub fn packing(&self) -> f64 {
        let thin = 1.0 - 0.5 * (-self.layer_thickness / self.diameter).exp();
        let speed = 1.0 / (1.0 + self.blade_speed / 0.5);
        let friction = 1.0 / (1.0 + 0.5 * self.friction.max(0.0) + self.rolling_friction.max(0.0));
        let g = self.surface_energy.max(0.0);
        let cohesion = g / (g + 0.05 * (self.diameter / 2.0).powi(2));
        0.6 * thin * speed * friction * (1.0 - 0.2 * cohesion)
    }
}

/// The depth under the tip before the pass after one that met `depth` and packed it at
/// `packing` (the point's being `p`), the drop `t` (m).
fn next_depth(plan: &Plan, k: usize, depth: f64, packing: f64, p: f64) -> f64 {
    let t = plan.layer_thickness;
    let deposit = packing * depth;
    if k <= plan.search_passes {
        // The depth a whole drop fills at this pass's packing.
        let asked = depth * t / deposit.max(plan.search_least_deposit);
        asked.min(plan.search_max_depth.max(t))
    } else if plan.fused {
        depth + t - deposit
    } else {
        t + depth * (1.0 - packing / p)
    }
}

/// The point's passes and steady layer, and the run's result from them (as the layout's own
/// measurement words it: the steady layer's relative density on a loose bed, its packing on a
/// fused one, as the answer); a point not steady by its last pass fails as `unsteady`, its
/// numbers kept.
pub fn passes(point: &mut StandInPoint) -> Result<RunResult, Rejected> {
    let scene = point.scene;
    let plan = plan_of(scene);
    let model = LayersPoint {
        layer_thickness: point.get("layer_thickness"),
        diameter: point.diameter_mm(),
        blade_speed: point.get("blade_speed"),
        friction: point.get("friction"),
        rolling_friction: point.get("rolling_friction"),
        surface_energy: point.get("surface_energy"),
    };
    let p = model.packing();
    let n = plan.most();
    let mean_volume: f64 =
        scene.size_classes.iter().map(|c| c.fraction * std::f64::consts::PI / 6.0 * c.diameter.powi(3)).sum();
    let dose = scene.particles / n.max(1);
    let (mut depth, mut noiseless) = (plan.drop_before(1), plan.drop_before(1));
    let (mut records, mut depths) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut laid_after_first = 0.0;
    for k in 1..=n {
        let own = if k == 1 { FIRST_PASS * p } else { p };
        let packing = (own * (1.0 + PACKING_NOISE * point.noise.normal())).max(0.01 * p);
        let deposit = packing * depth;
        if k > 1 {
            laid_after_first += deposit;
        }
        records.push(PassRecord {
            k,
            search: k <= plan.search_passes,
            deposit_m: deposit,
            relative_density: deposit / plan.drop_before(k),
            effective_thickness_m: depth,
            packing,
            covered_fraction: 1.0 - (-1.5 * deposit / scene.diameter).exp(),
            roughness_d: (0.35 + 0.02 * point.noise.normal()).max(0.0),
            bed_relative_density: (!plan.fused && k > 1)
                .then(|| laid_after_first / ((k - 1) as f64 * plan.layer_thickness)),
            particles: ((deposit * plan.plate_area / mean_volume).round() as usize).min(dose),
            // The stand-in models no roller's load.
            roller: None,
        });
        depths.push(noiseless);
        depth = next_depth(&plan, k, depth, packing, p);
        noiseless = next_depth(&plan, k, noiseless, own, p);
    }
    let limit = if plan.fused { plan.layer_thickness / p } else { plan.layer_thickness };
    let settled = |k: usize| (depths[k - 1] - limit).abs() <= STEADY_WITHIN * limit;
    let first = (plan.search_passes + 1..=n).find(|&k| settled(k)).unwrap_or(n + 1);
    let r = series_result(point, &plan, records, first);
    if r.steady {
        return Ok(r);
    }
    let why = format!(
        "layers not steady by pass {n}: fewer than {MIN_STEADY_PASSES} passes after the transient (the stand-in's depth settles at pass {first})"
    );
    Err(Rejected::measured(FailureClass::Unsteady, why, r))
}

/// The steady layer from pass `first` on (steady if [`MIN_STEADY_PASSES`] passes are left), and
/// the result.
fn series_result(point: &StandInPoint, plan: &Plan, passes: Vec<PassRecord>, first: usize) -> RunResult {
    let n = passes.len();
    let steady = n + 1 >= first + MIN_STEADY_PASSES;
    // An unsteady point's numbers over its last passes, for the record.
    let from = if steady { first } else { n.saturating_sub(MIN_STEADY_PASSES - 1).max(1) };
    // The stand-in's passes are drawn independently.
    let series = LayerSeries {
        numerical_error: Some(super::numerics::of(point.scene, plan)),
        ..super::measure::series_from(plan, passes, from, steady, (0.0, 0.0))
    };
    let answer = |p: &PassRecord| if plan.fused { p.packing } else { p.relative_density };
    RunResult {
        answer: series.answer(),
        mfr_flux: f64::NAN,
        answer_particles: series.passes.iter().map(|p| p.particles).sum(),
        answer_windows: series.passes.iter().map(answer).collect(),
        steady,
        steady_p: f64::NAN,
        vx: vec![None; VX_LAYERS],
        particles: point.scene.particles,
        layer: Some(Layer {
            layer_cv: f64::NAN,
            layer_cv_noise: f64::NAN,
            covered_fraction: series.covered_fraction,
            roughness_d: series.roughness_d,
            height_d: series.effective_thickness_m / point.scene.diameter,
            particles: series.passes.last().map_or(0, |p| p.particles),
        }),
        layer_thickness: Some(series.effective_thickness_m),
        layer_packing: Some(series.packing),
        layer_packing_se: Some(series.packing_se),
        own: crate::outcome::OwnResult::new(series),
        ..RunResult::default()
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::scenes::layers::settings::{with_own, LayersSettings};
    use crate::scenes::layers::Layers;
    use crate::scenes::stand_in::Noise;
    use crate::scenes::Layout;

    fn result(bed: &str, layers: usize, values: &[(&str, f64)], hash: &str) -> Result<RunResult, Rejected> {
        let settings = with_own(LayersSettings::default().settings(), |l| {
            l.bed = bed.into();
            l.layers = layers;
        });
        let values: BTreeMap<String, f64> = values.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        let scene = crate::scenes::build(&values, &settings).unwrap();
        let parameters: BTreeMap<String, f64> = crate::scene::params::CATALOGUE
            .iter()
            .map(|p| (p.name.to_string(), values.get(p.name).copied().unwrap_or(p.default)))
            .collect();
        passes(&mut StandInPoint { scene: &scene, parameters: &parameters, noise: Noise::new(hash) })
    }

    #[test]
    fn a_fused_bed_keeps_the_whole_drop_and_a_loose_one_its_packing_and_both_pass_the_checks() {
        let values = [("layer_thickness", 3.0), ("blade_speed", 0.1), ("friction", 0.5)];
        for hash in ["a", "b", "c"] {
            let fused = result("fused", 14, &values, hash).unwrap();
            let l = super::super::result::series(&fused).unwrap();
            assert!(fused.steady && l.steady_from > 1, "{l:?}");
            assert!((l.relative_density - 1.0).abs() < 0.05, "{l:?}");
            assert_eq!(fused.answer.value, l.packing);
            Layers.check_result(&fused).unwrap();
            let loose = result("loose", 8, &values, hash).unwrap();
            let l = super::super::result::series(&loose).unwrap();
            assert!(loose.steady && (l.relative_density - l.packing).abs() < 0.1 * l.packing, "{l:?}");
            assert_eq!(loose.answer.value, l.relative_density);
            Layers.check_result(&loose).unwrap();
        }
    }

    #[test]
    fn a_point_of_fewer_passes_than_a_steady_layer_needs_is_not_steady() {
        let e = result("loose", 2, &[("layer_thickness", 3.0)], "a").unwrap_err();
        assert_eq!(e.class, FailureClass::Unsteady);
        assert!(e.reason.contains("fewer than 3 passes"), "{}", e.reason);
        let r = e.measured.unwrap();
        assert!(!r.steady && !super::super::result::series(&r).unwrap().steady);
    }

    #[test]
    fn the_packing_falls_with_blade_speed_and_friction_and_rises_with_the_layer() {
        let at = |t: f64, v: f64, mu: f64| {
            LayersPoint {
                layer_thickness: t,
                diameter: 0.031,
                blade_speed: v,
                friction: mu,
                rolling_friction: 0.1,
                surface_energy: 1e-4,
            }
            .packing()
        };
        assert!(at(0.05, 0.2, 0.5) < at(0.05, 0.05, 0.5));
        assert!(at(0.05, 0.1, 0.6) < at(0.05, 0.1, 0.3));
        assert!(at(0.03, 0.1, 0.5) < at(0.08, 0.1, 0.5));
        assert!((0.2..0.45).contains(&at(0.05, 0.1, 0.5)), "{}", at(0.05, 0.1, 0.5));
    }
}
