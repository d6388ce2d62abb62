//! The layers study's comparison with a measured experiment (docs/study/layers.md): that
//! `docs/study/layers/compare.py` reads Gaboriault et al. 2025's layer n (their
//! `experimental.data` row n − 1) against our pass n + 1. The script is fed the experiment's own
//! rows as if they were our passes; every layer group's mean must come back as the experiment's,
//! computed here from the file on its own. Needs `python3` (on the CI machine); skips without it.

use std::process::Command;

use serde_json::Value;

use crate::support;

/// Their layer groups, as the study states them.
const GROUPS: [(&str, usize, usize); 3] = [("1", 1, 1), ("2–10", 2, 10), ("11–20", 11, 20)];

/// Each repeat's mean over their layers a..=b, straight from experimental.data: the row whose
/// `Layer_number` is n − 1 holds layer n. Summed in the layers' order, as the script sums.
fn experiment_means() -> Vec<[f64; 3]> {
    let text = std::fs::read_to_string(support::repo("docs/study/layers/experimental.data")).unwrap();
    let mut rows: Vec<(usize, [f64; 3])> = Vec::new();
    for line in text.lines().filter(|l| l.starts_with(|c: char| c.is_ascii_digit())) {
        let v: Vec<&str> = line.split_whitespace().collect();
        let r = |i: usize| v[i].parse::<f64>().unwrap();
        rows.push((v[0].parse().unwrap(), [r(1), r(2), r(3)]));
    }
    assert_eq!(rows.len(), 20, "experimental.data holds 20 layers");
    let layer = |n: usize| rows.iter().find(|(row, _)| *row == n - 1).unwrap().1;
    GROUPS
        .iter()
        .map(|&(_, a, b)| {
            let mut m = [0.0; 3];
            for (i, mi) in m.iter_mut().enumerate() {
                let mut s = 0.0;
                for n in a..=b {
                    s += layer(n)[i];
                }
                *mi = s / (b - a + 1) as f64;
            }
            m
        })
        .collect()
}

/// `compare.py --self-test --feed-shift shift`: its exit code and JSON.
fn self_test(shift: i32) -> Option<(i32, Value)> {
    let script = support::repo("docs/study/layers/compare.py");
    let out = Command::new("python3")
        .arg(&script)
        .args(["--self-test", "--feed-shift", &shift.to_string()])
        .output()
        .ok()?;
    let json = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("compare.py printed no JSON ({e}): {}", support::text(&out.stderr)));
    Some((out.status.code().unwrap_or(-1), json))
}

#[test]
fn the_comparison_reads_their_layer_n_against_our_pass_n_plus_1() {
    let name = "the_comparison_reads_their_layer_n_against_our_pass_n_plus_1";
    let Some((code, json)) = self_test(1) else {
        return support::skip(name, "needs python3 on PATH to run docs/study/layers/compare.py");
    };
    assert_eq!(code, 0, "compare.py's own check failed: {json:#}");
    let expected = experiment_means();
    for (i, repeat) in json["repeats"].as_array().unwrap().iter().enumerate() {
        let groups = repeat["groups"].as_array().unwrap();
        assert_eq!(groups.len(), GROUPS.len());
        for (g, (name, a, b)) in groups.iter().zip(GROUPS) {
            assert_eq!(g["group"], name);
            // The fed passes reach every layer of the group, and give back the experiment's
            // mean exactly: both sum the same numbers in the same order.
            assert_eq!(g["fed_layers"], serde_json::json!([a, b]), "R{}: group {name}", i + 1);
            let fed = g["fed"].as_f64().unwrap();
            let want = expected[GROUPS.iter().position(|x| x.0 == name).unwrap()][i];
            assert_eq!(fed, want, "R{}, layers {name}: the script read {fed}, the file holds {want}", i + 1);
        }
    }
    // The three repeats' means of the groups, as the study quotes them.
    let means: Vec<f64> =
        json["experiment"].as_array().unwrap().iter().map(|e| e["mean"].as_f64().unwrap()).collect();
    for (m, want) in means.iter().zip([0.552, 0.597, 0.652]) {
        assert!((m - want).abs() < 5e-4, "group mean {m}, the study says {want}");
    }

    // The check has teeth: the same rows fed one pass early (row n − 1 as pass n, the reading the
    // study made before) give other means, and the script says so.
    let (code, json) = self_test(0).unwrap();
    assert_eq!(code, 1, "a misaligned feed must fail: {json:#}");
    let first = &json["repeats"][0]["groups"][0];
    assert_ne!(first["fed"].as_f64().unwrap(), expected[0][0]);
}
