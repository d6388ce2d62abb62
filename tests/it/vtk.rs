//! `sweep run --vtk` on real LIGGGHTS: the particle and blade files parse as legacy VTK (the
//! format ParaView opens), hold every atom of the deck, and the blade moves between them.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};

use crate::support;

/// A legacy VTK POLYDATA file, read token by token as the format defines it (points, the
/// VERTICES/POLYGONS offset and connectivity arrays of format 5.1, FIELD arrays with their
/// declared component and tuple counts). Anything out of place is an error.
#[derive(Debug, Default)]
struct Vtk {
    points: Vec<[f64; 3]>,
    cells: BTreeMap<String, (Vec<usize>, Vec<usize>)>,
    /// Per FIELD array: components and values, for point and cell data.
    arrays: BTreeMap<String, (usize, Vec<f64>)>,
}

fn parse_vtk(text: &str) -> Result<Vtk, String> {
    let mut lines = text.lines();
    let head = lines.next().ok_or("empty")?;
    if !head.starts_with("# vtk DataFile Version") {
        return Err(format!("not a VTK legacy header: {head}"));
    }
    lines.next().ok_or("no title line")?;
    if lines.next().map(str::trim) != Some("ASCII") {
        return Err("expected ASCII".into());
    }
    if lines.next().map(str::trim) != Some("DATASET POLYDATA") {
        return Err("expected DATASET POLYDATA".into());
    }
    let mut t = lines.flat_map(str::split_whitespace).peekable();
    let num = |t: &mut std::iter::Peekable<_>| -> Result<f64, String> {
        let s: &str = t.next().ok_or("truncated")?;
        s.parse::<f64>().map_err(|_| format!("expected a number, found {s}"))
    };
    let mut v = Vtk::default();
    while let Some(key) = t.next() {
        match key {
            "POINTS" => {
                let n = num(&mut t)? as usize;
                t.next().ok_or("no POINTS type")?;
                for _ in 0..n {
                    v.points.push([num(&mut t)?, num(&mut t)?, num(&mut t)?]);
                }
            }
            "VERTICES" | "POLYGONS" | "LINES" => {
                let (no, nc) = (num(&mut t)? as usize, num(&mut t)? as usize);
                for want in ["OFFSETS", "CONNECTIVITY"] {
                    let (k, ty) = (t.next().ok_or("truncated")?, t.next().ok_or("truncated")?);
                    if k != want || !ty.starts_with("vtktype") {
                        return Err(format!("{key}: expected {want}, found {k} {ty}"));
                    }
                    let n = if want == "OFFSETS" { no } else { nc };
                    let vals =
                        (0..n).map(|_| num(&mut t).map(|x| x as usize)).collect::<Result<Vec<_>, _>>()?;
                    let e = v.cells.entry(key.to_string()).or_default();
                    if want == "OFFSETS" {
                        e.0 = vals;
                    } else {
                        e.1 = vals;
                    }
                }
            }
            "POINT_DATA" | "CELL_DATA" => {
                num(&mut t)?;
            }
            "FIELD" => {
                t.next().ok_or("no FIELD name")?;
                let arrays = num(&mut t)? as usize;
                for _ in 0..arrays {
                    let name = t.next().ok_or("no array name")?.to_string();
                    let (comp, tuples) = (num(&mut t)? as usize, num(&mut t)? as usize);
                    t.next().ok_or("no array type")?;
                    let vals = (0..comp * tuples).map(|_| num(&mut t)).collect::<Result<Vec<_>, _>>()?;
                    v.arrays.insert(name, (comp, vals));
                }
            }
            other => return Err(format!("unexpected token {other}")),
        }
    }
    Ok(v)
}

/// Files `prefix_<step>.vtk` in `dir`, by step.
fn series(dir: &Path, prefix: &str) -> BTreeMap<u64, std::path::PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| {
            let p = e.ok()?.path();
            let name = p.file_name()?.to_str()?.to_string();
            let step: u64 = name.strip_prefix(prefix)?.strip_suffix(".vtk")?.parse().ok()?;
            Some((step, p))
        })
        .collect()
}

