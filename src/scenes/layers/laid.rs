//! A laid dose (`scene.laid_dose`): the dose pass [`TEMPLATE_PASS`] let come to rest in front of
//! the blade is dumped by that pass's deck ([`DOSE_DUMP`]) and laid again, a layer higher a pass,
//! before every later pass — no fall, no wait for it to settle.
//!
//! LIGGGHTS 3.8 lays it with `read_dump … add yes`, which adds only the dump's atoms whose IDs
//! no atom holds (read_dump.cpp, `process_atoms`): on a loose bed pass 2's dose lies on the plate
//! under its own IDs, so the dump is copied with IDs above any the run will reach
//! ([`LAID_DOSE`]; the new atoms get fresh ones, `tag_extend`).

use std::path::Path;

use crate::sys::atomic::write;

/// The pass whose dose, at rest before its blade starts, every later pass lays again (the first
/// dose also fills the clearance: it is not the others').
pub const TEMPLATE_PASS: usize = 2;

/// The dump pass [`TEMPLATE_PASS`]'s deck writes of the powder beside the plate.
pub const DOSE_DUMP: &str = "dump.dose";

/// That dump with IDs no atom of the run holds, read by every later pass's deck.
pub const LAID_DOSE: &str = "dose.laid";

/// Added to every ID of the dump: above any ID a run reaches (a point inserts at most a few
/// hundred thousand atoms), and with the dose below LIGGGHTS's largest ID, 2³¹ − 1.
const ID_OFFSET: u64 = 1_000_000_000;

/// Write [`LAID_DOSE`] in `run_dir` from [`DOSE_DUMP`], unless it is there.
pub fn ready(run_dir: &Path) -> Result<(), String> {
    let laid = run_dir.join(LAID_DOSE);
    if laid.is_file() {
        return Ok(());
    }
    let dump = run_dir.join(DOSE_DUMP);
    let text = std::fs::read_to_string(&dump).map_err(|e| {
        format!(
            "cannot read {} (pass {TEMPLATE_PASS}'s dose, laid again by every later pass): {e}",
            dump.display()
        )
    })?;
    let copy = renumbered(&text).map_err(|why| format!("{}: {why}", dump.display()))?;
    write(&laid, copy.as_bytes()).map_err(|e| format!("cannot write {}: {e}", laid.display()))
}

/// A LIGGGHTS dump of one snapshot at step 0 with every atom's ID (the first column) raised by
/// [`ID_OFFSET`]. `Err`: it is not one whole snapshot with IDs first.
pub fn renumbered(text: &str) -> Result<String, String> {
    let lines: Vec<&str> = text.lines().collect();
    let at = |item: &str| lines.iter().position(|l| l.starts_with(item));
    let (Some(step), Some(count), Some(atoms)) =
        (at("ITEM: TIMESTEP"), at("ITEM: NUMBER OF ATOMS"), at("ITEM: ATOMS"))
    else {
        return Err("expected a LIGGGHTS dump (ITEM: TIMESTEP, NUMBER OF ATOMS, ATOMS)".into());
    };
    if !lines[atoms].starts_with("ITEM: ATOMS id ") {
        return Err(format!("expected the atoms' IDs in the first column, found \"{}\"", lines[atoms]));
    }
    let n: usize = lines
        .get(count + 1)
        .and_then(|l| l.trim().parse().ok())
        .ok_or("expected the number of atoms after ITEM: NUMBER OF ATOMS")?;
    let rows = &lines[atoms + 1..];
    if rows.len() != n {
        return Err(format!("{n} atoms announced, {} listed", rows.len()));
    }
    let mut out = String::new();
    for (i, l) in lines[..=atoms].iter().enumerate() {
        out.push_str(if i == step + 1 { "0" } else { l });
        out.push('\n');
    }
    for row in rows {
        let (id, rest) =
            row.trim().split_once(' ').ok_or_else(|| format!("a row without columns: \"{row}\""))?;
        let id: u64 = id.parse().map_err(|_| format!("an ID that is not a whole number: \"{id}\""))?;
        out.push_str(&format!("{} {rest}\n", ID_OFFSET + id));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DUMP: &str = "ITEM: TIMESTEP\n596118\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff pp ff\n0 1\n0 1\n0 1\n\
ITEM: ATOMS id type x y z radius mass density\n1041 1 0.1 0.2 0.3 1e-05 1e-11 4430\n7 1 0.4 0.5 0.6 2e-05 8e-11 4430\n";

    #[test]
    fn the_dose_is_copied_at_step_0_with_every_id_out_of_the_run_s_reach() {
        let copy = renumbered(DUMP).unwrap();
        let lines: Vec<&str> = copy.lines().collect();
        assert_eq!(lines[1], "0");
        assert_eq!(lines[9], "1000001041 1 0.1 0.2 0.3 1e-05 1e-11 4430");
        assert_eq!(lines[10], "1000000007 1 0.4 0.5 0.6 2e-05 8e-11 4430");
        // Everything but the step and the IDs is the dump's.
        assert_eq!(lines[2..9], DUMP.lines().collect::<Vec<_>>()[2..9]);
        assert!(ID_OFFSET + 1_000_000 < i32::MAX as u64);
    }

    #[test]
    fn a_cut_or_foreign_dump_is_refused_saying_what_was_expected() {
        let cut = DUMP.rsplit_once("7 1").unwrap().0;
        assert!(renumbered(cut).unwrap_err().contains("2 atoms announced, 1 listed"));
        assert!(renumbered("hello").unwrap_err().contains("expected a LIGGGHTS dump"));
        let no_id = DUMP.replace("ATOMS id type", "ATOMS type id");
        assert!(renumbered(&no_id).unwrap_err().contains("IDs in the first column"));
    }

    #[test]
    fn ready_writes_the_copy_once_and_says_which_dump_is_missing() {
        let dir = tempfile::tempdir().unwrap();
        let err = ready(dir.path()).unwrap_err();
        assert!(err.contains(DOSE_DUMP) && err.contains("pass 2"), "{err}");
        assert!(!dir.path().join(LAID_DOSE).exists());
        std::fs::write(dir.path().join(DOSE_DUMP), DUMP).unwrap();
        ready(dir.path()).unwrap();
        let first = std::fs::read_to_string(dir.path().join(LAID_DOSE)).unwrap();
        assert!(first.contains("1000001041"));
        // A resumed point keeps the copy it laid before.
        std::fs::write(dir.path().join(DOSE_DUMP), "changed").unwrap();
        ready(dir.path()).unwrap();
        assert_eq!(std::fs::read_to_string(dir.path().join(LAID_DOSE)).unwrap(), first);
    }
}
