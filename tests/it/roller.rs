//! The layers layout's roller (`blade_profile = "roller"`): its deck's motion through the real
//! LIGGGHTS against the closed form of a cylinder that travels and turns, a short roller run
//! that ends with a steady layer, and the bad input it refuses in one line.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support::{self, run_point};

/// A loose-bed layers sweep of 2 mm spheres spread by a roller of radius 5 mm, with `parameters`
/// after the common ones and `extra` in `[scene]`.
fn roller(dir: &Path, parameters: &str, extra: &str) -> PathBuf {
    crate::layers::bed_file(
        dir,
        "roller",
        parameters,
        &format!("blade_profile = \"roller\"\nblade_radius_mm = 5\n{extra}"),
    )
}

/// The vertices of an ASCII STL, in the file's order.
fn vertices(stl: &str) -> Vec<[f64; 3]> {
    stl.lines()
        .filter_map(|l| l.trim().strip_prefix("vertex"))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// The number after `key` on the deck's line starting with `start`.
fn after(deck: &str, start: &str, key: &str) -> f64 {
    let line =
        deck.lines().find(|l| l.starts_with(start)).unwrap_or_else(|| panic!("no {start:?} in the deck"));
    let rest =
        line[line.find(key).unwrap_or_else(|| panic!("no {key:?} in {line}")) + key.len()..].trim_start();
    let end = rest.find(|c: char| !(c.is_ascii_digit() || ".e-+".contains(c))).unwrap_or(rest.len());
    rest[..end].parse().unwrap_or_else(|_| panic!("{key:?} in {line}"))
}

#[test]
fn the_roller_travels_and_turns_as_a_cylinder_whose_surface_runs_at_its_speed_ratio() {
    support::require_liggghts!(
        "the_roller_travels_and_turns_as_a_cylinder_whose_surface_runs_at_its_speed_ratio"
    );
    let (_tmp, dir) = support::cwd();
    let (ratio, r, v) = (2.0, 5e-3, 0.5);
    let sweep = roller(&dir, &format!("roller_speed_ratio = {ratio}"), "layers = 1");
    let deck = dir.join("deck");
    support::ok(
        &dir,
        &["render", support::p(&sweep), "--set", "blade_speed=0.5", "--out", support::p(&deck)],
    );
    let input = std::fs::read_to_string(deck.join("in.liggghts")).unwrap();
    let dt = after(&input, "timestep", "timestep");
    let ramp = after(&input, "variable bladevx1", "<");
    let tip = after(&input, "fix blade1", "move 0 0 ");
    // The deck up to the roller's first run, which runs n − 1 steps; then one more with the
    // roller's mesh dumped (its velocity is zeroed at a run's setup and set again in each step).
    let n = 1000u64;
    let mut cut = String::new();
    let mut turning = false;
    for line in input.lines() {
        turning |= line.starts_with("fix roll1");
        if turning && line.starts_with("run ") {
            break;
        }
        cut += line;
        cut.push('\n');
    }
    assert!(turning, "the deck turns no roller:\n{input}");
    cut += &format!(
        "run {}\ndump rstl all mesh/stl 1 roller*.stl blade1\n\
         dump rvtk all mesh/vtk 1 roller*.vtk output face vel blade1\nrun 1\n\
         variable refx equal f_blade1[7]\nvariable refy equal f_blade1[8]\nvariable refz equal f_blade1[9]\n\
         print \"reference point ${{refx}} ${{refy}} ${{refz}}\"\n",
        n - 1
    );
    let (said, _) = run_cut(&deck, &cut);
    // The last dump of each (the first is the setup's).
    let last = |ext: &str| {
        let mut files: Vec<(u64, PathBuf)> = std::fs::read_dir(&deck)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter_map(|p| {
                let name = p.file_name()?.to_str()?.to_string();
                let step = name.strip_prefix("roller")?.strip_suffix(ext)?.parse().ok()?;
                Some((step, p))
            })
            .collect();
        files.sort();
        std::fs::read_to_string(&files.last().unwrap_or_else(|| panic!("no roller*{ext}")).1).unwrap()
    };

    // The closed form: the travel ramps from rest over `ramp` steps (step i moves v·min(i/ramp, 1)·dt),
    // and the roller turns about its own axis, carried with it, by −ratio × travel / radius about
    // +y — counter-rotating: its lowest line runs ahead of the axis.
    let steps = |k: u64| (1..=k).map(|i| (i as f64 / ramp).min(1.0)).sum::<f64>();
    let travel = v * dt * steps(n);
    let phi = -ratio * travel / r;
    let before = vertices(&std::fs::read_to_string(deck.join("blade.stl")).unwrap());
    let after_n = vertices(&last(".stl"));
    assert_eq!(before.len(), after_n.len());
    // The axis where the mesh file puts it: the middle of the circle's extent, raised to the tip.
    let (lo, hi) = before.iter().fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), p| {
        ([lo[0].min(p[0]), lo[1].min(p[2])], [hi[0].max(p[0]), hi[1].max(p[2])])
    });
    let (xc, zc) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]) + tip);
    assert!(
        (hi[1] - lo[1] - 2.0 * r).abs() < 1e-9 && (hi[0] - lo[0] - 2.0 * r).abs() < 1e-9,
        "{lo:?} {hi:?}"
    );
    // The dump writes 6 significant digits: a few 1e-8 m at these coordinates. One step of the
    // travel is v·dt = 1.8e-5 m, and an axis left behind by the travel would be off by about
    // travel × phi (0.07 m).
    let tol = 2e-7;
    for (p0, p) in before.iter().zip(&after_n) {
        let (x, z) = (p0[0] - xc, p0[2] + tip - zc);
        let want = [xc + travel + x * phi.cos() + z * phi.sin(), p0[1], zc - x * phi.sin() + z * phi.cos()];
        for i in 0..3 {
            assert!((p[i] - want[i]).abs() < tol, "node {p0:?} is at {p:?}, the closed form at {want:?}");
        }
    }
    // The torque the roller's mesh sums is about its reference point: carried with the axis by
    // the travel, and on it, so the turn about the axis leaves it there.
    let reference: Vec<f64> = said
        .lines()
        .find_map(|l| l.strip_prefix("reference point "))
        .unwrap_or_else(|| panic!("no reference point in\n{said}"))
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let axis = [xc + travel, 0.0, zc];
    for i in 0..3 {
        assert!((reference[i] - axis[i]).abs() < 1e-9, "reference point {reference:?}, the axis at {axis:?}");
    }
    // More than a radius of travel and half a turn: an error in either is far outside `tol`.
    assert!(
        travel > r && phi.abs() > std::f64::consts::PI,
        "a test of too little motion: {travel} m, {phi} rad"
    );

    // The velocity the contacts see: every face's, the travel plus ω × (centroid − axis), with
    // ω = −ratio · v / r about +y at full speed.
    let vtk = last(".vtk");
    let data = vtk.split("double\n").nth(1).unwrap_or_else(|| panic!("no velocities in\n{vtk}"));
    let vel: Vec<f64> = data.split_whitespace().map_while(|x| x.parse().ok()).collect();
    assert_eq!(vel.len(), after_n.len(), "one velocity a face");
    let omega = -ratio * v / r;
    let (xc_n, mut lowest) = (xc + travel, (f64::MAX, 0.0));
    for (face, u) in after_n.chunks(3).zip(vel.chunks(3)) {
        let c: Vec<f64> = (0..3).map(|i| face.iter().map(|p| p[i]).sum::<f64>() / 3.0).collect();
        let (x, z) = (c[0] - xc_n, c[2] - zc);
        // ω ŷ × (x, 0, z) = (ω z, 0, −ω x).
        let want = [v + omega * z, 0.0, -omega * x];
        for i in 0..3 {
            assert!(
                (u[i] - want[i]).abs() < 1e-4 * v,
                "face at {c:?} moves at {u:?}, the closed form {want:?}"
            );
        }
        if c[2] < lowest.0 {
            lowest = (c[2], u[0]);
        }
    }
    // Under the roller its surface runs ahead at (1 + ratio) × the travel speed (less the chord's
    // sag, cos(π/128)).
    assert!((lowest.1 - v * (1.0 + ratio)).abs() < 1e-3 * v, "the lowest face moves at {} m/s", lowest.1);
}

