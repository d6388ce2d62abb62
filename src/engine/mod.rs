//! The real engine: find LIGGGHTS, identify it, run one deck in its own directory, and read its
//! log for what went wrong; its dump files are read by [`dump`]. Knows nothing of sweeps.
//!
//! A run fails — with a class and a one-line reason, the log's tail kept — on a LIGGGHTS
//! `ERROR`, a non-zero exit, a drop in the atom count (nothing in our scenes removes atoms, so a
//! drop is lost atoms), or a non-finite or exploding kinetic energy. None of these is ever turned
//! into a number. Not responsible for dumps or metrics.

pub mod dump;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use sha2::{Digest, Sha256};

use crate::outcome::FailureClass;
use crate::sys::process::{self, CancelToken, ProcessOutcome};

/// Log file name in the run directory.
pub const LOG: &str = "log.liggghts";
/// Screen output (LIGGGHTS crashes when told `-screen none` while reading a mesh, so keep it).
pub const CONSOLE: &str = "screen.txt";
/// Lines of the log kept with a failure.
const TAIL_LINES: usize = 20;

#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    #[error("LIGGGHTS not found: {0} (install it with `bash scripts/setup.sh`, or set run.engine in the sweep file)")]
    NotFound(String),
    #[error("cannot identify LIGGGHTS at {path}: {reason}")]
    Identify { path: String, reason: String },
    #[error("interrupted while identifying LIGGGHTS")]
    Interrupted,
}

/// A missing or unidentifiable engine is exit 3; Ctrl-C while identifying it is an interruption.
impl From<EngineError> for crate::Error {
    fn from(e: EngineError) -> Self {
        match e {
            EngineError::Interrupted => crate::Error::Interrupted,
            e => crate::Error::Engine(Box::new(e)),
        }
    }
}

/// A located LIGGGHTS executable and what it says it is.
#[derive(Debug, Clone)]
pub struct Engine {
    pub path: PathBuf,
    /// First line of `liggghts -h`, e.g. "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, ...)".
    pub version: String,
    /// sha256 of the executable: a rebuilt engine is a different engine.
    pub binary_hash: String,
    /// MPI ranks of each run: above 1, LIGGGHTS runs under `mpirun -np ranks`. Not part of the
    /// identity: like `--jobs`, it is how a run is executed, chosen per session.
    pub ranks: u32,
}

impl Engine {
    /// Find LIGGGHTS: the given path, else `liggghts` on PATH.
    ///
    /// The identification (`liggghts -h`) runs under [`IDENTIFY_TIMEOUT`] and `cancel` (Ctrl-C,
    /// SIGTERM), in its own process group, in a scratch directory that is removed whatever
    /// happens (and, after a SIGKILL, by the next identification).
    pub fn locate(setting: Option<&Path>, cancel: &CancelToken) -> Result<Engine, EngineError> {
        let path = match setting {
            Some(p) => {
                if !p.is_file() {
                    return Err(EngineError::NotFound(format!("{} is not a file", p.display())));
                }
                p.to_path_buf()
            }
            None => find_on_path("liggghts")
                .ok_or_else(|| EngineError::NotFound("`liggghts` is not on PATH".into()))?,
        };
        let identify = |reason: String| EngineError::Identify { path: path.display().to_string(), reason };
        let version = identify_version(&path, cancel).map_err(|e| match e {
            Identification::Interrupted => EngineError::Interrupted,
            Identification::Failed(reason) => identify(reason),
        })?;
        // The Debian binary is a small launcher around libliggghts; hash both when we can see the
        // library, so an updated library is a different engine too.
        let mut h = Sha256::new();
        h.update(std::fs::read(&path).map_err(|e| identify(e.to_string()))?);
        for lib in ["/usr/lib/x86_64-linux-gnu/libliggghts.so.3", "/usr/lib/libliggghts.so.3"] {
            if let Ok(bytes) = std::fs::read(lib) {
                h.update(bytes);
            }
        }
        Ok(Engine { path, version, binary_hash: crate::sys::hex(&h.finalize()), ranks: 1 })
    }

