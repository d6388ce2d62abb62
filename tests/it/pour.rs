//! The pour layout: a rendered lifted-cylinder test, a real LIGGGHTS one, and the refusal of a
//! sweep of it.

use std::sync::OnceLock;

use serde_json::Value;

use crate::support::{self, stderr, sweep_bin};

const POUR: &str = "sweeps/pour.toml";

/// `sweep run` of half the example's column (1,000 spheres, 23–26 CPU s) at sliding friction
/// 0.5 and `rolling` friction: what it printed and its result.json. At the example's friction,
/// 0.3, half a column heaps under the 5 D a profile fit needs below rolling friction 0.3 (8.3 mm
/// at 0.1, 10.3 mm at 0.3); at 0.5 it stands 11.7–11.9 mm at 0.2 and 13.1–14.2 mm at 0.5.
fn half_pour(rolling: f64) -> (String, Value) {
    let dir = tempfile::tempdir().unwrap();
    let example = std::fs::read_to_string(POUR).unwrap();
    assert!(example.contains("\n[scene]\n"), "the example has a [scene] table");
    let half = example.replacen("\n[scene]\n", "\n[scene]\nsupply_factor = 0.5\n", 1);
    let file = support::write_file(&dir.path().join("half.toml"), &half);
    let out = dir.path().join("out");
    let set = format!("friction=0.5,rolling_friction={rolling}");
    let o = sweep_bin()
        .args(["run", support::p(&file), "--set", &set, "--out", support::p(&out)])
        .output()
        .unwrap();
    assert!(o.status.success(), "rolling friction {rolling}: {}", stderr(&o));
    let r = serde_json::from_str(&std::fs::read_to_string(out.join("result.json")).unwrap()).unwrap();
    (support::text(&o.stdout), r)
}

/// The pour at rolling friction 0.5, run once for the tests that read it.
fn pour_at_half() -> &'static (String, Value) {
    static POURED: OnceLock<(String, Value)> = OnceLock::new();
    POURED.get_or_init(|| half_pour(0.5))
}

/// A heap's angle and its standard error over the sectors, degrees.
fn angle(r: &Value) -> (f64, f64) {
    let h = &r["heap"];
    (h["angle_deg"].as_f64().unwrap(), h["angle_se_deg"].as_f64().unwrap())
}

/// Rolling friction steepens a heap: one pour at 0.2 against the shared one at 0.5, on the same
/// pile seed (the file's), about 50 CPU s in all.
///
/// The bound is the measured scatter of that difference: on the file's seed and three others
/// (12345, 1, 2, 3; one pour each, LIGGGHTS 3.8) the angles were 26.55, 26.92, 24.53, 25.69° at
/// 0.2 and 31.79, 33.65, 30.66, 33.02° at 0.5, so the difference on one seed 5.24, 6.73, 6.13,
/// 7.33°: mean 6.36°, SD 0.89°. It must be more than 3 SD of that scatter above zero, 2.7°:
/// a pour where rolling friction did nothing passes it about once in a thousand, the measured
/// effect fails it at 4 SD below its mean. (The sectors' SE, 1.0–1.5° a heap, is no measure of
/// it: the heaps of one seed share their lattice.) A rolling friction of 0.8 heaps no steeper
/// than 0.5 (31.4–33.7° on the same seeds): the effect saturates, so the pair is 0.2 and 0.5.
#[test]
fn more_rolling_friction_gives_a_steeper_heap() {
    support::require_liggghts!("more_rolling_friction_gives_a_steeper_heap");
    let (_, low) = half_pour(0.2);
    let (_, high) = pour_at_half();
    let ((a_low, se_low), (a_high, se_high)) = (angle(&low), angle(high));
    for (r, a, se) in [(&low, a_low, se_low), (high, a_high, se_high)] {
        // Monosized spheres heap at 20–40° with these frictions (Zhou et al. 2001, Phys. Rev. E
        // 64, 021301: the angle rises with both sliding and rolling friction).
        assert!((15.0..45.0).contains(&a), "angle {a}: {r}");
        assert!(se.is_finite() && se > 0.0 && se < 3.0, "SE {se}: {r}");
        // Nothing flows in a pour: no MFR is written.
        assert!(r.get("mfr").is_none() && r.get("mfr_flux").is_none(), "{r}");
    }
    assert!(
        a_high - a_low > 2.7,
        "rolling friction 0.2: {a_low} ± {se_low}°, 0.5: {a_high} ± {se_high}° (measured difference 6.4 ± 0.9°)"
    );
}

/// One pour of half the example's column: the heap, its angle with a standard error and its
/// packing, and the line `sweep run` prints.
#[test]
fn a_half_column_pour_heaps_at_a_physical_angle_with_its_standard_error() {
    support::require_liggghts!("a_half_column_pour_heaps_at_a_physical_angle_with_its_standard_error");
    let (printed, r) = pour_at_half();
    let h = &r["heap"];
    assert_eq!(
        h["particles_in_heap"].as_u64().unwrap() + h["particles_run_out"].as_u64().unwrap(),
        1000,
        "{r}"
    );
    let (a, se) = angle(r);
    // Monosized spheres with sliding friction 0.5 and rolling resistance heap at 20–40° (Zhou et
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
