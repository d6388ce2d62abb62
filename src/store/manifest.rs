//! `manifest.json`: the design, every distinct point with its content hash, every nested space,
//! and the identity (templates, mesh, engine, tool) a resume compares against.

use std::fs;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{io, DirLock, Store, StoreError, LOCK};

/// What is wrong inside a `manifest.json` that parsed: the field, and what was expected. Read
/// after "the manifest …"; [`Store::read_manifest`] adds the file and "was edited or is damaged".
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ManifestError {
    #[error("parameters: expected at least one swept parameter")]
    NoParameters,
    #[error("points[{point}].index = {index}: expected {point}")]
    Index { point: usize, index: usize },
    #[error("points[{point}].values: {values} values for {parameters} parameters")]
    Values { point: usize, values: usize, parameters: usize },
    /// The hash names a directory under `runs/`: 64 hex digits, nothing else.
    #[error("points[{point}].hash = {hash:?}: expected 64 hex digits")]
    Hash { point: usize, hash: String },
    #[error("points[{point}].hash: the same as points[{first}].hash")]
    SameHash { point: usize, first: usize },
    #[error("spaces: expected at least one space")]
    NoSpaces,
    #[error("spaces[{space}].points: empty")]
    EmptySpace { space: usize },
    #[error("spaces[{space}].points[{at}] = {point}: no such point (the manifest has {points})")]
    NoSuchPoint { space: usize, at: usize, point: usize, points: usize },
    #[error("design: lds step {step}, max {max}: expected 1 ≤ step ≤ max")]
    LdsSteps { step: usize, max: usize },
    #[error(
        "design: adapt first {first}, batch {batch}, max {max}, repeats {repeats}: expected 1 ≤ first × repeats ≤ max, batch ≥ 1, repeats ≥ 1"
    )]
    AdaptSizes { first: usize, batch: usize, max: usize, repeats: usize },
    #[error("design: lattice levels {levels:?}: expected each at least 2")]
    LatticeLevels { levels: Vec<usize> },
    #[error("seals: expected one per point ({points})")]
    SealCount { points: usize },
    /// Two points each holding the other's hash.
    #[error(
        "points: the hashes of points {first} and {second} are swapped: each names the run of the \
         other (swap them back, or start the sweep in a new directory)"
    )]
    Swapped { first: usize, second: usize },
    /// Points whose values or hash no longer match their seal: the first, and how many more.
    #[error(
        "points[{first}].values or points[{first}].hash: edited since the sweep wrote them (they no \
         longer match seals[{first}]){}; restore it from a copy, or start the sweep in a new directory",
        and_more(.more)
    )]
    Edited { first: usize, more: usize },
}

/// `" (and N more points)"`, or nothing when there are none.
fn and_more(more: &usize) -> String {
    if *more > 0 {
        format!(" (and {more} more points)")
    } else {
        String::new()
    }
}

impl Store {
    pub fn manifest_path(dir: &Path) -> PathBuf {
        dir.join("manifest.json")
    }

    /// Write `sweep.toml` and `manifest.json` (atomically each) and create `runs/` and the joblog.
    pub fn write_manifest(&self, sweep_toml: &str, manifest: &Manifest) -> Result<(), StoreError> {
        self.write_manifest_checked(sweep_toml, manifest, |_| Ok(()))
    }

    /// [`Store::write_manifest`], creating the directory if needed, under the directory's lock,
    /// after `check` has accepted the manifest already there (`None` for a new directory).
    ///
    /// `manifest.json` is written last: a directory without it holds at most `runs/`, the
    /// joblog and `sweep.toml` of a creation that was killed, which the next creation redoes.
    pub fn write_manifest_checked<E: From<StoreError>>(
        &self,
        sweep_toml: &str,
        manifest: &Manifest,
        check: impl FnOnce(Option<(Manifest, String)>) -> Result<(), E>,
    ) -> Result<(), E> {
        self.update_manifest(|old| {
            check(old)?;
            Ok(Some((manifest.clone(), sweep_toml.to_string())))
        })
        .map(drop)
    }

