//! Planning a sweep: the design's points resolved and hashed into a manifest, the directory
//! checked before it is touched (writable, an extension that keeps its points), the resolved
//! sweep file, and the rule's starting point on an extended directory.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;

use super::MAX_POINTS;
use crate::design::{halton::halton, lattice::lattice};
use crate::error::{Error, Result};
use crate::run::pool::Executor;
use crate::run::progress::ProgressMode;
use crate::run::RunError;
use crate::store::{DesignRecord, Manifest, PointRecord, SpaceRecord, Store};
use crate::sweep::Sweep;
use crate::sys::process::CancelToken;

/// The default sweep directory, `runs/<sweep name>`.
pub fn default_out(sweep: &Sweep) -> PathBuf {
    Path::new("runs").join(&sweep.file.name)
}

/// A design laid out for running.
pub struct SweepPlan<J> {
    pub spaces: Vec<SpaceRecord>,
    /// Distinct points (by hash), in order of first appearance.
    pub points: Vec<PointRecord>,
    /// The prepared job of each point.
    pub jobs: Vec<J>,
}

/// The spaces and distinct points of a design, with the prepared job of each point.
///
/// Stops with [`Error::Interrupted`] (nothing written) when `cancel` fires.
pub fn plan<E: Executor>(
    exec: &E,
    sweep: &Sweep,
    design: &DesignRecord,
    cancel: &CancelToken,
) -> Result<SweepPlan<E::Job>> {
    plan_with_progress(exec, sweep, design, cancel, ProgressMode::Quiet)
}

/// A point to plan: its swept values and its own `scene.seed` (a repeat), or the sweep's.
pub(super) type Seeded = (Vec<f64>, Option<u64>);

/// Time planning may take before it says how far it is.
const PLAN_QUIET_FOR: std::time::Duration = std::time::Duration::from_secs(1);

/// Prepare (render and hash) every point on all cores; unless `progress` is quiet, say how
/// many are done once this takes longer than [`PLAN_QUIET_FOR`], then every
/// [`crate::run::progress::LINE_EVERY`] (a 10⁶-point lattice takes minutes).
fn prepare_all<E: Executor>(
    exec: &E,
    values: &[Seeded],
    cancel: &CancelToken,
    progress: ProgressMode,
) -> Result<Vec<E::Job>> {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let done = AtomicUsize::new(0);
    let over = AtomicBool::new(false);
    let total = values.len();
    std::thread::scope(|scope| {
        if progress != ProgressMode::Quiet {
            scope.spawn(|| {
                let start = Instant::now();
                let mut next = PLAN_QUIET_FOR;
                while !over.load(Ordering::SeqCst) {
                    std::thread::sleep(std::time::Duration::from_millis(50));
                    if start.elapsed() >= next && !over.load(Ordering::SeqCst) {
                        eprintln!(
                            "sweep: planning: {} of {total} decks rendered and hashed",
                            done.load(Ordering::Relaxed)
                        );
                        next = start.elapsed() + crate::run::progress::LINE_EVERY;
                    }
                }
            });
        }
        let jobs = values
            .par_iter()
            .map(|(v, seed)| {
                if cancel.is_cancelled() {
                    return Err(Error::Interrupted);
                }
                let job = exec.prepare_seeded(v, *seed);
                done.fetch_add(1, Ordering::Relaxed);
                job
            })
            .collect::<Result<Vec<_>>>();
        over.store(true, Ordering::SeqCst);
        jobs
    })
}