#[test]
fn a_short_roller_run_spreads_layers_and_ends_with_a_steady_layer() {
    support::require_liggghts!("a_short_roller_run_spreads_layers_and_ends_with_a_steady_layer");
    let (_tmp, dir) = support::cwd();
    let sweep = roller(&dir, "roller_speed_ratio = { lo = 0.0, hi = 4.0 }", "layers = 5");
    let (code, r, stderr) = run_point(&sweep, "blade_speed=0.5,roller_speed_ratio=2");
    assert_eq!(code, 0, "the run failed: {}\n{stderr}", r["reason"]);
    let layers = &r["layers"];
    let passes = layers["passes"].as_array().unwrap_or_else(|| panic!("no passes: {r}"));
    assert!(passes.len() >= 4, "{r}");
    for p in passes {
        assert!(p["particles"].as_u64().unwrap() > 0, "a pass deposited nothing: {p}");
        let rd = p["relative_density"].as_f64().unwrap();
        assert!(rd > 0.0 && rd < 0.75, "{p}");
    }
    let packing = layers["relative_density"].as_f64().unwrap();
    assert!(packing > 0.0 && packing < 0.75 && layers["steady"] == true, "{r}");
    // Its load: turning against the powder (counter-rotating) and pushing through it both take
    // power in every pass; the steady load is the steady passes' mean.
    let load =
        |p: &serde_json::Value, key: &str| p["roller"][key].as_f64().unwrap_or_else(|| panic!("{key}: {p}"));
    for p in passes {
        for key in ["turning_power_w_per_m", "push_n_per_m", "pushing_power_w_per_m", "torque_nm_per_m"] {
            assert!(load(p, key) > 0.0, "pass {}: {key} {}", p["k"], load(p, key));
        }
    }
    let from = layers["steady_from"].as_u64().unwrap() as usize;
    let kept: Vec<f64> = passes[from - 1..].iter().map(|p| load(p, "turning_power_w_per_m")).collect();
    let mean = kept.iter().sum::<f64>() / kept.len() as f64;
    let steady = layers["roller"]["mean"]["turning_power_w_per_m"].as_f64().unwrap();
    assert!((steady - mean).abs() <= 1e-12 * mean, "{steady} against the steady passes' {mean}");
    // The powder it sent over its top: measured in every pass (none of it is negative), the
    // steady figure the steady passes' mean.
    let kept: Vec<f64> =
        passes[from - 1..].iter().map(|p| p["roller"]["ejected_kg_per_m"].as_f64().unwrap()).collect();
    assert!(passes.iter().all(|p| p["roller"]["ejected_kg_per_m"].as_f64().is_some_and(|e| e >= 0.0)), "{r}");
    let mean = kept.iter().sum::<f64>() / kept.len() as f64;
    let steady = layers["roller"]["mean"]["ejected_kg_per_m"].as_f64().unwrap();
    assert!((steady - mean).abs() <= 1e-12 * mean.max(1e-30), "{steady} against the steady passes' {mean}");
    assert!(layers["roller"]["se"]["ejected_kg_per_m"].as_f64().is_some(), "{r}");
}