    /// Under the directory's lock (creating the directory if needed): `decide` sees the
    /// manifest and `sweep.toml` there (`None` for a new directory) and returns what to write
    /// instead (`None`: leave them). Returns the manifest in force afterwards, if any.
    pub fn update_manifest<E: From<StoreError>>(
        &self,
        decide: impl FnOnce(Option<(Manifest, String)>) -> Result<Option<(Manifest, String)>, E>,
    ) -> Result<Option<(Manifest, String)>, E> {
        // A directory this call creates is removed again if it cannot be made whole (a full
        // disk): a half-made one would read as "not a sweep directory" ever after.
        let created = self.dir.ancestors().take_while(|d| !d.as_os_str().is_empty() && !d.exists()).last();
        let created = created.map(Path::to_path_buf);
        fs::create_dir_all(&self.dir).map_err(io(&self.dir))?;
        let made = self.write_manifest_locked(decide);
        if let (Err(_), Some(top)) = (&made, &created) {
            if !Self::manifest_path(&self.dir).exists() {
                let _ = fs::remove_dir_all(top);
            }
        }
        made
    }

    fn write_manifest_locked<E: From<StoreError>>(
        &self,
        decide: impl FnOnce(Option<(Manifest, String)>) -> Result<Option<(Manifest, String)>, E>,
    ) -> Result<Option<(Manifest, String)>, E> {
        let _lock = DirLock::take(&self.dir.join(LOCK))?;
        let path = Self::manifest_path(&self.dir);
        let old = if path.exists() { Some(Self::read_manifest(&self.dir)?) } else { None };
        let had = old.clone();
        let Some((manifest, sweep_toml)) = decide(old)? else {
            return Ok(had);
        };
        let runs = self.dir.join("runs");
        fs::create_dir_all(&runs).map_err(io(&runs))?;
        self.joblog_header()?;
        let toml_path = self.dir.join("sweep.toml");
        crate::sys::atomic::write(&toml_path, sweep_toml.as_bytes()).map_err(io(&toml_path))?;
        let written = Written { manifest: &manifest, seals: seals(&manifest), sweep_toml: &sweep_toml };
        crate::sys::atomic::write_json(&path, &written).map_err(io(&path))?;
        Ok(Some((manifest, sweep_toml)))
    }

    /// `key: recorded → now` for every setting of `DIR/sweep.toml` that differs from the copy
    /// the manifest recorded when it was written (none for a manifest without a copy).
    pub fn sweep_toml_changes(dir: &Path, now: &str) -> Vec<String> {
        let Ok(text) = read_text(&Self::manifest_path(dir), super::MANIFEST_CAP) else { return Vec::new() };
        let recorded = serde_json::from_str::<serde_json::Value>(&text)
            .ok()
            .and_then(|v| v.get("sweep_toml")?.as_str().map(str::to_string));
        match recorded {
            Some(recorded) => toml_changes(&recorded, now),
            None => Vec::new(),
        }
    }

    /// Read `manifest.json` and `sweep.toml` of `dir`.
    pub fn read_manifest(dir: &Path) -> Result<(Manifest, String), StoreError> {
        let path = Self::manifest_path(dir);
        let text = read_text(&path, super::MANIFEST_CAP).map_err(|e| StoreError::NotASweep {
            path: dir.to_path_buf(),
            reason: format!(
                "not a sweep directory (cannot read manifest.json: {})",
                match e.kind() {
                    std::io::ErrorKind::NotFound => format!(
                        "no such file); a sweep file starts one there: `sweep lds SWEEP.toml --out {}` \
                         (or lattice, adapt",
                        crate::sys::shell::quote_path(dir)
                    ),
                    _ => e.to_string(),
                }
            ),
        })?;
        let not_a_sweep = |reason: String| StoreError::NotASweep { path: path.clone(), reason };
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| not_a_sweep(format!("truncated or not JSON ({e}); the manifest is damaged")))?;
        let format = value.get("format").and_then(|f| f.as_u64());
        if format != Some(MANIFEST_FORMAT as u64) {
            return Err(not_a_sweep(format!(
                "manifest format {}: expected {MANIFEST_FORMAT}",
                format.map_or("missing".into(), |f| f.to_string())
            )));
        }
        let manifest: Manifest =
            serde_json::from_str(&text).map_err(|e| not_a_sweep(format!("unreadable manifest: {e}")))?;
        manifest
            .validate()
            .and_then(|()| check_seals(&manifest, value.get("seals")))
            .map_err(|source| StoreError::Damaged { path: path.clone(), source })?;
        let toml_path = dir.join("sweep.toml");
        let sweep = read_text(&toml_path, super::SWEEP_TOML_CAP).map_err(|e| StoreError::NotASweep {
            path: toml_path.clone(),
            reason: format!("cannot read the resolved sweep file: {e}"),
        })?;
        Ok((manifest, sweep))
    }
}

