//! Benchmarks behind `sweep bench`: run time against error of the fidelity presets
//! ([`fidelity`]), the scene's stability edge ([`stability`]), the contact reference
//! solver's own stability ([`contact`]), and the designs against a known answer ([`designs`]).
//!
//! The top of the pipeline beside the command line: a bench may use every stage below it.

pub mod contact;
pub mod designs;
pub mod fidelity;
pub mod stability;

/// An optional number with `digits` decimals, or `absent` when there is none: the one formatter
/// of the benches' fixed-point cells.
pub fn opt_or(v: Option<f64>, digits: usize, absent: &str) -> String {
    v.map_or_else(|| absent.to_string(), |v| format!("{v:.digits$}"))
}

/// An optional number with `digits` decimals, empty when absent (a CSV cell).
pub fn opt(v: Option<f64>, digits: usize) -> String {
    opt_or(v, digits, "")
}

/// `v` in scientific notation for a table cell, or "-".
pub fn cell(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.2e}"))
}

/// What a bench refuses or fails at: a flag, a file of its output, a plot, LIGGGHTS.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A flag's value: `--variant fine: expected NAME:key=value,...`.
    #[error("{given}: {why}")]
    Flag { given: String, why: String },
    /// The output directory could not be created.
    #[error("cannot create {}: {source}", path.display())]
    Create { path: std::path::PathBuf, source: std::io::Error },
    /// An output file could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Write { path: std::path::PathBuf, source: std::io::Error },
    /// The bench's figure could not be drawn.
    #[error("{bench} plot: {why}")]
    Plot { bench: &'static str, why: String },
    /// A thread running one case panicked.
    #[error("run thread panicked")]
    Panicked,
    /// LIGGGHTS ran none of the contact timestep ladder's cases.
    #[error("LIGGGHTS failed on every ladder case: {first}")]
    NoLadderCase { first: String },
}

/// A flag is bad input (exit 2), LIGGGHTS failing every case is the engine (3), the rest is
/// internal (4).
impl From<BenchError> for crate::Error {
    fn from(e: BenchError) -> Self {
        match e {
            BenchError::Flag { .. } => crate::Error::Input(Box::new(e)),
            BenchError::NoLadderCase { .. } => crate::Error::Engine(Box::new(e)),
            _ => crate::Error::Internal(Box::new(e)),
        }
    }
}

/// Write a bench's `tables` (file name, text) and its figure, drawn by `plot`, as
/// `{bench}.svg` and `{bench}.png`, into `out`, each file atomically: their paths, in that order.
/// Nothing is written when the figure cannot be drawn.
pub fn write_outputs(
    out: &std::path::Path,
    bench: &'static str,
    tables: Vec<(&str, String)>,
    plot: impl FnOnce() -> Result<String, Box<dyn std::error::Error>>,
) -> Result<Vec<std::path::PathBuf>, BenchError> {
    let plot_err = |e: Box<dyn std::error::Error>| BenchError::Plot { bench, why: e.to_string() };
    let svg = plot().map_err(plot_err)?;
    let png = crate::report::to_png(&svg).map_err(plot_err)?;
    let figures = [(format!("{bench}.svg"), svg.into_bytes()), (format!("{bench}.png"), png)];
    let files = tables.into_iter().map(|(name, text)| (name.to_string(), text.into_bytes())).chain(figures);
    let mut paths = Vec::new();
    for (name, bytes) in files {
        let p = out.join(name);
        crate::sys::atomic::write(&p, &bytes)
            .map_err(|source| BenchError::Write { path: p.clone(), source })?;
        paths.push(p);
    }
    Ok(paths)
}

/// The CSV text of a header and rows.
pub fn csv_text(head: Vec<String>, rows: impl IntoIterator<Item = Vec<String>>) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    // Writing into memory cannot fail.
    w.write_record(&head).expect("in memory");
    for row in rows {
        w.write_record(&row).expect("in memory");
    }
    String::from_utf8(w.into_inner().expect("in memory")).expect("UTF-8 fields")
}

#[cfg(test)]
mod tests {
    use super::csv_text;

    #[test]
    fn a_field_with_a_quote_or_a_comma_reads_back_and_an_ordinary_one_is_written_bare() {
        let head = vec!["point".to_string(), "reason".to_string()];
        let odd = "said \"no\", twice";
        let text = csv_text(head, [vec!["1".into(), odd.into()], vec!["2".into(), "plain text".into()]]);
        assert!(text.ends_with("\n2,plain text\n"), "{text}");
        let mut r = csv::Reader::from_reader(text.as_bytes());
        let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
        assert_eq!(&rows[0][1], odd);
        assert_eq!(&rows[1][1], "plain text");
    }
}
