//! Disk-space diagnostics: whether a file system is nearly full, and an I/O error told with
//! the device and mount point it happened on.

use std::fs;
use std::path::{Path, PathBuf};

/// Free space under which a failed run is taken for one that ran out of disk: LIGGGHTS does
/// not check its writes, so a full disk shows up as a cut-off dump or log, not as an error.
pub const LOW_SPACE: u64 = 64 * 1024;

/// Whether the file system holding `path` has less than [`LOW_SPACE`] left for us (counting
/// the blocks reserved for root when we are root).
pub fn low_on_space(path: &Path) -> bool {
    use std::os::unix::ffi::OsStrExt;
    let Ok(c) = std::ffi::CString::new(path.as_os_str().as_bytes()) else { return false };
    // SAFETY: statvfs(3) fills the struct we pass for a NUL-terminated path.
    let mut st: libc::statvfs = unsafe { std::mem::zeroed() };
    if unsafe { libc::statvfs(c.as_ptr(), &mut st) } != 0 {
        return false;
    }
    // SAFETY: geteuid cannot fail.
    let blocks = if unsafe { libc::geteuid() } == 0 { st.f_bfree } else { st.f_bavail };
    (blocks as u64).saturating_mul(st.f_frsize as u64) < LOW_SPACE
}

/// `ENOSPC` or `EDQUOT`.
pub fn is_no_space(e: &std::io::Error) -> bool {
    matches!(e.raw_os_error(), Some(libc::ENOSPC) | Some(libc::EDQUOT))
}

/// "no space left on /dev/sdb1 (/scratch) while writing PATH" for a full file system, else
/// "PATH: the OS error".
pub fn describe_io(path: &Path, e: &std::io::Error) -> String {
    let what = match e.raw_os_error() {
        Some(libc::ENOSPC) => "no space left",
        Some(libc::EDQUOT) => "disk quota exceeded",
        _ => return format!("{}: {e}", path.display()),
    };
    let on = match mount_of(path) {
        Some((source, mount)) => format!("{source} ({})", mount.display()),
        None => "the device".into(),
    };
    format!("{what} on {on} while writing {}", path.display())
}

/// The file system holding `path`: its source (device) and mount point, from
/// `/proc/self/mountinfo` (the longest mount point that contains the path).
fn mount_of(path: &Path) -> Option<(String, PathBuf)> {
    let abs = path.ancestors().find_map(|p| fs::canonicalize(p).ok())?;
    let info = fs::read_to_string("/proc/self/mountinfo").ok()?;
    // "36 35 98:0 /mnt1 /mnt/parent rw,noatime master:1 - ext3 /dev/root rw,errors=continue"
    let unescape = |s: &str| s.replace("\\040", " ").replace("\\011", "\t").replace("\\134", "\\");
    info.lines()
        .filter_map(|l| {
            let (left, right) = l.split_once(" - ")?;
            let mount = PathBuf::from(unescape(left.split(' ').nth(4)?));
            let source = unescape(right.split(' ').nth(1)?);
            abs.starts_with(&mount).then_some((source, mount))
        })
        .max_by_key(|(_, m)| m.components().count())
}
