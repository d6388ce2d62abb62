//! The dump parser on a dump LIGGGHTS 3.8 wrote (`tests/data/falling.dump`, made by
//! `tests/data/in.falling`: 112 spheres, d = 1.5 mm, ρ = 2500 kg/m³, falling under gravity onto a
//! plate, dumped every 2000 steps of 1e-5 s), on column orders LIGGGHTS did not write, and on
//! malformed dumps.

use demsweep::engine::dump::{read_dump, DumpError, DumpReader, Snapshot};
use proptest::prelude::*;
use std::io::Read;
use std::path::Path;

const DUMP: &str = "tests/data/falling.dump";
/// Lines per snapshot of the LIGGGHTS dump: 9 header lines + 112 atom rows.
const SNAP_LINES: usize = 121;

fn text() -> String {
    std::fs::read_to_string(DUMP).unwrap()
}

fn parse(s: &str) -> Result<Vec<Snapshot>, DumpError> {
    DumpReader::new(s.as_bytes(), "mem.dump").collect()
}

fn parse_err(s: &str) -> DumpError {
    parse(s).expect_err("malformed dump parsed")
}

/// `s` with 1-based line `n` replaced by `new`.
fn with_line(s: &str, n: usize, new: &str) -> String {
    let mut lines: Vec<&str> = s.lines().collect();
    lines[n - 1] = new;
    lines.join("\n") + "\n"
}

fn line(s: &str, n: usize) -> &str {
    s.lines().nth(n - 1).unwrap()
}

#[test]
fn liggghts_dump_headers() {
    let snaps = read_dump(DUMP, &["id", "type", "x", "y", "z", "vx", "vy", "vz", "radius", "mass"]).unwrap();
    let steps: Vec<u64> = snaps.iter().map(|s| s.timestep).collect();
    assert_eq!(steps, [0, 2000, 4000, 6000, 8000, 10000]);
    for s in &snaps {
        assert_eq!(s.len(), 112);
        // boundary p p f, region domain block 0 0.01 0 0.01 0 0.02 in the deck.
        assert_eq!(s.periodic, [true, true, false]);
        assert_eq!(s.box_bounds, [[0.0, 0.01], [0.0, 0.01], [0.0, 0.02]]);
        assert_eq!(s.tilt, None);
        let mut ids: Vec<f64> = s.column_values(s.column("id").unwrap()).collect();
        ids.sort_by(f64::total_cmp);
        assert_eq!(ids, (1..=112).map(f64::from).collect::<Vec<_>>());
        assert!(s.column_values(s.column("type").unwrap()).all(|t| t == 1.0 || t == 2.0));
    }
}

/// mass = 4/3 π r³ ρ with r = 0.75 mm, ρ = 2500 kg/m³ (`set ... diameter 0.0015 density 2500`).
#[test]
fn liggghts_dump_mass_matches_radius_and_density() {
    let s = &read_dump(DUMP, &["radius", "mass"]).unwrap()[0];
    let (r, m) = (s.column("radius").unwrap(), s.column("mass").unwrap());
    for i in 0..s.len() {
        assert_eq!(s.get(i, r), 0.00075);
        let expected = 4.0 / 3.0 * std::f64::consts::PI * 0.00075f64.powi(3) * 2500.0;
        // The dump prints 6 significant digits.
        assert!((s.get(i, m) - expected).abs() / expected < 1e-5, "{}", s.get(i, m));
    }
}

/// At t = 0.02 s no sphere has touched the plate or another (lowest centre 4 mm up, fall
/// g t²/2 = 1.962 mm, lattice spacing 2 mm > d), so every atom is in free fall from rest:
/// z = z0 − g t²/2, vz = −g t, x, y unchanged.
#[test]
fn liggghts_dump_free_fall_closed_form() {
    let snaps = read_dump(DUMP, &["id", "x", "y", "z", "vz"]).unwrap();
    let (s0, s1) = (&snaps[0], &snaps[1]);
    let t = s1.timestep as f64 * 1e-5;
    let g = 9.81;
    let col = |s: &Snapshot, n: &str| s.column(n).unwrap();
    for i in 0..s1.len() {
        let id = s1.get(i, col(s1, "id"));
        let j = (0..s0.len()).find(|&j| s0.get(j, col(s0, "id")) == id).unwrap();
        let z = s0.get(j, col(s0, "z")) - 0.5 * g * t * t;
        assert!((s1.get(i, col(s1, "z")) - z).abs() < 1e-8, "atom {id}");
        assert!((s1.get(i, col(s1, "vz")) + g * t).abs() < 1e-8, "atom {id}");
        assert_eq!(s1.get(i, col(s1, "x")), s0.get(j, col(s0, "x")));
        assert_eq!(s1.get(i, col(s1, "y")), s0.get(j, col(s0, "y")));
    }
}

