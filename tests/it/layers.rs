//! Layer after layer (the layers layout) through the real LIGGGHTS: a small bed of 2 mm spheres,
//! a few passes, each spread onto the ones before.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::support::{self, run_point};

/// A layers sweep at D = 2 mm over blade speed, with `extra` in `[scene]`.
fn bed(dir: &Path, extra: &str) -> PathBuf {
    bed_file(dir, "layers", "", extra)
}

/// The same bed as the sweep `name` (in `name.toml`), with `parameters` after the common ones and
/// `extra` in `[scene]`: the roller's tests spread it too.
pub(crate) fn bed_file(dir: &Path, name: &str, parameters: &str, extra: &str) -> PathBuf {
    support::write_file(
        &dir.join(format!("{name}.toml")),
        &format!(
            r#"name = "{name}"
[parameters]
blade_speed     = {{ lo = 0.2, hi = 0.8, unit = "m/s" }}
diameter        = 2.0
layer_thickness = {{ value = 3.0, unit = "mm" }}
friction        = 0.3
rolling_friction = 0.1
restitution     = 0.4
{parameters}
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
    // Four passes of this loose bed are steady from pass 2 (its record: packing 0.22 ± 0.02): a
    // run that failed fails the test, whatever its passes measured.
    assert_eq!(code, 0, "the run failed: {}\n{stderr}", r["reason"]);
    let passes = r["layers"]["passes"].as_array().unwrap_or_else(|| panic!("no passes: {r}"));
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

/// The particles of a pass's dump over the plate: id and centre.
fn plate_dump(run: &Path, k: usize) -> Vec<(u64, [f64; 3])> {
    let text = std::fs::read_to_string(run.join(format!("dump.layer.{k}"))).unwrap();
    let mut lines = text.lines().skip_while(|l| !l.starts_with("ITEM: ATOMS"));
    lines.next();
    lines
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            (v[0] as u64, [v[1], v[2], v[3]])
        })
        .collect()
}

#[test]
fn a_loose_bed_deep_under_the_top_is_held_still_and_every_particle_keeps_its_id() {
    support::require_liggghts!(
        "a_loose_bed_deep_under_the_top_is_held_still_and_every_particle_keeps_its_id"
    );
    let (_tmp, dir) = support::cwd();
    // 2 mm spheres in 3 mm layers: from pass 3 the bed 3 D (6 mm) under the top is held still,
    // and from the pass whose top is 10 mm up (the held skin two largest diameters deep) the bed
    // under that is removed at the pass's end.
    let sweep = bed(&dir, "layers = 6\nleast_layers = 6\nfreeze_depth_diameters = 3");
    let run = dir.join("run");
    let o =
        support::sweep(&["run", support::p(&sweep), "--set", "blade_speed=0.5", "--out", support::p(&run)]);
    // Four passes may or may not make a steady layer; every pass must have run.
    let err = support::stderr(&o);
    assert!(o.status.success() || err.contains("(unsteady)"), "{err}");
    assert!(run.join("dump.layer.6").is_file(), "{err}");
    // Where pass k's deck holds the bed still (`deep`) or removes it (`buried`): under this
    // height (m), if anywhere.
    let under = |k: usize, what: &str| -> Option<f64> {
        let deck = std::fs::read_to_string(run.join(format!("in.pass.{k}"))).unwrap();
        let head = format!("region {what}{k} block");
        let line = deck.lines().find(|l| l.starts_with(&head))?;
        Some(line.split_whitespace().nth(8).unwrap().parse().unwrap())
    };
    let cut = |k: usize| under(k, "deep");
    assert_eq!(cut(2), None, "pass 2's top is under 6 mm: nothing held still");
    let mut held = 0;
    for k in 3..=6 {
        let z = cut(k).unwrap_or_else(|| panic!("pass {k} holds nothing still"));
        let (before, after) = (plate_dump(&run, k - 1), plate_dump(&run, k));
        let now: std::collections::HashMap<u64, [f64; 3]> = after.iter().copied().collect();
        // (What the pass before removed is checked below.)
        let removed = under(k - 1, "buried").unwrap_or(f64::NEG_INFINITY);
        for (id, x) in before.iter().filter(|(_, x)| x[2] < z && x[2] >= removed) {
            // The same particle, under the same id, exactly where it was.
            assert_eq!(now.get(id), Some(x), "pass {k}: particle {id} below {z} m moved or lost its id");
            held += 1;
        }
        // This pass's new particles have ids the last dump did not hold.
        let ids: std::collections::HashSet<u64> = before.iter().map(|p| p.0).collect();
        assert!(after.iter().any(|(id, _)| !ids.contains(id)), "pass {k}: no new particle");
    }
    assert!(held > 20, "{held} particles held still over four passes");

    // The bed a pass removes is what its dump held under the cut, as its log says; nothing of the
    // held skin above goes; and the measure counts it on the plate of every later pass.
    let k = (1..6).find(|&k| under(k, "buried").is_some()).expect("a pass before the last removes the bed");
    let z = under(k, "buried").unwrap();
    let log = std::fs::read_to_string(run.join(format!("log.pass.{k}"))).unwrap();
    let said: Vec<f64> = log
        .lines()
        .find_map(|l| l.strip_prefix(&format!("demsweep: buried {k} mass ")))
        .expect("the pass says what it removed")
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    let (before, after) = (plate_dump(&run, k), plate_dump(&run, k + 1));
    let gone: Vec<u64> = before.iter().filter(|(_, x)| x[2] < z).map(|p| p.0).collect();
    assert_eq!(said[1], gone.len() as f64, "pass {k} removed the {} particles under {z} m", gone.len());
    assert!(!gone.is_empty());
    let now: std::collections::HashMap<u64, [f64; 3]> = after.iter().copied().collect();
    assert!(gone.iter().all(|id| !now.contains_key(id)), "removed particles are gone from pass {}", k + 1);
    let skin = cut(k + 1).unwrap();
    for (id, x) in before.iter().filter(|(_, x)| x[2] >= z && x[2] < skin) {
        assert_eq!(now.get(id), Some(x), "the held skin's particle {id} stays");
    }
    // Equal spheres: the bed's relative density after a pass is its count over the first pass's,
    // the removed ones counted.
    let layers = measured(&run)["layers"].clone();
    let bed_rd = |j: usize| layers["passes"][j - 1]["bed_relative_density"].as_f64().unwrap();
    let first = plate_dump(&run, 1).len() as f64;
    let count = |j: usize| plate_dump(&run, j).len() as f64 + if j > k { gone.len() as f64 } else { 0.0 };
    let ratio = bed_rd(k + 1) / bed_rd(k);
    let counted = ((count(k + 1) - first) / k as f64) / ((count(k) - first) / (k - 1) as f64);
    assert!((ratio - counted).abs() < 1e-9, "pass {}: {ratio} against {counted} counting the removed", k + 1);
}

#[test]
fn a_fused_bed_s_search_pass_sets_the_next_depth_by_its_deposit_and_the_layers_after_it_are_laid() {
    support::require_liggghts!(
        "a_fused_bed_s_search_pass_sets_the_next_depth_by_its_deposit_and_the_layers_after_it_are_laid"
    );
    let (_tmp, dir) = support::cwd();
    // The round blade (the machine sweeps'), which no other LIGGGHTS test spreads with.
    // Six passes: with four the steady layer had two passes after its transient, too few, and
    // the run failed as unsteady; with six it is steady from pass 4 (10.5 CPU s).
    let sweep = bed(&dir, "bed = \"fused\"\nlayers = 6\nsearch_passes = 1\nblade_profile = \"round\"");
    let (code, r, stderr) = run_point(&sweep, "blade_speed=0.5");
    assert_eq!(code, 0, "the run failed: {}\n{stderr}", r["reason"]);
    let layers = &r["layers"];
    let passes = layers["passes"].as_array().unwrap_or_else(|| panic!("no passes: {r}"));
    assert_eq!(passes.len(), 6);
    let f = |k: usize, key: &str| passes[k - 1][key].as_f64().unwrap_or_else(|| panic!("{key} in {r}"));
    let t = 3e-3;
    assert_eq!(passes[0]["search"], true, "{r}");
    assert!(passes[1..].iter().all(|p| p.get("search").is_none()), "{r}");
    // The search: pass 2 meets pass 1's depth times the drop over its deposit (a deposit under
    // a third of a drop counted as a third, the depth kept within 1 and 20 drops) — LIGGGHTS's
    // arithmetic in the deck against ours.
    let counted = f(1, "deposit_m").max(t / 3.0);
    let asked = (f(1, "effective_thickness_m") * t / counted).clamp(t, 20.0 * t);
    assert!((f(2, "effective_thickness_m") - asked).abs() < 1e-9, "asked {asked}: {r}");
    // Then layers on the one before: the solid rises by each deposit, the platform by a drop.
    for k in 3..=6 {
        let expected = f(k - 1, "effective_thickness_m") + t - f(k - 1, "deposit_m");
        assert!((f(k, "effective_thickness_m") - expected).abs() < 1e-9, "pass {k}: {r}");
    }
    // The search pass is never the steady layer.
    assert!(layers["steady_from"].as_u64().unwrap() >= 2, "{r}");
}

#[test]
fn a_layers_lattice_runs_every_point_to_its_steady_layer_and_answers_in_the_layer_s_terms() {
    support::require_liggghts!(
        "a_layers_lattice_runs_every_point_to_its_steady_layer_and_answers_in_the_layer_s_terms"
    );
    let (_tmp, dir) = support::cwd();
    // A loose bed, five passes: both corners (0.2 and 0.8 m/s) steady, 14 CPU s. (A fused bed of
    // five passes was steady at neither: two passes after the transient at 0.2 m/s, and at
    // 0.8 m/s the bed fell behind, each pass leaving 0.39 of the drop.)
    let sweep = bed(&dir, "layers = 5");
    let out = support::sweep(&[
        "lattice",
        support::p(&sweep),
        "--levels",
        "2",
        "--out",
        support::p(&dir.join("s")),
    ]);
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), support::stderr(&out));
    // No point's record is unreadable or refused (a layers result measures no flux past the
    // blade, and a failed one's passes may hold measures it could not take).
    assert!(!stderr.contains("left out"), "{stderr}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s/summary.json")).unwrap()).unwrap();
    let counts = &summary["counts"];
    // Both points done: a failed run fails the test, with the failures the summary counts.
    assert_eq!(counts["done"].as_u64().unwrap(), 2, "{counts}\n{stderr}");
    let recommended =
        stdout.lines().find(|l| l.starts_with("recommended:")).unwrap_or_else(|| panic!("{stdout}"));
    // The setup speaks of a bed dosed pass by pass: no initial pile, no window of travel, no MFR.
    let page = std::fs::read_to_string(dir.join("s/report/report.html")).unwrap();
    for pile in ["initial pile", "measured over", "MFR = 0"] {
        assert!(!page.contains(pile), "the layers report says {pile:?}");
    }
    // The centre sentence counts a pass's dose, not every dose's particles as one number.
    assert!(page.contains("5 passes of ") && page.contains(" particles' dose onto a loose bed"), "centre");
    // Its setup lists what a layers point reads: the layer thickness, not the gap above a plate,
    // a held heap's height, a mono-sized powder's Weibull parameters, the plate's substrate or the
    // v_x band in front of the blade.
    assert!(page.contains(r#"<td class="l">layer_thickness</td>"#), "no layer_thickness row");
    for unread in ["gap", "heap_height", "weibull_shape", "weibull_scale"] {
        assert!(
            !page.contains(&format!(r#"<td class="l">{unread}</td>"#)),
            "the layers report lists {unread}"
        );
    }
    for row in [r#"<th class="l">substrate</th>"#, "v_x band", "v_x class", "at the window's end"] {
        assert!(!page.contains(row), "the layers report lists {row:?}");
    }
    // A loose bed is judged by its relative density (a fused one by its packing), in the answer
    // and on the page: its statistics and distribution are of it, not of an MFR no layers run
    // measures.
    assert!(recommended.contains("steady-layer relative density"), "{recommended}");
    assert!(recommended.contains("µm of powder under the blade"), "{recommended}");
    let says = |s: &str| page.contains(s);
    assert!(says("steady-layer relative density distribution"), "no distribution of the measure");
    let mfr = ["MFR distribution", "Emulator of MFR", "statistic of MFR", "<th>MFR", "MFR = 0"];
    for said in mfr.iter().chain(&["green ideal", "CV / noise"]) {
        assert!(!says(said), "the layers report says {said:?}");
    }
    // Each point pass by pass and its last layer from above, both points drawn; no v_x panels,
    // which a layers run does not measure.
    let report = dir.join("s/report");
    let drawn = |f: &str| report.join(f).exists();
    assert!(drawn("passes.png") && drawn("top-view.png") && !drawn("profiles.png"), "no empty v_x panels");
    assert!(page.contains("seen from above") && !page.contains("not drawn:"), "the top view");
    // The thesis's claims are of MFR: a layers sweep is not judged by them.
    assert!(!page.contains("The thesis's conclusions"), "thesis conclusions on a layers report");
}

#[test]
fn a_bad_layer_count_or_thickness_is_refused_in_one_line() {
    let (_tmp, dir) = support::cwd();
    for (extra, key) in [
        ("layers = 0", "scene.layers"),
        ("bed = \"molten\"", "scene.bed"),
        // More least passes than the most.
        ("layers = 4\nleast_layers = 5", "scene.least_layers"),
        // A radius that overflowed the blade's mesh (it panicked), one that took minutes to mesh.
        ("blade_profile = \"round\"\nblade_radius_mm = 1e155", "scene.blade_radius_mm"),
        ("blade_profile = \"round\"\nblade_radius_mm = 1e10", "scene.blade_radius_mm"),
        ("blade_profile = \"round\"\nblade_radius_mm = 0", "scene.blade_radius_mm"),
        // A radius a flat blade would ignore, a clearance of a kilometre.
        ("blade_radius_mm = 3.0", "scene.blade_radius_mm"),
        ("blade_clearance_mm = 1e6", "scene.blade_clearance_mm"),
    ] {
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

#[test]
fn a_fine_powder_in_thin_layers_is_dosed_sparser_and_spread_at_the_depth_it_asked_for() {
    support::require_liggghts!(
        "a_fine_powder_in_thin_layers_is_dosed_sparser_and_spread_at_the_depth_it_asked_for"
    );
    let (_tmp, dir) = support::cwd();
    // 40 µm in 40 µm layers: at a volume fraction of 0.3 the dose's region would be under
    // LIGGGHTS's least insertion region ("Unable to calculate region volume").
    let sweep = support::write_file(
        &dir.join("fine.toml"),
        r#"name = "fine"
[parameters]
blade_speed     = { lo = 0.08, hi = 0.12, unit = "m/s" }
diameter        = 0.04
layer_thickness = { value = 0.04, unit = "mm" }
density         = 4430
youngs_modulus  = { value = 5, unit = "MPa" }
friction        = 0.3
restitution     = 0.4
[scene]
layout = "layers"
layers = 5
plate_diameters = 10
"#,
    );
    let deck = dir.join("deck");
    support::ok(
        &dir,
        &["render", support::p(&sweep), "--set", "blade_speed=0.1", "--out", support::p(&deck)],
    );
    let input = std::fs::read_to_string(deck.join("in.liggghts")).unwrap();
    let word_after = |line: &str, word: &str| -> f64 {
        let mut it = line.split_whitespace().skip_while(|w| *w != word);
        it.next();
        it.next().unwrap().parse().unwrap()
    };
    let inserts: Vec<&str> = input.lines().filter(|l| l.contains("insert/pack")).collect();
    assert_eq!(inserts.len(), 5, "one dose a pass");
    for line in &inserts {
        let fraction = word_after(line, "volumefraction_region");
        assert!(fraction > 0.0 && fraction < 0.3, "{line}");
        // Thrown down: the third velocity component is negative.
        let vz: f64 =
            line.split("vel constant ").nth(1).unwrap().split_whitespace().nth(2).unwrap().parse().unwrap();
        assert!((-0.5 - 1e-9..0.0).contains(&vz), "{line}");
    }
    // The periodic depth stays a few diameters: the box is not widened for the dose.
    let depth =
        input.lines().find(|l| l.starts_with("region domain")).unwrap().split_whitespace().nth(6).unwrap();
    let depth: f64 = depth.parse().unwrap();
    assert!(depth < 10.0 * 40e-6, "depth {depth}");

    // A loose bed, five passes: steady from pass 3 (7.4 CPU s). Two passes of a fused bed, as
    // this test ran, are never steady (it read the failed run's passes); and a fused bed of this
    // powder at 0.1 m/s falls behind, each pass leaving 0.54 of the drop (0.61 at twice the dose).
    let (code, r, stderr) = run_point(&sweep, "blade_speed=0.1");
    assert_eq!(code, 0, "the run failed: {}\n{stderr}", r["reason"]);
    let passes = r["layers"]["passes"].as_array().unwrap_or_else(|| panic!("no passes: {r}"));
    assert_eq!(passes.len(), 5, "{r}");
    for p in passes {
        assert!(p["particles"].as_u64().unwrap() > 0, "the pass deposited nothing: {p}");
        assert!(p["deposit_m"].as_f64().unwrap() > 0.0, "{p}");
    }
}

/// The passes' records of a point's run directory, and its result.
pub(crate) fn passes_of(dir: &Path) -> Vec<Value> {
    let r: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("result.json")).unwrap()).unwrap();
    r["layers"]["passes"].as_array().unwrap().clone()
}

#[test]
fn a_layers_point_killed_in_its_third_pass_goes_on_from_its_second_and_ends_as_an_uninterrupted_one() {
    support::require_liggghts!(
        "a_layers_point_killed_in_its_third_pass_goes_on_from_its_second_and_ends_as_an_uninterrupted_one"
    );
    let (_tmp, dir) = support::cwd();
    let sweep = bed(&dir, "layers = 4\nleast_layers = 4");
    let run = |out: &Path| {
        support::sweep_bin()
            .args(["run", support::p(&sweep), "--set", "blade_speed=0.5", "--out", support::p(out)])
            .output()
            .unwrap()
    };
    let whole = dir.join("whole");
    let out = run(&whole);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    // A terminal is told each pass as it ends, in order.
    let said: Vec<String> =
        err.lines().filter(|l| l.starts_with("pass ")).map(|l| l[..19].to_string()).collect();
    assert_eq!(said, (1..=4).map(|k| format!("pass {k} of at most 4")).collect::<Vec<_>>(), "{err}");
    // Every pass is its own engine run, and only the last one's restart is kept.
    for k in 1..=4 {
        assert!(whole.join(format!("log.pass.{k}")).is_file(), "pass {k}'s log");
    }
    assert!(whole.join("restart.pass.4").is_file() && !whole.join("restart.pass.3").exists());

    // Killed (SIGKILL, the whole process group) once pass 3's engine run has started.
    let cut = dir.join("cut");
    let args = ["run", support::p(&sweep), "--set", "blade_speed=0.5", "--out", support::p(&cut)];
    kill_once(support::sweep_bin().args(args), &cut.join("in.pass.3"));
    assert!(!cut.join("pass.3.json").exists() && cut.join("restart.pass.2").is_file());
    // The earlier attempt's passes are made to look 1,000 s long each: a point resumed gets its
    // whole timeout (600 s) again, as a new job gets its walltime, and does not fail at once.
    let cpu_12: f64 = (1..=2)
        .map(|k| {
            let f = cut.join(format!("pass.{k}.json"));
            let mut r: Value = serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
            r["wall_time"] = 1000.0.into();
            std::fs::write(&f, r.to_string()).unwrap();
            r["cpu_time"].as_f64().unwrap()
        })
        .sum();
    // Run again: it goes on from pass 2's restart, passes 1 and 2 not run again.
    let out = run(&cut);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("going on from pass 2")
            && err.contains("pass 3 of at most 4")
            && !err.contains("pass 2 of"),
        "{err}"
    );
    let first_log = std::fs::read_to_string(cut.join("log.pass.1")).unwrap();
    assert!(first_log.contains("demsweep: layer 1"), "pass 1's log kept");
    let r: Value = serde_json::from_str(&std::fs::read_to_string(cut.join("result.json")).unwrap()).unwrap();
    assert!(r["cpu_time"].as_f64().unwrap() > cpu_12, "the point's CPU counts its passes before the kill");
    // Each pass goes on from the restart the pass before wrote either way: the same passes.
    let (a, b) = (passes_of(&whole), passes_of(&cut));
    assert_eq!(a.len(), 4);
    assert_eq!(a, b, "an interrupted point ends where an uninterrupted one does");

    // Ctrl-C in a pass: exit 130 and one line that says what is kept and how it goes on.
    let ctrl_c = dir.join("ctrl-c");
    let child = support::sweep_bin()
        .args(["run", support::p(&sweep), "--set", "blade_speed=0.5", "--out", support::p(&ctrl_c)])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    support::wait_until("pass 2 to start", std::time::Duration::from_secs(120), || {
        ctrl_c.join("in.pass.2").is_file()
    });
    // SAFETY: kill(2) on our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let o = child.wait_with_output().unwrap();
    let err = support::stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    let said = format!(
        "interrupted: {} is kept: the same command again goes on from its last finished pass",
        ctrl_c.display()
    );
    assert!(err.contains(&said) && !err.contains("error: interrupted"), "{err}");
}

#[test]
fn a_layers_point_stops_once_its_steady_layer_holds_and_at_its_most_passes_otherwise() {
    support::require_liggghts!(
        "a_layers_point_stops_once_its_steady_layer_holds_and_at_its_most_passes_otherwise"
    );
    let (_tmp, dir) = support::cwd();
    let sweep = bed(&dir, "layers = 9\nleast_layers = 5");
    let (code, r, stderr) = run_point(&sweep, "blade_speed=0.5");
    let layers = if code == 0 { &r["layers"] } else { &r["measured"]["layers"] };
    let passes = layers["passes"].as_array().unwrap_or_else(|| panic!("exit {code}: {stderr}\n{r}"));
    let ran = passes.len();
    assert!((5..=9).contains(&ran), "between the least and the most passes: {ran}");
    if code == 0 {
        // Steady: it stopped at the first pass from the least on where its steady layer kept at
        // least four passes, and no later.
        let kept = ran + 1 - layers["steady_from"].as_u64().unwrap() as usize;
        assert!(kept >= 4 || ran == 9, "stopped at pass {ran} with {kept} steady passes");
    } else {
        // Not steady: it ran its most passes, failed as unsteady (nothing else), and says why.
        assert_eq!(ran, 9, "a point not steady runs its most passes: {stderr}");
        assert_eq!(r["class"], "unsteady", "{r}");
        let why = r["reason"].as_str().unwrap();
        assert!(
            ["trends over passes", "fewer than", "falls behind"].iter().any(|s| why.contains(s)),
            "an unsteady point says what is not steady: {why}"
        );
    }
}

/// What a layers point measured, whether it ended steady (result.json) or not (failure.json's
/// measure).
pub(crate) fn measured(run: &Path) -> Value {
    let read = |f: &str| {
        std::fs::read_to_string(run.join(f)).ok().map(|t| serde_json::from_str::<Value>(&t).unwrap())
    };
    match (read("result.json"), read("failure.json")) {
        (Some(r), _) => r,
        (None, Some(f)) => f["measured"].clone(),
        (None, None) => panic!("{}: neither result.json nor failure.json", run.display()),
    }
}

/// The passes a layers point measured, steady or not.
fn measured_passes(run: &Path) -> Vec<Value> {
    let layers = measured(run)["layers"].clone();
    layers["passes"].as_array().unwrap_or_else(|| panic!("no passes in {layers}")).clone()
}

/// Run `cmd` in its own process group and SIGKILL the group once `file` exists.
pub(crate) fn kill_once(cmd: &mut std::process::Command, file: &Path) {
    use std::os::unix::process::CommandExt;
    let mut child = cmd.process_group(0).spawn().unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(600);
    while !file.is_file() {
        assert!(std::time::Instant::now() < deadline, "{} never appeared", file.display());
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // SAFETY: kill(2) on the child's own process group.
    unsafe { libc::kill(-(child.id() as i32), libc::SIGKILL) };
    let _ = child.wait();
}

/// The one run directory of a one-point sweep directory.
fn only_run(sweep_dir: &Path) -> PathBuf {
    let runs: Vec<PathBuf> =
        std::fs::read_dir(sweep_dir.join("runs")).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(runs.len(), 1, "{runs:?}");
    runs[0].clone()
}

#[test]
fn sweep_extend_gives_a_layers_point_not_steady_at_its_most_more_passes_and_survives_a_kill() {
    support::require_liggghts!(
        "sweep_extend_gives_a_layers_point_not_steady_at_its_most_more_passes_and_survives_a_kill"
    );
    let (_tmp, dir) = support::cwd();
    // Two passes: too few for a steady layer (three after the transient), so the point fails
    // as unsteady; its machine is built for four.
    let sweep = bed(&dir, "layers = 2\nleast_layers = 2\n[design.lds]\nstep = 1\nmax = 1");
    let unsteady = |name: &str| {
        let d = dir.join(name);
        let out = support::sweep(&["lds", support::p(&sweep), "--out", support::p(&d)]);
        let run = only_run(&d);
        let f: Value = serde_json::from_str(
            &std::fs::read_to_string(run.join("failure.json"))
                .unwrap_or_else(|_| panic!("not a failure: {}", support::stderr(&out))),
        )
        .unwrap();
        assert_eq!(f["class"], "unsteady", "{f}");
        assert_eq!(measured_passes(&run).len(), 2);
        (d, run)
    };
    let (whole, whole_run) = unsteady("whole");
    // An SE means nothing to a point run by the pass: one line naming --passes, nothing changed.
    let failure_before = std::fs::read(whole_run.join("failure.json")).unwrap();
    let out = support::sweep(&["extend", support::p(&whole)]);
    assert_eq!(out.status.code(), Some(2));
    let err = support::stderr(&out);
    assert!(err.contains("--passes") && err.lines().count() == 1, "{err}");
    assert_eq!(std::fs::read(whole_run.join("failure.json")).unwrap(), failure_before);

    let first_log = std::fs::read(whole_run.join("log.pass.1")).unwrap();
    let out = support::sweep(&["extend", support::p(&whole), "--passes", "2"]);
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), support::stderr(&out));
    assert!(stdout.contains("extend by up to 2 passes: 1 finished points"), "{stdout}\n{stderr}");
    // It went on from pass 2: passes 1 and 2 not run again, 3 and 4 run (it may stop steady
    // only at its new most: four passes cannot keep four after the transient before it).
    assert_eq!(std::fs::read(whole_run.join("log.pass.1")).unwrap(), first_log, "pass 1 ran again");
    let passes = measured_passes(&whole_run);
    assert_eq!(passes.len(), 4, "{stderr}");
    let steady = whole_run.join("result.json").is_file();
    assert_eq!(steady, stderr.contains("steady now"), "{stderr}");
    assert_eq!(!steady, stderr.contains("still not steady"), "{stderr}");
    // Again: a steady point says so and runs nothing; one at its machine's last pass says why.
    let out = support::sweep(&["extend", support::p(&whole), "--passes", "2"]);
    let stderr = support::stderr(&out);
    if steady {
        assert!(stderr.contains("steady already"), "{stderr}");
    } else {
        assert!(
            stderr.contains("no room for 2 more passes") && stderr.contains("built for 4 passes"),
            "{stderr}"
        );
    }
    assert!(!whole_run.join("log.pass.5").exists());

    // Killed (SIGKILL, the whole process group) in the extension's first pass: the point keeps
    // its earlier outcome, and extending it again goes on from pass 2 to where the
    // uninterrupted extension ended.
    let (cut, cut_run) = unsteady("cut");
    kill_once(
        support::sweep_bin().args(["extend", support::p(&cut), "--passes", "2"]),
        &cut_run.join("in.pass.3"),
    );
    assert!(cut_run.join("failure.json").is_file() && !cut_run.join("pass.3.json").exists());
    let out = support::sweep(&["extend", support::p(&cut), "--passes", "2"]);
    assert!(out.status.code().is_some(), "{}", support::stderr(&out));
    assert_eq!(
        measured_passes(&cut_run),
        passes,
        "an interrupted extension ends where an uninterrupted one does"
    );
    assert_eq!(cut_run.join("result.json").is_file(), steady);
}

/// The run directories of a sweep directory with their result (or failure's measure).
fn measured_runs(sweep_dir: &Path) -> Vec<(PathBuf, Value)> {
    let mut runs: Vec<(PathBuf, Value)> = std::fs::read_dir(sweep_dir.join("runs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|run| {
            let r = measured(&run);
            (run, r)
        })
        .collect();
    runs.sort_by(|a, b| a.0.cmp(&b.0));
    runs
}

#[test]
fn a_fused_bed_warm_started_from_its_neighbour_searches_from_its_depth_and_resumes_as_it_began() {
    support::require_liggghts!(
        "a_fused_bed_warm_started_from_its_neighbour_searches_from_its_depth_and_resumes_as_it_began"
    );
    let (_tmp, dir) = support::cwd();
    let sweep = bed(&dir, "bed = \"fused\"\nlayers = 12\nwarm_start = true\n[design.lds]\nstep = 2\nmax = 2");
    let lds =
        |out: &Path| support::sweep(&["lds", support::p(&sweep), "--jobs", "1", "--out", support::p(out)]);
    let whole = dir.join("whole");
    lds(&whole);
    let runs = measured_runs(&whole);
    assert_eq!(runs.len(), 2);
    let (warm, cold): (Vec<_>, Vec<_>) = runs.iter().partition(|(_, r)| !r["warm_start"].is_null());
    assert_eq!((warm.len(), cold.len()), (1, 1), "the second point starts from the first");
    let ((warm_run, w), (cold_run, c)) = (warm[0], cold[0]);
    assert_eq!(w["warm_start"]["from"], c["hash"]);
    let searched =
        |r: &Value| r["layers"]["passes"].as_array().unwrap().iter().filter(|p| p["search"] == true).count();
    let warm_search = demsweep::scenes::layers::warm::WARM_SEARCH_PASSES;
    assert_eq!((searched(c), searched(w)), (6, warm_search), "six search passes cold, fewer warm");
    // Its first pass lies on a solid set at the neighbour's steady depth (in layer thicknesses)
    // under its tip, not on the plate.
    let depth_layers = c["layers"]["effective_thickness_m"].as_f64().unwrap()
        / c["layers"]["layer_thickness_m"].as_f64().unwrap();
    let first = &w["layers"]["passes"][0];
    let depth =
        first["effective_thickness_m"].as_f64().unwrap() / w["layers"]["layer_thickness_m"].as_f64().unwrap();
    assert!(
        (depth - depth_layers).abs() < 1e-9,
        "first pass {depth} layers under the tip, neighbour's {depth_layers}"
    );
    let plate_floor = "plate.stl type 2 move 0 0 0.0\n";
    assert!(std::fs::read_to_string(cold_run.join("in.pass.1")).unwrap().contains(plate_floor));
    assert!(!std::fs::read_to_string(warm_run.join("in.pass.1")).unwrap().contains(plate_floor));
    assert!(warm_run.join("warm-start.json").is_file());

    // Killed in the warm point's third pass, then resumed with its neighbour's result gone: it
    // goes on from the warm start it recorded and ends where the uninterrupted sweep's did.
    let cut = dir.join("cut");
    let warm_cut = cut.join("runs").join(warm_run.file_name().unwrap());
    kill_once(
        support::sweep_bin().args(["lds", support::p(&sweep), "--jobs", "1", "--out", support::p(&cut)]),
        &warm_cut.join("in.pass.3"),
    );
    let neighbour = cut.join("runs").join(cold_run.file_name().unwrap()).join("result.json");
    std::fs::remove_file(&neighbour).unwrap();
    let records = |run: &Path| {
        (1..=2)
            .map(|k| std::fs::read_to_string(run.join(format!("pass.{k}.json"))).unwrap())
            .collect::<Vec<_>>()
    };
    let before = records(&warm_cut);
    let out = support::sweep(&["resume", support::p(&cut), "--jobs", "1"]);
    assert!(out.status.code().is_some(), "{}", support::stderr(&out));
    // The resume goes on from pass 2: passes 1 and 2 are not run again.
    assert_eq!(records(&warm_cut), before, "a resumed sweep keeps a point's finished passes");
    let resumed =
        measured_runs(&cut).into_iter().find(|(run, _)| run.file_name() == warm_run.file_name()).unwrap().1;
    assert_eq!(resumed["warm_start"], w["warm_start"]);
    assert_eq!(
        resumed["layers"]["passes"], w["layers"]["passes"],
        "a resumed warm point ends as an uninterrupted one"
    );
}
