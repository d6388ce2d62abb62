//! docs/architecture.md's "Adding a layout" steps, held to the code: the methods of `Layout`
//! they list (each one every layout writes, or a default it overrides: no more, no fewer), every
//! file, type and function they name, and what they say each layout has — its folder registered,
//! its `Layout` and its scene's part, its template embedded, its tests, its deck case.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::support::repo;

/// Where the section starts; it ends at the next `## ` heading.
const HEADING: &str = "## Adding a layout";
/// Step 1's words between the methods every layout writes and the defaults it overrides.
const DEFAULTS: &str = "It overrides the defaults";

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The section of the document.
fn section(doc: &str) -> &str {
    let start = doc.find(HEADING).unwrap_or_else(|| panic!("docs/architecture.md: no {HEADING:?}"));
    let rest = &doc[start + HEADING.len()..];
    &rest[..rest.find("\n## ").unwrap_or(rest.len())]
}

/// The `code spans` of a text.
fn spans(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).collect()
}

/// The methods a text names as `name()`.
fn methods_named(text: &str) -> BTreeSet<String> {
    spans(text)
        .into_iter()
        .filter_map(|s| s.strip_suffix("()"))
        .filter(|s| {
            !s.is_empty() && s.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        })
        .map(String::from)
        .collect()
}

/// The methods of `trait NAME` in a source file: (without a default, with one).
fn trait_methods(source: &str, name: &str) -> (BTreeSet<String>, BTreeSet<String>) {
    let open = format!("pub trait {name}");
    let start = source.find(&open).unwrap_or_else(|| panic!("no {open}"));
    let body = &source[start..];
    let body = &body[..body.find("\n}\n").expect("the trait's end")];
    let (mut required, mut provided) = (BTreeSet::new(), BTreeSet::new());
    for (at, _) in body.match_indices("\n    fn ") {
        let sig = &body[at + "\n    fn ".len()..];
        let method: String = sig.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        let end = sig.find([';', '{']).expect("a method's end");
        let set = if sig.as_bytes()[end] == b';' { &mut required } else { &mut provided };
        set.insert(method);
    }
    (required, provided)
}

/// Whether `text` defines `item` (a type, trait, function, constant or module, or an enum's
/// variant) or re-exports it.
fn defines(text: &str, item: &str) -> bool {
    defines_as(text, item, &["struct", "enum", "trait", "type", "fn", "const", "static", "mod"])
}