/// [`plan`], showing progress on stderr as `progress` says.
pub fn plan_with_progress<E: Executor>(
    exec: &E,
    sweep: &Sweep,
    design: &DesignRecord,
    cancel: &CancelToken,
    progress: ProgressMode,
) -> Result<SweepPlan<E::Job>> {
    let dim = sweep.dim();
    // Each space as a list of unit points.
    let spaces: Vec<(String, Vec<Vec<f64>>)> = match design {
        DesignRecord::Lattice { levels } => {
            let mut out = Vec::new();
            for &l in levels {
                if l < 2 {
                    return Err(RunError::Design {
                        design: format!("lattice level {l}"),
                        why: "expected at least 2 values per dimension".into(),
                    }
                    .into());
                }
                let n = l.checked_pow(dim as u32).filter(|&n| n <= MAX_POINTS);
                if n.is_none() {
                    return Err(RunError::Design {
                        design: format!("lattice level {l} in {dim} dimensions"),
                        why: format!("more than {MAX_POINTS} points"),
                    }
                    .into());
                }
                out.push((format!("lattice {l}"), lattice(dim, l)));
            }
            out
        }
        DesignRecord::Lds { step, max, scrambling, seed } => {
            if *step == 0 || *max == 0 || *max > MAX_POINTS || max < step {
                return Err(RunError::Design {
                    design: format!("lds step {step}, max {max}"),
                    why: format!("expected 1 ≤ step ≤ max ≤ {MAX_POINTS}"),
                }
                .into());
            }
            let all = halton(dim, *max, *scrambling, *seed);
            let mut ends: Vec<usize> = (1..).map(|k| k * step).take_while(|&n| n < *max).collect();
            ends.push(*max);
            ends.into_iter().map(|n| (format!("lds {n}"), all[..n].to_vec())).collect()
        }
        // The design alone fixes only the first batch; the driver plans the others from the
        // results ([`crate::run::adapt`]).
        DesignRecord::Adapt { first, max, seed, repeats, .. } => {
            if *first == 0 || *repeats == 0 || *max > MAX_POINTS || *max < first * repeats {
                return Err(RunError::Design {
                    design: format!("adapt first {first}, max {max}, repeats {repeats}"),
                    why: format!("expected 1 ≤ first × repeats ≤ max ≤ {MAX_POINTS}"),
                }
                .into());
            }
            let settings = halton(dim, *first, crate::sweep::Scrambling::Random, *seed);
            let seeds = repeat_seeds(sweep, *repeats);
            let points = settings
                .iter()
                .flat_map(|u| seeds.iter().map(|s| (crate::sweep::space::scale_point(sweep, u), *s)))
                .collect();
            return plan_values(
                exec,
                sweep,
                vec![(format!("adapt {}", first * repeats), points)],
                cancel,
                progress,
            );
        }
    };
    let spaces = spaces
        .into_iter()
        .map(|(label, unit)| {
            (label, unit.iter().map(|u| (crate::sweep::space::scale_point(sweep, u), None)).collect())
        })
        .collect();
    plan_values(exec, sweep, spaces, cancel, progress)
}

/// The seeds of `repeats` runs of one setting: the sweep's own `scene.seed` (`None`), then the
/// next seeds after it.
pub fn repeat_seeds(sweep: &Sweep, repeats: usize) -> Vec<Option<u64>> {
    let base = sweep.file.scene.seed;
    (0..repeats.max(1)).map(|k| (k > 0).then(|| base.wrapping_add(k as u64))).collect()
}

/// [`plan_with_progress`] of spaces given as lists of points in the sweep's units.
pub(super) fn plan_values<E: Executor>(
    exec: &E,
    sweep: &Sweep,
    spaces: Vec<(String, Vec<Seeded>)>,
    cancel: &CancelToken,
    progress: ProgressMode,
) -> Result<SweepPlan<E::Job>> {
    // Distinct values first (LDS prefixes and nested lattices repeat points), each prepared
    // once, on every core: rendering and hashing 10,000 decks takes tens of seconds on one.
    let mut distinct: Vec<Seeded> = Vec::new();
    let mut by_bits: HashMap<(Vec<u64>, Option<u64>), usize> = HashMap::new();
    let space_values: Vec<(String, Vec<usize>)> = spaces
        .into_iter()
        .map(|(label, points)| {
            let members = points
                .into_iter()
                .map(|(values, seed)| {
                    let bits = (values.iter().map(|v| v.to_bits()).collect(), seed);
                    *by_bits.entry(bits).or_insert_with(|| {
                        distinct.push((values, seed));
                        distinct.len() - 1
                    })
                })
                .collect();
            (label, members)
        })
        .collect();
    let prepared = prepare_all(exec, &distinct, cancel, progress)?;
    // Then distinct runs: two values may render the same deck.
    let mut points: Vec<PointRecord> = Vec::new();
    let mut jobs = Vec::new();
    let mut by_hash: HashMap<String, usize> = HashMap::new();
    let mut point_of_value = Vec::with_capacity(distinct.len());
    for ((values, seed), job) in distinct.into_iter().zip(prepared) {
        let hash = exec.hash(&job).to_string();
        let closed = sweep.file.run.screen && exec.closed(&job);
        let index = *by_hash.entry(hash.clone()).or_insert_with(|| {
            points.push(PointRecord { index: points.len(), values, hash, closed, seed });
            jobs.push(job);
            points.len() - 1
        });
        point_of_value.push(index);
    }
    let records = space_values
        .into_iter()
        .map(|(label, members)| SpaceRecord {
            label,
            points: members.into_iter().map(|v| point_of_value[v]).collect(),
        })
        .collect();
    Ok(SweepPlan { spaces: records, points, jobs })
}

