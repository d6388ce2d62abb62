//! Columns of any CSV file by header name, for `sweep stats`: numbers, empty and non-numeric
//! cells counted.

use std::path::Path;

use crate::analysis::stats;

use super::ReportError;

/// Columns of a CSV file, by header name, for `sweep stats`.
#[derive(Debug, Clone)]
pub struct CsvColumns {
    /// The described column: its numbers, with empty and non-numeric cells counted.
    pub column: stats::Column,
    /// Rows where the column and every `by` column are numbers: (by values, column value).
    pub xy: Vec<(Vec<f64>, f64)>,
}

/// Read `column` (and the `by` columns) of a CSV file by header name: empty cells and
/// non-numbers are skipped and counted. A missing file or column, or a column with no numbers,
/// is bad input, named in one line.
pub fn read_columns(path: &Path, column: &str, by: &[String]) -> Result<CsvColumns, ReportError> {
    let bad = |why: String| ReportError::Csv { path: path.to_path_buf(), why };
    let bytes = std::fs::read(path).map_err(|e| ReportError::Read {
        path: path.to_path_buf(),
        why: if e.kind() == std::io::ErrorKind::NotFound {
            "no such file".to_string()
        } else {
            e.to_string()
        },
    })?;
    let mut r = csv::ReaderBuilder::new().flexible(true).from_reader(bytes.as_slice());
    let header = r.headers().map_err(|e| bad(format!("not a CSV file: {e}")))?.clone();
    if header.is_empty() || header.iter().all(|h| h.trim().is_empty()) {
        return Err(bad(format!("empty file; expected a header row with a column `{column}`")));
    }
    let find = |name: &str| {
        header.iter().position(|h| h.trim() == name).ok_or_else(|| {
            bad(format!(
                "no column `{name}`{}; columns: {}",
                crate::error::hint(name, header.iter()),
                header.iter().collect::<Vec<_>>().join(", ")
            ))
        })
    };
    let i = find(column)?;
    let js: Vec<usize> = by.iter().map(|b| find(b)).collect::<Result<_, _>>()?;
    let mut cells = Vec::new();
    let mut xy = Vec::new();
    let num = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    for (line, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| bad(format!("row {}: {e}", line + 2)))?;
        let cell = rec.get(i).unwrap_or("");
        if let Some(y) = num(cell) {
            let x: Option<Vec<f64>> = js.iter().map(|&j| num(rec.get(j).unwrap_or(""))).collect();
            if let Some(x) = x {
                xy.push((x, y));
            }
        }
        cells.push(cell.to_string());
    }
    let c = stats::parse_cells(cells.iter().map(String::as_str));
    if c.values.is_empty() {
        return Err(bad(format!(
            "column `{column}` has no numbers ({} empty, {} not numbers)",
            c.empty, c.non_numeric
        )));
    }
    Ok(CsvColumns { column: c, xy })
}