    /// What identifies this engine in a run's hash.
    pub fn identity(&self) -> String {
        format!("{} sha256:{}", self.version, self.binary_hash)
    }

    /// Run `deck` (a file name inside `dir`) in `dir` with a timeout, then read the log.
    pub fn run(
        &self,
        dir: &Path,
        deck: &str,
        limits: &LogLimits,
        timeout: Duration,
        cancel: &CancelToken,
    ) -> EngineRun {
        let cmd = match command_ranks(&self.path, dir, deck, self.ranks) {
            Ok(c) => c,
            Err(e) => {
                let reason = format!("cannot create {CONSOLE} in {}: {e}", dir.display());
                return EngineRun::failed(FailureClass::CouldNotStart, reason, String::new(), 0.0);
            }
        };
        // Read the log as LIGGGHTS writes it (the deck flushes it at every thermo line) and stop a
        // run the moment its energy explodes or it loses atoms: it can only fail from there,
        // and an exploding run with a shrink-wrapped box can grab gigabytes before it ends.
        let log_path = dir.join(LOG);
        let mut watch = || {
            let log = read_lossy(&log_path);
            match analyse_log(&log, limits).failure {
                Some((class @ (FailureClass::Unstable | FailureClass::LostAtoms), reason)) => {
                    Some(format!("{}: {reason}", class.as_str()))
                }
                _ => None,
            }
        };
        let finished = process::run_watched(cmd, timeout, cancel, &mut watch);
        let (outcome, wall) = (finished.outcome, finished.wall.as_secs_f64());
        let cpu_time = finished.cpu.map(|c| c.as_secs_f64());
        let log = read_lossy(&dir.join(LOG));
        let tail = tail(&log, TAIL_LINES);
        let fail = |class, reason: String| EngineRun::failed(class, reason, tail.clone(), wall);
        match outcome {
            ProcessOutcome::SpawnFailed(e) => {
                return fail(
                    FailureClass::CouldNotStart,
                    format!("cannot start {}: {e}", self.path.display()),
                )
            }
            ProcessOutcome::Stopped(_) => {
                // The watcher saw the failure in the log; classify it from the log as written.
                let analysis = analyse_log(&log, limits);
                let (class, reason) = analysis.failure.unwrap_or((FailureClass::Unstable, "stopped".into()));
                return fail(class, format!("{reason} (stopped early)"));
            }
            ProcessOutcome::TimedOut => {
                return fail(FailureClass::TimedOut, format!("timed out after {} s", timeout.as_secs_f64()))
            }
            ProcessOutcome::Cancelled => {
                return EngineRun {
                    wall_time: wall,
                    cpu_time,
                    status: RunStatus::Cancelled,
                    warnings: Vec::new(),
                    log: String::new(),
                }
            }
            ProcessOutcome::Signalled(sig) => {
                // LIGGGHTS may have printed an ERROR before dying.
                if let Some(e) = first_error_in(dir) {
                    return fail(FailureClass::EngineError, e);
                }
                return fail(FailureClass::Signalled, format!("killed by signal {sig}"));
            }
            ProcessOutcome::Exited(code) => {
                if let Some(e) = first_error_in(dir) {
                    // `thermo_modify lost error` stops LIGGGHTS at the first lost atom.
                    let class = if e.contains("Lost atoms") {
                        FailureClass::LostAtoms
                    } else {
                        FailureClass::EngineError
                    };
                    return fail(class, e);
                }
                if code != 0 {
                    return fail(FailureClass::EngineError, format!("exited with code {code}"));
                }
            }
        }
        let analysis = analyse_log(&log, limits);
        match analysis.failure {
            Some((class, reason)) => fail(class, reason),
            None => EngineRun {
                wall_time: wall,
                cpu_time,
                status: RunStatus::Ok,
                warnings: analysis.warnings,
                log,
            },
        }
    }
}

