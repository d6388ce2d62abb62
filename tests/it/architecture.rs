//! The layering of `src/` as docs/architecture.md states it: every import points down its table,
//! and no two files import each other in a loop. The table is read from the document, so the
//! document cannot go stale without this test failing.
//!
//! An import is any `crate::NAME` (or `demsweep::NAME` in the binary) outside comments, in
//! production code and in test modules alike: a test that builds its case from a stage above
//! belongs at that stage (or in `tests/it/`), not below it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The table's rows: the folder or file (without `src/`) and its rank, the bottom row 0.
fn table() -> BTreeMap<String, usize> {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/architecture.md"))
        .expect("docs/architecture.md");
    let mut rows = BTreeMap::new();
    for line in doc.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | # | folder | what it is | imports |
        let (Some(rank), Some(folder)) = (cells.get(1), cells.get(2)) else { continue };
        let Ok(rank) = rank.parse::<usize>() else { continue };
        for name in folder.split(',') {
            let name = name.trim().trim_matches('`').trim_start_matches("src/").trim_end_matches('/');
            let name = name.trim_end_matches(".rs");
            rows.insert(name.to_string(), rank);
        }
    }
    assert!(rows.len() > 10, "docs/architecture.md: no layer table found");
    rows
}

/// Every `.rs` file under `dir`.
pub(crate) fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The product code of a file: comments and `#[cfg(test)]` modules left out.
fn production_lines(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        out.push(line.split("//").next().unwrap_or(""));
    }
    out
}

/// Every line of code of a file, comments left out, each with the module it is in: the file's
/// own, or after a `#[cfg(test)]` on an inline `mod NAME {`, that test module (so that its
/// `super::` is the file). Test modules close the file, as they do throughout `src/`.
fn code_lines<'a>(text: &'a str, module: &[String]) -> Vec<(&'a str, Vec<String>)> {
    let mut out = Vec::new();
    let mut current = module.to_vec();
    let mut after_cfg_test = false;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("//") {
            continue;
        }
        if after_cfg_test && !t.starts_with("#[") {
            let decl = t.strip_prefix("pub ").unwrap_or(t);
            if let Some(name) = decl.strip_prefix("mod ").and_then(|r| r.strip_suffix('{')) {
                current = module.to_vec();
                current.push(name.trim().to_string());
            }
            after_cfg_test = false;
        }
        if t.starts_with("#[cfg(test)]") {
            after_cfg_test = true;
        }
        out.push((line.split("//").next().unwrap_or(""), current.clone()));
    }
    out
}

/// The module path of a file under `src/`: `run/pool.rs` → ["run", "pool"].
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> =
        rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// The paths a file names: `crate::a::b` (and `demsweep::a::b`), as segments.
fn imports(lines: &[(&str, Vec<String>)], in_binary: bool) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let roots: &[&str] =
        if in_binary { &["demsweep::", "crate::", "super::"] } else { &["crate::", "super::"] };
    for (line, module) in lines {
        for root in roots {
            for (i, _) in line.match_indices(root) {
                let before = line[..i].chars().last();
                if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                    continue;
                }
                let rest = &line[i + root.len()..];
                // `crate::{a, b::c}`: each item its own path.
                let items: Vec<&str> = if let Some(group) = rest.strip_prefix('{') {
                    group.split('}').next().unwrap_or("").split(',').collect()
                } else {
                    vec![rest]
                };
                for item in items {
                    let item = item.trim();
                    let end = item
                        .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                        .unwrap_or(item.len());
                    let segments: Vec<String> =
                        item[..end].split("::").take_while(|s| !s.is_empty()).map(String::from).collect();
                    if segments.is_empty() {
                        continue;
                    }
                    if *root == "super::" {
                        // `super::x` in a/b.rs (module [a, b]) or in a/b/mod.rs (module [a, b]) is a::x.
                        let mut full = module[..module.len().saturating_sub(1)].to_vec();
                        full.extend(segments);
                        out.push(full);
                    } else {
                        out.push(segments);
                    }
                }
            }
        }
    }
    out
}

struct Graph {
    /// Top-level module of each file, the file's module path, and what it imports.
    files: Vec<(String, Vec<String>, Vec<Vec<String>>)>,
}

