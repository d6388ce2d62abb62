//! Throughput of the dump parser against a naive line-by-line parser, measured in the same run.
//!
//! Writes a synthetic LIGGGHTS-style `custom` dump (columns `id type x y z vx vy vz radius mass`,
//! numbers printed like C's `%g` as LIGGGHTS does) to a temp dir, then parses it repeatedly with
//! [`demsweep::engine::dump::DumpReader`] and with the baseline: `BufRead::lines()`, then
//! `split_whitespace().map(str::parse::<f64>)` collected into a `Vec` per line. Reports the best
//! of several runs (the file is in the page cache after the first write, so this measures parsing,
//! not the disk).
//!
//! `cargo bench --bench dump_parse`; set `DUMP_BENCH_ATOMS` (default 1 000 000) and
//! `DUMP_BENCH_SNAPSHOTS` (default 2) to change the file size.

use demsweep::engine::dump::{DumpReader, Snapshot};
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::Path;
use std::time::Instant;

const COLUMNS: &str = "id type x y z vx vy vz radius mass";
const RUNS: usize = 3;

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// `v` formatted like C's `%g` (6 significant digits, trailing zeros dropped).
fn g(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let exp = v.abs().log10().floor() as i32;
    if (-5..6).contains(&exp) {
        let s = format!("{:.*}", (5 - exp) as usize, v);
        let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.') } else { &s };
        s.to_string()
    } else {
        let s = format!("{v:.5e}");
        let (m, e) = s.split_once('e').unwrap();
        let m = m.trim_end_matches('0').trim_end_matches('.');
        let e: i32 = e.parse().unwrap();
        format!("{m}e{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
    }
}

fn write_dump(path: &Path, natoms: usize, snapshots: usize) {
    let mut w = BufWriter::new(File::create(path).unwrap());
    // A fixed-seed LCG: the same file every run.
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut rnd = move || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for s in 0..snapshots {
        writeln!(w, "ITEM: TIMESTEP\n{}", s * 10_000).unwrap();
        writeln!(w, "ITEM: NUMBER OF ATOMS\n{natoms}").unwrap();
        writeln!(w, "ITEM: BOX BOUNDS pp pp ff\n0 0.1\n0 0.01\n0 0.02").unwrap();
        writeln!(w, "ITEM: ATOMS {COLUMNS} ").unwrap();
        for id in 1..=natoms {
            let r = 0.0005 * (1.0 + rnd());
            let m = 4.0 / 3.0 * std::f64::consts::PI * r * r * r * 2500.0;
            writeln!(
                w,
                "{id} {} {} {} {} {} {} {} {} {} ",
                1 + (id % 2),
                g(0.1 * rnd()),
                g(0.01 * rnd()),
                g(0.02 * rnd()),
                g(rnd() - 0.5),
                g(0.1 * (rnd() - 0.5)),
                g(-rnd()),
                g(r),
                g(m),
            )
            .unwrap();
        }
    }
    w.flush().unwrap();
}

/// The parser under test, reusing one snapshot; returns (atoms, sum of x) as a check.
fn parse_fast(path: &Path) -> (usize, f64) {
    let mut r = DumpReader::open(path).unwrap();
    let mut s = Snapshot::default();
    let (mut atoms, mut sum) = (0, 0.0);
    while r.read_snapshot_into(&mut s).unwrap() {
        atoms += s.len();
        sum += s.column_values(s.column("x").unwrap()).sum::<f64>();
    }
    (atoms, sum)
}

/// The naive baseline: a `String` per line, a `Vec<f64>` per atom row.
fn parse_naive(path: &Path) -> (usize, f64) {
    let mut lines = BufReader::new(File::open(path).unwrap()).lines();
    let (mut atoms, mut sum) = (0, 0.0);
    while let Some(l) = lines.next() {
        assert_eq!(l.unwrap(), "ITEM: TIMESTEP");
        let _timestep: u64 = lines.next().unwrap().unwrap().trim().parse().unwrap();
        lines.next();
        let n: usize = lines.next().unwrap().unwrap().trim().parse().unwrap();
        for _ in 0..4 {
            lines.next();
        }
        let header = lines.next().unwrap().unwrap();
        let x = header.split_whitespace().skip(2).position(|c| c == "x").unwrap();
        let mut rows: Vec<Vec<f64>> = Vec::with_capacity(n);
        for _ in 0..n {
            let l = lines.next().unwrap().unwrap();
            let row: Vec<f64> = l.split_whitespace().map(|f| f.parse::<f64>().unwrap()).collect();
            rows.push(row);
        }
        atoms += rows.len();
        sum += rows.iter().map(|r| r[x]).sum::<f64>();
    }
    (atoms, sum)
}

fn best_of(f: impl Fn() -> (usize, f64)) -> (f64, (usize, f64)) {
    let mut best = f64::INFINITY;
    let mut out = (0, 0.0);
    for _ in 0..RUNS {
        let t = Instant::now();
        out = std::hint::black_box(f());
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, out)
}

fn main() {
    let natoms = env_usize("DUMP_BENCH_ATOMS", 1_000_000);
    let snapshots = env_usize("DUMP_BENCH_SNAPSHOTS", 2);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bench.dump");
    write_dump(&path, natoms, snapshots);
    let mb = std::fs::metadata(&path).unwrap().len() as f64 / 1e6;
    let atoms = (natoms * snapshots) as f64;
    println!("dump: {snapshots} snapshots x {natoms} atoms, 10 columns, {mb:.1} MB; best of {RUNS}");

    let (t_fast, r_fast) = best_of(|| parse_fast(&path));
    let (t_naive, r_naive) = best_of(|| parse_naive(&path));
    assert_eq!(r_fast.0, r_naive.0, "atom counts differ");
    assert_eq!(r_fast.1, r_naive.1, "parsed values differ");

    for (name, t) in [("DumpReader", t_fast), ("naive baseline", t_naive)] {
        println!("{name:>15}: {t:7.3} s  {:7.1} MB/s  {:6.2} M atoms/s", mb / t, atoms / t / 1e6);
    }
    println!("speed-up DumpReader / naive: {:.2}x", t_naive / t_fast);

    // The float parser alone, on the fields of the first rows: why fast-float2 and not std.
    let text = std::fs::read(&path).unwrap();
    let fields: Vec<&[u8]> = text
        .split(|&b| b == b'\n')
        .skip(9)
        .take(natoms.min(500_000))
        .flat_map(|l| l.split(|&b| b == b' ').filter(|f| !f.is_empty()))
        .collect();
    let (t_std, s_std) = best_of(|| {
        let sum = fields.iter().map(|f| std::str::from_utf8(f).unwrap().parse::<f64>().unwrap()).sum();
        (fields.len(), sum)
    });
    let (t_ff, s_ff) = best_of(|| {
        let sum = fields.iter().map(|f| fast_float2::parse::<f64, _>(f).unwrap()).sum();
        (fields.len(), sum)
    });
    assert_eq!(s_std, s_ff, "float parsers disagree");
    let n = fields.len() as f64;
    println!(
        "float parsing only, {} fields: str::parse {:.1} ns/field, fast-float2 {:.1} ns/field, ratio {:.2}x",
        fields.len(),
        t_std / n * 1e9,
        t_ff / n * 1e9,
        t_std / t_ff
    );
}
