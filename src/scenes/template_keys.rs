//! Every key a layout's built-in deck reads is a key of its scene: the deck's context is built
//! from the scene's types by serde, so a key the template reads and the types lack fails here,
//! even where Tera would not fail the render (a bare `{% if scene.own.x %}` of an undefined `x`
//! is false).

use std::collections::{BTreeMap, BTreeSet};

/// Keys a deck reads only inside a test that they are set (`{% if scene.own.extend %}`): absent
/// from a scene where they are not.
const ONLY_WHEN_SET: &[&str] = &["own.extend", "own.resume", "own.first_floor"];

/// The keys of `scene.…` a template reads: the first after `scene.`, and the second under `own`.
fn keys(template: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (at, _) in template.match_indices("scene.") {
        // `docs/scene.md` in a comment, `the_scene.x`: not the context's scene.
        let before = template[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '/') {
            continue;
        }
        let path: String = template[at + "scene.".len()..]
            .chars()
            .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_' || *c == '.')
            .collect();
        let parts: Vec<&str> = path.split('.').filter(|p| !p.is_empty()).collect();
        let depth = if parts.first() == Some(&"own") { 2 } else { 1 };
        if parts.len() >= depth {
            out.insert(parts[..depth].join("."));
        }
    }
    out
}

#[test]
fn every_key_a_built_in_deck_reads_is_a_key_of_its_layouts_scene() {
    for layout in super::LAYOUTS {
        let settings = super::settings::defaults(*layout);
        let scene = super::build(&BTreeMap::new(), &settings).unwrap();
        let context = serde_json::to_value(&scene).unwrap();
        let read = keys(layout.template().source);
        assert!(read.len() > 20, "{}: {read:?}", layout.name());
        for key in read {
            let found = key.split('.').try_fold(&context, |v, k| v.get(k)).is_some();
            assert!(
                found || ONLY_WHEN_SET.contains(&key.as_str()),
                "the {} deck reads scene.{key}, which its scene lacks",
                layout.name()
            );
        }
    }
}

#[test]
fn a_key_the_scene_lacks_is_found() {
    assert_eq!(
        keys("run {{ scene.gap }} {% if scene.own.fused %} # docs/scene.md {{ scene.own.x.y }}"),
        ["gap", "own.fused", "own.x"].into_iter().map(String::from).collect()
    );
}
