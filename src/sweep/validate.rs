//! Reading a sweep file: TOML syntax errors and unknown keys told with the key and a "did you
//! mean", and the values checked against the scene's catalogue of parameters.

use std::path::Path;

use super::file::*;
use super::SweepError;
use super::{ParamKind, Parameter};
use crate::error::hint;
use crate::scene::cohesion::CohesionScaling;
use crate::scene::params::{self, ParamInfo};
use crate::scene::settings::{quoted, SizeDistributionSpec, FIDELITIES};

pub(super) fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => e.to_string(),
    }
}

/// Turn a (multi-line) toml error into one line:
/// `file:line: key.path: message (did you mean ..?)`.
pub(super) fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> SweepError {
    let start = e.span().map(|s| s.start.min(text.len()));
    let line = start.map(|s| text[..s].matches('\n').count() + 1);
    let msg = e
        .message()
        .trim()
        .replace('\n', " ")
        .replace("expected usize", "expected a whole number ≥ 0")
        .replace("expected u64", "expected a whole number ≥ 0")
        .replace("expected u32", "expected a whole number ≥ 0");
    let mut extra = String::new();
    // serde's message: "unknown field `frction`, expected one of `a`, `b`".
    if let Some(rest) = msg.strip_prefix("unknown field `") {
        if let Some((word, tail)) = rest.split_once('`') {
            let candidates: Vec<&str> = tail.split('`').skip(1).step_by(2).collect();
            extra = hint(word, candidates);
        }
    }
    let key = start.and_then(|s| key_at(text, s));
    SweepError::Syntax { path: path.to_path_buf(), line, key, why: format!("{msg}{extra}") }
}

/// A `[scene]` table's error as the sweep file's: a key's value or name with its line, a key
/// only other layouts read or a layout or preset that is none by its key.
pub(super) fn scene_error(path: &Path, text: &str, e: &crate::scenes::settings::SettingError) -> SweepError {
    use crate::scenes::settings::SettingError::*;
    let (key, why) = (e.key(), e.why());
    match e {
        Unknown { key: k, .. } if k == "heap_diameters" => {
            let why = "replaced by the parameter heap_height, the heap's height above the \
                 blade tip in mm (e.g. `heap_height = 20` under [parameters]); heap_diameters × D keeps today's \
                 heap at that D: 10 at D = 2 mm is heap_height = 20";
            SweepError::Syntax {
                path: path.to_path_buf(),
                line: line_of(text, "scene", k),
                key: Some(key),
                why: why.into(),
            }
        }
        Unknown { key: k, .. } | Value { key: k, .. } => {
            let line = line_of(text, "scene", k);
            let why = why
                .replace("expected usize", "expected a whole number ≥ 0")
                .replace("expected u64", "expected a whole number ≥ 0");
            SweepError::Syntax { path: path.to_path_buf(), line, key: Some(key), why }
        }
        Unread(_) | Choice { .. } => SweepError::Key { path: path.to_path_buf(), key, why },
    }
}

/// The line of `key = …` in `[table]` of `text` (the first, 1-based), if written so.
fn line_of(text: &str, table: &str, key: &str) -> Option<usize> {
    let mut here = String::new();
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.starts_with('[') {
            here = l.trim_matches(|c| c == '[' || c == ']').replace([' ', '"', '\''], "");
            continue;
        }
        let Some((k, _)) = l.split_once('=') else { continue };
        let k = k.trim().replace([' ', '"', '\''], "");
        if (here == table && k == key) || (here.is_empty() && k == format!("{table}.{key}")) {
            return Some(i + 1);
        }
    }
    None
}

