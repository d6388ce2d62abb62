//! Laid doses (`scene.laid_dose`) through the real LIGGGHTS: the dose pass 2 let come to rest in
//! front of the blade, laid again a layer higher before every later pass.

use std::path::Path;

use crate::layers::{bed_file, kill_once, measured, passes_of};
use crate::support;

/// `sweep run` of `sweep`'s point at 0.5 m/s into `out`.
fn run_at(sweep: &Path, out: &Path) -> std::process::Output {
    let args = ["run", support::p(sweep), "--set", "blade_speed=0.5", "--out", support::p(out)];
    support::sweep_bin().args(args).output().unwrap()
}

/// The rows of a LIGGGHTS dump: its columns as numbers.
fn dump_rows(file: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let mut lines = text.lines().skip_while(|l| !l.starts_with("ITEM: ATOMS"));
    lines.next();
    lines.map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect()).collect()
}

/// The numbers after `key` on the log's lines that start with `start`, in order.
fn logged(log: &str, start: &str, key: &str) -> Vec<f64> {
    log.lines()
        .filter(|l| l.starts_with(start))
        .filter_map(|l| l.split(key).nth(1)?.split_whitespace().next()?.trim_end_matches(',').parse().ok())
        .collect()
}

#[test]
fn a_laid_dose_is_pass_2_s_at_rest_laid_a_layer_higher_each_pass_and_a_killed_point_lays_the_same() {
    support::require_liggghts!(
        "a_laid_dose_is_pass_2_s_at_rest_laid_a_layer_higher_each_pass_and_a_killed_point_lays_the_same"
    );
    let (_tmp, dir) = support::cwd();
    let sweep = bed_file(&dir, "laid", "", "layers = 5\nleast_layers = 5\nlaid_dose = true");
    let args = |out: &Path| {
        ["run", support::p(&sweep), "--set", "blade_speed=0.5", "--out", support::p(out)].map(String::from)
    };
    let whole = dir.join("whole");
    let out = support::sweep_bin().args(args(&whole)).output().unwrap();
    assert!(out.status.success(), "{}", support::stderr(&out));

    // Pass 2's dose as it lay, and its copy with IDs no atom of the run holds.
    let dose = dump_rows(&whole.join("dump.dose"));
    let laid = dump_rows(&whole.join("dose.laid"));
    assert!(dose.len() > 100, "pass 2's dose: {} atoms", dose.len());
    assert_eq!(laid.len(), dose.len());
    for (d, l) in dose.iter().zip(&laid) {
        assert_eq!(l[0], d[0] + 1e9);
        assert_eq!(l[1..], d[1..]);
    }
    let log = |k: usize| std::fs::read_to_string(whole.join(format!("log.pass.{k}"))).unwrap();
    for k in 3..=5 {
        // Every atom of it is added (none matched an atom of the bed) and every later pass's
        // dose stands a layer (3 mm) higher than the one before, as it was laid.
        let l = log(k);
        assert!(
            l.contains(&format!("{} atoms added", dose.len())) && l.contains("0 atoms replaced"),
            "pass {k}"
        );
        assert!(!l.contains("insert/pack"), "pass {k} inserts no dose");
    }
    let top = |k: usize| logged(&log(k), "demsweep: pass", "at z")[0];
    for k in 4..=5 {
        let rise = top(k) - top(k - 1);
        assert!((rise - 3e-3).abs() < 0.2 * 2e-3, "pass {k}'s dose rose {rise} m over pass {}'s", k - 1);
    }
    // The step goes on across the passes (read_dump sets it to the dump's: the deck sets it back).
    let steps: Vec<f64> = (1..=5).flat_map(|k| logged(&log(k), "demsweep: layer ", "step")).collect();
    assert_eq!(steps.len(), 5);
    assert!(steps.windows(2).all(|w| w[1] > w[0]), "steps {steps:?}");
    let passes = passes_of(&whole);
    assert_eq!(passes.len(), 5);
    for p in &passes {
        assert!(p["particles"].as_u64().unwrap() > 0, "the pass deposited nothing: {p}");
    }

    // SIGKILL in pass 4, run again: it lays the same dose and ends where the whole run did.
    let cut = dir.join("cut");
    kill_once(support::sweep_bin().args(args(&cut)), &cut.join("in.pass.4"));
    assert!(cut.join("dose.laid").is_file() && !cut.join("pass.4.json").exists());
    let out = support::sweep_bin().args(args(&cut)).output().unwrap();
    assert!(out.status.success(), "{}", support::stderr(&out));
    assert_eq!(passes_of(&cut), passes, "an interrupted point ends where an uninterrupted one does");

    // Without pass 2's dump the point cannot lay a dose: it says which file it needed.
    let lost = dir.join("lost");
    kill_once(support::sweep_bin().args(args(&lost)), &lost.join("in.pass.3"));
    // (Pass 3's deck is written once pass 2 is recorded.)
    assert!(lost.join("pass.2.json").is_file());
    for f in ["dump.dose", "dose.laid"] {
        let _ = std::fs::remove_file(lost.join(f));
    }
    let out = support::sweep_bin().args(args(&lost)).output().unwrap();
    let err = support::stderr(&out);
    assert!(!out.status.success() && err.contains("dump.dose") && err.contains("pass 3"), "{err}");
}

