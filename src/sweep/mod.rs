//! Sweep files: the TOML a user writes, parsed and validated into a [`Sweep`].
//!
//! Responsible for syntax, unknown keys (with "did you mean"), and values that make no sense
//! (lo ≥ hi, non-finite, zero levels, N = 0). Every error is one line naming the file and the
//! key. Not responsible for the physics meaning of parameters: that is the scene's catalogue
//! ([`crate::scene::params`]), which this module consults for names and units.

mod error;
mod file;
pub mod space;
mod validate;

pub use crate::analysis::convergence::ConvergenceSettings;
pub use crate::design::halton::Scrambling;
pub use crate::scene::settings::{SceneSettings, SizeDistributionSpec, FIDELITIES, KNOBS};
pub use error::SweepError;
pub use file::{
    AdaptSettings, DesignSettings, LdsSettings, RunSettings, Scale, SweepFile, DEFAULT_SEED, SWEEP_FORMAT,
};
use validate::{io_reason, scene_error, toml_error, validate};

use std::path::{Path, PathBuf};

use serde::Serialize;

/// One parameter after validation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Parameter {
    pub name: String,
    pub unit: &'static str,
    pub kind: ParamKind,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum ParamKind {
    Swept { lo: f64, hi: f64, scale: Scale },
    Fixed(f64),
}

/// A validated sweep: the file as written plus its parameters resolved against the catalogue.
#[derive(Debug, Clone)]
pub struct Sweep {
    pub path: PathBuf,
    pub file: SweepFile,
    /// Swept parameters in file order: the design's dimensions.
    pub swept: Vec<Parameter>,
    /// Fixed parameters as written.
    pub fixed: Vec<Parameter>,
}

impl Sweep {
    pub fn load(path: &Path) -> Result<Sweep, SweepError> {
        let unreadable = |why: String| SweepError::Read { path: path.to_path_buf(), why };
        let text = read_text(path).map_err(unreadable)?;
        Sweep::parse(&text, path)
    }

    /// Parse and validate; `path` is only used in messages and to resolve relative paths.
    pub fn parse(text: &str, path: &Path) -> Result<Sweep, SweepError> {
        let raw: toml::Table = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        refuse_keys_of_mono(&raw, path)?;
        // `[scene]` first, for its error's key and line (serde's would be the table's).
        let scene = raw.get("scene").and_then(|v| v.as_table()).cloned().unwrap_or_default();
        crate::scenes::settings::parse(&scene).map_err(|e| scene_error(path, text, &e))?;
        let mut file: SweepFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        include(&mut file, path)?;
        let (swept, fixed) = validate(&file, path)?;
        Ok(Sweep { path: path.to_path_buf(), file, swept, fixed })
    }

    /// This sweep with other scene settings, validated as if they had been written in the file.
    pub fn with_scene(&self, scene: SceneSettings) -> Result<Sweep, SweepError> {
        let mut file = self.file.clone();
        file.scene = scene;
        let (swept, fixed) = validate(&file, &self.path)?;
        Ok(Sweep { path: self.path.clone(), file, swept, fixed })
    }

    pub fn names(&self) -> Vec<&str> {
        self.swept.iter().map(|p| p.name.as_str()).collect()
    }

    /// The design's dimension.
    pub fn dim(&self) -> usize {
        self.swept.len()
    }

    /// Resolve the template override path against the sweep file's directory.
    pub fn template_path(&self) -> Option<PathBuf> {
        self.file.scene.template.as_ref().map(|t| {
            if t.is_absolute() {
                t.clone()
            } else {
                self.path.parent().unwrap_or(Path::new(".")).join(t)
            }
        })
    }
}

/// A monodisperse `[scene.size_distribution]` has no keys but `kind`: any other (a `classes`
/// left from another kind, a typo) would be dropped without a word, so it is refused.
fn refuse_keys_of_mono(raw: &toml::Table, path: &Path) -> Result<(), SweepError> {
    let Some(psd) = raw.get("scene").and_then(|s| s.get("size_distribution")).and_then(|d| d.as_table())
    else {
        return Ok(());
    };
    if psd.get("kind").and_then(|k| k.as_str()) != Some("mono") {
        return Ok(());
    }
    match psd.keys().find(|k| *k != "kind") {
        Some(other) => Err(SweepError::Key {
            path: path.to_path_buf(),
            key: format!("scene.size_distribution.{other}"),
            why: "not a key of kind = \"mono\" (every particle has the `diameter` parameter; \
                  `classes`, `weibull` and `lognormal` take keys)"
                .into(),
        }),
        None => Ok(()),
    }
}

/// Largest sweep file or include read, in bytes: a sweep file is a page of TOML; 16 MiB holds a
/// design written out point by point, and refuses a link to `/dev/zero` or a file given by slip.
pub const FILE_CAP: u64 = 16 << 20;