/// Whether `text` defines `item` after one of `keywords`, or re-exports it, or has it as a variant.
fn defines_as(text: &str, item: &str, keywords: &[&str]) -> bool {
    let word_at = |line: &str, at: usize| {
        !line[at + item.len()..].starts_with(|c: char| c.is_alphanumeric() || c == '_')
            && !line[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_')
    };
    text.lines().any(|line| {
        let t = line.trim_start();
        let named = |kw: &str| {
            t.split(' ')
                .collect::<Vec<_>>()
                .windows(2)
                .any(|w| w[0] == kw && w[1].starts_with(item) && word_at(w[1], 0))
        };
        keywords.iter().any(|kw| named(kw))
            || (t.starts_with("pub use") && line.match_indices(item).any(|(at, _)| word_at(line, at)))
            // An enum's variant: `    Name,` or `    Name {` or `    Name(…)`.
            || (t.starts_with(item) && word_at(t, 0) && item.starts_with(char::is_uppercase)
                && t[item.len()..].trim_start().starts_with([',', '{', '(']))
    })
}

/// The source file of a module path under `src/` (`["scene", "own"]`), if there is one.
fn module_file(src: &Path, path: &[&str]) -> Option<PathBuf> {
    if path.is_empty() {
        return Some(src.join("lib.rs"));
    }
    let dir = src.join(path.join("/"));
    [dir.with_extension("rs"), dir.join("mod.rs")].into_iter().find(|f| f.is_file())
}

/// Why a Rust path the document names (`scene::own::LayoutData`, `Scene::new`, `Layout`) does
/// not resolve in `src/`, if it does not.
fn unresolved(src: &Path, sources: &[(PathBuf, String)], path: &str) -> Option<String> {
    let segments: Vec<&str> = path.split("::").collect();
    // The longest module prefix that is a file; the rest is an item and, maybe, its member.
    let mut depth = segments.len();
    while module_file(src, &segments[..depth]).is_none() {
        depth -= 1;
    }
    let rest = &segments[depth..];
    let (&item, member) = rest.split_first()?;
    let file = module_file(src, &segments[..depth]).unwrap();
    // A bare name (`Layout`) may live anywhere; a path's item in its module's file.
    let found = if depth == 0 {
        sources.iter().any(|(_, text)| defines(text, item))
    } else {
        defines(&read(&file), item)
    };
    if !found {
        return Some(format!("`{path}`: no `{item}` in {}", file.display()));
    }
    // `Type::method` or `Enum::Variant`: in a file that defines the type.
    if let Some(&member) = member.first() {
        let owners = sources.iter().filter(|(_, text)| defines_as(text, item, &["struct", "enum", "trait"]));
        if !owners.clone().any(|(_, text)| defines(text, member)) {
            let files: Vec<String> = owners.map(|(f, _)| f.display().to_string()).collect();
            return Some(format!("`{path}`: no `{member}` beside `{item}` ({})", files.join(", ")));
        }
    }
    None
}

/// What in the section does not hold of the code at `root`: its methods of `Layout` against the
/// trait's, its files, and its Rust paths.
fn step_problems(root: &Path, doc: &str) -> Vec<String> {
    let src = root.join("src");
    let (required, provided) = trait_methods(&read(&src.join("scenes/mod.rs")), "Layout");
    let section = section(doc);
    let step1 = &section[section.find("\n1. ").expect("step 1")..section.find("\n2. ").expect("step 2")];
    let split = step1.find(DEFAULTS).unwrap_or_else(|| panic!("step 1 has no {DEFAULTS:?}"));
    let mut problems = Vec::new();
    let mut compare = |what: &str, named: BTreeSet<String>, real: &BTreeSet<String>| {
        for m in real.difference(&named) {
            problems.push(format!("{what}: `{m}()` is not in step 1"));
        }
        for m in named.difference(real) {
            problems.push(format!("{what}: step 1 names `{m}()`, which is not one"));
        }
    };
    compare("a method every layout writes", methods_named(&step1[..split]), &required);
    compare("a default a layout overrides", methods_named(&step1[split..]), &provided);
    for m in methods_named(section) {
        if !required.contains(&m) && !provided.contains(&m) {
            problems.push(format!("`{m}()` is not a method of `Layout`"));
        }
    }
    let mut paths = Vec::new();
    crate::architecture::rust_files(&src, &mut paths);
    let sources: Vec<(PathBuf, String)> = paths.into_iter().map(|p| (p.clone(), read(&p))).collect();
    for span in spans(section) {
        // A placeholder (`src/scenes/NAME/`) or a command line is not a name to check.
        if span.contains("NAME") || span.contains(' ') {
            continue;
        }
        if ["src/", "tests/", "templates/", "sweeps/"].iter().any(|p| span.starts_with(p)) {
            if !root.join(span).exists() {
                problems.push(format!("`{span}` does not exist"));
            }
            continue;
        }
        // A Rust path (`scenes::Layout`, `Scene::own::<T>()`) or a type (`Base`), a constant
        // (`LAYOUTS`).
        let path = span.split("::<").next().unwrap().trim_end_matches("()");
        let is_path = path.split("::").all(|s| {
            s.starts_with(|c: char| c.is_ascii_alphabetic())
                && s.chars().all(|c| c.is_alphanumeric() || c == '_')
        });
        if is_path && (path.contains("::") || path.starts_with(char::is_uppercase)) {
            problems.extend(unresolved(&src, &sources, path));
        }
    }
    problems
}

#[test]
fn the_steps_name_every_method_of_layout_and_only_things_that_exist() {
    let root = repo(".");
    let problems = step_problems(&root, &read(&root.join("docs/architecture.md")));
    assert!(problems.is_empty(), "docs/architecture.md \"{HEADING}\":\n{}", problems.join("\n"));
}

#[test]
fn the_step_check_fails_on_a_missing_method_a_method_out_of_place_and_a_name_that_is_gone() {
    let root = repo(".");
    let doc = read(&root.join("docs/architecture.md"));
    for (from, to, expected) in [
        ("`pass_series()`, ", "", "`pass_series()` is not in step 1"),
        ("`atoms_kept()`, ", "", "`atoms_kept()` is not in step 1"),
        ("`what_runs()`, ", "`what_runs()`, `held_heap()`, ", "names `held_heap()`, which is not one"),
        ("`top_view()`", "`top_view()`, `bottom_view()`", "`bottom_view()` is not a method of `Layout`"),
        ("`src/scenes/keys.rs`", "`src/scenes/locks.rs`", "`src/scenes/locks.rs` does not exist"),
        ("`scene::own::LayoutData`", "`scene::own::LayoutPart`", "no `LayoutPart`"),
        ("`Scene::new`", "`Scene::anew`", "no `anew` beside `Scene`"),
        ("`outcome::AnswerKind`", "`outcome::AnswerSort`", "no `AnswerSort`"),
    ] {
        assert!(doc.contains(from), "the document no longer has {from:?}");
        let problems = step_problems(&root, &doc.replacen(from, to, 1));
        assert!(problems.iter().any(|p| p.contains(expected)), "{from:?} → {to:?}: {problems:?}");
    }
}

/// The folders of `src/scenes/` (each a layout's, or a family's).
pub(crate) fn layout_folders(root: &Path) -> Vec<String> {
    let mut folders: Vec<String> = std::fs::read_dir(root.join("src/scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    folders.sort();
    folders
}

#[test]
fn every_layout_folder_is_registered_and_has_what_the_steps_say() {
    let root = repo(".");
    let registry = read(&root.join("src/scenes/mod.rs"));
    // `pub const LAYOUTS: &[&dyn Layout] = &[&a::A, &b::B];`
    let list = &registry[registry.find("pub const LAYOUTS").expect("LAYOUTS")..];
    let list = &list[list.find('=').expect("LAYOUTS's value")..];
    let list = &list[list.find("&[").expect("LAYOUTS's list") + "&[".len()..];
    let list = &list[..list.find(']').expect("the end of LAYOUTS")];
    let entries: Vec<&str> =
        list.split(',').map(|e| e.trim().trim_start_matches('&')).filter(|e| !e.is_empty()).collect();
    assert_eq!(entries.len(), demsweep::scenes::LAYOUTS.len(), "LAYOUTS: {entries:?}");
    let folders = layout_folders(&root);
    let mut problems = Vec::new();
    for e in &entries {
        let folder = e.split("::").next().unwrap();
        if !folders.iter().any(|f| f == folder) {
            problems.push(format!("LAYOUTS's {e} is not of a folder of src/scenes/"));
        }
    }
    for folder in &folders {
        let dir = root.join("src/scenes").join(folder);
        let mut files = Vec::new();
        crate::architecture::rust_files(&dir, &mut files);
        let text: String = files.iter().map(|f| read(f)).collect();
        let mine = format!("src/scenes/{folder}/");
        let mut lacks = |what: &str, has: bool| {
            if !has {
                problems.push(format!("{mine}: {what}"));
            }
        };
        lacks("no `pub mod` line in src/scenes/mod.rs", registry.contains(&format!("\npub mod {folder};")));
        lacks("no struct of it in LAYOUTS", entries.iter().any(|e| e.starts_with(&format!("{folder}::"))));
        let mod_rs = read(&dir.join("mod.rs"));
        lacks("its mod.rs does not implement `Layout`", mod_rs.contains("Layout for "));
        lacks("no type of it implements `LayoutData`", text.contains("LayoutData for "));
        lacks("no `#[cfg(test)]` tests", text.contains("#[cfg(test)]"));
        let embedded = text.match_indices("include_str!(\"../../../templates/").any(|(at, _)| {
            let name = &text[at + "include_str!(\"../../../".len()..];
            let name = &name[..name.find('"').unwrap()];
            name.ends_with(".liggghts.tera") && root.join(name).is_file()
        });
        lacks("no deck of templates/*.liggghts.tera embedded with include_str!", embedded);
    }
    assert!(
        folders.len() >= 4 && problems.is_empty(),
        "layout folders {folders:?}:\n{}",
        problems.join("\n")
    );
}

#[test]
fn every_layout_has_its_template_in_templates_and_a_deck_case() {
    let root = repo(".");
    let mut covered = BTreeSet::new();
    for (case, file, edits) in crate::decks::CASES {
        let mut toml = read(&root.join(file));
        for (from, to) in *edits {
            toml = toml.replacen(from, to, 1);
        }
        let value: toml::Value = toml::from_str(&toml).unwrap_or_else(|e| panic!("{case}: {e}"));
        // The sweep file's default layout is the conveyor.
        let layout = value.get("scene").and_then(|s| s.get("layout")).and_then(|l| l.as_str());
        covered.insert(layout.unwrap_or("conveyor").to_string());
    }
    for layout in demsweep::scenes::LAYOUTS {
        let t = layout.template();
        let file = root.join("templates").join(t.name);
        assert!(file.is_file(), "{}: its template {} is not in templates/", layout.name(), t.name);
        assert_eq!(read(&file), t.source, "{}: not templates/{}", layout.name(), t.name);
        assert!(
            covered.contains(layout.name()),
            "{}: no case in tests/it/decks.rs ({covered:?})",
            layout.name()
        );
    }
}