/// The dotted key whose `key = value` line holds byte `offset` of `text`, prefixed with the
/// enclosing `[table]` header, e.g. `design.lds.max`; `None` on a header or a blank line.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line = text[line_start..].lines().next().unwrap_or("").trim();
    let (key, _) = line.split_once('=')?;
    let key = key.trim().replace([' ', '"', '\''], "");
    if key.is_empty() || key.starts_with('[') || key.starts_with('#') {
        return None;
    }
    let header = text[..line_start].lines().rev().find_map(|l| {
        let l = l.trim();
        l.starts_with('[')
            .then(|| l.trim_start_matches('[').split(']').next().unwrap_or("").replace([' ', '"', '\''], ""))
    });
    Some(match header {
        Some(h) if !h.is_empty() => format!("{h}.{key}"),
        _ => key,
    })
}

type Params = (Vec<Parameter>, Vec<Parameter>);

pub(super) fn validate(file: &SweepFile, path: &Path) -> Result<Params, SweepError> {
    let bad = |key: &str, why: String| SweepError::Key { path: path.to_path_buf(), key: key.into(), why };
    if file.name.trim().is_empty() || file.name.contains(['/', '\\']) || file.name.starts_with('.') {
        return Err(bad("name", "expected a non-empty name without slashes".into()));
    }
    // The name becomes a directory and a line of the report: no newlines, tabs or escapes.
    if file.name.chars().any(char::is_control) {
        return Err(bad(
            "name",
            format!("{:?}: expected no control characters (newline, tab, escape)", file.name),
        ));
    }
    // Invisible characters that reorder or hide text (a right-to-left override) would make the
    // directory and the report's title read as another name.
    if let Some(c) = file.name.chars().find(|c| is_format_char(*c)) {
        return Err(bad(
            "name",
            format!(
                "{:?}: expected no invisible formatting characters (U+{:04X}: bidirectional \
                 override, zero-width or similar)",
                file.name, c as u32
            ),
        ));
    }
    if file.name.len() > MAX_NAME_BYTES {
        return Err(bad(
            "name",
            format!(
                "{} bytes long: expected at most {MAX_NAME_BYTES} (it names the directory runs/<name>)",
                file.name.len()
            ),
        ));
    }
    let mut swept = Vec::new();
    let mut fixed = Vec::new();
    for (name, value) in &file.parameters {
        let key = format!("parameters.{name}");
        let info: &ParamInfo = params::lookup(name).ok_or_else(|| {
            bad(
                &key,
                format!(
                    "unknown parameter{}; known: {}",
                    hint(name, params::CATALOGUE.iter().map(|i| i.name)),
                    params::CATALOGUE.iter().map(|i| i.name).collect::<Vec<_>>().join(", ")
                ),
            )
        })?;
        let entry: ParamEntry = match value {
            toml::Value::Float(_) | toml::Value::Integer(_) => ParamEntry {
                lo: None,
                hi: None,
                value: Some(as_f64(value).unwrap()),
                unit: None,
                scale: Scale::Linear,
            },
            toml::Value::Table(_) => value.clone().try_into().map_err(|e: toml::de::Error| {
                let msg = e.message().trim().replace('\n', " ");
                let mut extra = String::new();
                if let Some(rest) = msg.strip_prefix("unknown field `") {
                    if let Some((word, _)) = rest.split_once('`') {
                        extra = hint(word, ["lo", "hi", "value", "unit", "scale"]);
                    }
                }
                bad(&key, format!("{msg}{extra}"))
            })?,
            _ => {
                return Err(bad(
                    &key,
                    "expected a number or a table { lo = .., hi = .. } / { value = .. }".into(),
                ))
            }
        };
        if let Some(unit) = &entry.unit {
            if unit != info.unit {
                return Err(bad(
                    &format!("{key}.unit"),
                    format!(
                        "is \"{unit}\" but {name} is given in \"{}\"{}",
                        info.unit,
                        converted(&entry, unit, info.unit)
                    ),
                ));
            }
        }
        let check = |k: &str, v: f64| -> Result<f64, SweepError> {
            if !v.is_finite() {
                return Err(bad(&format!("{key}.{k}"), format!("{v} is not a finite number")));
            }
            if !info.accepts(v) {
                return Err(bad(&format!("{key}.{k}"), format!("{v} is outside {}", info.domain())));
            }
            Ok(v)
        };
        let kind = match (entry.lo, entry.hi, entry.value) {
            (Some(lo), Some(hi), None) => {
                let (lo, hi) = (check("lo", lo)?, check("hi", hi)?);
                if lo >= hi {
                    return Err(bad(&key, format!("lo = {lo} must be below hi = {hi}")));
                }
                if entry.scale == Scale::Log && lo <= 0.0 {
                    return Err(bad(&format!("{key}.scale"), "log scale needs lo > 0".into()));
                }
                ParamKind::Swept { lo, hi, scale: entry.scale }
            }
            (None, None, Some(v)) => ParamKind::Fixed(check("value", v)?),
            _ => {
                return Err(bad(&key, "expected either both `lo` and `hi` (swept) or `value` (fixed)".into()))
            }
        };
        let param = Parameter { name: name.clone(), unit: info.unit, kind };
        match param.kind {
            ParamKind::Swept { .. } => swept.push(param),
            ParamKind::Fixed(_) => fixed.push(param),
        }
    }
    if swept.is_empty() {
        return Err(bad("parameters", "expected at least one swept parameter { lo, hi }".into()));
    }
    for p in &swept {
        if let Some(why) = crate::scenes::ignored(&file.scene, &p.name) {
            return Err(bad(&format!("parameters.{}", p.name), format!("swept, but {why}")));
        }
    }
    for p in &fixed {
        if let ParamKind::Fixed(v) = p.kind {
            if let Some(why) = crate::scenes::set_but_unread(&file.scene, &p.name, v) {
                return Err(bad(&format!("parameters.{}", p.name), format!("{v}, but {why}")));
            }
        }
    }
    let d = &file.design;
    if d.lattice_levels.is_empty() {
        return Err(bad(
            "design.lattice_levels",
            "expected at least one level, e.g. [5, 6, 7, 9, 10]".into(),
        ));
    }
    // Only the level count here: whether n^d points are too many matters only when a lattice
    // is built (`design::lattice_size`), and an LDS sweep never builds one.
    if let Some(i) = d.lattice_levels.iter().position(|&n| n < 2) {
        return Err(bad(
            &format!("design.lattice_levels[{i}]"),
            format!("{}: expected at least 2 values per dimension", d.lattice_levels[i]),
        ));
    }
    for (key, n) in
        [("design.lds.step", d.lds.step), ("design.lds.max", d.lds.max), ("design.adapt.max", d.adapt.max)]
    {
        crate::design::lds_size(n).map_err(|e| bad(key, format!("{n}: {e}")))?;
    }
    let c = &file.convergence;
    if crate::analysis::convergence::Rule::parse(&c.rule).is_none() {
        return Err(bad(
            "convergence.rule",
            format!("\"{}\": expected \"scaled\", \"any\" or \"all\"", c.rule),
        ));
    }
    if crate::analysis::weights::LatticeWeights::parse(&c.lattice_weights).is_none() {
        return Err(bad(
            "convergence.lattice_weights",
            format!("\"{}\": expected \"trapezoid\" or \"equal\"", c.lattice_weights),
        ));
    }
    if crate::analysis::convergence::judged_statistics(&c.statistics).is_none() {
        return Err(bad(
            "convergence.statistics",
            format!(
                "{:?}: expected one or more of \"mean\", \"std\", \"skewness\", \"kurtosis\"",
                c.statistics
            ),
        ));
    }
    for (k, v) in [("convergence.tolerance", c.tolerance), ("convergence.floor", c.floor)] {
        if !v.is_finite() || v < 0.0 {
            return Err(bad(k, format!("{v}: expected a finite number ≥ 0")));
        }
    }
    if c.hold == 0 {
        return Err(bad("convergence.hold", "expected at least 1".into()));
    }
    let s = &file.scene;
    if !FIDELITIES.contains(&s.fidelity.as_str()) {
        return Err(bad(
            "scene.fidelity",
            format!("\"{}\": expected one of {}", s.fidelity, quoted(&FIDELITIES)),
        ));
    }
    let Some(layout) = crate::scenes::lookup(&s.layout) else {
        return Err(bad(
            "scene.layout",
            format!("\"{}\": expected one of {}", s.layout, quoted(&crate::scenes::names())),
        ));
    };
    // Before the layout's own checks: a key it does not read is not its to judge.
    if let Some(u) = crate::scenes::unread(s) {
        return Err(bad(&format!("scene.{}", u.key), u.to_string()));
    }
    if let Err(e) = layout.check_settings(s) {
        return Err(bad(e.key, e.why));
    }
    if !["rough", "smooth", "powder"].contains(&s.substrate.as_str()) {
        return Err(bad(
            "scene.substrate",
            format!("\"{}\": expected \"rough\", \"smooth\" or \"powder\"", s.substrate),
        ));
    }
    for (k, v) in [
        ("scene.rest_speed", s.rest_speed),
        ("scene.settle_max_s", s.settle_max_s),
        ("scene.supply_factor", s.supply_factor),
        ("scene.rayleigh_fraction", s.rayleigh_fraction),
        ("scene.depth_diameters", s.depth_diameters),
        ("scene.vx_band_diameters", s.vx_band_diameters),
        ("scene.stiffness_factor", s.stiffness_factor),
        ("scene.skin_diameters", s.skin_diameters),
    ] {
        if !v.is_finite() || v <= 0.0 {
            return Err(bad(k, format!("{v}: expected a finite number > 0")));
        }
    }
    if !s.timestep_s.is_finite() || s.timestep_s < 0.0 {
        return Err(bad(
            "scene.timestep_s",
            format!("{}: expected a finite number ≥ 0 (0: off)", s.timestep_s),
        ));
    }
    if s.stiffness_factor > 1.0 {
        return Err(bad(
            "scene.stiffness_factor",
            format!("{}: expected at most 1 (a reduction)", s.stiffness_factor),
        ));
    }
    if s.mesh_cells_across == 0 {
        return Err(bad("scene.mesh_cells_across", "expected at least 1".into()));
    }
    if s.rayleigh_fraction > 1.0 {
        return Err(bad("scene.rayleigh_fraction", format!("{}: expected at most 1", s.rayleigh_fraction)));
    }
    match &s.size_distribution {
        SizeDistributionSpec::Mono => {}
        SizeDistributionSpec::Classes { classes, relative, .. } => {
            check_classes(classes, *relative).map_err(|(k, why)| bad(&k, why))?;
        }
        SizeDistributionSpec::Weibull { bins } => {
            if *bins == 0 || *bins > MAX_CLASSES {
                return Err(bad(
                    "scene.size_distribution.bins",
                    format!("{bins}: expected 1 to {MAX_CLASSES}"),
                ));
            }
        }
        SizeDistributionSpec::Lognormal { d10_um, d50_um, d90_um, cut_um, bins, .. } => {
            check_lognormal([*d10_um, *d50_um, *d90_um], *cut_um, *bins).map_err(|(k, why)| bad(k, why))?;
        }
    }
    if !(s.material_youngs_gpa.is_finite() && s.material_youngs_gpa >= 0.0) {
        return Err(bad(
            "scene.material_youngs_gpa",
            format!(
                "{}: expected the powder's Young's modulus in GPa (e.g. 110 for Ti-6Al-4V)",
                s.material_youngs_gpa
            ),
        ));
    }
    if s.cohesion_scaling == CohesionScaling::Haervig && s.material_youngs_gpa == 0.0 {
        return Err(bad(
            "scene.material_youngs_gpa",
            "not given: cohesion_scaling = \"haervig\" scales the surface energy by the deck's modulus over the powder's (e.g. 110 GPa for Ti-6Al-4V)".into(),
        ));
    }
    if !(file.run.timeout_s.is_finite() && file.run.timeout_s > 0.0) {
        return Err(bad("run.timeout_s", format!("{}: expected seconds > 0", file.run.timeout_s)));
    }
    let r = &file.run;
    if !(r.screen_sample.is_finite() && (0.0..=1.0).contains(&r.screen_sample)) {
        return Err(bad("run.screen_sample", format!("{}: expected a fraction in [0, 1]", r.screen_sample)));
    }
    if r.screen_sample_min == 0 {
        return Err(bad(
            "run.screen_sample_min",
            "0: expected at least 1 (a screen is trusted only once verified; `screen = false` runs every point)"
                .into(),
        ));
    }
    let cl = &file.cluster;
    if let Some(c) = &cl.command {
        if c.trim().is_empty() || c.chars().any(|c| c.is_control() || c.is_whitespace()) {
            return Err(bad(
                "cluster.command",
                format!("{c:?}: expected one command or path, without spaces (e.g. \"sweep\" or \"/opt/bin/sweep\")"),
            ));
        }
    }
    if let Some((i, line)) = cl.prologue.iter().enumerate().find(|(_, l)| l.chars().any(char::is_control)) {
        return Err(bad(
            &format!("cluster.prologue[{i}]"),
            format!("{line:?}: expected one line of shell without control characters (give each line as its own string)"),
        ));
    }
    Ok((swept, fixed))
}