/// Longest wait for `liggghts -h` to print its version (it takes well under a second).
pub const IDENTIFY_TIMEOUT: Duration = Duration::from_secs(15);
/// Prefix of the identification's scratch directories in the temp directory; the pid follows.
const SCRATCH_PREFIX: &str = "sweep-engine-";

enum Identification {
    Interrupted,
    Failed(String),
}

/// The first line of `path -log none -h` that names LIGGGHTS.
fn identify_version(path: &Path, cancel: &CancelToken) -> Result<String, Identification> {
    let failed = Identification::Failed;
    remove_dead_scratch_dirs();
    // `-log none`: LIGGGHTS opens `log.liggghts` in its working directory even for `-h`.
    // And in an empty scratch directory, so that nothing is written where `sweep` was
    // started whatever a future LIGGGHTS does with `-h`.
    let scratch = tempfile::Builder::new()
        .prefix(&format!("{SCRATCH_PREFIX}{}-", std::process::id()))
        .tempdir()
        .map_err(|e| failed(format!("cannot create a scratch directory: {e}")))?;
    let file = |name: &str| {
        std::fs::File::create(scratch.path().join(name))
            .map_err(|e| failed(format!("cannot write in the scratch directory: {e}")))
    };
    let mut cmd = Command::new(path);
    serial_mpi(&mut cmd);
    cmd.args(["-log", "none", "-h"])
        .current_dir(scratch.path())
        .stdin(Stdio::null())
        .stdout(file("out")?)
        .stderr(file("err")?);
    let (outcome, _) = process::run(cmd, IDENTIFY_TIMEOUT, cancel);
    let read = |name: &str| std::fs::read(scratch.path().join(name)).unwrap_or_default();
    let (out, err) = (read("out"), read("err"));
    drop(scratch);
    match outcome {
        ProcessOutcome::Cancelled => return Err(Identification::Interrupted),
        ProcessOutcome::TimedOut => {
            return Err(failed(format!(
                "`-h` did not answer within {} s (killed it)",
                IDENTIFY_TIMEOUT.as_secs()
            )))
        }
        ProcessOutcome::SpawnFailed(e) => return Err(failed(e)),
        _ => {}
    }
    let text = String::from_utf8_lossy(&out);
    text.lines().find(|l| l.contains("LIGGGHTS")).map(|l| l.trim().to_string()).ok_or_else(|| {
        // What it said instead (OpenMPI's "system limit on number of pipes", a missing library).
        let said = String::from_utf8_lossy(&err);
        match said.lines().map(str::trim).find(|l| !l.is_empty()) {
            Some(l) => failed(format!("`-h` did not print a LIGGGHTS version; it said: {l}")),
            None => failed("`-h` did not print a LIGGGHTS version".into()),
        }
    })
}