/// The sweep file as resolved for `DIR/sweep.toml`: defaults filled in, the design actually run,
/// and the template path made absolute (the directory may be resumed from anywhere).
pub fn resolved_toml(sweep: &Sweep, design: &DesignRecord) -> Result<String> {
    let mut f = sweep.file.clone();
    if let Some(t) = sweep.template_path() {
        f.scene.template = Some(std::path::absolute(&t).unwrap_or(t));
    }
    match design {
        DesignRecord::Lattice { levels } => f.design.lattice_levels = levels.clone(),
        DesignRecord::Lds { step, max, scrambling, seed } => {
            f.design.lds.step = *step;
            f.design.lds.max = *max;
            f.design.lds.scrambling = *scrambling;
            f.design.lds.seed = *seed;
        }
        DesignRecord::Adapt { first, batch, max, seed, .. } => {
            f.design.adapt.first = *first;
            f.design.adapt.batch = *batch;
            f.design.adapt.max = *max;
            f.design.adapt.seed = *seed;
        }
    }
    let body = toml::to_string(&f).map_err(|e| RunError::Resolve(e.to_string()))?;
    Ok(format!(
        "# The sweep as resolved by demsweep {} (resolved-sweep format {}).\n{body}",
        env!("CARGO_PKG_VERSION"),
        crate::sweep::SWEEP_FORMAT
    ))
}

/// Whether `out` can be a sweep directory: an existing directory we may write in, or a path
/// whose nearest existing ancestor is one. Checked before anything is written or run; the
/// message names the path and what is wrong with it.
pub fn check_out_dir(out: &Path) -> Result<(), RunError> {
    let bad = |why: String| Err(RunError::OutDir { dir: out.to_path_buf(), why });
    match std::fs::metadata(out) {
        Ok(m) if !m.is_dir() => bad("exists and is not a directory".into()),
        Ok(_) => match writable(out) {
            Ok(()) => Ok(()),
            Err(e) => bad(format!("cannot write in it ({})", plain_io(&e))),
        },
        Err(e) if matches!(e.kind(), std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory) => {
            let abs = std::path::absolute(out)
                .map_err(|e| RunError::Dir { path: out.to_path_buf(), why: e.to_string() })?;
            let mut up = abs.parent();
            while let Some(p) = up {
                match std::fs::metadata(p) {
                    Ok(m) if m.is_dir() => {
                        // A real probe: access(2) says yes to root in /proc and on read-only mounts.
                        let probe = writable(p).and_then(|_| {
                            tempfile::Builder::new().prefix(".sweep-probe-").tempdir_in(p).map(drop)
                        });
                        return match probe {
                            Ok(()) => Ok(()),
                            Err(e) => bad(format!(
                                "cannot create it: {} is not writable ({})",
                                p.display(),
                                plain_io(&e)
                            )),
                        };
                    }
                    Ok(_) => return bad(format!("cannot create it: {} is not a directory", p.display())),
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => up = p.parent(),
                    Err(e) => return bad(format!("cannot create it: {}: {}", p.display(), plain_io(&e))),
                }
            }
            Ok(())
        }
        Err(e) => bad(plain_io(&e)),
    }
}