/// Longest sweep name, in bytes: it becomes a directory name (at most 255 bytes on Linux) and
/// the report's title.
pub const MAX_NAME_BYTES: usize = 100;

/// Unicode format characters (category Cf) that change how text around them displays:
/// bidirectional controls, zero-width spaces and joiners, the soft hyphen, the byte-order mark.
fn is_format_char(c: char) -> bool {
    matches!(
        c as u32,
        0x00AD | 0x061C | 0x180E | 0x200B..=0x200F | 0x202A..=0x202E | 0x2060..=0x2064 | 0x2066..=0x206F
            | 0xFEFF | 0xFFF9..=0xFFFB
    )
}

/// Units a value is often written in by mistake, and the factor to the catalogue's unit.
const SLIPS: &[(&str, &str, f64)] = &[
    ("m", "mm", 1e3),
    ("cm", "mm", 10.0),
    ("um", "mm", 1e-3),
    ("µm", "mm", 1e-3),
    ("Pa", "MPa", 1e-6),
    ("GPa", "MPa", 1e3),
    ("mm/s", "m/s", 1e-3),
];

/// For a unit slip with a known factor: `; values are in mm — did you mean lo = 2, hi = 4?`.
fn converted(entry: &ParamEntry, written: &str, wanted: &str) -> String {
    let Some(&(_, _, factor)) = SLIPS.iter().find(|(w, c, _)| *w == written && *c == wanted) else {
        return String::new();
    };
    let show = |v: f64| crate::scene::plausible::show(v * factor);
    let values = match (entry.lo, entry.hi, entry.value) {
        (Some(lo), Some(hi), _) => format!("lo = {}, hi = {}", show(lo), show(hi)),
        (_, _, Some(v)) => format!("value = {}", show(v)),
        _ => return format!("; values are in {wanted}"),
    };
    format!("; values are in {wanted} — did you mean {values}, unit = \"{wanted}\"?")
}

