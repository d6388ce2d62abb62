//! The recoater's measurement against what bounds it: the heap in millimetres acts, the layer's
//! packing stays under the packing of spheres at thin gaps, and a monolayer on a smooth plate
//! under its geometric ceiling. Real LIGGGHTS, the conveyor layout at D = 2 mm.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::support;

fn sweep_file(dir: &Path, substrate: &str) -> PathBuf {
    let path = dir.join(format!("{substrate}.toml"));
    std::fs::write(
        &path,
        format!(
            r#"name = "recoater"
[parameters]
gap         = {{ lo = 2.0, hi = 6.0, unit = "mm" }}
blade_speed = {{ lo = 0.1, hi = 1.0, unit = "m/s" }}
diameter = 2.0
friction = 0.2
[scene]
layout = "conveyor"
substrate = "{substrate}"
"#
        ),
    )
    .unwrap();
    path
}

/// A point's result.json, with the command's exit code.
fn run_point(sweep: &Path, set: &str) -> (i32, Value) {
    let (code, json, stderr) = support::run_point(sweep, set);
    assert!(json.is_object(), "{set}: no result: {stderr}");
    (code, json)
}

fn f(r: &Value, key: &str) -> f64 {
    r[key].as_f64().unwrap_or_else(|| panic!("{key} missing in {r}"))
}

#[test]
fn a_monolayer_on_a_smooth_plate_stays_under_its_geometric_ceiling() {
    support::require_liggghts!("a_monolayer_on_a_smooth_plate_stays_under_its_geometric_ceiling");
    // At D ≤ gap < 1.8 D no second layer fits under the tip: the deposit is one layer of spheres
    // whose centres are at most a hexagonal packing's, 2/√3 per D² of area, each of volume
    // π D³/6: π/(3√3) D = 0.6046 D of solid per area, so its packing over the gap is at most
    // 0.6046 · D / gap.
    let dir = tempfile::tempdir().unwrap();
    let (code, r) = run_point(&sweep_file(dir.path(), "smooth"), "gap=2.8,blade_speed=0.4");
    assert_eq!(code, 0, "{r}");
    let (packing, se) = (f(&r, "layer_packing"), f(&r, "layer_packing_se"));
    let ceiling = std::f64::consts::PI / (3.0 * 3f64.sqrt()) / 1.4;
    assert!(packing > 0.0 && packing <= ceiling + 2.0 * se, "packing {packing} ± {se} against {ceiling}");
    // On a smooth plate the layer is the gap: the packing is MFR.
    assert_eq!(f(&r, "layer_packing"), f(&r, "mfr"));
}

#[test]
fn the_layer_packing_at_a_thin_gap_on_the_rough_substrate_stays_under_random_close_packing() {
    support::require_liggghts!(
        "the_layer_packing_at_a_thin_gap_on_the_rough_substrate_stays_under_random_close_packing"
    );
    // gap 1.26 D at 0.14 m/s: where MFR over the gap alone passed 0.64 (the deposit fills the
    // substrate's pockets below the tops too).
    let dir = tempfile::tempdir().unwrap();
    let (code, r) = run_point(&sweep_file(dir.path(), "rough"), "gap=2.52,blade_speed=0.14");
    assert_eq!(code, 0, "{r}");
    let (packing, se) = (f(&r, "layer_packing"), f(&r, "layer_packing_se"));
    assert!(packing <= 0.64 + 2.0 * se, "packing {packing} ± {se}");
    assert!(f(&r, "layer_thickness") > 2.52e-3, "{r}");
}

#[test]
fn a_taller_heap_pushes_more_powder_under_the_blade() {
    support::require_liggghts!("a_taller_heap_pushes_more_powder_under_the_blade");
    let dir = tempfile::tempdir().unwrap();
    let sweep = sweep_file(dir.path(), "rough");
    let (c1, low) = run_point(&sweep, "gap=5,blade_speed=0.4,heap_height=8");
    let (c2, high) = run_point(&sweep, "gap=5,blade_speed=0.4,heap_height=30");
    assert_eq!((c1, c2), (0, 0), "{low}\n{high}");
    let (a, b) = (f(&low, "mfr"), f(&high, "mfr"));
    let se = f(&low, "mfr_se").hypot(f(&high, "mfr_se"));
    assert!(b - a > 2.0 * se, "heap 8 mm: {a}, 30 mm: {b}, combined SE {se}");
    // The heap per width of blade is what was asked for: 0.6 of the 30° triangle's solid mass.
    let per_width = |r: &Value, h: f64| {
        let held = r["steady_state"]["heap_mass_per_width"].as_f64().unwrap();
        let height = (5.0 + h) * 1e-3;
        let triangle = 0.5 * height * height / 30f64.to_radians().tan() * 7980.0;
        held / (0.6 * triangle)
    };
    for (r, h) in [(&low, 8.0), (&high, 30.0)] {
        let ratio = per_width(r, h);
        assert!((0.8..1.25).contains(&ratio), "heap {h} mm holds {ratio} of its planned mass per width");
    }
}
