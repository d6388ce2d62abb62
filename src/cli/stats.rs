//! `sweep stats`: the statistics of a CSV column.

use std::path::PathBuf;

use super::error::CliError;
use clap::Args;
use demsweep::analysis::stats::Bootstrap;
use demsweep::error::Error;

#[derive(Args)]
pub(super) struct StatsArgs {
    /// A CSV file with a header row (e.g. DIR/results.csv).
    file: PathBuf,
    /// The column to describe, by header name (e.g. mfr).
    #[arg(long)]
    column: String,
    /// Also the first-order sensitivity indices of the column to these columns (adjusted
    /// correlation ratio, as in `sweep report`), on the rows where all are numbers.
    #[arg(long, value_delimiter = ',', value_name = "COLUMNS")]
    by: Vec<String>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

pub(super) fn stats(a: StatsArgs) -> Result<(), Error> {
    let table = demsweep::report::read_columns(&a.file, &a.column, &a.by)?;
    let column = &table.column;
    let m = demsweep::analysis::stats::moments(&column.values);
    let sensitivity = if a.by.is_empty() {
        Vec::new()
    } else {
        let (x, y): (Vec<Vec<f64>>, Vec<f64>) = table.xy.iter().cloned().unzip();
        demsweep::analysis::sensitivity::ranked(demsweep::analysis::sensitivity::with_intervals(
            &a.by,
            &x,
            &y,
            &Bootstrap::default(),
        ))
    };
    let iv = demsweep::analysis::stats::bootstrap(&column.values, &Bootstrap::default());
    if a.json {
        let intervals: serde_json::Map<String, serde_json::Value> = demsweep::analysis::stats::STATISTICS
            .iter()
            .zip(iv)
            .map(|(s, i)| (s.name().to_string(), serde_json::json!(i)))
            .collect();
        let out = serde_json::json!({
            "file": a.file.display().to_string(),
            "column": a.column,
            "n": m.n,
            "skipped_empty": column.empty,
            "skipped_non_numeric": column.non_numeric,
            "mean": m.mean,
            "std": m.std,
            "skewness": m.skewness,
            "kurtosis": m.kurtosis,
            "moment_skewness": m.moment_skewness,
            "median": m.median,
            "intervals": intervals,
            "sensitivity": sensitivity,
        });
        println!("{}", serde_json::to_string_pretty(&out).map_err(CliError::Json)?);
    } else {
        let f = |v: Option<f64>| v.map_or("undefined".to_string(), |v| format!("{v:.6}"));
        println!(
            "{} column {}: n = {} ({} empty, {} not numbers skipped)",
            a.file.display(),
            a.column,
            m.n,
            column.empty,
            column.non_numeric
        );
        for (s, i) in demsweep::analysis::stats::STATISTICS.iter().zip(iv) {
            println!("  {:<16} {:>12}   95% interval [{}, {}]", s.name(), f(s.of(&m)), f(i.lo), f(i.hi));
        }
        println!("  {:<16} {:>12}", "moment_skewness", f(m.moment_skewness));
        println!("  {:<16} {:>12}", "median", f(m.median));
        if !sensitivity.is_empty() {
            println!("first-order sensitivity of {} ({} rows):", a.column, table.xy.len());
            for s in &sensitivity {
                println!("  {:<16} {:>12}", s.parameter, f(s.first_order));
            }
        }
    }
    Ok(())
}