fn as_f64(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// A lognormal's datasheet values in order, its cut around its D50, and a fit that reproduces
/// them (a powder that is not lognormal is given as its measured table instead).
fn check_lognormal(q: [f64; 3], cut: Option<[f64; 2]>, bins: usize) -> Result<(), (&'static str, String)> {
    let [d10, d50, d90] = q;
    if !(q.iter().all(|d| d.is_finite() && *d > 0.0) && d10 < d50 && d50 < d90) {
        return Err((
            "scene.size_distribution",
            format!("d10_um {d10}, d50_um {d50}, d90_um {d90}: expected sizes in µm with D10 < D50 < D90"),
        ));
    }
    if let Some([lo, hi]) = cut {
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo < d50 && d50 < hi) {
            return Err((
                "scene.size_distribution.cut_um",
                format!("[{lo}, {hi}]: expected the sieve cut in µm, below and above D50 {d50}"),
            ));
        }
    }
    if !(2..=MAX_CLASSES).contains(&bins) {
        return Err(("scene.size_distribution.bins", format!("{bins}: expected 2 to {MAX_CLASSES}")));
    }
    let fit = crate::scene::psd::Lognormal::fit(q.map(|d| d * 1e-6), cut.map(|c| c.map(|d| d * 1e-6)));
    if fit.residual > MAX_FIT_MISS {
        return Err((
            "scene.size_distribution",
            format!(
                "D10/D50/D90 {d10}/{d50}/{d90} µm: no lognormal{} within {:.0} % (its best misses by {:.1} %); \
                 give the measured table as `kind = \"classes\"` with `basis = \"volume\"`",
                cut.map(|[lo, hi]| format!(" cut at {lo}–{hi} µm")).unwrap_or_default(),
                MAX_FIT_MISS * 100.0,
                fit.residual * 100.0
            ),
        ));
    }
    Ok(())
}

