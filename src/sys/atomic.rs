//! Files written whole or not at all: a temporary name beside the target, fsync, rename.
//!
//! A reader (a resuming sweep, a crash) sees the old file or the new one, never half of one.
//! A write that fails removes its temporary; one killed mid-write leaves it, named after its
//! host and process (`.NAME.tmp.HOST.PID.N`), so that the next open of the sweep directory can
//! tell a dead writer's leftovers from a live writer's file ([`temporary_owner`]).

use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// Write `bytes` to `path` atomically.
pub fn write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temporary(path);
    let written = std::fs::File::create(&tmp).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    });
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// A temporary name beside `path`, unique per writer: two threads of one process may write the
/// same file at once.
fn temporary(path: &Path) -> std::path::PathBuf {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    static WRITES: AtomicU64 = AtomicU64::new(0);
    let n = WRITES.fetch_add(1, Ordering::SeqCst);
    dir.join(format!(".{name}.tmp.{}.{}.{n}", host(), std::process::id()))
}

/// Write `value` as pretty JSON (with a final newline) to `path` atomically.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> std::io::Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value)?;
    bytes.push(b'\n');
    write(path, &bytes)
}

/// Write `value` as pretty JSON (with a final newline) to `path` only if no file is there yet:
/// whole or not at all, and never over a file another writer made first (a hard link, which
/// fails where the target exists). `Ok(false)`: one was there.
pub fn create_json<T: serde::Serialize>(path: &Path, value: &T) -> std::io::Result<bool> {
    let mut bytes = serde_json::to_vec_pretty(value)?;
    bytes.push(b'\n');
    let tmp = temporary(path);
    let written = std::fs::File::create(&tmp).and_then(|mut f| {
        f.write_all(&bytes)?;
        f.sync_all()
    });
    let linked = written.and_then(|_| match std::fs::hard_link(&tmp, path) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
        Err(e) => Err(e),
    });
    let _ = std::fs::remove_file(&tmp);
    linked
}

fn host() -> &'static str {
    static HOST: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    // A dot in a host name would be read back as a field separator.
    HOST.get_or_init(|| crate::sys::host::hostname().replace('.', "_"))
}

/// The writer of a temporary file of [`write`], from its name: host (`None` for the older
/// `.NAME.tmp.PID.N` form) and pid. `None` when `name` is not such a temporary.
pub fn temporary_owner(name: &str) -> Option<(Option<&str>, u32)> {
    let rest = &name[name.strip_prefix('.')?.find(".tmp.")? + 1 + ".tmp.".len()..];
    let fields: Vec<&str> = rest.split('.').collect();
    fields.last()?.parse::<u64>().ok()?;
    match fields[..] {
        [pid, _] => Some((None, pid.parse().ok()?)),
        [ref h @ .., pid, _] if !h.is_empty() => {
            let host_len = rest.len() - pid.len() - fields.last()?.len() - 2;
            Some((Some(&rest[..host_len]), pid.parse().ok()?))
        }
        _ => None,
    }
}

/// This host as [`write`] names it in temporaries.
pub fn temporary_host() -> &'static str {
    host()
}

#[cfg(test)]
mod tests {
    #[test]
    fn replaces_the_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.json");
        super::write(&path, b"old").unwrap();
        super::write(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn create_json_never_replaces_a_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.json");
        assert!(super::create_json(&path, &1).unwrap());
        assert!(!super::create_json(&path, &2).unwrap());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "1\n");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_failed_write_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        // Renaming a file onto a non-empty directory fails after the temporary is written.
        let target = dir.path().join("t");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("x"), "").unwrap();
        assert!(super::write(&target, b"data").is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn temporaries_name_their_writer() {
        use super::temporary_owner as owner;
        assert_eq!(owner(".result.json.tmp.node-1.4242.7"), Some((Some("node-1"), 4242)));
        assert_eq!(owner(".failure.json.tmp.4242.0"), Some((None, 4242)));
        assert_eq!(owner("result.json"), None);
        assert_eq!(owner(".result.json.tmp.x"), None);
        let name = format!(".m.tmp.{}.{}.0", super::host(), std::process::id());
        assert_eq!(owner(&name), Some((Some(super::host()), std::process::id())));
    }
}