/// The `demsweep: ejected k mass M count N` lines of a log, by pass.
fn ejected_lines(log: &str) -> Vec<(usize, f64, usize)> {
    log.lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.trim().strip_prefix("demsweep: ejected ")?.split_whitespace().collect();
            Some((f[0].parse().ok()?, f[2].parse().ok()?, f.get(4)?.parse::<f64>().ok()? as usize))
        })
        .collect()
}

#[test]
fn the_powder_sent_over_the_roller_is_the_mass_whose_centres_cross_its_top_line_going_up() {
    support::require_liggghts!(
        "the_powder_sent_over_the_roller_is_the_mass_whose_centres_cross_its_top_line_going_up"
    );
    let (_tmp, dir) = support::cwd();
    // Fast enough to throw: its surface runs at 2 m/s about its axis (a throw of 0.2 m, far over
    // its 10 mm height).
    let sweep = roller(&dir, "roller_speed_ratio = 4", "layers = 2");
    let deck = dir.join("deck");
    support::ok(
        &dir,
        &["render", support::p(&sweep), "--set", "blade_speed=0.5", "--out", support::p(&deck)],
    );
    let input = std::fs::read_to_string(deck.join("in.liggghts")).unwrap();
    // Independently of the deck's count: every particle within 1 mm under the plane or above it,
    // every step, with its mass, over the span the deck counts in (from its count's fix to its
    // line in the log).
    let mut cut = String::new();
    let mut planes = Vec::new();
    for line in input.lines() {
        cut += line;
        cut.push('\n');
        if let Some(k) = line.strip_prefix("fix ejected").and_then(|r| r.split_whitespace().next()) {
            let z = after(&input, &format!("fix over{k} "), "move 0 0 ");
            planes.push(z);
            cut += &format!(
                "region band{k} block INF INF INF INF {} INF units box\n\
                 dump band{k} all custom 1 band{k}.dump id z mass\n\
                 dump_modify band{k} region band{k} format \"%d %.17g %.17g\"\n",
                z - 1e-3
            );
        }
        if let Some(k) =
            line.strip_prefix("print \"demsweep: ejected ").and_then(|r| r.split_whitespace().next())
        {
            cut += &format!("undump band{k}\n");
        }
    }
    assert_eq!(planes.len(), 2, "the deck counts in {} passes:\n{input}", planes.len());
    let (_, log) = run_cut(&deck, &cut);
    let counted = ejected_lines(&log);
    assert_eq!(counted.len(), 2, "{log}");
    let mut thrown = 0;
    for ((k, mass, count), z) in counted.into_iter().zip(&planes) {
        // A particle crosses once it has been seen at or under the plane and then over it; each
        // counts once in the pass.
        let dump = std::fs::read_to_string(deck.join(format!("band{k}.dump"))).unwrap();
        let (mut under, mut crossed) = (std::collections::HashSet::new(), std::collections::HashMap::new());
        let mut atoms = false;
        for line in dump.lines() {
            if line.starts_with("ITEM:") {
                atoms = line.starts_with("ITEM: ATOMS");
                continue;
            }
            if !atoms {
                continue;
            }
            let f: Vec<f64> = line.split_whitespace().map(|x| x.parse().unwrap()).collect();
            let (id, zi, m) = (f[0] as u64, f[1], f[2]);
            if zi <= *z {
                under.insert(id);
            } else if under.contains(&id) {
                crossed.entry(id).or_insert(m);
            }
        }
        let truth: f64 = crossed.values().sum();
        assert_eq!(
            count,
            crossed.len(),
            "pass {k}: the deck counted {count}, the positions show {}",
            crossed.len()
        );
        assert!((mass - truth).abs() <= 1e-9 * truth.max(1e-30), "pass {k}: {mass} kg against {truth} kg");
        eprintln!(
            "pass {k}: {count} particles, {mass:.4e} kg over the roller (the positions: {}, {truth:.4e} kg)",
            crossed.len()
        );
        thrown += count;
    }
    assert!(thrown > 0, "nothing went over the roller: a test of nothing\n{log}");

    // The result reads the same lines, per metre of the slice's width (the box's y extent).
    let domain: Vec<&str> =
        input.lines().find(|l| l.starts_with("region domain")).unwrap().split_whitespace().collect();
    let depth: f64 = domain[6].parse::<f64>().unwrap() - domain[5].parse::<f64>().unwrap();
    let read = demsweep::scenes::layers::measure::parse_ejected(&log, depth);
    for ((k, per_m), (j, mass, _)) in read.iter().zip(ejected_lines(&log)) {
        assert!(*k == j && (per_m * depth - mass).abs() <= 1e-12 * mass.max(1e-30), "pass {k}: {per_m} kg/m");
    }
}

