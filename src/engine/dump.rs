//! Streaming parser for LIGGGHTS (and LAMMPS) `custom` dump files.
//!
//! A dump is a sequence of snapshots, each written by `dump ... custom` as
//!
//! ```text
//! ITEM: TIMESTEP
//! 2000
//! ITEM: NUMBER OF ATOMS
//! 112
//! ITEM: BOX BOUNDS pp pp ff          (or `xy xz yz pp pp ff` with a third tilt value per line)
//! 0 0.01
//! 0 0.01
//! 0 0.02
//! ITEM: ATOMS id type x y z vx ...
//! 1 1 0.002 0.002 0.002038 ...       (one row per atom, columns in header order)
//! ```
//!
//! (LIGGGHTS 3.8 `src/dump_custom.cpp`, `header_item` / `write_lines`). Columns are found by
//! name, in whatever order the deck asked for them. [`DumpReader`] reads one snapshot at a time
//! and can refill a caller's [`Snapshot`] without allocating ([`DumpReader::read_snapshot_into`]);
//! [`read_dump`] reads a whole file and checks that the columns a caller needs are present.
//!
//! Every field must be a finite number: a truncated file, a missing column, a non-numeric or
//! non-finite field, a row with the wrong number of fields and an atom count that does not match
//! the rows are all [`DumpError`]s naming the file, the snapshot (index and timestep) and the line.
//!
//! It does not interpret the columns (units, which column is a position): that is the metrics'
//! job. It reads text dumps only, not binary or gzipped ones, and not `ITEM: UNITS`/`ITEM: TIME`
//! headers, which LIGGGHTS 3.8 never writes.

use std::fmt;
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

/// Longest line read, in bytes with its newline (a dump row is a few hundred bytes).
pub const MAX_LINE: usize = 64 * 1024;

/// Where in a dump an error was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    pub file: PathBuf,
    /// 0-based index of the snapshot in the file.
    pub snapshot: usize,
    /// The snapshot's timestep, once its `ITEM: TIMESTEP` line has been read.
    pub timestep: Option<u64>,
    /// 1-based line number.
    pub line: u64,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{} (snapshot {}", self.file.display(), self.line, self.snapshot)?;
        if let Some(t) = self.timestep {
            write!(f, ", timestep {t}")?;
        }
        write!(f, ")")
    }
}

/// What went wrong reading a dump. Every variant but `Open` carries the [`Location`].
#[derive(Debug, thiserror::Error)]
pub enum DumpError {
    #[error("cannot open dump {}: {source}", file.display())]
    Open { file: PathBuf, source: std::io::Error },
    #[error("cannot read dump at {at}: {source}")]
    Io { at: Location, source: std::io::Error },
    /// The file ends inside a snapshot, or its last line has no newline (LIGGGHTS ends every
    /// line with one, so a missing one means a cut-off write).
    #[error("dump truncated at {at}: expected {expected}")]
    Truncated { at: Location, expected: String },
    /// A header line is not the `ITEM:` line (or value line) that must come next.
    #[error("bad dump header at {at}: expected {expected}, found `{found}`")]
    Header { at: Location, expected: String, found: String },
    /// A field that must be a number is not one (or is not finite).
    #[error("non-numeric field at {at}: column `{column}` is `{field}`, expected a finite number")]
    NotANumber { at: Location, column: String, field: String },
    /// An atom row has a different number of fields than the `ITEM: ATOMS` header has columns.
    #[error("wrong field count at {at}: row has {found} fields, the ATOMS header has {expected} columns")]
    FieldCount { at: Location, expected: usize, found: usize },
    /// `ITEM: NUMBER OF ATOMS` does not match the number of atom rows that follow.
    #[error("atom count mismatch at {at}: NUMBER OF ATOMS says {declared}, found {found} rows")]
    AtomCount { at: Location, declared: u64, found: u64 },
    /// A line longer than [`MAX_LINE`] bytes: not a LIGGGHTS dump (its rows are a few hundred
    /// bytes), and not held in memory whole.
    #[error("line too long at {at}: more than {limit} bytes without a newline; not a LIGGGHTS text dump")]
    LineTooLong { at: Location, limit: usize },
    /// A column the caller needs is not in the `ITEM: ATOMS` header.
    #[error("missing column `{column}` at {at}: the dump has columns {available}")]
    MissingColumn { at: Location, column: String, available: String },
}

