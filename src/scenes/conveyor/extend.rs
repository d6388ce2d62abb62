//! Extending a finished run: its window continued from where the run ended, with no warm-up
//! again, until a tighter SE target is met or the window cap (`sweep extend`).
//!
//! Every conveyor deck writes a LIGGGHTS restart at its end ([`RESTART`]): every particle with
//! its contacts' history, the walls' and the mesh's state, the step. A continuation deck reads
//! it in place of the substrate and the heap, numbers its blocks on from the last, and starts
//! its stop rule from the earlier parts' prefix sums, so it judges the whole series as one run
//! would. The result is measured over every part's blocks and v_x snapshots.
//!
//! How close to one unbroken run (tests/it/extend.rs): the blocks after the join are those of
//! the same point run at the tighter target from the start for the first two blocks, to the
//! digits the log prints; the restart does not carry the insertion's random state, so from the
//! third block on the two part as two seeds of a chaotic flow would.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::engine::LOG;
use crate::measure::steady::{self, Block};
use crate::scene::Scene;

/// The restart a conveyor deck writes at its end.
pub const RESTART: &str = "restart.end";
/// What a done run's directory keeps of it: gzipped, about a sixth of its size.
pub const KEPT_RESTART: &str = "restart.end.gz";
/// The earlier part's restart, unpacked into a continuation's run directory for its deck.
pub const PRIOR_RESTART: &str = "prior.restart";

/// Where a continuation deck starts: the deck's `scene.own.extend`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Continuation {
    /// The restart it reads, in its run directory.
    pub restart: String,
    /// The first block it runs; the earlier parts ran the ones before.
    pub first_block: u64,
    /// The strip's mass when the earlier parts ended, kg (a block's deposit is the mass that
    /// reached the delete region plus the strip's change).
    pub strip_before: f64,
    /// Prefix sums over the earlier blocks after the warm-up, the deck's `p1_k`, `p2_k`, `p3_k`.
    pub sums: Vec<PrefixSums>,
}

/// Σ y, Σ y², Σ k·y over the first k blocks after the warm-up.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PrefixSums {
    pub y: f64,
    pub yy: f64,
    pub ky: f64,
}

/// Why a finished run cannot be continued.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum NotExtendable {
    #[error("its run left no {KEPT_RESTART} (runs from before runs could be extended): run it again")]
    NoRestart,
    /// Its restart is there but is no regular file (issue 70: a FIFO read "left no restart").
    #[error("{} is not a regular file (a FIFO, a device or a directory): remove it and run the point again", path.display())]
    NotAFile { path: PathBuf },
    #[error("cannot unpack its restart into {}: {why}", path.display())]
    Unpack { path: PathBuf, why: String },
    #[error(
        "it stopped at the window cap ({blocks} blocks); a longer window needs a larger \
         scene.window_cap_diameters"
    )]
    AtCap { blocks: u64 },
    #[error("{}: {why}", path.display())]
    Log { path: PathBuf, why: String },
}

/// The blocks of a run's parts (`parts`: its directories, oldest first), in order, and how the
/// last part stopped.
pub fn earlier_blocks(parts: &[PathBuf]) -> Result<(Vec<Block>, Option<String>), NotExtendable> {
    let mut blocks = Vec::new();
    let mut stop = None;
    for dir in parts {
        let path = dir.join(LOG);
        let log = std::fs::read_to_string(&path)
            .map_err(|e| NotExtendable::Log { path: path.clone(), why: e.to_string() })?;
        let (these, s) = steady::parse_blocks(&log)
            .map_err(|e| NotExtendable::Log { path: path.clone(), why: e.to_string() })?;
        blocks.extend(these);
        stop = s;
    }
    Ok((blocks, stop))
}