/// Remove the scratch directories of identifications whose process is gone (SIGKILLed).
fn remove_dead_scratch_dirs() {
    let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) else { return };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = name.strip_prefix(SCRATCH_PREFIX).and_then(|r| r.split('-').next()) else { continue };
        let Ok(pid) = pid.parse::<u32>() else { continue };
        if pid != std::process::id() && crate::sys::host::process_start_ticks(pid).is_none() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Remove the `restart_forced_liggghts_*.data` files LIGGGHTS writes when it is stopped (about
/// 1 MB each): a failed run's directory keeps its log and failure, not a restart nobody reads.
pub fn remove_forced_restarts(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        if e.file_name().to_string_lossy().starts_with("restart_forced_") {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// The command that runs `deck` (a file in `dir`) with LIGGGHTS at `engine`, in `dir`: log to
/// [`LOG`], screen output to [`CONSOLE`], no echo.
///
/// LIGGGHTS aborts through MPI_Abort without flushing its log or a redirected stdout, so the
/// ERROR line would be lost; stdout is line-buffered with coreutils' stdbuf when it is there.
pub fn command(engine: &Path, dir: &Path, deck: &str) -> std::io::Result<Command> {
    command_ranks(engine, dir, deck, 1)
}

/// [`command`] on `ranks` MPI ranks: `mpirun -np ranks` in front when `ranks` > 1.
///
/// `--bind-to none`: several runs share a node, and Open MPI would bind every run's rank 0 to
/// core 0. `--oversubscribe`: `sweep` counts the cores itself (`--jobs` in ranks). As root,
/// Open MPI refuses to start without `--allow-run-as-root`.
pub fn command_ranks(engine: &Path, dir: &Path, deck: &str, ranks: u32) -> std::io::Result<Command> {
    let screen = std::fs::File::create(dir.join(CONSOLE))?;
    let screen_err = screen.try_clone()?;
    let mut argv: Vec<std::ffi::OsString> = Vec::new();
    if ranks > 1 {
        argv.push(find_on_path("mpirun").unwrap_or_else(|| PathBuf::from("mpirun")).into());
        // SAFETY: geteuid cannot fail.
        if unsafe { libc::geteuid() } == 0 {
            argv.push("--allow-run-as-root".into());
        }
        argv.extend(["--bind-to", "none", "--oversubscribe", "-np"].map(Into::into));
        argv.push(ranks.to_string().into());
    }
    if let Some(stdbuf) = find_on_path("stdbuf") {
        argv.extend([stdbuf.into(), "-oL".into(), "-eL".into()]);
    }
    argv.push(engine.into());
    let mut cmd = Command::new(&argv[0]);
    if ranks <= 1 {
        serial_mpi(&mut cmd);
    }
    cmd.args(&argv[1..]);
    cmd.args(["-in", deck, "-log", LOG, "-echo", "none", "-nocite"])
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(screen)
        .stderr(screen_err);
    Ok(cmd)
}

/// Open MPI's transports for a run on one rank, which talks to nobody: its point-to-point layer
/// `ob1` over `self`. Left to choose, Debian's Open MPI 4.1 probes UCX and libfabric first, which
/// costs 0.2 s of idle wall time at every start (0.33 s against 0.13 s for an empty deck) — a
/// tenth of a short point's. A user's own `OMPI_MCA_pml` or `OMPI_MCA_btl` is kept.
pub fn serial_mpi(cmd: &mut Command) {
    for (key, value) in [("OMPI_MCA_pml", "ob1"), ("OMPI_MCA_btl", "self")] {
        if std::env::var_os(key).is_none() {
            cmd.env(key, value);
        }
    }
}

/// The step at which the deck's settle ended, from the line it prints
/// (`demsweep: settled at step N`); otherwise the failure: `not-settled` when the deck says the
/// pile was still moving at its cap, `unparsable` when the line is missing or unreadable.
pub fn settled_at(log: &str) -> Result<u64, (FailureClass, String)> {
    for line in log.lines() {
        let t = line.trim();
        if let Some(rest) = t.strip_prefix("demsweep: settled at step ") {
            return rest
                .trim()
                .parse()
                .map_err(|_| (FailureClass::Unparsable, format!("unreadable settle line in the log: {t}")));
        }
        if let Some(why) = t.strip_prefix("demsweep: not settled") {
            return Err((FailureClass::NotSettled, format!("not settled{why}")));
        }
    }
    Err((FailureClass::Unparsable, "the log has no settle line (demsweep: settled at step N)".into()))
}

/// The first LIGGGHTS ERROR line a run in `dir` left, in its log or on its screen output.
pub fn first_error_in(dir: &Path) -> Option<String> {
    first_error(&read_lossy(&dir.join(LOG))).or_else(|| first_error(&read_lossy(&dir.join(CONSOLE))))
}

/// A log as text, whatever it holds: LIGGGHTS prints stray bytes after some errors, and a
/// failed UTF-8 decode must not hide the ERROR line before them. Missing file: empty.
fn read_lossy(path: &Path) -> String {
    std::fs::read(path).map(|b| String::from_utf8_lossy(&b).into_owned()).unwrap_or_default()
}

fn find_on_path(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH")?.to_str()?.split(':').map(|d| Path::new(d).join(name)).find(|p| p.is_file())
}

/// What the log must respect for a run to count.
#[derive(Debug, Clone, Copy)]
pub struct LogLimits {
    /// Kinetic energy above which the run is unstable, J.
    pub ke_limit: f64,
    /// Atoms expected once inserted; fewer at the end is lost atoms. None: the count varies by
    /// design (a fed scene inserts and deletes); LIGGGHTS's own lost-atom error guards it.
    pub atoms: Option<u64>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum RunStatus {
    Ok,
    Failed { class: FailureClass, reason: String, log_tail: String },
    Cancelled,
}

/// What one LIGGGHTS process did.
#[derive(Debug, Clone)]
pub struct EngineRun {
    pub status: RunStatus,
    pub wall_time: f64,
    /// CPU seconds of the LIGGGHTS process (and its ranks), when it ended by itself.
    pub cpu_time: Option<f64>,
    /// Distinct LIGGGHTS warnings, in order.
    pub warnings: Vec<String>,
    /// The log as read once the run ended (empty unless the run succeeded): what the caller
    /// reads of it, without reading the file again.
    pub log: String,
}

impl EngineRun {
    fn failed(class: FailureClass, reason: String, log_tail: String, wall_time: f64) -> Self {
        EngineRun {
            status: RunStatus::Failed { class, reason, log_tail },
            wall_time,
            cpu_time: None,
            warnings: Vec::new(),
            log: String::new(),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermoRow {
    pub step: u64,
    pub atoms: u64,
    pub ke: f64,
}

#[derive(Debug, Default)]
struct LogAnalysis {
    thermo: Vec<ThermoRow>,
    warnings: Vec<String>,
    failure: Option<(FailureClass, String)>,
}

/// The first LIGGGHTS error line ("ERROR: ..." or "ERROR on proc N: ..."), trimmed.
fn first_error(log: &str) -> Option<String> {
    log.lines().find(|l| l.trim_start().starts_with("ERROR")).map(|l| l.trim().to_string())
}

fn tail(log: &str, n: usize) -> String {
    let lines: Vec<&str> = log.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

/// Every LIGGGHTS warning of a log, each whole on one line. A multi-line warning is `WARNING: `
/// alone on its line, then tab-indented lines, a blank line and the indented source location
/// (`(./src/contact_models.h:364)`): its lines are joined with single spaces.
fn warnings(log: &str) -> Vec<String> {
    let lines: Vec<&str> = log.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let t = lines[i].trim();
        i += 1;
        if !t.starts_with("WARNING") {
            continue;
        }
        let mut parts = vec![t.to_string()];
        if t == "WARNING:" || t == "WARNING" {
            let indented = |l: &str| l.starts_with([' ', '\t']) && !l.trim().is_empty();
            while i < lines.len() {
                let l = lines[i];
                if indented(l) {
                    parts.push(l.trim().to_string());
                    i += 1;
                } else if l.trim().is_empty()
                    && lines.get(i + 1).is_some_and(|n| indented(n) && n.trim().starts_with('('))
                {
                    // The blank line before the source location.
                    i += 1;
                } else {
                    break;
                }
                if parts.last().is_some_and(|p| p.starts_with('(') && p.ends_with(')')) {
                    break;
                }
            }
        }
        out.push(parts.join(" "));
    }
    out
}

/// A LIGGGHTS warning a user of `sweep` cannot act on, and the one line that says so instead:
/// the contact model runs unoptimised because it is not in the whitelist LIGGGHTS was compiled
/// with (only recompiling LIGGGHTS changes that). The warning stays in the run's log and
/// `result.json`.
pub fn chatter(warning: &str) -> Option<&'static str> {
    warning.contains("not located in any whitelist").then_some(
        "LIGGGHTS runs this contact model unoptimised (up to 20 % slower; it is not in the \
         whitelist LIGGGHTS was compiled with): harmless, nothing to do",
    )
}

/// The distinct LIGGGHTS warnings of a log, in order.
pub fn distinct_warnings(log: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for w in warnings(log) {
        if !out.contains(&w) {
            out.push(w);
        }
    }
    out
}

/// Read the thermo blocks (`thermo_style custom step atoms ke`) and warnings of a log.
fn analyse_log(log: &str, limits: &LogLimits) -> LogAnalysis {
    let mut a = LogAnalysis { warnings: distinct_warnings(log), ..LogAnalysis::default() };
    let mut in_block = false;
    let mut max_atoms = 0u64;
    for line in log.lines() {
        let t = line.trim();
        if t.starts_with("WARNING") {
            continue;
        }
        if t.starts_with("Step") && t.contains("Atoms") {
            in_block = true;
            continue;
        }
        if !in_block {
            continue;
        }
        let mut it = t.split_whitespace();
        let (Some(s), Some(n), Some(k)) = (it.next(), it.next(), it.next()) else {
            in_block = !t.is_empty() && !t.starts_with("Loop time");
            continue;
        };
        let (Ok(step), Ok(atoms)) = (s.parse::<u64>(), n.parse::<u64>()) else {
            // Informational lines (INFO: ...) may interleave with a block.
            in_block = !t.starts_with("Loop time");
            continue;
        };
        let ke: f64 = k.parse().unwrap_or(f64::NAN);
        a.thermo.push(ThermoRow { step, atoms, ke });
        if a.failure.is_none() {
            if !ke.is_finite() {
                a.failure = Some((FailureClass::Unstable, format!("kinetic energy is {k} at step {step}")));
            } else if ke > limits.ke_limit {
                a.failure = Some((
                    FailureClass::Unstable,
                    format!("kinetic energy {ke:.3e} J at step {step} exceeds {:.3e} J", limits.ke_limit),
                ));
            } else if limits.atoms.is_some() && atoms < max_atoms {
                a.failure = Some((
                    FailureClass::LostAtoms,
                    format!("atom count fell from {max_atoms} to {atoms} by step {step} (lost atoms)"),
                ));
            }
        }
        max_atoms = max_atoms.max(atoms);
    }
    if a.failure.is_none() {
        match a.thermo.last() {
            None => a.failure = Some((FailureClass::Unparsable, "no thermo output in the log".into())),
            Some(last) if limits.atoms.is_some_and(|n| last.atoms != n) => {
                let expected = limits.atoms.unwrap_or(0);
                a.failure = Some((
                    if last.atoms < expected { FailureClass::LostAtoms } else { FailureClass::Unparsable },
                    format!("{} atoms at the end, expected {expected}", last.atoms),
                ))
            }
            _ => {}
        }
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: LogLimits = LogLimits { ke_limit: 1.0, atoms: Some(700) };

    #[test]
    fn a_run_on_one_rank_skips_open_mpi_s_network_probes_and_one_under_mpirun_does_not() {
        let dir = tempfile::tempdir().unwrap();
        let env = |ranks| {
            let cmd = command_ranks(Path::new("/usr/bin/liggghts"), dir.path(), "in.deck", ranks).unwrap();
            cmd.get_envs()
                .map(|(k, v)| (k.to_string_lossy().into_owned(), v.map(|v| v.to_string_lossy().into_owned())))
                .collect::<Vec<_>>()
        };
        if std::env::var_os("OMPI_MCA_pml").is_none() {
            assert!(env(1).contains(&("OMPI_MCA_pml".into(), Some("ob1".into()))), "{:?}", env(1));
        }
        assert!(env(2).iter().all(|(k, _)| !k.starts_with("OMPI_MCA")), "{:?}", env(2));
    }

    #[test]
    fn a_multi_line_warning_is_kept_whole() {
        // As LIGGGHTS 3.8 prints it for `pair_style gran ... rolling_friction epsd2`.
        let log = "pair_style gran model hertz tangential history rolling_friction epsd2\nWARNING: \n\tThe contact model you specified is not located in any whitelist.\n\tBecause of this the model will be run in an unoptimized version (increasing runtime by up to 20%).\n\t\t(i)  Run the script\n\n (./src/contact_models.h:364)\nWARNING: Less insertions than requested (../fix_insert.cpp:792)\n    Step    Atoms         KinEng \n       0      700              0 \n";
        let w = warnings(log);
        assert_eq!(w.len(), 2, "{w:?}");
        assert_eq!(
            w[0],
            "WARNING: The contact model you specified is not located in any whitelist. Because of this the model will be run in an unoptimized version (increasing runtime by up to 20%). (i)  Run the script (./src/contact_models.h:364)"
        );
        // A one-line warning does not swallow the thermo header or rows after it.
        assert_eq!(w[1], "WARNING: Less insertions than requested (../fix_insert.cpp:792)");
    }

    #[test]
    fn the_whitelist_warning_is_chatter_and_others_are_not() {
        let log = "WARNING: \n\tThe contact model you specified is not located in any whitelist.\n\tBecause of this\n\n (./src/contact_models.h:364)\nWARNING: Less insertions than requested (../fix_insert.cpp:792)\n";
        let w = warnings(log);
        assert!(chatter(&w[0]).is_some(), "{w:?}");
        assert_eq!(chatter(&w[1]), None);
    }

    fn log(rows: &str) -> String {
        format!("LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0)\n    Step    Atoms         KinEng \nINFO: inserted\n{rows}Loop time of 2.8 on 1 procs\n")
    }

    #[test]
    fn a_clean_log_passes_and_keeps_its_thermo() {
        let a =
            analyse_log(&log("       0        0              0 \n    1000      700  9.7e-05 \n"), &LIMITS);
        assert_eq!(a.failure, None);
        assert_eq!(a.thermo.len(), 2);
        assert_eq!(a.thermo[1], ThermoRow { step: 1000, atoms: 700, ke: 9.7e-5 });
    }

    #[test]
    fn a_drop_in_atoms_is_lost_atoms() {
        let a = analyse_log(&log("1000 700 1e-4\n2000 698 1e-4\n3000 700 1e-4\n"), &LIMITS);
        let (class, reason) = a.failure.unwrap();
        assert_eq!(class, FailureClass::LostAtoms);
        assert!(reason.contains("700 to 698"), "{reason}");
    }

    #[test]
    fn nan_or_exploding_energy_is_unstable() {
        let a = analyse_log(&log("1000 700 nan\n"), &LIMITS);
        assert_eq!(a.failure.unwrap().0, FailureClass::Unstable);
        let a = analyse_log(&log("1000 700 5.0\n"), &LIMITS);
        assert_eq!(a.failure.unwrap().0, FailureClass::Unstable);
    }

    #[test]
    fn no_thermo_is_unparsable() {
        assert_eq!(analyse_log("nothing here\n", &LIMITS).failure.unwrap().0, FailureClass::Unparsable);
    }

    #[test]
    fn the_settle_line_gives_the_step_or_says_why_not() {
        assert_eq!(settled_at("x\ndemsweep: settled at step 11822\nmore\n"), Ok(11822));
        let (class, e) =
            settled_at("demsweep: not settled after 62500 steps, kinetic energy 1e-3 J\n").unwrap_err();
        assert_eq!(class, FailureClass::NotSettled);
        assert!(e.starts_with("not settled after 62500 steps"), "{e}");
        assert!(settled_at("no marker\n").unwrap_err().1.contains("no settle line"));
        assert!(settled_at("demsweep: settled at step x\n").unwrap_err().1.contains("unreadable"));
    }

    #[test]
    fn errors_are_found_in_either_form() {
        assert_eq!(
            first_error("x\nERROR on proc 0: Mesh elements have been lost\n").unwrap(),
            "ERROR on proc 0: Mesh elements have been lost"
        );
        assert_eq!(first_error("ERROR: Unknown command\n").unwrap(), "ERROR: Unknown command");
        assert_eq!(first_error("all good\n"), None);
    }
}