impl DumpError {
    /// The location of the error, if it has one (all but `Open`).
    pub fn location(&self) -> Option<&Location> {
        match self {
            DumpError::Open { .. } => None,
            DumpError::Io { at, .. }
            | DumpError::Truncated { at, .. }
            | DumpError::Header { at, .. }
            | DumpError::NotANumber { at, .. }
            | DumpError::FieldCount { at, .. }
            | DumpError::AtomCount { at, .. }
            | DumpError::LineTooLong { at, .. }
            | DumpError::MissingColumn { at, .. } => Some(at),
        }
    }

    /// The 1-based line of the error, if it has one.
    pub fn line(&self) -> Option<u64> {
        self.location().map(|at| at.line)
    }
}

/// The index of a column in a [`Snapshot`], found by name with [`Snapshot::column`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ColumnIdx(pub usize);

/// One snapshot of a dump: header values and the atom table, row-major, one `f64` per field.
///
/// Integer columns (`id`, `type`) are stored as `f64`, exact up to 2^53.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Snapshot {
    pub timestep: u64,
    /// `[lo, hi]` per axis x, y, z, in dump length units (m for `units si`). For a triclinic box
    /// these are the bounding-box values LIGGGHTS writes, not the box corners.
    pub box_bounds: [[f64; 2]; 3],
    /// `xy xz yz` tilt factors of a triclinic box, `None` for an orthogonal one.
    pub tilt: Option<[f64; 3]>,
    /// Periodic per axis (flag `pp`); `f`, `s` and `m` boundaries are not periodic.
    pub periodic: [bool; 3],
    columns: Vec<String>,
    data: Vec<f64>,
    natoms: usize,
}

impl Snapshot {
    /// Number of atoms (rows).
    pub fn len(&self) -> usize {
        self.natoms
    }

    pub fn is_empty(&self) -> bool {
        self.natoms == 0
    }

    /// The column names, in file order.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The index of the column named `name`, if present.
    pub fn column(&self, name: &str) -> Option<ColumnIdx> {
        self.columns.iter().position(|c| c == name).map(ColumnIdx)
    }

    /// The value of column `col` for atom row `row`. Panics if `row >= len()`.
    pub fn get(&self, row: usize, col: ColumnIdx) -> f64 {
        assert!(row < self.natoms, "row {row} out of {} rows", self.natoms);
        self.data[row * self.columns.len() + col.0]
    }

    /// All fields of atom row `row`, in column order. Panics if `row >= len()`.
    pub fn row(&self, row: usize) -> &[f64] {
        let n = self.columns.len();
        &self.data[row * n..(row + 1) * n]
    }

    /// The values of one column, atom by atom.
    pub fn column_values(&self, col: ColumnIdx) -> impl ExactSizeIterator<Item = f64> + '_ {
        let n = self.columns.len().max(1);
        self.data.iter().skip(col.0).step_by(n).copied().take(self.natoms)
    }
}

/// Reads snapshots one by one from a dump. As an [`Iterator`] it yields fresh snapshots and
/// stops after the first error; [`DumpReader::read_snapshot_into`] reuses a snapshot's buffers.
pub struct DumpReader<R> {
    input: R,
    file: PathBuf,
    required: Vec<String>,
    line: Vec<u8>,
    line_no: u64,
    snapshot: usize,
    timestep: Option<u64>,
    /// NUMBER OF ATOMS of the snapshot being read (or last read).
    natoms: u64,
    failed: bool,
}

impl DumpReader<BufReader<File>> {
    /// Opens the dump at `path` for reading.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, DumpError> {
        let path = path.as_ref();
        let f = File::open(path).map_err(|source| DumpError::Open { file: path.to_path_buf(), source })?;
        // A larger buffer than the 8 KiB default halves the number of read calls on big dumps.
        Ok(DumpReader::new(BufReader::with_capacity(1 << 17, f), path))
    }
}