/// `scene` (the point's held heap, at the SE target to run to) continued from the run whose
/// parts are `parts` (their run directories, oldest first) by a new part in `part_dir`, with the
/// last part's restart unpacked there for its deck.
pub fn continuation(scene: &Scene, parts: &[PathBuf], part_dir: &Path) -> Result<Scene, NotExtendable> {
    let last = parts.last().ok_or(NotExtendable::NoRestart)?;
    if !last.join(KEPT_RESTART).is_file() && !last.join(RESTART).is_file() {
        // One that is there but no regular file (a FIFO, a device) is named as such.
        if let Some(name) =
            [KEPT_RESTART, RESTART].into_iter().find(|n| last.join(n).symlink_metadata().is_ok())
        {
            return Err(NotExtendable::NotAFile { path: last.join(name) });
        }
        return Err(NotExtendable::NoRestart);
    }
    let c = super::held(scene);
    let (blocks, stop) = earlier_blocks(parts)?;
    let ran = blocks.len() as u64;
    if stop.as_deref() == Some("cap") || ran >= c.max_blocks {
        return Err(NotExtendable::AtCap { blocks: ran });
    }
    let y = steady::block_mfr(&blocks, c.ideal_block_mass);
    let mut sums = Vec::new();
    let mut s = PrefixSums { y: 0.0, yy: 0.0, ky: 0.0 };
    for (k, y) in y.iter().skip(c.warmup_blocks as usize).enumerate() {
        s = PrefixSums { y: s.y + y, yy: s.yy + y * y, ky: s.ky + (k + 1) as f64 * y };
        sums.push(s);
    }
    if sums.is_empty() {
        // A run that ended in its warm-up did not stop on its target or its cap.
        return Err(NotExtendable::Log {
            path: last.join(LOG),
            why: format!("{ran} blocks, none after the {}-block warm-up", c.warmup_blocks),
        });
    }
    let into = part_dir.join(PRIOR_RESTART);
    unpack(last, &into).map_err(|e| NotExtendable::Unpack { path: into.clone(), why: e.to_string() })?;
    let more = Continuation {
        restart: PRIOR_RESTART.into(),
        first_block: ran + 1,
        strip_before: blocks.last().map_or(0.0, |b| b.strip),
        sums,
    };
    Ok(super::with_held(scene.clone(), |h| h.extend = Some(more)))
}

/// What a finished run's directory keeps of its restarts: a done run's own gzipped (for a
/// later extension), nothing of a failed run's, nor the earlier part's copy a continuation read.
pub fn keep_restart(run_dir: &Path, done: bool) -> std::io::Result<()> {
    let _ = std::fs::remove_file(run_dir.join(PRIOR_RESTART));
    let raw = run_dir.join(RESTART);
    if !raw.is_file() {
        return Ok(());
    }
    let kept = if done { pack(&raw, &run_dir.join(KEPT_RESTART)) } else { Ok(()) };
    std::fs::remove_file(&raw)?;
    kept
}

/// gzip `from` into `to`, whole or not at all.
fn pack(from: &Path, to: &Path) -> std::io::Result<()> {
    let tmp = to.with_extension("gz.tmp");
    let written = (|| {
        let mut gz = flate2::write::GzEncoder::new(std::fs::File::create(&tmp)?, flate2::Compression::fast());
        std::io::copy(&mut std::fs::File::open(from)?, &mut gz)?;
        gz.finish()?.sync_all()?;
        std::fs::rename(&tmp, to)
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// The restart the run in `run_dir` kept, into `to`: gzipped, or as LIGGGHTS wrote it (a run
/// whose directory was not tidied, e.g. one made before restarts were packed).
fn unpack(run_dir: &Path, to: &Path) -> std::io::Result<()> {
    let kept = run_dir.join(KEPT_RESTART);
    if !kept.is_file() {
        return std::fs::copy(run_dir.join(RESTART), to).map(|_| ());
    }
    let mut gz = flate2::read::GzDecoder::new(std::fs::File::open(kept)?);
    std::io::copy(&mut gz, &mut std::fs::File::create(to)?).map(|_| ())
}
