//! The decks every layout renders, held to what they rendered before: each shipped sweep file
//! (and the layouts and beds no shipped file uses) at the centre of its space and at two points of
//! its design, every file of each deck by its SHA-256. A change to the scene's code that is meant
//! to change no deck must leave this test passing; one that is meant to rewrites the snapshot
//! with `UPDATE_SNAPSHOTS=1` and says why in its commit.

use std::fmt::Write;
use std::path::Path;

use sha2::{Digest, Sha256};

use crate::support::{self, ok, points, repo, text};

/// Lines of a shipped sweep file replaced to make a case: (from, to).
pub(crate) type Edits = &'static [(&'static str, &'static str)];

/// The sweep files rendered: (case, shipped file, the edits turning it into the case).
pub(crate) const CASES: &[(&str, &str, Edits)] = &[
    ("quick", "sweeps/quick.toml", &[]),
    ("quick-gated", "sweeps/quick.toml", support::QUICK_AS_GATED),
    ("quick-powder-bed", "sweeps/quick.toml", &[("substrate = \"rough\"", "substrate = \"powder\"")]),
    ("thesis-scene", "sweeps/thesis-scene.toml", &[]),
    ("thesis-lds", "sweeps/thesis-lds.toml", &[]),
    ("psd-6d", "sweeps/psd-6d.toml", &[]),
    ("ti64-machine", "sweeps/ti64-machine.toml", &[]),
    ("pour", "sweeps/pour.toml", &[]),
    ("ti64-layers", "sweeps/ti64-layers.toml", &[]),
    (
        "ti64-layers-loose-flat",
        "sweeps/ti64-layers.toml",
        &[("bed = \"fused\"", "bed = \"loose\""), ("blade_profile = \"round\"", "blade_profile = \"flat\"")],
    ),
    ("layers-gaboriault", "sweeps/layers-gaboriault.toml", &[]),
    ("roller", "sweeps/roller.toml", &[]),
];

/// `case point file sha256` for every file `sweep render` writes.
fn rendered(dir: &Path, case: &str, point: &str, sweep: &Path, set: Option<&str>) -> String {
    let out = dir.join(format!("{case}-{point}"));
    let mut args = vec!["render", support::p(sweep), "--out", support::p(&out)];
    if let Some(set) = set {
        args.extend(["--set", set]);
    }
    ok(dir, &args);
    let mut files: Vec<_> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    let mut lines = String::new();
    for f in files {
        let hash = Sha256::digest(std::fs::read(&f).unwrap());
        let hex: String = hash.iter().map(|b| format!("{b:02x}")).collect();
        let _ = writeln!(lines, "{case} {point} {} {hex}", f.file_name().unwrap().to_string_lossy());
    }
    lines
}

#[test]
fn every_layout_renders_the_decks_it_rendered_before() {
    let dir = tempfile::tempdir().unwrap();
    let mut got = String::new();
    for (case, file, replace) in CASES {
        let mut toml = std::fs::read_to_string(repo(file)).unwrap();
        for (from, to) in *replace {
            assert!(toml.contains(from), "{file} has no line {from:?}");
            toml = toml.replacen(from, to, 1);
        }
        let sweep = support::write_file(&dir.path().join(format!("{case}.toml")), &toml);
        got += &rendered(dir.path(), case, "centre", &sweep, None);
        // Two points of its design (a pour is one point: it refuses a design).
        let design = points(&sweep, &["--lds", "2"]);
        if !design.status.success() {
            assert!(case.starts_with("pour"), "{case}: {}", text(&design.stderr));
            continue;
        }
        let csv = text(&design.stdout);
        let mut rows = csv.lines();
        let names: Vec<&str> = rows.next().unwrap().split(',').collect();
        for (i, row) in rows.enumerate() {
            let set: Vec<String> =
                names.iter().zip(row.split(',')).map(|(n, v)| format!("{n}={v}")).collect();
            got += &rendered(dir.path(), case, &format!("lds{i}"), &sweep, Some(&set.join(",")));
        }
    }
    support::compare_snapshot("decks.txt", &got);
}