/// A file of the directory as UTF-8 text: a regular file of at most `cap` bytes.
fn read_text(path: &Path, cap: u64) -> std::io::Result<String> {
    let bytes = crate::sys::read::read_capped(path, cap)?;
    String::from_utf8(bytes).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
}

/// `manifest.json` as written: the manifest, each point's seal (in point order) and the
/// resolved sweep file it was planned from.
#[derive(Serialize)]
struct Written<'a> {
    #[serde(flatten)]
    manifest: &'a Manifest,
    seals: Vec<String>,
    sweep_toml: &'a str,
}

/// A point's seal: 16 hex digits of SHA-256 over its index, values and hash. A hand edit of a
/// point's values or hash (which pairs it with another run, or none) no longer matches it.
fn seal(index: usize, values: &[f64], hash: &str) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    h.update(format!("{index}\n"));
    for v in values {
        h.update(format!("{:016x}\n", v.to_bits()));
    }
    h.update(hash.as_bytes());
    crate::sys::hex(&h.finalize()[..8])
}

fn seals(m: &Manifest) -> Vec<String> {
    use rayon::prelude::*;
    m.points.par_iter().map(|p| seal(p.index, &p.values, &p.hash)).collect()
}

/// Every point matches its seal (a manifest written before seals has none); the error names
/// the point, or the two points whose hashes were swapped.
fn check_seals(m: &Manifest, seals: Option<&serde_json::Value>) -> Result<(), ManifestError> {
    let Some(seals) = seals else { return Ok(()) };
    let seals: Vec<&str> = match seals.as_array() {
        Some(a) if a.len() == m.points.len() => a.iter().map(|s| s.as_str().unwrap_or("")).collect(),
        _ => return Err(ManifestError::SealCount { points: m.points.len() }),
    };
    let ours = self::seals(m);
    let wrong: Vec<usize> = (0..seals.len()).filter(|&i| seals[i] != ours[i]).collect();
    let Some(&first) = wrong.first() else { return Ok(()) };
    // Two points each holding the other's hash: a swap.
    if wrong.len() <= 1000 {
        for &i in &wrong {
            let p = &m.points[i];
            let partner = wrong.iter().find(|&&j| {
                let q = &m.points[j];
                j != i && seal(i, &p.values, &q.hash) == seals[i] && seal(j, &q.values, &p.hash) == seals[j]
            });
            if let Some(&j) = partner {
                return Err(ManifestError::Swapped { first: i.min(j), second: i.max(j) });
            }
        }
    }
    Err(ManifestError::Edited { first, more: wrong.len() - 1 })
}

/// `key: a → b` for every leaf that differs between two sweep files, design, convergence and
/// cluster left out (an extension changes the design; the rule and how a cluster starts `sweep`
/// may change freely).
fn toml_changes(a: &str, b: &str) -> Vec<String> {
    fn walk(path: &str, a: Option<&toml::Value>, b: Option<&toml::Value>, out: &mut Vec<String>) {
        match (a, b) {
            (Some(toml::Value::Table(x)), Some(toml::Value::Table(y))) => {
                let keys: std::collections::BTreeSet<&String> = x.keys().chain(y.keys()).collect();
                for k in keys {
                    let p = if path.is_empty() { k.clone() } else { format!("{path}.{k}") };
                    if path.is_empty() && ["design", "convergence", "cluster"].contains(&k.as_str()) {
                        continue;
                    }
                    walk(&p, x.get(k), y.get(k), out);
                }
            }
            _ if a != b => {
                let show = |v: Option<&toml::Value>| v.map_or("(absent)".to_string(), |v| v.to_string());
                out.push(format!("{path} = {} (the sweep ran with {})", show(b), show(a)));
            }
            _ => {}
        }
    }
    let parse = |t: &str| t.parse::<toml::Table>().ok().map(toml::Value::Table);
    let mut out = Vec::new();
    walk("", parse(a).as_ref(), parse(b).as_ref(), &mut out);
    out
}

/// Version of `manifest.json`.
pub const MANIFEST_FORMAT: u32 = 1;