/// `sweep render` of `sweep` at `set` into `dir/d`: exit 2 and one stderr line holding every
/// needle, no panic, nothing written.
fn refused(dir: &Path, sweep: &Path, set: &str, needles: &[&str]) {
    let out = dir.join("d");
    let o = support::sweep(&["render", support::p(sweep), "--set", set, "--out", support::p(&out)]);
    let err = support::stderr(&o);
    let case = format!("{}\n--set {set}", std::fs::read_to_string(sweep).unwrap());
    assert_eq!(o.status.code(), Some(2), "{case}\n{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{case}\n{err}");
    for needle in needles {
        assert!(err.contains(needle), "{case}\nno {needle:?} in: {err}");
    }
    assert!(!err.contains("panick"), "{err}");
    assert!(!out.exists(), "{case}\nwrote a deck");
}

/// [`roller`]'s sweep with its `blade_radius_mm = 5` and `blade_profile = "roller"` lines
/// replaced by `radius` and `profile`.
fn with(dir: &Path, parameters: &str, radius: &str, profile: &str) -> PathBuf {
    let sweep = roller(dir, parameters, "");
    let toml = std::fs::read_to_string(&sweep)
        .unwrap()
        .replace("blade_radius_mm = 5\n", &format!("blade_radius_mm = {radius}\n"))
        .replace("blade_profile = \"roller\"", &format!("blade_profile = \"{profile}\""));
    support::write_file(&sweep, &toml)
}

