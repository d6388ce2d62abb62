//! `joblog.tsv`: one line per attempt, appended and numbered under the directory lock.
//!
//! The columns are GNU parallel's `--joblog` (Seq, Host, Starttime, JobRuntime, Send, Receive,
//! Exitval, Signal, Command), then the point's index, the run hash, the status, the failure
//! class and the pid. A joblog of an earlier version (`seq host pid start runtime_s status class
//! hash`) is still read, and appended to in its own format, so one file never mixes the two.

use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use super::{io, DirLock, Store, StoreError, LOCK};

impl Store {
    /// Create the joblog with its header if it is missing. Call under the lock, so that no
    /// process appends before the header.
    pub(super) fn joblog_header(&self) -> Result<(), StoreError> {
        let path = self.dir.join(JOBLOG);
        let mut file = OpenOptions::new().create(true).append(true).open(&path).map_err(io(&path))?;
        if file.metadata().map_err(io(&path))?.len() == 0 {
            file.write_all(format!("{JOBLOG_HEADER}\n").as_bytes()).map_err(io(&path))?;
        }
        Ok(())
    }

    /// Refuse a joblog this version would not read back (see [`joblog_format`]); a missing one
    /// is fine (it is created when the first attempt is logged).
    pub fn check_joblog(&self) -> Result<(), StoreError> {
        let path = self.dir.join(JOBLOG);
        match std::fs::symlink_metadata(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            _ => joblog_format(&path).map(drop),
        }
    }

    /// Open the joblog for appending attempts, creating it with its header if missing.
    pub fn joblog(&self) -> Result<Joblog, StoreError> {
        let lock = self.dir.join(LOCK);
        let _lock = DirLock::take(&lock)?;
        self.joblog_header()?;
        let path = self.dir.join(JOBLOG);
        let file = OpenOptions::new().read(true).append(true).open(&path).map_err(io(&path))?;
        let old = joblog_format(&path)?;
        Ok(Joblog { file, path, lock, host: self.host.clone(), old, index: HashMap::new() })
    }
}

/// Whether the joblog at `path` is of the earlier format (else the current one). A joblog of
/// any other header (GNU parallel's own, of nine columns) is refused: lines appended under it
/// would not be read back, and their numbering would start again.
fn joblog_format(path: &Path) -> Result<bool, StoreError> {
    use std::io::{BufRead, Read};
    let file = crate::sys::read::open_regular(path).map_err(io(path))?;
    let mut first = Vec::new();
    std::io::BufReader::new(file.take(4096)).read_until(b'\n', &mut first).map_err(io(path))?;
    let first = String::from_utf8_lossy(&first);
    let first = first.trim_end_matches(['\n', '\r']);
    if first.starts_with(OLD_HEADER_START) {
        return Ok(true);
    }
    // An empty file gets the header before the first line.
    if first == JOBLOG_HEADER || first.is_empty() {
        return Ok(false);
    }
    let columns = first.split('\t').count();
    Err(StoreError::NotASweep {
        path: path.to_path_buf(),
        reason: format!(
            "its header ({columns} columns, {:?}) is not the one sweep writes ({FIELDS} columns, \
             starting Seq, Host, …, ending Index, Hash, Status, Class, Pid); move the file away and \
             sweep starts a new joblog",
            first.chars().take(60).collect::<String>()
        ),
    })
}

/// The joblog's file name.
pub(super) const JOBLOG: &str = "joblog.tsv";

/// Header of `joblog.tsv`: GNU parallel's `--joblog` columns, then the point's index, the run
/// hash, the status, the failure class and the pid.
pub const JOBLOG_HEADER: &str =
    "Seq\tHost\tStarttime\tJobRuntime\tSend\tReceive\tExitval\tSignal\tCommand\tIndex\tHash\tStatus\tClass\tPid";
/// Fields of a line under [`JOBLOG_HEADER`].
const FIELDS: usize = 14;
/// The header of an earlier version, and its field count.
const OLD_HEADER_START: &str = "seq\thost\tpid\t";
const OLD_FIELDS: usize = 8;

fn is_header(line: &str) -> bool {
    line.starts_with("seq\t") || line.starts_with("Seq\t")
}