/// `access(2)` for writing and entering a directory (honours read-only mounts and, for root,
/// nothing else, exactly as a later `mkdir` would).
fn writable(dir: &Path) -> std::io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).map_err(std::io::Error::other)?;
    // SAFETY: access(2) on a NUL-terminated path we own.
    if unsafe { libc::access(c.as_ptr(), libc::W_OK | libc::X_OK) } == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// "permission denied" rather than "Permission denied (os error 13)".
fn plain_io(e: &std::io::Error) -> String {
    let s = e.to_string();
    let s = s.split(" (os error").next().unwrap_or(&s).to_string();
    let mut c = s.chars();
    c.next().map(|f| f.to_lowercase().chain(c).collect()).unwrap_or(s)
}

/// An existing directory may be run again with the same sweep, or extended: the same design
/// kind and sweep apart from the design, and its points a prefix of ours (a changed engine or
/// template is refused where it changes them).
pub(super) fn check_extension(
    dir: &Path,
    old: &Manifest,
    old_toml: &str,
    new: &Manifest,
    new_toml: &str,
) -> Result<()> {
    let d = crate::sys::shell::quote_path(dir).into_owned();
    // The design may grow; the convergence rule may change (it decides when to stop, not what
    // a run gives).
    // Compared with defaults filled in, so that a key added since (such as `run.screen`) does
    // not make an older directory's sweep file look different.
    let without_design = |t: &str| -> Option<toml::Table> {
        let file: crate::sweep::SweepFile = toml::from_str(t).ok()?;
        let mut v = toml::Table::try_from(&file).ok()?;
        v.remove("design");
        v.remove("convergence");
        // How a cluster starts `sweep` changes no result.
        v.remove("cluster");
        Some(v)
    };
    if std::mem::discriminant(&old.design) != std::mem::discriminant(&new.design) {
        let why = format!("holds {} sweep, not {} one", a_kind(&old.design), a_kind(&new.design));
        return Err(RunError::OutDir { dir: dir.to_path_buf(), why }.into());
    }
    if without_design(old_toml) != without_design(new_toml) {
        let why =
            format!("holds sweep `{}` made from a different sweep file (compare {d}/sweep.toml)", old.name);
        return Err(RunError::OutDir { dir: dir.to_path_buf(), why }.into());
    }
    let diff = identity_diff(&old.identity, &new.identity);
    // A point's hash is its deck's, mesh's and engine's: a changed template that renders every
    // point as before changes no run.
    let same_runs = old.points.iter().zip(&new.points).all(|(a, b)| a.hash == b.hash);
    if !diff.is_empty() && !same_runs {
        let why = format!(
            "the engine or templates changed since it was made ({}); choose another --out, \
             or `sweep resume {d} --force` to re-run its points",
            diff.join("; ")
        );
        return Err(RunError::Dir { path: dir.to_path_buf(), why }.into());
    }
    // An adaptive design is planned a batch at a time: its first batch starts the points
    // already there.
    let grows = old.points.len() <= new.points.len() || new.design.is_adaptive();
    let prefix = grows && same_runs;
    if !prefix {
        let why = format!(
            "its {} points are not the first points of this design ({}); a design can \
             only be extended (larger --max, more levels)",
            old.points.len(),
            design_label(&new.design)
        );
        return Err(RunError::OutDir { dir: dir.to_path_buf(), why }.into());
    }
    Ok(())
}

/// "a lattice", "an lds", "an adapt": the design's kind with its article.
fn a_kind(d: &DesignRecord) -> String {
    let k = design_kind(d);
    let article = if k.starts_with(['a', 'e', 'i', 'o', 'u', 'l']) && k != "lattice" { "an" } else { "a" };
    format!("{article} {k}")
}

fn design_kind(d: &DesignRecord) -> &'static str {
    match d {
        DesignRecord::Lattice { .. } => "lattice",
        DesignRecord::Lds { .. } => "lds",
        DesignRecord::Adapt { .. } => "adapt",
    }
}