#[test]
fn a_roller_s_bad_radius_or_ratio_and_a_ratio_without_a_roller_are_refused_in_one_line() {
    let (_tmp, dir) = support::cwd();
    let swept = "roller_speed_ratio = { lo = 0.0, hi = 4.0 }";
    // A radius of nothing, a negative one, one that overflows the mesh, one that is no number.
    for (radius, says) in [("0", "0: "), ("-1", "-1: "), ("1e155", ": "), ("nan", "NaN: ")] {
        let sweep = with(&dir, swept, radius, "roller");
        refused(
            &dir,
            &sweep,
            "blade_speed=0.5",
            &["scene.blade_radius_mm", says, "expected a number above 0"],
        );
    }
    // A ratio that is not a number, in the file or on the command line.
    for ratio in ["inf", "-inf", "nan"] {
        let sweep = with(&dir, &format!("roller_speed_ratio = {ratio}"), "5", "roller");
        refused(&dir, &sweep, "blade_speed=0.5", &["parameters.roller_speed_ratio", "not a finite number"]);
    }
    let sweep = with(&dir, swept, "5", "roller");
    refused(
        &dir,
        &sweep,
        "blade_speed=0.5,roller_speed_ratio=inf",
        &["roller_speed_ratio", "expected a finite number"],
    );
    // A ratio where no roller reads it — swept, set in the file or on the command line — names
    // the layout's blade and the profile that reads it.
    let blade = [
        "roller_speed_ratio",
        "the layers layout turns no roller with this blade",
        "blade_profile = \"roller\"",
    ];
    // (A flat blade takes no radius: the default's.)
    for (profile, radius) in [("round", "5"), ("flat", "2.5")] {
        refused(&dir, &with(&dir, swept, radius, profile), "blade_speed=0.5", &blade);
        refused(&dir, &with(&dir, "roller_speed_ratio = 1.5", radius, profile), "blade_speed=0.5", &blade);
        refused(&dir, &with(&dir, "", radius, profile), "blade_speed=0.5,roller_speed_ratio=3", &blade);
    }
    // Another layout: the conveyor has no roller.
    let conveyor = support::write_file(
        &dir.join("conveyor.toml"),
        "name = \"c\"\n[parameters]\nroller_speed_ratio = { lo = 0.0, hi = 2.0 }\n[scene]\nlayout = \"conveyor\"\n",
    );
    refused(
        &dir,
        &conveyor,
        "gap=3",
        &["parameters.roller_speed_ratio", "the conveyor layout has no roller"],
    );
    // The roller's mesh: a count of segments out of range, or one for a blade.
    let sweep = with(&dir, swept, "5", "roller");
    for n in ["8", "5000"] {
        let toml = std::fs::read_to_string(&sweep)
            .unwrap()
            .replace("[scene]\n", &format!("[scene]\nroller_segments = {n}\n"));
        let file = support::write_file(&dir.join("segments.toml"), &toml);
        refused(
            &dir,
            &file,
            "blade_speed=0.5",
            &["scene.roller_segments", &format!("{n}: "), "from 16 to 4096"],
        );
    }
    let toml = std::fs::read_to_string(with(&dir, "", "5", "round"))
        .unwrap()
        .replace("[scene]\n", "[scene]\nroller_segments = 64\n");
    let file = support::write_file(&dir.join("segments.toml"), &toml);
    refused(&dir, &file, "blade_speed=0.5", &["scene.roller_segments", "64: ", "blade_profile = \"roller\""]);
    // A ratio of 0 set on a blade is the default, not a roller's: nothing to refuse.
    let sweep = with(&dir, "roller_speed_ratio = 0", "2.5", "round");
    support::ok(&dir, &["render", support::p(&sweep), "--set", "blade_speed=0.5", "--out", "d0"]);
}

/// Run `cut` (a point's deck cut short) as `in.cut` in `deck` through LIGGGHTS: its screen
/// output and its log.
fn run_cut(deck: &Path, cut: &str) -> (String, String) {
    std::fs::write(deck.join("in.cut"), cut).unwrap();
    let out = Command::new("liggghts")
        .args(["-in", "in.cut", "-log", "log.cut"])
        .current_dir(deck)
        .output()
        .unwrap();
    let said = support::text(&out.stdout);
    assert!(out.status.success(), "LIGGGHTS failed: {said}");
    (said, std::fs::read_to_string(deck.join("log.cut")).unwrap_or_default())
}