/// Rewrites the ATOMS header and every atom row with the columns in `order` (indices into the
/// original columns).
fn permute_columns(s: &str, order: &[usize]) -> String {
    let mut out = String::new();
    let mut in_atoms = false;
    for l in s.lines() {
        if let Some(cols) = l.strip_prefix("ITEM: ATOMS ") {
            let cols: Vec<&str> = cols.split_whitespace().collect();
            let p: Vec<&str> = order.iter().map(|&i| cols[i]).collect();
            out += &format!("ITEM: ATOMS {}\n", p.join(" "));
            in_atoms = true;
        } else if l.starts_with("ITEM:") {
            in_atoms = false;
            out += l;
            out += "\n";
        } else if in_atoms {
            let f: Vec<&str> = l.split_whitespace().collect();
            let p: Vec<&str> = order.iter().map(|&i| f[i]).collect();
            out += &p.join("\t");
            out += "\n";
        } else {
            out += l;
            out += "\n";
        }
    }
    out
}

#[test]
fn columns_found_by_name_in_any_order() {
    let original = parse(&text()).unwrap();
    for order in [
        vec![9, 8, 7, 6, 5, 4, 3, 2, 1, 0],
        vec![4, 2, 0, 9, 1, 3, 5, 8, 7, 6],
        vec![2, 3, 4, 0, 1, 5, 6, 7, 8, 9],
    ] {
        let permuted = parse(&permute_columns(&text(), &order)).unwrap();
        assert_eq!(permuted.len(), original.len());
        for (p, o) in permuted.iter().zip(&original) {
            assert_eq!(p.timestep, o.timestep);
            assert_ne!(p.columns(), o.columns());
            for name in o.columns() {
                let a: Vec<f64> = p.column_values(p.column(name).unwrap()).collect();
                let b: Vec<f64> = o.column_values(o.column(name).unwrap()).collect();
                assert_eq!(a, b, "column {name}");
            }
        }
    }
}

#[test]
fn subset_of_columns_and_a_missing_one() {
    // A deck that dumps only what the metrics read (id x z vx mass).
    let s = permute_columns(&text(), &[0, 2, 4, 5, 9]);
    let snaps = parse(&s).unwrap();
    assert_eq!(snaps[0].columns(), ["id", "x", "z", "vx", "mass"]);
    let path = std::env::temp_dir().join(format!("demsweep-dump-{}.dump", std::process::id()));
    std::fs::write(&path, &s).unwrap();
    let e = read_dump(&path, &["id", "radius"]).unwrap_err();
    std::fs::remove_file(&path).unwrap();
    match &e {
        DumpError::MissingColumn { at, column, .. } => {
            assert_eq!(column, "radius");
            assert_eq!((at.snapshot, at.timestep, at.line), (0, Some(0), 9));
            assert_eq!(at.file, path);
        }
        e => panic!("{e}"),
    }
    let msg = e.to_string();
    assert!(msg.contains("radius") && msg.contains(path.to_str().unwrap()), "{msg}");
}

#[test]
fn read_snapshot_into_reuses_a_snapshot() {
    let all = parse(&text()).unwrap();
    let t = text();
    let mut r = DumpReader::new(t.as_bytes(), "mem.dump");
    let mut s = Snapshot::default();
    let mut n = 0;
    while r.read_snapshot_into(&mut s).unwrap() {
        assert_eq!(s, all[n]);
        n += 1;
    }
    assert_eq!(n, 6);
}

#[test]
fn open_missing_file() {
    let e = read_dump("tests/data/no-such.dump", &[]).unwrap_err();
    assert!(matches!(e, DumpError::Open { .. }), "{e}");
    assert!(e.to_string().contains("no-such.dump"));
}

#[test]
fn triclinic_box() {
    let s = "ITEM: TIMESTEP\n5\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS xy xz yz pp ff fm\n\
             -1 1 0.1\n-2 2 0.2\n0 3 -0.3\nITEM: ATOMS x id\n0.5 7\n";
    let snaps = parse(s).unwrap();
    let s = &snaps[0];
    assert_eq!(s.timestep, 5);
    assert_eq!(s.box_bounds, [[-1.0, 1.0], [-2.0, 2.0], [0.0, 3.0]]);
    assert_eq!(s.tilt, Some([0.1, 0.2, -0.3]));
    assert_eq!(s.periodic, [true, false, false]);
    assert_eq!(s.row(0), [0.5, 7.0]);
}

