//! Decks: rendering a Tera template with a scene, and the content hash that names a run.
//!
//! The built-in template is embedded in the binary; a sweep file may point at its own. A
//! template that uses a variable the scene does not define is an error naming the variable.

use std::path::Path;

use sha2::{Digest, Sha256};

use crate::scene::{pile, Scene};
use crate::scenes::Layout;
use crate::sys::hex;

#[derive(Debug, thiserror::Error)]
pub enum DeckError {
    #[error("cannot read template {path}: {reason}")]
    Read { path: String, reason: String },
    #[error("template {name}: {reason}")]
    Syntax { name: String, reason: String },
    #[error("template {name}: {reason}")]
    Render { name: String, reason: String },
}

/// A parsed template, ready to render many points.
#[derive(Clone)]
pub struct Template {
    name: String,
    source: String,
    tera: tera::Tera,
}

impl Template {
    /// The layout's built-in template, or the file at `path` (which renders any layout).
    pub fn load(path: Option<&Path>, layout: &dyn Layout) -> Result<Template, DeckError> {
        match path {
            None => {
                let builtin = layout.template();
                Template::from_source(builtin.name, builtin.source)
            }
            Some(p) => {
                let read = |reason: String| DeckError::Read { path: p.display().to_string(), reason };
                let bytes = crate::sys::read::read_capped(p, crate::sweep::FILE_CAP)
                    .map_err(|e| read(e.to_string()))?;
                let source = String::from_utf8(bytes).map_err(|_| read("not UTF-8 text".into()))?;
                Template::from_source(&p.display().to_string(), &source)
            }
        }
    }

    pub fn from_source(name: &str, source: &str) -> Result<Template, DeckError> {
        let mut tera = tera::Tera::default();
        tera.autoescape_on(vec![]);
        tera.add_raw_template(name, source)
            .map_err(|e| DeckError::Syntax { name: name.into(), reason: chain(&e) })?;
        Ok(Template { name: name.into(), source: source.into(), tera })
    }

    /// sha256 of the template source, for the manifest.
    pub fn hash(&self) -> String {
        hex(&Sha256::digest(self.source.as_bytes()))
    }

    /// Render the deck of one scene.
    pub fn render(&self, scene: &Scene) -> Result<String, DeckError> {
        let mut context = tera::Context::new();
        context.insert("scene", scene);
        self.tera
            .render(&self.name, &context)
            .map_err(|e| DeckError::Render { name: self.name.clone(), reason: chain(&e) })
    }
}

/// Tera nests the useful message ("Variable `scene.foo` not found in context ...") in its
/// source chain; flatten it into one line.
fn chain(e: &tera::Error) -> String {
    let mut parts = vec![e.to_string()];
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        parts.push(s.to_string());
        source = s.source();
    }
    parts.join(": ").replace('\n', " ")
}

/// The files of one run and the hash that identifies it.
#[derive(Debug, Clone)]
pub struct Deck {
    pub input: String,
    pub mesh: String,
    /// The layout's other wall meshes: (file name, ASCII STL).
    pub extra_meshes: Vec<(&'static str, String)>,
    pub pile: String,
    /// sha256 over the deck, the mesh and the engine identity: equal hashes, equal runs.
    pub hash: String,
    /// Comment lines written above the deck: the point's values and its hash. Not hashed (it
    /// names the hash, and the values are the scene's, already in the deck).
    pub header: String,
}

impl Deck {
    pub const INPUT: &'static str = "in.liggghts";
    pub const MESH: &'static str = "blade.stl";

    pub fn new(
        template: &Template,
        layout: &dyn Layout,
        scene: &Scene,
        engine_identity: &str,
    ) -> Result<Deck, DeckError> {
        let input = template.render(scene)?;
        let mesh = layout.mesh(scene);
        let pile = layout.pile(scene);
        let extra_meshes = layout.extra_meshes(scene);
        let mut h = Sha256::new();
        // Length-prefix each part so no two different sets of parts hash alike. A layout with
        // no extra meshes hashes exactly as before they existed.
        let mut parts = vec![input.as_bytes(), mesh.as_bytes(), pile.as_bytes(), engine_identity.as_bytes()];
        for (name, stl) in &extra_meshes {
            parts.extend([name.as_bytes(), stl.as_bytes()]);
        }
        for part in parts {
            h.update((part.len() as u64).to_le_bytes());
            h.update(part);
        }
        Ok(Deck { input, mesh, extra_meshes, pile, hash: hex(&h.finalize()), header: String::new() })
    }