impl<R: BufRead> DumpReader<R> {
    /// Reads a dump from `input`; `file` is the name errors report.
    pub fn new(input: R, file: impl Into<PathBuf>) -> Self {
        DumpReader {
            input,
            file: file.into(),
            required: Vec::new(),
            line: Vec::with_capacity(256),
            line_no: 0,
            snapshot: 0,
            timestep: None,
            natoms: 0,
            failed: false,
        }
    }

    /// Makes every snapshot without one of these columns an error naming the column.
    pub fn require(mut self, columns: &[&str]) -> Self {
        self.required = columns.iter().map(|c| c.to_string()).collect();
        self
    }

    /// Reads the next snapshot into `snap`, reusing its buffers. Returns `Ok(false)` at the end
    /// of the file (only whitespace-only lines may follow the last snapshot). On error `snap`
    /// holds partial data and the reader should not be used further.
    pub fn read_snapshot_into(&mut self, snap: &mut Snapshot) -> Result<bool, DumpError> {
        let r = self.read_snapshot(snap);
        if r.is_err() {
            self.failed = true;
        }
        r
    }

    fn read_snapshot(&mut self, snap: &mut Snapshot) -> Result<bool, DumpError> {
        // Blank lines between snapshots and at the end are tolerated.
        loop {
            if !self.next_line()? {
                return Ok(false);
            }
            if !self.text().trim_ascii().is_empty() {
                break;
            }
        }
        // A number where a snapshot should start: more atom rows than NUMBER OF ATOMS said.
        // The error belongs to the previous snapshot, whose timestep is still in `self.timestep`.
        if self.snapshot > 0 && self.starts_with_number() {
            let at = Location { snapshot: self.snapshot - 1, ..self.at() };
            let declared = self.natoms;
            let mut found = declared;
            loop {
                found += 1;
                if !self.next_line()? || !self.starts_with_number() {
                    break;
                }
            }
            return Err(DumpError::AtomCount { at, declared, found });
        }
        self.timestep = None;

        self.expect_item("TIMESTEP")?;
        self.expect_value_line("the timestep")?;
        snap.timestep = self.parse_int("timestep")?;
        self.timestep = Some(snap.timestep);

        self.expect_line("`ITEM: NUMBER OF ATOMS`")?;
        self.expect_item("NUMBER OF ATOMS")?;
        self.expect_value_line("the number of atoms")?;
        let natoms = self.parse_int("number of atoms")?;
        self.natoms = natoms;

        self.expect_line("`ITEM: BOX BOUNDS`")?;
        let rest = self.expect_item("BOX BOUNDS")?;
        let (triclinic, periodic) = self.parse_bounds_flags(rest)?;
        snap.periodic = periodic;
        let mut tilt = [0.0; 3];
        for (bounds, tilt) in snap.box_bounds.iter_mut().zip(&mut tilt) {
            self.expect_value_line("a box bounds line")?;
            let n = if triclinic { 3 } else { 2 };
            let mut vals = [0.0; 3];
            let mut found = 0;
            for field in Fields::new(&self.line) {
                if found < 3 {
                    vals[found] = self.parse_f64(field, "box bounds")?;
                }
                found += 1;
            }
            if found != n {
                return Err(self.header_err(if triclinic {
                    "3 numbers `lo hi tilt`"
                } else {
                    "2 numbers `lo hi`"
                }));
            }
            *bounds = [vals[0], vals[1]];
            *tilt = vals[2];
        }
        snap.tilt = triclinic.then_some(tilt);

        self.expect_line("`ITEM: ATOMS`")?;
        let rest = self.expect_item("ATOMS")?;
        let header_line = self.line_no;
        self.parse_columns(rest, snap)?;
        for req in &self.required {
            if snap.column(req).is_none() {
                return Err(DumpError::MissingColumn {
                    at: self.at(),
                    column: req.clone(),
                    available: snap.columns.join(" "),
                });
            }
        }

        let ncols = snap.columns.len();
        snap.data.clear();
        snap.natoms = 0;
        // Reserve from the declared count, capped so a corrupt count cannot exhaust memory.
        snap.data.reserve((natoms as usize).saturating_mul(ncols).min(1 << 24));
        for row in 0..natoms {
            if !self.next_line()? {
                return Err(self.truncated(&format!(
                    "{natoms} atom rows after the ATOMS header at line {header_line}, found {row}"
                )));
            }
            self.require_newline("the rest of an atom row")?;
            if self.text().trim_ascii_start().starts_with(b"ITEM:") {
                return Err(DumpError::AtomCount { at: self.at(), declared: natoms, found: row });
            }
            let mut found = 0;
            let mut rest = &self.line[..];
            while found < ncols {
                match next_number(&mut rest) {
                    None => break,
                    Some(Ok(v)) => snap.data.push(v),
                    Some(Err(field)) => return Err(self.nan_err(field, &snap.columns[found])),
                }
                found += 1;
            }
            found += Fields::new(rest).count();
            if found != ncols {
                return Err(DumpError::FieldCount { at: self.at(), expected: ncols, found });
            }
            snap.natoms += 1;
        }
        self.snapshot += 1;
        Ok(true)
    }