// ---- malformed dumps: each asserts the error kind, the line, the snapshot and timestep ----

fn assert_at(e: &DumpError, line: u64, snapshot: usize, timestep: Option<u64>) {
    let at = e.location().unwrap_or_else(|| panic!("no location: {e}"));
    assert_eq!((at.line, at.snapshot, at.timestep), (line, snapshot, timestep), "{e}");
    assert!(e.to_string().contains(&format!("mem.dump:{line}")), "{e}");
}

#[test]
fn truncated_between_atom_rows() {
    let t = text();
    // Snapshot 1 (timestep 2000) keeps its header and 50 rows.
    let cut: String = t.lines().take(SNAP_LINES + 9 + 50).map(|l| format!("{l}\n")).collect();
    let e = parse_err(&cut);
    assert!(matches!(e, DumpError::Truncated { .. }), "{e}");
    assert_at(&e, (SNAP_LINES + 59) as u64, 1, Some(2000));
}

#[test]
fn truncated_inside_a_number() {
    let t = text();
    // Cut the last row just after its z field's first digits: the number itself still parses.
    let last_row = t.lines().count();
    let start = t.len() - line(&t, last_row).len() - 1;
    let cut = &t[..start + "112 1 0.008 0.008 0.00".len()];
    let e = parse_err(cut);
    assert!(matches!(e, DumpError::Truncated { .. }), "{e}");
    assert_at(&e, last_row as u64, 5, Some(10000));
}

#[test]
fn truncated_in_header() {
    let t = text();
    let cut: String = t.lines().take(SNAP_LINES + 3).map(|l| format!("{l}\n")).collect();
    let e = parse_err(&cut);
    assert!(matches!(e, DumpError::Truncated { .. }), "{e}");
    assert_at(&e, (SNAP_LINES + 3) as u64, 1, Some(2000));
}

#[test]
fn non_numeric_field() {
    let t = text();
    for bad in ["abc", "0.0O2", "nan", "-inf", "1e999"] {
        let s = with_line(&t, 12, &format!("3 1 0.006 0.002 {bad} 0 0 0 0.00075 4.41786e-06"));
        let e = parse_err(&s);
        match &e {
            DumpError::NotANumber { column, field, .. } => {
                assert_eq!((column.as_str(), field.as_str()), ("z", bad));
            }
            e => panic!("{e}"),
        }
        assert_at(&e, 12, 0, Some(0));
    }
}

#[test]
fn wrong_field_count() {
    let t = text();
    for (row, found) in [
        ("3 1 0.006 0.002 0.004 0 0 0 0.00075", 9),
        ("3 1 0.006 0.002 0.004 0 0 0 0.00075 4.41786e-06 7", 11),
    ] {
        let s = with_line(&t, SNAP_LINES + 15, row);
        let e = parse_err(&s);
        assert!(matches!(e, DumpError::FieldCount { expected: 10, found: f, .. } if f == found), "{e}");
        assert_at(&e, (SNAP_LINES + 15) as u64, 1, Some(2000));
    }
}

#[test]
fn fewer_rows_than_declared() {
    let s = with_line(&text(), 4, "113");
    let e = parse_err(&s);
    assert!(matches!(e, DumpError::AtomCount { declared: 113, found: 112, .. }), "{e}");
    // The next snapshot's `ITEM: TIMESTEP` stands where row 113 should be.
    assert_at(&e, (SNAP_LINES + 1) as u64, 0, Some(0));
}

#[test]
fn more_rows_than_declared() {
    let s = with_line(&text(), SNAP_LINES + 4, "110");
    let e = parse_err(&s);
    assert!(matches!(e, DumpError::AtomCount { declared: 110, found: 112, .. }), "{e}");
    // Row 111 of snapshot 1 (line 9 + 111 of that snapshot).
    assert_at(&e, (SNAP_LINES + 9 + 111) as u64, 1, Some(2000));
    // Also in the last snapshot, where the file ends instead of a next header.
    let s = with_line(&text(), 5 * SNAP_LINES + 4, "111");
    let e = parse_err(&s);
    assert!(matches!(e, DumpError::AtomCount { declared: 111, found: 112, .. }), "{e}");
    assert_at(&e, (6 * SNAP_LINES) as u64, 5, Some(10000));
}