#[test]
fn a_round_blade_starts_where_its_arc_clears_the_laid_dose_and_crosses_that_much_less() {
    support::require_liggghts!(
        "a_round_blade_starts_where_its_arc_clears_the_laid_dose_and_crosses_that_much_less"
    );
    let (_tmp, dir) = support::cwd();
    // A large arc over a small dose: its front reaches far ahead of the lowest line, but at the
    // dose's height far less.
    let extra = "layers = 4\nleast_layers = 4\nlaid_dose = true\nblade_profile = \"round\"\n\
                 blade_radius_mm = 20.0\nsupply_factor = 0.5";
    let sweep = bed_file(&dir, "arc", "", extra);
    let run = dir.join("run");
    let out = run_at(&sweep, &run);
    assert!(out.status.success(), "{}", support::stderr(&out));
    let log = |k: usize| std::fs::read_to_string(run.join(format!("log.pass.{k}"))).unwrap();
    let shifts: Vec<f64> = (3..=4).map(|k| logged(&log(k), "demsweep: blade", "starts")[0]).collect();
    // The same dose laid a layer higher under a tip a layer higher: the same start, ahead of the
    // first passes' by more than half a diameter (1 mm) and less than the arc's reach (18.5 mm).
    assert!(shifts[0] > 1e-3 && shifts[0] < 18.5e-3, "{shifts:?}");
    // (Each pass nudges its dose by up to 2 nm: the start moves by as little.)
    assert!((shifts[0] - shifts[1]).abs() < 1e-8, "{shifts:?}");
    // Its crossing is that much shorter: the steps from the blade's start to the layer's measure
    // (the crossing and the same rest after it).
    let steps = |k: usize| {
        logged(&log(k), "demsweep: layer ", "step")[0] - logged(&log(k), "demsweep: pass", "step")[0]
    };
    let deck = std::fs::read_to_string(run.join("in.pass.2")).unwrap();
    let dt: f64 = deck.lines().find_map(|l| l.strip_prefix("timestep")).unwrap().trim().parse().unwrap();
    let saved = steps(2) - steps(3);
    assert!((saved * 0.5 * dt - shifts[0]).abs() < 2.0 * 0.5 * dt, "{saved} steps saved for {} m", shifts[0]);
    for p in passes_of(&run) {
        assert!(p["particles"].as_u64().unwrap() > 0, "the pass deposited nothing: {p}");
    }
}

#[test]
fn a_fused_bed_s_laid_passes_differ_from_each_other_though_the_dose_is_the_same() {
    support::require_liggghts!(
        "a_fused_bed_s_laid_passes_differ_from_each_other_though_the_dose_is_the_same"
    );
    let (_tmp, dir) = support::cwd();
    // The same dose on the same flat solid: without a nudge of its own each pass repeated the
    // one before to the last digit once the depth had settled (deposits 0.93 ± 0.00 of the
    // drop over passes 4–6), leaving no scatter to measure the steady layer's SE from.
    let extra = "bed = \"fused\"\nlayers = 6\nleast_layers = 6\nsearch_passes = 1\nblade_profile = \"round\"\nlaid_dose = true";
    let sweep = bed_file(&dir, "fused", "", extra);
    let run = dir.join("run");
    let out = run_at(&sweep, &run);
    assert!(
        run.join("result.json").is_file() || run.join("failure.json").is_file(),
        "{}",
        support::stderr(&out)
    );
    let layers = &measured(&run)["layers"];
    let deposits: Vec<f64> =
        layers["passes"].as_array().unwrap().iter().map(|p| p["deposit_m"].as_f64().unwrap()).collect();
    assert_eq!(deposits.len(), 6);
    let laid = &deposits[2..];
    assert!(laid.windows(2).all(|w| w[0] != w[1]), "laid passes repeat: {deposits:?}");
}