/// GNU parallel's Exitval for a status: 0 done, 1 failed, 130 cut off (cancelled, interrupted),
/// 4 the directory could not be written.
fn exitval(status: &str) -> u8 {
    match status {
        "done" => 0,
        "failed" => 1,
        "store-error" => 4,
        _ => 130,
    }
}

/// One attempt, as a joblog line.
#[derive(Debug, Clone, PartialEq)]
pub struct AttemptRecord {
    pub hash: String,
    pub start: SystemTime,
    pub runtime_s: f64,
    /// `done`, `failed` or `cancelled`.
    pub status: &'static str,
    /// The failure class, if it failed.
    pub class: Option<&'static str>,
}

impl AttemptRecord {
    /// The line of a finished run written for an attempt that was cut off before it wrote its
    /// own (`claimed_at`: when that attempt claimed the run, Unix seconds).
    pub fn finished(hash: &str, outcome: &crate::outcome::RunOutcome, claimed_at: f64) -> AttemptRecord {
        use crate::outcome::RunOutcome;
        let (status, class, runtime_s) = match outcome {
            RunOutcome::Done(r) => ("done", None, r.wall_time),
            RunOutcome::Failed(f) => ("failed", Some(f.class.as_str()), f.wall_time),
            RunOutcome::Cancelled => ("cancelled", None, f64::NAN),
        };
        let start = UNIX_EPOCH + std::time::Duration::from_secs_f64(claimed_at.max(0.0));
        AttemptRecord { hash: hash.to_string(), start, runtime_s, status, class }
    }
}

/// `joblog.tsv`, opened for appending. Each line is appended under the directory's lock with
/// the next sequence number after the file's last line, so that two processes sharing the
/// directory never write the same `seq`.
#[derive(Debug)]
pub struct Joblog {
    file: File,
    path: PathBuf,
    lock: PathBuf,
    host: String,
    /// The file has the earlier version's header: append in its format.
    old: bool,
    /// The point index of each run hash (from the manifest).
    index: HashMap<String, usize>,
}

impl Joblog {
    /// Name each run's point index in its lines.
    pub fn with_indices(mut self, index: HashMap<String, usize>) -> Joblog {
        self.index = index;
        self
    }

    /// Append one attempt; returns its sequence number.
    pub fn append(&mut self, a: &AttemptRecord) -> Result<u64, StoreError> {
        let host = self.host.clone();
        self.append_as(a, &host, std::process::id())
    }

    /// [`Joblog::append`] of an attempt made by another process (`host`, `pid`): the line a
    /// killed attempt owes, written by the process that found its claim.
    pub fn append_as(&mut self, a: &AttemptRecord, host: &str, pid: u32) -> Result<u64, StoreError> {
        let _lock = DirLock::take(&self.lock)?;
        let (last, cut) = last_seq(&self.file).map_err(io(&self.path))?;
        // A line cut short (a full disk, a kill mid-write) is no record, and its number would
        // be ours: it is dropped, so that ours starts a line and numbers stay unique.
        if let Some(at) = cut {
            self.file.set_len(at).map_err(io(&self.path))?;
        }
        let seq = last + 1;
        let start = a.start.duration_since(UNIX_EPOCH).map(|d| d.as_secs_f64()).unwrap_or(0.0);
        let runtime = if a.runtime_s.is_finite() { format!("{:.3}", a.runtime_s) } else { "-".into() };
        let open =
            if cut.is_none() && !ends_with_newline(&self.file).map_err(io(&self.path))? { "\n" } else { "" };
        // Tabs and newlines would break the line's columns.
        let host = host.replace(['\t', '\n', '\r'], " ");
        let (status, class, hash) = (a.status, a.class.unwrap_or("-"), &a.hash);
        let line = if self.old {
            format!("{open}{seq}\t{host}\t{pid}\t{start:.3}\t{runtime}\t{status}\t{class}\t{hash}\n")
        } else {
            let index = self.index.get(hash).map_or("-".to_string(), |i| i.to_string());
            let exit = exitval(status);
            format!(
                "{open}{seq}\t{host}\t{start:.3}\t{runtime}\t0\t0\t{exit}\t0\truns/{hash}/in.liggghts\t{index}\t{hash}\t{status}\t{class}\t{pid}\n"
            )
        };
        self.file.write_all(line.as_bytes()).map_err(io(&self.path))?;
        Ok(seq)
    }
}