fn graph() -> Graph {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut paths = Vec::new();
    rust_files(&src, &mut paths);
    paths.sort();
    let mut files = Vec::new();
    for path in paths {
        let module = module_of(&src, &path);
        if module == ["lib"] {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let binary = module[0] == "main" || module[0] == "cli";
        let top = module[0].clone();
        let found = imports(&code_lines(&text, &module), binary);
        files.push((top, module, found));
    }
    Graph { files }
}

#[test]
fn every_import_points_down_the_table_in_docs_architecture_md() {
    let rank = table();
    let mut upward = Vec::new();
    for (top, module, imports) in &graph().files {
        let Some(&mine) = rank.get(top) else {
            upward.push(format!("src/{}: not in the table of docs/architecture.md", module.join("/")));
            continue;
        };
        for path in imports {
            let target = &path[0];
            if target == top || !rank.contains_key(target) {
                continue;
            }
            if rank[target] >= mine {
                upward.push(format!(
                    "src/{} imports {} (row {} is not below row {mine})",
                    module.join("/"),
                    path.join("::"),
                    rank[target]
                ));
            }
        }
    }
    upward.sort();
    upward.dedup();
    assert!(
        upward.is_empty(),
        "imports that do not point down docs/architecture.md's table:\n{}",
        upward.join("\n")
    );
}

#[test]
fn no_two_files_import_each_other_in_a_loop() {
    let g = graph();
    let modules: BTreeSet<Vec<String>> = g.files.iter().map(|(_, m, _)| m.clone()).collect();
    // The file an import lands in: its longest prefix that is a file's module.
    let owner = |path: &[String]| -> Option<Vec<String>> {
        (1..=path.len()).rev().map(|n| path[..n].to_vec()).find(|p| modules.contains(p))
    };
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (_, module, imports) in &g.files {
        for path in imports {
            if let Some(to) = owner(path) {
                // A file importing its own folder's mod.rs (a parent) is not a loop.
                if &to != module && !module.starts_with(&to) {
                    edges.entry(module.clone()).or_default().insert(to);
                }
            }
        }
    }
    // Depth-first search for a back edge.
    fn visit(
        n: &Vec<String>,
        edges: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        state: &mut BTreeMap<Vec<String>, u8>,
        stack: &mut Vec<Vec<String>>,
    ) -> Option<Vec<Vec<String>>> {
        state.insert(n.clone(), 1);
        stack.push(n.clone());
        for m in edges.get(n).into_iter().flatten() {
            match state.get(m) {
                Some(1) => {
                    let start = stack.iter().position(|s| s == m).unwrap();
                    let mut cycle = stack[start..].to_vec();
                    cycle.push(m.clone());
                    return Some(cycle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(m, edges, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(n.clone(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in edges.keys() {
        if !state.contains_key(n) {
            if let Some(cycle) = visit(n, &edges, &mut state, &mut Vec::new()) {
                let names: Vec<String> = cycle.iter().map(|m| m.join("/")).collect();
                panic!("an import loop: {}", names.join(" → "));
            }
        }
    }
}

/// What of `line` names a layout: a layout's name compared as a string, or a path into a
/// layout's own folder (`scenes::pour::…`).
fn names_a_layout(line: &str, names: &[&str], folders: &[String]) -> Option<String> {
    for name in names {
        let lit = format!("\"{name}\"");
        for (i, _) in line.match_indices(&lit) {
            let before = line[..i].trim_end();
            let after = line[i + lit.len()..].trim_start();
            let compared = ["==", "!=", "|", "matches!("].iter().any(|op| before.ends_with(op))
                || ["==", "!=", "=>", "|"].iter().any(|op| after.starts_with(op));
            if compared {
                return Some(format!("compares the layout name {lit}"));
            }
        }
    }
    folders
        .iter()
        .find(|f| line.contains(&format!("scenes::{f}")))
        .map(|f| format!("reaches into scenes/{f}/"))
}

#[test]
fn the_layout_name_test_sees_a_comparison_and_a_reach_into_a_folder() {
    let (names, folders) = (["pour", "gated", "layers"], ["conveyor".to_string(), "layers".to_string()]);
    for line in [
        "if sweep.file.scene.layout == \"pour\" {",
        "measured_by: |l| l != \"gated\",",
        "\"pour\" => heap(),",
        "use crate::scenes::conveyor::warm::STATE_DUMP;",
        "matches!(layout, \"layers\" | \"pour\")",
        "let dump = crate::scenes::layers::measure::layer_dump(k);",
    ] {
        assert!(names_a_layout(line, &names, &folders).is_some(), "{line}");
    }
    for line in ["layout: \"pour\".into(),", "find(\"thesis\")", "crate::scenes::of(&settings)"] {
        assert_eq!(names_a_layout(line, &names, &folders), None, "{line}");
    }
}

#[test]
fn no_production_line_outside_the_scene_folders_names_a_layout() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let names = demsweep::scenes::names();
    let folders = crate::adding_a_layout::layout_folders(Path::new(env!("CARGO_MANIFEST_DIR")));
    assert!(folders.len() >= 3 && names.len() >= 4, "layouts {names:?}, folders {folders:?}");
    let mut paths = Vec::new();
    rust_files(&src, &mut paths);
    paths.sort();
    let mut found = Vec::new();
    for path in paths {
        let rel = path.strip_prefix(&src).unwrap().to_string_lossy().replace('\\', "/");
        if rel.starts_with("scenes/") || rel.starts_with("scene/") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for line in production_lines(&text) {
            if let Some(why) = names_a_layout(line, &names, &folders) {
                found.push(format!("src/{rel}: {why}: {}", line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "production lines outside src/scenes/ and src/scene/ that name a layout (ask the `Layout` instead):\n{}",
        found.join("\n")
    );
}

/// Most lines a file under `src/`, `tests/` or `benches/` may have, and `src/main.rs`
/// (docs/architecture.md "Size").
const MAX_LINES: usize = 700;
const MAX_MAIN_LINES: usize = 100;

#[test]
fn no_file_under_src_or_tests_is_over_its_size() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut paths = Vec::new();
    for dir in ["src", "tests", "benches"] {
        rust_files(&root.join(dir), &mut paths);
    }
    paths.sort();
    let mut over = Vec::new();
    for path in paths {
        let rel = path.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/");
        let lines = std::fs::read_to_string(&path).unwrap().lines().count();
        let most = if rel == "src/main.rs" { MAX_MAIN_LINES } else { MAX_LINES };
        if lines > most {
            over.push(format!("{rel}: {lines} lines (at most {most})"));
        }
    }
    assert!(over.is_empty(), "files over their size; split each along a concept:\n{}", over.join("\n"));
}
