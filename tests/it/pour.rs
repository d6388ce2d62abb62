//! The pour layout: a rendered lifted-cylinder test, a real LIGGGHTS one, and the refusal of a
//! sweep of it.

use std::path::Path;
use std::process::Output;

use crate::support::{self, stderr, sweep_bin};

const POUR: &str = "sweeps/pour.toml";

/// `sweep run` of the example pour at a rolling friction, in `out`: its output and result.json.
fn pour(rolling: f64, out: &Path) -> (Output, serde_json::Value) {
    let o = sweep_bin()
        .args(["run", POUR, "--set", &format!("rolling_friction={rolling}"), "--out"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("result.json")).unwrap();
    (o, serde_json::from_str(&text).unwrap())
}

// Two pours of about 90 CPU seconds each (docs/study/pour), one after the other: run with
// `--ignored`.
#[test]
#[ignore = "two LIGGGHTS pours, about 90 CPU seconds each"]
fn more_rolling_friction_gives_a_steeper_heap_with_a_small_standard_error() {
    support::require_liggghts!("more_rolling_friction_gives_a_steeper_heap_with_a_small_standard_error");
    let dir = tempfile::tempdir().unwrap();
    let low = pour(0.1, &dir.path().join("low"));
    let high = pour(0.3, &dir.path().join("high"));
    let angle = |r: &serde_json::Value| {
        let h = &r["heap"];
        (h["angle_deg"].as_f64().unwrap(), h["angle_se_deg"].as_f64().unwrap())
    };
    let ((a_low, se_low), (a_high, se_high)) = (angle(&low.1), angle(&high.1));
    for (r, a, se) in [(&low.1, a_low, se_low), (&high.1, a_high, se_high)] {
        // Monosized spheres with sliding friction 0.3 and rolling resistance heap at 20–40°
        // (Zhou et al. 2001, Phys. Rev. E 64, 021301: the angle rises with both frictions).
        assert!((15.0..45.0).contains(&a), "angle {a}: {r}");
        assert!(se.is_finite() && se > 0.0 && se < 2.0, "SE {se}: {r}");
        // A heap's bulk: looser than random close packing, denser than a loose pour.
        let packing = r["heap"]["packing"].as_f64().unwrap();
        assert!((0.5..0.64).contains(&packing), "packing {packing}: {r}");
        // Nothing flows in a pour: no MFR is written.
        assert!(r.get("mfr").is_none() && r.get("mfr_flux").is_none(), "{r}");
    }
    assert!(
        a_high - a_low > 3.0 * se_low.hypot(se_high),
        "rolling friction 0.1: {a_low} ± {se_low}°, 0.3: {a_high} ± {se_high}°"
    );
    // `sweep run` prints the angle with its standard error.
    let printed = String::from_utf8_lossy(&high.0.stdout).into_owned();
    assert!(printed.contains(&format!("angle of repose  {a_high:.2} ± {se_high:.2}°")), "{printed}");
}

/// One pour of half the example's column (1,000 spheres, about 45 CPU seconds): the heap, its
/// angle with a standard error and its packing, in the suite on every run.
#[test]
fn a_half_column_pour_heaps_at_a_physical_angle_with_its_standard_error() {
    support::require_liggghts!("a_half_column_pour_heaps_at_a_physical_angle_with_its_standard_error");
    let dir = tempfile::tempdir().unwrap();
    let example = std::fs::read_to_string(POUR).unwrap();
    assert!(example.contains("\n[scene]\n"), "the example has a [scene] table");
    let half = example.replacen("\n[scene]\n", "\n[scene]\nsupply_factor = 0.5\n", 1);
    let file = dir.path().join("half.toml");
    std::fs::write(&file, half).unwrap();
    let out = dir.path().join("out");
    let o = sweep_bin()
        .args(["run", support::p(&file), "--set", "rolling_friction=0.3", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("result.json")).unwrap()).unwrap();
    let h = &r["heap"];
    assert_eq!(
        h["particles_in_heap"].as_u64().unwrap() + h["particles_run_out"].as_u64().unwrap(),
        1000,
        "{r}"
    );
    let (a, se) = (h["angle_deg"].as_f64().unwrap(), h["angle_se_deg"].as_f64().unwrap());
    // Monosized spheres with sliding friction 0.3 and rolling resistance heap at 20–40° (Zhou et
    // al. 2001, Phys. Rev. E 64, 021301); a heap of 1,000 measures it to a few degrees.
    assert!((15.0..45.0).contains(&a), "angle {a}: {r}");
    assert!(se.is_finite() && se > 0.0 && se < 3.0, "SE {se}: {r}");
    // The eight sectors it is the mean of, and an SE that is their scatter over √8.
    let sectors: Vec<f64> =
        h["sector_angles_deg"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(sectors.len(), 8);
    let mean = sectors.iter().sum::<f64>() / 8.0;
    let sd = (sectors.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 7.0).sqrt();
    assert!((mean - a).abs() < 1e-6 && (sd / 8f64.sqrt() - se).abs() < 1e-6, "{r}");
    // A heap's bulk: looser than random close packing, denser than a loose pour.
    let packing = h["packing"].as_f64().unwrap();
    assert!((0.5..0.64).contains(&packing), "packing {packing}: {r}");
    let printed = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(printed.contains(&format!("angle of repose  {a:.2} ± {se:.2}°")), "{printed}");
}

#[test]
fn a_sweep_of_a_pour_is_refused_with_what_to_do_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for design in ["lds", "lattice"] {
        let out = dir.path().join(design);
        let o = sweep_bin().args([design, POUR, "--out"]).arg(&out).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        let e = stderr(&o);
        assert_eq!(e.trim().lines().count(), 1, "{e}");
        assert!(e.contains("scene.layout \"pour\"") && e.contains("`sweep run`"), "{e}");
        assert!(!out.exists(), "{design}: {} was written", out.display());
    }
}

#[test]
fn a_rendered_pour_holds_the_column_and_the_cylinder() {
    let dir = tempfile::tempdir().unwrap();
    let o = sweep_bin().args(["render", POUR, "--out"]).arg(dir.path()).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("2000 particles poured from a 24.0 mm cylinder"), "{}", stderr(&o));
    let pile = std::fs::read_to_string(dir.path().join("pile.data")).unwrap();
    assert!(pile.contains("\n2000 atoms\n"));
    let stl = std::fs::read_to_string(dir.path().join("blade.stl")).unwrap();
    assert!(stl.starts_with("solid cylinder"));
    let deck = std::fs::read_to_string(dir.path().join("in.liggghts")).unwrap();
    assert!(deck.contains("move/mesh mesh cylinder linear 0.0 0.0") && deck.contains("dump.heap"));
}