    /// Reads the next line into `self.line`; `false` at end of input.
    fn next_line(&mut self) -> Result<bool, DumpError> {
        use std::io::Read;
        self.line.clear();
        let n = (&mut self.input)
            .take(MAX_LINE as u64 + 1)
            .read_until(b'\n', &mut self.line)
            .map_err(|source| DumpError::Io { at: self.at(), source })?;
        if n == 0 {
            return Ok(false);
        }
        self.line_no += 1;
        if n > MAX_LINE && self.line.last() != Some(&b'\n') {
            return Err(DumpError::LineTooLong { at: self.at(), limit: MAX_LINE });
        }
        Ok(true)
    }

    /// The current line without its line ending.
    fn text(&self) -> &[u8] {
        let l = self.line.strip_suffix(b"\n").unwrap_or(&self.line);
        l.strip_suffix(b"\r").unwrap_or(l)
    }

    fn expect_line(&mut self, expected: &str) -> Result<(), DumpError> {
        if !self.next_line()? {
            return Err(self.truncated(expected));
        }
        self.require_newline(expected)
    }

    fn expect_value_line(&mut self, expected: &str) -> Result<(), DumpError> {
        self.expect_line(expected)?;
        if self.text().starts_with(b"ITEM:") {
            return Err(self.header_err(expected));
        }
        Ok(())
    }

    /// A line cut off by the end of the file may be a cut-off number: refuse it.
    fn require_newline(&self, expected: &str) -> Result<(), DumpError> {
        if self.line.last() == Some(&b'\n') {
            Ok(())
        } else {
            Err(self.truncated(expected))
        }
    }

    /// Checks that the current line is `ITEM: <name>...`; returns the bytes after the name.
    fn expect_item(&self, name: &str) -> Result<&[u8], DumpError> {
        let text = self.text();
        let rest = text
            .strip_prefix(b"ITEM:")
            .map(|r| r.trim_ascii_start())
            .and_then(|r| r.strip_prefix(name.as_bytes()));
        match rest {
            Some(r) if r.first().is_none_or(|b| b.is_ascii_whitespace()) => Ok(r),
            _ => Err(self.header_err(&format!("`ITEM: {name}`"))),
        }
    }