    /// Write the deck, mesh and pile into `dir`.
    /// The files [`Deck::write`] writes, in its order.
    pub fn file_names(&self) -> Vec<&str> {
        let mut names = vec![Self::INPUT, Self::MESH];
        names.extend(self.extra_meshes.iter().map(|(name, _)| *name));
        names.push(pile::PILE_DATA);
        names
    }

    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        std::fs::write(dir.join(Self::INPUT), format!("{}{}", self.header, self.input))?;
        std::fs::write(dir.join(Self::MESH), &self.mesh)?;
        for (name, stl) in &self.extra_meshes {
            std::fs::write(dir.join(name), stl)?;
        }
        std::fs::write(dir.join(pile::PILE_DATA), &self.pile)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::settings::{SceneSettings, SizeDistributionSpec};
    use crate::scenes::moving_blade::GATED;
    use std::collections::BTreeMap;

    fn scene(settings: &SceneSettings, pairs: &[(&str, f64)]) -> Scene {
        let values: BTreeMap<String, f64> = pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        crate::scenes::build(&values, settings).unwrap()
    }

    #[test]
    fn the_names_it_gives_are_the_files_it_writes() {
        let deck = Deck {
            input: "run 0\n".into(),
            mesh: String::new(),
            extra_meshes: vec![("feed.stl", String::new()), ("pit.stl", String::new())],
            pile: String::new(),
            hash: String::new(),
            header: String::new(),
        };
        let dir = tempfile::tempdir().unwrap();
        deck.write(dir.path()).unwrap();
        let mut written: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        written.sort();
        let mut named: Vec<String> = deck.file_names().iter().map(|n| n.to_string()).collect();
        named.sort();
        assert_eq!(written, named);
        assert!(named.contains(&"feed.stl".to_string()));
    }

    #[test]
    fn switched_off_features_leave_no_lines() {
        let t = Template::load(None, &crate::scenes::moving_blade::GATED).unwrap();
        let thesis = SceneSettings { layout: "thesis".into(), ..SceneSettings::gated() };
        let deck = t.render(&scene(&thesis, &[("rolling_friction", 0.0)])).unwrap();
        assert!(!deck.contains("rolling"), "{deck}");
        assert!(!deck.contains("vtk"));
        // The thesis layout has no gate, no substrate and a fixed-time settle.
        assert!(
            !deck.contains("fix gate")
                && !deck.contains("group           substrate")
                && !deck.contains("settleloop")
        );
        // The default: rolling friction on every contact (pair, plate, two end walls, blade,
        // gate), a gate, a substrate, a settle until at rest.
        let rolled = t.render(&scene(&SceneSettings::gated(), &[("rolling_friction", 0.1)])).unwrap();
        assert!(rolled.contains("coefficientRollingFriction"));
        assert_eq!(rolled.matches("rolling_friction epsd2").count(), 6);
        assert!(rolled.contains("unfix gate") && rolled.contains("group           substrate type 3"));
        assert!(rolled.contains("jump SELF settleloop"));
    }

    #[test]
    fn a_size_distribution_puts_every_class_in_the_pile() {
        let settings = SceneSettings {
            size_distribution: SizeDistributionSpec::Weibull { bins: 5 },
            ..SceneSettings::gated()
        };
        let s = scene(&settings, &[]);
        let pile = pile::pile_data(&s);
        for c in &s.size_classes {
            assert!(pile.contains(&format!(" 1 {} ", c.diameter)), "class {} missing", c.diameter);
        }
    }

    #[test]
    fn an_undefined_variable_is_an_error_naming_it() {
        let t = Template::from_source("t", "run {{ scene.no_such_thing }}").unwrap();
        let err = t.render(&scene(&SceneSettings::gated(), &[])).unwrap_err().to_string();
        assert!(err.contains("scene.no_such_thing"), "{err}");
        assert!(!err.contains('\n'));
    }

    #[test]
    fn the_hash_changes_with_deck_mesh_and_engine() {
        let t = Template::load(None, &crate::scenes::moving_blade::GATED).unwrap();
        let s = scene(&SceneSettings::gated(), &[]);
        let a = Deck::new(&t, &GATED, &s, "liggghts 3.8").unwrap();
        assert_eq!(a.hash, Deck::new(&t, &GATED, &s, "liggghts 3.8").unwrap().hash);
        assert_ne!(a.hash, Deck::new(&t, &GATED, &s, "liggghts 3.9").unwrap().hash);
        let s2 = scene(&SceneSettings::gated(), &[("gap", 3.5)]);
        assert_ne!(a.hash, Deck::new(&t, &GATED, &s2, "liggghts 3.8").unwrap().hash);
    }
}