/// How the points were chosen; enough to extend the design later.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum DesignRecord {
    Lattice {
        levels: Vec<usize>,
    },
    Lds {
        step: usize,
        max: usize,
        scrambling: crate::sweep::Scrambling,
        seed: u64,
    },
    /// `sweep adapt`: a scrambled-Halton first batch, then batches chosen from the results so
    /// far; the manifest grows by one space per batch.
    Adapt {
        first: usize,
        batch: usize,
        max: usize,
        seed: u64,
        /// Runs of each planned setting, each with its own `scene.seed` (`sweep calibrate
        /// --repeats`): `first` and `batch` count settings, `max` runs. Absent (1) in manifests
        /// written before repeats.
        #[serde(default = "one", skip_serializing_if = "is_one")]
        repeats: usize,
    },
}

fn one() -> usize {
    1
}

fn is_one(n: &usize) -> bool {
    *n == 1
}

impl DesignRecord {
    /// Whether the points were planned batch by batch from the results (`sweep adapt`, `sweep
    /// calibrate`): the runs are then not a sample of the space.
    pub fn is_adaptive(&self) -> bool {
        matches!(self, DesignRecord::Adapt { .. })
    }
}

/// One nested space: a lattice level or an LDS prefix.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SpaceRecord {
    /// `"lattice 5"`, `"lds 400"`, `"adapt 48"`.
    pub label: String,
    /// Indices into [`Manifest::points`].
    pub points: Vec<usize>,
}

/// One distinct design point.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct PointRecord {
    pub index: usize,
    /// Swept parameter values in file order, in the sweep file's units.
    pub values: Vec<f64>,
    pub hash: String,
    /// Nothing can pass under the blade here ([`crate::run::screen`]): skipped as MFR = 0 once the
    /// screen is verified. Absent (false) in manifests written before the screen.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub closed: bool,
    /// The `scene.seed` this point runs with, when not the sweep's: a repeat of a setting
    /// (the same values, another initial packing). Absent in manifests written before repeats.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

/// `manifest.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    pub format: u32,
    /// `demsweep <version>` that wrote it.
    pub tool: String,
    pub name: String,
    /// Swept parameter names: the columns of [`PointRecord::values`].
    pub parameters: Vec<String>,
    pub design: DesignRecord,
    pub spaces: Vec<SpaceRecord>,
    pub points: Vec<PointRecord>,
    /// Template, mesh generator and engine identity; a resume refuses when it changed.
    pub identity: serde_json::Value,
}

impl Manifest {
    /// Check what the types cannot: every index in range, one hash per point, as many values
    /// as parameters. The error names the field.
    pub fn validate(&self) -> Result<(), ManifestError> {
        let n = self.points.len();
        if self.parameters.is_empty() {
            return Err(ManifestError::NoParameters);
        }
        let mut hashes: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
        for (i, p) in self.points.iter().enumerate() {
            if p.index != i {
                return Err(ManifestError::Index { point: i, index: p.index });
            }
            if p.values.len() != self.parameters.len() {
                return Err(ManifestError::Values {
                    point: i,
                    values: p.values.len(),
                    parameters: self.parameters.len(),
                });
            }
            // The hash names a directory under runs/: 64 hex digits, nothing else.
            if p.hash.len() != 64 || !p.hash.bytes().all(|b| b.is_ascii_hexdigit()) {
                return Err(ManifestError::Hash { point: i, hash: p.hash.clone() });
            }
            if let Some(j) = hashes.insert(&p.hash, i) {
                return Err(ManifestError::SameHash { point: i, first: j });
            }
        }
        if self.spaces.is_empty() {
            return Err(ManifestError::NoSpaces);
        }
        for (k, s) in self.spaces.iter().enumerate() {
            if s.points.is_empty() {
                return Err(ManifestError::EmptySpace { space: k });
            }
            if let Some((j, &v)) = s.points.iter().enumerate().find(|(_, &v)| v >= n) {
                return Err(ManifestError::NoSuchPoint { space: k, at: j, point: v, points: n });
            }
        }
        match &self.design {
            DesignRecord::Lds { step, max, .. } if *step == 0 || max < step => {
                Err(ManifestError::LdsSteps { step: *step, max: *max })
            }
            DesignRecord::Adapt { first, batch, max, repeats, .. }
                if *first == 0 || *batch == 0 || *repeats == 0 || *max < first * repeats =>
            {
                Err(ManifestError::AdaptSizes { first: *first, batch: *batch, max: *max, repeats: *repeats })
            }
            DesignRecord::Lattice { levels } if levels.iter().any(|&l| l < 2) => {
                Err(ManifestError::LatticeLevels { levels: levels.clone() })
            }
            _ => Ok(()),
        }
    }
}