    fn parse_int(&self, what: &str) -> Result<u64, DumpError> {
        let t = self.text().trim_ascii();
        std::str::from_utf8(t)
            .ok()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| self.header_err(&format!("{what} (a non-negative integer)")))
    }

    fn parse_f64(&self, field: &[u8], column: &str) -> Result<f64, DumpError> {
        parse_f64(field).ok_or_else(|| self.nan_err(field, column))
    }

    /// Flags after `BOX BOUNDS`: optional `xy xz yz`, then one flag per axis (`pp`, `ff`, `fs`..).
    fn parse_bounds_flags(&self, rest: &[u8]) -> Result<(bool, [bool; 3]), DumpError> {
        let mut words = Fields::new(rest).peekable();
        let triclinic = words.peek() == Some(&&b"xy"[..]);
        if triclinic {
            for tilt in [&b"xy"[..], b"xz", b"yz"] {
                if words.next() != Some(tilt) {
                    return Err(self.header_err("`BOX BOUNDS xy xz yz` followed by 3 boundary flags"));
                }
            }
        }
        let mut periodic = [false; 3];
        let mut n = 0;
        for w in words {
            let valid = w == b"pp" || (w.len() == 2 && w.iter().all(|b| matches!(b, b'f' | b's' | b'm')));
            if !valid || n == 3 {
                return Err(self.header_err("3 boundary flags such as `pp pp ff`"));
            }
            periodic[n] = w == b"pp";
            n += 1;
        }
        if n != 3 {
            return Err(self.header_err("3 boundary flags such as `pp pp ff`"));
        }
        Ok((triclinic, periodic))
    }

    fn parse_columns(&self, rest: &[u8], snap: &mut Snapshot) -> Result<(), DumpError> {
        let names = Fields::new(rest);
        // Reuse the previous snapshot's names when they are the same (the usual case).
        if names.clone().eq(snap.columns.iter().map(|c| c.as_bytes())) && !snap.columns.is_empty() {
            return Ok(());
        }
        snap.columns.clear();
        for name in names {
            let name =
                std::str::from_utf8(name).map_err(|_| self.header_err("column names in ASCII"))?.to_string();
            if snap.columns.contains(&name) {
                return Err(self.header_err(&format!("distinct column names (`{name}` twice)")));
            }
            snap.columns.push(name);
        }
        if snap.columns.is_empty() {
            return Err(self.header_err("at least one column name after `ITEM: ATOMS`"));
        }
        Ok(())
    }

    fn at(&self) -> Location {
        Location {
            file: self.file.clone(),
            snapshot: self.snapshot,
            timestep: self.timestep,
            line: self.line_no,
        }
    }

    /// Whether the current line's first field is a number (an atom row, not a header).
    fn starts_with_number(&self) -> bool {
        Fields::new(&self.line).next().is_some_and(|f| parse_f64(f).is_some())
    }

    fn truncated(&self, expected: &str) -> DumpError {
        DumpError::Truncated { at: self.at(), expected: expected.to_string() }
    }

    fn header_err(&self, expected: &str) -> DumpError {
        DumpError::Header {
            at: self.at(),
            expected: expected.to_string(),
            found: String::from_utf8_lossy(self.text()).chars().take(80).collect(),
        }
    }

    fn nan_err(&self, field: &[u8], column: &str) -> DumpError {
        DumpError::NotANumber {
            at: self.at(),
            column: column.to_string(),
            field: String::from_utf8_lossy(field).chars().take(40).collect(),
        }
    }
}

impl<R: BufRead> Iterator for DumpReader<R> {
    type Item = Result<Snapshot, DumpError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        let mut snap = Snapshot::default();
        match self.read_snapshot_into(&mut snap) {
            Ok(true) => Some(Ok(snap)),
            Ok(false) => None,
            Err(e) => Some(Err(e)),
        }
    }
}

/// Reads every snapshot of the dump at `path`; a snapshot without one of `required_columns` is
/// a [`DumpError::MissingColumn`].
pub fn read_dump(path: impl AsRef<Path>, required_columns: &[&str]) -> Result<Vec<Snapshot>, DumpError> {
    DumpReader::open(path)?.require(required_columns).collect()
}

/// Parses one field as a finite `f64`, correctly rounded.
///
/// fast-float2 parses bytes directly (no UTF-8 check) and measured faster than `str::parse`
/// (`cargo bench --bench dump_parse`, BENCHMARKS.md); it rejects trailing characters.
fn parse_f64(field: &[u8]) -> Option<f64> {
    let v: f64 = fast_float2::parse(field).ok()?;
    v.is_finite().then_some(v)
}