/// `sweep run FILE --vtk --json --out OUT` at the thesis's blade speed (the demo's machine
/// speeds take several times the blade travel time), which must succeed: its output.
fn run_vtk(file: &Path, out: &Path) -> std::process::Output {
    let o = Command::new(env!("CARGO_BIN_EXE_sweep"))
        .args([
            "run",
            support::p(file),
            "--set",
            "blade_speed=1.4",
            "--vtk",
            "--json",
            "--out",
            support::p(out),
        ])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

#[test]
fn run_with_vtk_writes_particle_and_blade_files_paraview_reads() {
    support::require_liggghts!("run_with_vtk_writes_particle_and_blade_files_paraview_reads");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("point");
    // The gated layout: a fixed set of atoms and a moving blade, so each file can be checked
    // against the data file's atom count and the blade's travel.
    let quick = tmp.path().join("quick-gated.toml");
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("sweeps/quick.toml")).unwrap();
    let gated = support::QUICK_AS_GATED.iter().fold(text, |t, (from, to)| {
        assert!(t.contains(from), "sweeps/quick.toml has no {from:?}");
        t.replacen(from, to, 1)
    });
    std::fs::write(&quick, gated).unwrap();
    let o = run_vtk(&quick, &out);
    // The deck's own atom count: the data file it reads ("N atoms"), powder and substrate.
    let data = std::fs::read_to_string(out.join("pile.data")).unwrap();
    let atoms: usize = data
        .lines()
        .find_map(|l| l.trim().strip_suffix(" atoms").and_then(|n| n.trim().parse().ok()))
        .expect("pile.data states its atoms");
    let result: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(atoms > result["particles"].as_u64().unwrap() as usize, "the substrate is in the files too");

    let particles = series(&out, "particles_");
    assert!(particles.len() >= 3, "{particles:?}");
    for (step, path) in &particles {
        let v =
            parse_vtk(&std::fs::read_to_string(path).unwrap()).unwrap_or_else(|e| panic!("{path:?}: {e}"));
        assert_eq!(v.points.len(), atoms, "step {step}");
        let ids: std::collections::BTreeSet<u64> = v.arrays["id"].1.iter().map(|&x| x as u64).collect();
        assert_eq!(ids.len(), atoms, "one id per atom");
        for (name, comp) in [("radius", 1), ("mass", 1), ("type", 1), ("v", 3)] {
            assert_eq!(v.arrays[name].0, comp, "{name}");
            assert_eq!(v.arrays[name].1.len(), comp * atoms, "{name} at step {step}");
        }
        // quick.toml's D = 1.5 mm: every radius 0.75 mm (the substrate's spheres may differ).
        assert!(v.arrays["radius"].1.iter().all(|&r| r > 0.0 && r < 2e-3));
    }

    let blade = series(&out, "blade_");
    assert_eq!(blade.keys().collect::<Vec<_>>(), particles.keys().collect::<Vec<_>>());
    let first = parse_vtk(&std::fs::read_to_string(blade.values().next().unwrap()).unwrap()).unwrap();
    let last = parse_vtk(&std::fs::read_to_string(blade.values().last().unwrap()).unwrap()).unwrap();
    let (offsets, conn) = &first.cells["POLYGONS"];
    assert!(offsets.windows(2).all(|w| w[1] > w[0]) && *offsets.last().unwrap() == conn.len());
    assert!(conn.iter().all(|&i| i < first.points.len()));
    // The blade moved in +x between the first and the last file, not in y or z.
    let mean = |v: &Vtk, k: usize| v.points.iter().map(|p| p[k]).sum::<f64>() / v.points.len() as f64;
    assert!(mean(&last, 0) > mean(&first, 0) + 1e-3, "{} {}", mean(&first, 0), mean(&last, 0));
    assert!((mean(&last, 2) - mean(&first, 2)).abs() < 1e-9);
}

#[test]
fn vtk_needs_a_kept_run_directory() {
    let quick = Path::new(env!("CARGO_MANIFEST_DIR")).join("sweeps/quick.toml");
    let o = Command::new(env!("CARGO_BIN_EXE_sweep"))
        .args(["run", quick.to_str().unwrap(), "--vtk"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--out"));
}

#[test]
fn the_conveyor_writes_vtk_files_too() {
    support::require_liggghts!("the_conveyor_writes_vtk_files_too");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("point");
    let quick = Path::new(env!("CARGO_MANIFEST_DIR")).join("sweeps/quick.toml");
    run_vtk(&quick, &out);
    let particles = series(&out, "particles_");
    assert!(particles.len() >= 3, "{particles:?}");
    assert_eq!(series(&out, "blade_").len(), particles.len());
    for path in particles.values() {
        let v =
            parse_vtk(&std::fs::read_to_string(path).unwrap()).unwrap_or_else(|e| panic!("{path:?}: {e}"));
        // The held heap and the substrate: never empty, one radius per point.
        assert!(!v.points.is_empty());
        assert_eq!(v.arrays["radius"].1.len(), v.points.len());
    }
}