/// The text of a sweep file or an include: a regular file of at most [`FILE_CAP`] bytes, in
/// UTF-8. A FIFO, a device or a directory is refused at once, without waiting for a writer.
fn read_text(path: &Path) -> Result<String, String> {
    let bytes = crate::sys::read::read_capped(path, FILE_CAP).map_err(|e| io_reason(&e))?;
    String::from_utf8(bytes).map_err(|e| format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()))
}

/// Take the `[parameters]` of each file of `include` that the sweep file does not set itself,
/// then drop the include: the sweep holds them now. Two includes that set one parameter the
/// sweep file leaves out to different values are refused, naming both: which one was meant is
/// the user's to say.
fn include(file: &mut SweepFile, path: &Path) -> Result<(), SweepError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    // The parameters an include set, and which file set them.
    let mut set_by: std::collections::BTreeMap<String, PathBuf> = std::collections::BTreeMap::new();
    for inc in std::mem::take(&mut file.include) {
        let full = if inc.is_absolute() { inc.clone() } else { dir.join(&inc) };
        let bad = |why: String| SweepError::Key { path: path.to_path_buf(), key: "include".into(), why };
        let text = read_text(&full).map_err(|why| bad(format!("cannot read {}: {why}", full.display())))?;
        let table: toml::Table = toml::from_str(&text)
            .map_err(|e| bad(format!("{}: not TOML: {}", full.display(), e.message())))?;
        if let Some(other) = table.keys().find(|k| *k != "parameters") {
            return Err(bad(format!(
                "{}: holds [{other}]; an included file holds only [parameters]",
                full.display()
            )));
        }
        let Some(toml::Value::Table(params)) = table.get("parameters") else {
            return Err(bad(format!("{}: no [parameters] table", full.display())));
        };
        for (k, v) in params {
            match (file.parameters.get(k), set_by.get(k)) {
                (None, _) => {
                    file.parameters.insert(k.clone(), v.clone());
                    set_by.insert(k.clone(), full.clone());
                }
                (Some(first), Some(first_file)) if first != v => {
                    return Err(SweepError::Key {
                        path: path.to_path_buf(),
                        key: format!("parameters.{k}"),
                        why: format!(
                            "set to {first} by {} and to {v} by {}; set it in the sweep file, or include one of them",
                            first_file.display(),
                            full.display()
                        ),
                    });
                }
                // The sweep file's own value wins; the same value twice is no conflict.
                _ => {}
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod include_tests {
    use super::*;

    #[test]
    fn included_parameters_fill_what_the_file_leaves_out_and_the_file_wins() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("powder.toml"),
            "[parameters]\nfriction = { value = 0.31 }\nrolling_friction = { lo = 0.17, hi = 0.24 }\ngap = 9.0\n",
        )
        .unwrap();
        let path = dir.path().join("s.toml");
        let text = "name = \"s\"\ninclude = [\"powder.toml\"]\n[parameters]\ngap = { lo = 2.0, hi = 3.0 }\n";
        let s = Sweep::parse(text, &path).unwrap();
        assert_eq!(s.names(), ["gap", "rolling_friction"]);
        assert!(s.fixed.iter().any(|p| p.name == "friction" && p.kind == ParamKind::Fixed(0.31)));
        assert!(s.file.include.is_empty(), "the resolved sweep holds the parameters, not the include");
        let missing = Sweep::parse(&text.replace("powder", "nowhere"), &path).unwrap_err().to_string();
        assert!(missing.contains("include: cannot read") && missing.contains("nowhere.toml"), "{missing}");
        // Issue 70, defect 10: two includes setting friction 0.31 and 0.5: the first won silently.
        std::fs::write(dir.path().join("other.toml"), "[parameters]\nfriction = { value = 0.5 }\n").unwrap();
        let two = text.replace("[\"powder.toml\"]", "[\"powder.toml\", \"other.toml\"]");
        let both = Sweep::parse(&two, &path).unwrap_err().to_string();
        assert!(
            both.contains("parameters.friction")
                && both.contains("by ")
                && both.contains("powder.toml")
                && both.contains("other.toml"),
            "{both}"
        );
        // The same value twice, or a value the file sets itself, is no conflict.
        std::fs::write(
            dir.path().join("other.toml"),
            "[parameters]\nfriction = { value = 0.31 }\ngap = 1.0\n",
        )
        .unwrap();
        assert!(Sweep::parse(&two, &path).is_ok());
        std::fs::write(dir.path().join("bad.toml"), "[scene]\nlayout = \"pour\"\n").unwrap();
        let other = Sweep::parse(&text.replace("powder", "bad"), &path).unwrap_err().to_string();
        assert!(other.contains("holds [scene]; an included file holds only [parameters]"), "{other}");
    }
}

#[cfg(test)]
mod preset_tests {
    use super::*;

    fn scene_of(scene: &str) -> Result<SceneSettings, SweepError> {
        let text = format!("name = \"t\"\n[parameters]\ngap = {{ lo = 1.0, hi = 2.0 }}\n[scene]\n{scene}\n");
        Sweep::parse(&text, Path::new("t.toml")).map(|s| s.file.scene)
    }

    #[test]
    fn a_preset_sets_the_knobs_the_file_leaves_out_and_the_file_wins_where_it_speaks() {
        let r = scene_of("fidelity = \"reference\"").unwrap();
        let conveyor = crate::scenes::lookup("conveyor").unwrap();
        assert_eq!(r, crate::scenes::settings::preset(conveyor, "reference").unwrap());
        assert!(!r.own.keys().sweep_precision(), "every point to its own target at the reference");
        // The reference is finer in every knob it changes, the layout's own as the others.
        let fast = SceneSettings::default();
        assert!(r.rayleigh_fraction < fast.rayleigh_fraction && r.depth_diameters > fast.depth_diameters);
        assert!(r.rest_speed < fast.rest_speed && r.stiffness_factor >= fast.stiffness_factor);
        let window = |s: &SceneSettings| crate::scenes::moving_blade::own(s).window_diameters;
        let gated = scene_of("layout = \"gated\"\nfidelity = \"reference\"").unwrap();
        assert!(window(&gated) > window(&SceneSettings::gated()));
        let mine =
            scene_of("layout = \"gated\"\nfidelity = \"reference\"\ndepth_diameters = 5\nseed = 7").unwrap();
        assert_eq!((mine.depth_diameters, mine.seed, window(&mine)), (5.0, 7, window(&gated)));
        let thesis = scene_of("layout = \"thesis\"\nfidelity = \"thesis\"").unwrap();
        assert_eq!(thesis.timestep_s, crate::scene::THESIS_TIMESTEP);
        let keys = crate::scenes::moving_blade::own(&thesis);
        assert!(keys.run_to_end && keys.full_dump_every_s > 0.0);
        assert_eq!(scene_of("").unwrap(), SceneSettings::default());
    }

    #[test]
    fn the_retired_heap_diameters_names_what_replaces_it_in_one_line() {
        let err = scene_of("heap_diameters = 10").unwrap_err().to_string();
        assert!(
            err.starts_with("t.toml:5: scene.heap_diameters: replaced by the parameter heap_height"),
            "{err}"
        );
        assert!(err.contains("10 at D = 2 mm is heap_height = 20") && !err.contains('\n'), "{err}");
    }

    #[test]
    fn the_resolved_settings_read_back_to_themselves() {
        // DIR/sweep.toml holds every key, those its layout does not read at its preset's values:
        // a resume must see the same knobs, and refuse none.
        let cases = crate::scenes::names().into_iter().flat_map(|l| FIDELITIES.map(|f| (l, f, "")));
        for (layout, fidelity, knob) in cases.chain([("gated", "thesis", "window_diameters = 30\n")]) {
            let text = format!(
                "name = \"t\"\n[parameters]\nfriction = {{ lo = 0.1, hi = 0.3 }}\n[scene]\n\
                 layout = \"{layout}\"\nfidelity = \"{fidelity}\"\n{knob}"
            );
            let first = Sweep::parse(&text, Path::new("t.toml")).unwrap();
            let body = toml::to_string(&first.file).unwrap();
            let again = Sweep::parse(&body, Path::new("sweep.toml")).unwrap();
            assert_eq!(again.file.scene, first.file.scene, "{layout}, {fidelity}");
            assert!(
                knob.is_empty()
                    || crate::scenes::moving_blade::own(&again.file.scene).window_diameters == 30.0
            );
        }
    }

    #[test]
    fn a_bad_fidelity_or_knob_is_one_line_naming_the_key() {
        for (scene, key) in [
            ("fidelity = \"fastest\"", "scene.fidelity"),
            ("stiffness_factor = 2", "scene.stiffness_factor"),
            ("mesh_cells_across = 0", "scene.mesh_cells_across"),
            ("timestep_s = -1", "scene.timestep_s"),
        ] {
            let e = scene_of(scene).unwrap_err().to_string();
            assert!(e.contains(key) && !e.contains('\n'), "{scene}: {e}");
        }
    }

    #[test]
    fn knobs_of_a_preset_replace_only_the_knobs() {
        let mine =
            SceneSettings { supply_factor: 1.5, seed: 3, depth_diameters: 4.0, ..SceneSettings::default() };
        let r = crate::scenes::settings::with_knobs_of(&mine, "reference").unwrap();
        assert!(
            mine.own.keys().sweep_precision() && !r.own.keys().sweep_precision(),
            "a knob of the layout's own"
        );
        assert_eq!((r.supply_factor, r.seed, r.fidelity.as_str()), (1.5, 3, "reference"));
        assert_eq!(r.depth_diameters, 12.0);
        let k = crate::scenes::settings::with_knob(&mine, "rayleigh_fraction", "0.3").unwrap();
        assert_eq!((k.rayleigh_fraction, k.supply_factor), (0.3, 1.5));
        assert!(crate::scenes::settings::with_knob(&mine, "supply_factor", "2")
            .unwrap_err()
            .to_string()
            .contains("not a numerical knob"));
        assert!(crate::scenes::settings::with_knob(&SceneSettings::gated(), "run_to_end", "maybe").is_err());
    }
}
