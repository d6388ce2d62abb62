//! Helpers shared by the integration tests that read a sweep directory.

use std::path::Path;

/// results.csv as (hash, status, failure, mfr) per point index.
pub fn results(dir: &Path) -> Vec<(String, String, String, String)> {
    let mut r = csv::Reader::from_path(dir.join("results.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let cols = [col("hash"), col("status"), col("failure"), col("mfr")];
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            let f = |i: usize| rec[cols[i]].to_string();
            (f(0), f(1), f(2), f(3))
        })
        .collect()
}