/// Parses the next whitespace-separated field of `rest` as a finite `f64` and advances past it:
/// `None` when only whitespace is left, `Err(field)` when the field is not a finite number.
///
/// One pass over the bytes: the float parser reports how far it read, so the field is not
/// scanned first to find its end.
fn next_number<'a>(rest: &mut &'a [u8]) -> Option<Result<f64, &'a [u8]>> {
    let s = rest.trim_ascii_start();
    if s.is_empty() {
        *rest = s;
        return None;
    }
    match fast_float2::parse_partial::<f64, _>(s) {
        Ok((v, n)) if v.is_finite() && s.get(n).is_none_or(u8::is_ascii_whitespace) => {
            *rest = &s[n..];
            Some(Ok(v))
        }
        _ => {
            let end = s.iter().position(u8::is_ascii_whitespace).unwrap_or(s.len());
            *rest = &s[end..];
            Some(Err(&s[..end]))
        }
    }
}

/// The whitespace-separated fields of a line, without allocating.
#[derive(Clone)]
struct Fields<'a> {
    rest: &'a [u8],
}

impl<'a> Fields<'a> {
    fn new(line: &'a [u8]) -> Self {
        Fields { rest: line }
    }
}

impl<'a> Iterator for Fields<'a> {
    type Item = &'a [u8];

    fn next(&mut self) -> Option<&'a [u8]> {
        let start = self.rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let rest = &self.rest[start..];
        let end = rest.iter().position(|b| b.is_ascii_whitespace()).unwrap_or(rest.len());
        self.rest = &rest[end..];
        Some(&rest[..end])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_split_on_any_ascii_whitespace() {
        let f: Vec<&[u8]> = Fields::new(b"  1\t2.5e-3  x \r\n").collect();
        assert_eq!(f, [&b"1"[..], b"2.5e-3", b"x"]);
        assert_eq!(Fields::new(b" \t\n").next(), None);
    }

    #[test]
    fn parse_f64_accepts_finite_numbers_only() {
        assert_eq!(parse_f64(b"4.41786e-06"), Some(4.41786e-06));
        assert_eq!(parse_f64(b"-0.1962"), Some(-0.1962));
        assert_eq!(parse_f64(b"112"), Some(112.0));
        for bad in [&b"nan"[..], b"-nan", b"inf", b"1e400", b"1,5", b"", b"\xff"] {
            assert_eq!(parse_f64(bad), None, "{}", String::from_utf8_lossy(bad));
        }
    }

    #[test]
    fn next_number_walks_a_row() {
        let mut rest = &b" 1\t-2.5e-3 0.0O2 7x 1e999 8 \r\n"[..];
        assert_eq!(next_number(&mut rest), Some(Ok(1.0)));
        assert_eq!(next_number(&mut rest), Some(Ok(-2.5e-3)));
        assert_eq!(next_number(&mut rest), Some(Err(&b"0.0O2"[..])));
        assert_eq!(next_number(&mut rest), Some(Err(&b"7x"[..])));
        assert_eq!(next_number(&mut rest), Some(Err(&b"1e999"[..])));
        assert_eq!(next_number(&mut rest), Some(Ok(8.0)));
        assert_eq!(next_number(&mut rest), None);
        assert_eq!(next_number(&mut &b"3.25"[..]), Some(Ok(3.25)));
    }

    #[test]
    fn location_names_file_line_snapshot_and_timestep() {
        let mut at =
            Location { file: "runs/a/dump.spread".into(), snapshot: 3, timestep: Some(42000), line: 17 };
        assert_eq!(at.to_string(), "runs/a/dump.spread:17 (snapshot 3, timestep 42000)");
        at.timestep = None;
        assert_eq!(at.to_string(), "runs/a/dump.spread:17 (snapshot 3)");
    }

    #[test]
    fn column_values_walk_one_column() {
        let s = Snapshot {
            columns: vec!["id".into(), "x".into()],
            data: vec![1.0, 0.1, 2.0, 0.2, 3.0, 0.3],
            natoms: 3,
            ..Snapshot::default()
        };
        let x = s.column("x").unwrap();
        assert_eq!(s.column_values(x).collect::<Vec<_>>(), [0.1, 0.2, 0.3]);
        assert_eq!(s.get(2, ColumnIdx(0)), 3.0);
        assert_eq!(s.row(1), [2.0, 0.2]);
        assert_eq!(s.column("vx"), None);
    }
}