#[test]
fn bad_headers() {
    let t = text();
    for (n, new, ts) in [
        (1, "ITEM: TIMESTAMP", None),
        (2, "12.5", None),
        (2, "-3", None),
        (3, "ITEM: NUMBER OF ATOM", Some(0)),
        (4, "many", Some(0)),
        (5, "ITEM: BOX BOUNDS pp pp", Some(0)),
        (5, "ITEM: BOX BOUNDS pp pp fp", Some(0)),
        (5, "ITEM: BOX BOUNDS xy xz pp pp ff", Some(0)),
        (6, "0 0.01 0.5", Some(0)),
        (7, "ITEM: ATOMS", Some(0)),
        (9, "ITEM: ATOMS", Some(0)),
        (9, "ITEM: ATOMS id type x x vx vy vz radius mass", Some(0)),
    ] {
        let e = parse_err(&with_line(&t, n, new));
        assert!(matches!(e, DumpError::Header { .. }), "{new}: {e}");
        assert_at(&e, n as u64, 0, ts);
    }
    // Garbage where the second snapshot should start.
    let e = parse_err(&with_line(&t, SNAP_LINES + 1, "ITEM: TIMESTEPS"));
    assert!(matches!(e, DumpError::Header { .. }), "{e}");
    assert_at(&e, (SNAP_LINES + 1) as u64, 1, None);
}

#[test]
fn blank_lines_and_crlf_are_accepted() {
    let t = text();
    let crlf = t.replace('\n', "\r\n") + "\n\n";
    assert_eq!(parse(&crlf).unwrap(), parse(&t).unwrap());
    assert!(parse("").unwrap().is_empty());
}

/// Offsets where a snapshot starts: cutting the file there leaves a valid, shorter dump.
fn snapshot_starts(t: &str) -> Vec<usize> {
    let mut v: Vec<usize> = t.match_indices("ITEM: TIMESTEP").map(|(i, _)| i).collect();
    v.push(t.len());
    v
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
        let _ = DumpReader::new(&bytes[..], "mem.dump").collect::<Result<Vec<_>, _>>();
    }

    #[test]
    fn random_bytes_after_a_header_never_panic(
        natoms in 1u64..u64::MAX,
        tail in proptest::collection::vec(any::<u8>(), 0..500),
    ) {
        let mut s = format!(
            "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n{natoms}\nITEM: BOX BOUNDS pp pp ff\n\
             0 1\n0 1\n0 1\nITEM: ATOMS id x\n"
        ).into_bytes();
        s.extend(tail);
        prop_assert!(DumpReader::new(&s[..], "mem.dump").collect::<Result<Vec<_>, _>>().is_err());
    }

    /// A cut anywhere but at a snapshot boundary is an error; at a boundary it is the snapshots
    /// before the cut.
    #[test]
    fn truncation_is_an_error(frac in 0.0f64..1.0) {
        let t = text();
        let cut = ((t.len() as f64) * frac) as usize;
        let starts = snapshot_starts(&t);
        let r = parse(&t[..cut]);
        match starts.iter().position(|&s| s == cut) {
            Some(n) => prop_assert_eq!(r.unwrap().len(), n),
            None => prop_assert!(r.is_err()),
        }
    }

    #[test]
    fn mutations_never_panic(
        edits in proptest::collection::vec((0.0f64..1.0, any::<u8>()), 1..8),
        cut in 0.0f64..1.0,
    ) {
        let mut b = text().into_bytes();
        for (pos, byte) in edits {
            let i = ((b.len() as f64) * pos) as usize;
            b[i] = byte;
        }
        let cut = ((b.len() as f64) * (0.5 + cut / 2.0)) as usize;
        let _ = DumpReader::new(&b[..cut], Path::new("mem.dump")).collect::<Result<Vec<_>, _>>();
    }
}

#[test]
fn a_line_of_any_length_is_refused_at_the_cap_not_held_in_memory() {
    // A header, then an atom row that never ends: an endless stream, so that reading it whole
    // would never return.
    let t = text();
    let head: String = t.lines().take(10).map(|l| format!("{l}\n")).collect();
    let endless = std::io::Cursor::new(head.into_bytes()).chain(std::io::repeat(b'7'));
    let mut reader = DumpReader::new(std::io::BufReader::new(endless), "mem.dump");
    let e = reader.next().expect("a result").expect_err("an endless line parsed");
    assert!(matches!(e, DumpError::LineTooLong { limit: demsweep::engine::dump::MAX_LINE, .. }), "{e}");
    assert_at(&e, 11, 0, Some(0));
    assert!(e.to_string().contains("line too long"), "{e}");
    // A long line that ends is still read (and fails on its content, not its length).
    let long = with_line(&t, 10, &"1 ".repeat(1000));
    assert!(matches!(parse_err(&long), DumpError::FieldCount { .. }));
}