/// Whether the file is empty or ends with a newline.
fn ends_with_newline(file: &File) -> std::io::Result<bool> {
    use std::os::unix::fs::FileExt;
    let len = file.metadata()?.len();
    let mut last = [b'\n'];
    if len > 0 {
        file.read_exact_at(&mut last, len - 1)?;
    }
    Ok(last[0] == b'\n')
}

/// The sequence number of the last whole line of a joblog (0 when it has none), and where a
/// last line cut short (no newline) starts, if the file ends with one. Reads only the file's tail.
fn last_seq(file: &File) -> std::io::Result<(u64, Option<u64>)> {
    use std::os::unix::fs::FileExt;
    let len = file.metadata()?.len();
    let mut from = len.saturating_sub(8192);
    loop {
        let mut buf = vec![0u8; (len - from) as usize];
        file.read_exact_at(&mut buf, from)?;
        let ends = buf.last().is_none_or(|&b| b == b'\n');
        let cut = match buf.iter().rposition(|&b| b == b'\n') {
            _ if ends => None,
            Some(i) => Some(from + i as u64 + 1),
            // No line end in the tail: read the whole file.
            None if from > 0 => {
                from = 0;
                continue;
            }
            // A file of one line without its end (the header): it is closed, not dropped.
            None => None,
        };
        // The cut line is not counted.
        let buf = &buf[..cut.map_or(buf.len(), |c| (c - from) as usize)];
        let text = String::from_utf8_lossy(buf);
        // The first line of a tail may be cut; only whole lines count.
        let whole = if from == 0 { &text[..] } else { text.split_once('\n').map_or("", |(_, r)| r) };
        let seq = whole
            .lines()
            .rev()
            .filter(|l| !is_header(l) && matches!(l.split('\t').count(), FIELDS | OLD_FIELDS))
            .find_map(|l| l.split('\t').next()?.parse::<u64>().ok());
        match seq {
            Some(s) => return Ok((s, cut)),
            None if from == 0 => return Ok((0, cut)),
            None => from = 0,
        }
    }
}

/// A parsed joblog line (for status and tests).
#[derive(Debug, Clone, PartialEq)]
pub struct JoblogLine {
    pub seq: u64,
    pub host: String,
    pub pid: u32,
    pub status: String,
    pub class: String,
    pub hash: String,
}

/// The runs that have a `done` or `failed` line in `DIR/joblog.tsv`.
pub fn logged_outcomes(dir: &Path) -> Result<std::collections::BTreeSet<String>, StoreError> {
    Ok(read_joblog(dir)?
        .into_iter()
        .filter(|l| l.status == "done" || l.status == "failed")
        .map(|l| l.hash)
        .collect())
}

/// Read `DIR/joblog.tsv`.
pub fn read_joblog(dir: &Path) -> Result<Vec<JoblogLine>, StoreError> {
    let path = dir.join(JOBLOG);
    let text = crate::sys::read::read_text_capped(&path, super::JOBLOG_CAP).map_err(io(&path))?;
    Ok(text
        .lines()
        .filter(|l| !is_header(l))
        .filter_map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            match f.len() {
                FIELDS => Some(JoblogLine {
                    seq: f[0].parse().unwrap_or(0),
                    host: f[1].to_string(),
                    pid: f[13].parse().unwrap_or(0),
                    status: f[11].to_string(),
                    class: f[12].to_string(),
                    hash: f[10].to_string(),
                }),
                OLD_FIELDS => Some(JoblogLine {
                    seq: f[0].parse().unwrap_or(0),
                    host: f[1].to_string(),
                    pid: f[2].parse().unwrap_or(0),
                    status: f[5].to_string(),
                    class: f[6].to_string(),
                    hash: f[7].to_string(),
                }),
                _ => None,
            }
        })
        .collect())
}
