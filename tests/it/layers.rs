//! Layer after layer (the layers layout) through the real LIGGGHTS: a small bed of 2 mm spheres,
//! a few passes, each spread onto the ones before.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::support::{self, run_point};

/// A layers sweep at D = 2 mm over blade speed, with `extra` in `[scene]`.
fn bed(dir: &Path, extra: &str) -> PathBuf {
    support::write_file(
        &dir.join("layers.toml"),
        &format!(
            r#"name = "layers"
[parameters]
blade_speed     = {{ lo = 0.2, hi = 0.8, unit = "m/s" }}
diameter        = 2.0
layer_thickness = {{ value = 3.0, unit = "mm" }}
friction        = 0.3
rolling_friction = 0.1
restitution     = 0.4
[scene]
layout = "layers"
plate_diameters = 12
{extra}
"#
        ),
    )
}

#[test]
fn each_layer_lies_on_the_one_before_and_the_platform_drops_by_the_layer_thickness() {
    support::require_liggghts!(
        "each_layer_lies_on_the_one_before_and_the_platform_drops_by_the_layer_thickness"
    );
    let (_tmp, dir) = support::cwd();
    let sweep = bed(&dir, "layers = 4");
    // The deck raises the machine's frame by the layer thickness before every pass.
    let deck = dir.join("deck");
    let out = support::ok(
        &dir,
        &["render", support::p(&sweep), "--set", "blade_speed=0.5", "--out", support::p(&deck)],
    );
    assert!(out.status.success());
    let input = std::fs::read_to_string(deck.join("in.liggghts")).unwrap();
    let tops: Vec<f64> = input
        .lines()
        .filter(|l| l.starts_with("fix top"))
        .map(|l| l.rsplit(' ').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(tops.len(), 4, "{tops:?}");
    for (k, t) in tops.iter().enumerate() {
        assert!((t - 3e-3 * (k + 1) as f64).abs() < 1e-12, "pass {}: top {t}", k + 1);
    }

    let (code, r, stderr) = run_point(&sweep, "blade_speed=0.5");
    // A 4-pass bed may not yet be steady; its passes are measured either way.
    let layers: &Value = if code == 0 { &r["layers"] } else { &r["measured"]["layers"] };
    assert!(layers.is_object(), "exit {code}: {stderr}\n{r}");
    let passes = layers["passes"].as_array().unwrap();
    assert_eq!(passes.len(), 4);
    let f = |p: &Value, k: &str| p[k].as_f64().unwrap_or_else(|| panic!("{k} in {p}"));
    for p in passes {
        let k = p["k"].as_u64().unwrap();
        // Every pass brings its own particles and covers part of the plate with them.
        assert!(p["particles"].as_u64().unwrap() > 0, "pass {k} deposited nothing: {p}");
        assert!((0.0..=1.0).contains(&f(p, "covered_fraction")), "{p}");
        // A layer cannot be denser than packed spheres, whatever the bed.
        assert!(f(p, "relative_density") > 0.0 && f(p, "relative_density") < 0.75, "{p}");
    }
    // The second and later passes meet the bed the first left: their powder under the tip is
    // less than the whole height of the well, and more than nothing.
    for p in &passes[1..] {
        let depth = f(p, "effective_thickness_m");
        let k = p["k"].as_u64().unwrap() as f64;
        assert!(depth > 0.0 && depth < k * 3e-3, "pass {k}: depth {depth}");
    }
}

#[test]
fn a_bad_layer_count_or_thickness_is_refused_in_one_line() {
    let (_tmp, dir) = support::cwd();
    for (extra, key) in [("layers = 0", "scene.layers"), ("bed = \"molten\"", "scene.bed")] {
        let sweep = bed(&dir, extra);
        let out = support::sweep(&[
            "render",
            support::p(&sweep),
            "--set",
            "blade_speed=0.5",
            "--out",
            support::p(&dir.join("d")),
        ]);
        assert_eq!(out.status.code(), Some(2), "{extra}");
        let err = support::stderr(&out);
        assert!(err.contains(key), "{extra}: {err}");
        assert_eq!(err.trim_end().lines().filter(|l| l.starts_with("error")).count(), 1, "{err}");
        assert!(!dir.join("d").exists(), "{extra}: wrote a deck");
    }
    let sweep = bed(&dir, "").to_string_lossy().into_owned();
    let out =
        support::sweep(&["render", &sweep, "--set", "blade_speed=0.5,layer_thickness=-1", "--out", "d"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(support::stderr(&out).contains("layer_thickness"), "{}", support::stderr(&out));
}