pub(super) fn design_label(d: &DesignRecord) -> String {
    match d {
        DesignRecord::Lattice { levels } => {
            format!("lattice levels {}", levels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(","))
        }
        DesignRecord::Lds { step, max, .. } => format!("lds step {step}, max {max}"),
        DesignRecord::Adapt { first, batch, max, .. } => {
            format!("adapt first {first}, batch {batch}, max {max}")
        }
    }
}

/// Identity keys recorded for the reader but not compared: where the engine was found (the
/// same binary through a symlink or another PATH is the same engine; its content and version
/// are what identify it).
const NOT_COMPARED: &[&str] = &["engine_path"];

/// `key: old → new` for every leaf that differs between two identity records.
pub fn identity_diff(old: &serde_json::Value, new: &serde_json::Value) -> Vec<String> {
    fn walk(path: &str, a: &serde_json::Value, b: &serde_json::Value, out: &mut Vec<String>) {
        match (a, b) {
            (serde_json::Value::Object(x), serde_json::Value::Object(y)) => {
                let keys: std::collections::BTreeSet<&String> = x.keys().chain(y.keys()).collect();
                let null = serde_json::Value::Null;
                for k in keys.into_iter().filter(|k| !NOT_COMPARED.contains(&k.as_str())) {
                    let p = if path.is_empty() { k.clone() } else { format!("{path}.{k}") };
                    walk(&p, x.get(k).unwrap_or(&null), y.get(k).unwrap_or(&null), out);
                }
            }
            _ if a != b => out.push(format!("{path}: {a} → {b}")),
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk("", old, new, &mut out);
    out
}

/// The `min_points` a run of `design` into `out` judges convergence from.
///
/// Extending an existing directory (a larger `--max`, more levels) is asked for on purpose, so
/// no space it already had may stop the extension: judging starts past its largest space. Running
/// the same design again keeps the directory's own `min_points`. A new directory (or one that is
/// not a sweep: `start` refuses it) uses the sweep file's.
pub fn judge_from(out: &Path, sweep: &Sweep, design: &DesignRecord) -> Result<usize> {
    let own = sweep.file.convergence.min_points;
    let Ok((old, old_toml)) = Store::read_manifest(out) else {
        return Ok(own);
    };
    let old_min =
        Sweep::parse(&old_toml, &out.join("sweep.toml")).map_or(0, |s| s.file.convergence.min_points);
    let extends = match (&old.design, design) {
        (DesignRecord::Lds { max: a, .. }, DesignRecord::Lds { max: b, .. })
        | (DesignRecord::Adapt { max: a, .. }, DesignRecord::Adapt { max: b, .. }) => b > a,
        (DesignRecord::Lattice { levels: a }, DesignRecord::Lattice { levels: b }) => {
            b.len() > a.len() && b.starts_with(a)
        }
        _ => false,
    };
    let extent = old.spaces.iter().map(|s| s.points.len()).max().unwrap_or(0);
    Ok(if extends { own.max(extent + 1) } else { own.max(old_min) })
}

/// Read the sweep of an existing directory (its resolved `sweep.toml`), checked against its
/// manifest.
pub fn load_dir_sweep(dir: &Path) -> Result<Sweep> {
    let (manifest, text) = Store::read_manifest(dir)?;
    let sweep = Sweep::parse(&text, &dir.join("sweep.toml"))?;
    check_parameters(dir, &manifest, &sweep)?;
    Ok(sweep)
}

/// The manifest's `parameters` are the swept parameters of the directory's `sweep.toml`.
pub(super) fn check_parameters(dir: &Path, manifest: &Manifest, sweep: &Sweep) -> Result<()> {
    if sweep.names() != manifest.parameters {
        let why = format!(
            "parameters [{}] are not the swept parameters of {} [{}]; the manifest or the \
             sweep file was edited",
            manifest.parameters.join(", "),
            dir.join("sweep.toml").display(),
            sweep.names().join(", ")
        );
        return Err(RunError::Dir { path: Store::manifest_path(dir), why }.into());
    }
    Ok(())
}