/// Most size classes a distribution may have: a laser-diffraction table has up to about 100,
/// and each class is a particle template the deck inserts from (10,000 took minutes to plan).
pub const MAX_CLASSES: usize = 100;

/// How far the fractions of a `classes` table may sum from 1 (or from 100, in %): the rounding
/// of a measured table, not a table with classes left out.
const FRACTION_SUM_SLACK: f64 = 0.02;

/// A `classes` table: 1 to [`MAX_CLASSES`] classes of distinct positive diameters (each at least
/// the scene's smallest, 10 µm, unless `relative`), fractions positive and summing to 1 or to 100.
fn check_classes(classes: &[[f64; 2]], relative: bool) -> Result<(), (String, String)> {
    let key = "scene.size_distribution.classes".to_string();
    if classes.is_empty() || classes.len() > MAX_CLASSES {
        return Err((key, format!("{} classes: expected 1 to {MAX_CLASSES}", classes.len())));
    }
    for (i, [dia, frac]) in classes.iter().enumerate() {
        let at = || format!("{key}[{i}]");
        if !(dia.is_finite() && *dia > 0.0 && frac.is_finite() && *frac > 0.0) {
            return Err((at(), format!("[{dia}, {frac}]: expected a positive diameter and fraction")));
        }
        let floor = crate::scene::plausible::MIN_DIAMETER_MM;
        if !relative && *dia < floor {
            return Err((
                at(),
                format!(
                    "[{dia}, {frac}]: diameter {dia} mm is below the {} µm the scene is built for; \
                     diameters are in mm — did you mean {}?",
                    floor * 1e3,
                    dia * 1e3
                ),
            ));
        }
        if let Some(j) = classes[..i].iter().position(|[d, _]| d == dia) {
            return Err((at(), format!("diameter {dia} is also class [{j}]: expected each diameter once")));
        }
    }
    let sum: f64 = classes.iter().map(|[_, f]| f).sum();
    let near = |total: f64| (sum / total - 1.0).abs() <= FRACTION_SUM_SLACK;
    if !near(1.0) && !near(100.0) {
        return Err((
            key,
            format!(
                "fractions sum to {sum}: expected 1 (fractions) or 100 (%) within {} %; a table \
                 with classes left out would be scaled up without a word",
                FRACTION_SUM_SLACK * 100.0
            ),
        ));
    }
    Ok(())
}

/// The largest relative miss of D10/D50/D90 a lognormal fit may leave.
const MAX_FIT_MISS: f64 = 0.05;
