//! Words a user may paste into a shell: a path or a name in a printed command line, quoted so
//! that the shell passes it as one word and expands nothing in it.

use std::borrow::Cow;

/// `word` as one POSIX shell word: unchanged when it holds only characters no shell treats
/// specially (letters, digits, `_ - . / , : = + @ %`), else in single quotes, each `'` in it
/// written `'\''`. `ok name` → `'ok name'`, `*` → `'*'`, `it's` → `'it'\''s'`.
pub fn quote(word: &str) -> Cow<'_, str> {
    let plain = |c: char| c.is_ascii_alphanumeric() || "_-./,:=+@%".contains(c);
    if !word.is_empty() && word.chars().all(plain) {
        Cow::Borrowed(word)
    } else {
        Cow::Owned(format!("'{}'", word.replace('\'', r"'\''")))
    }
}

/// A path as one shell word: [`quote`] of it when it is UTF-8; otherwise bash's `$'…'` with
/// each byte outside printable ASCII written `\xNN`, so that a hint holding a path that is not
/// UTF-8 still names that path (bash, zsh and ksh read it; `display()` would put U+FFFD there).
pub fn quote_path(path: &std::path::Path) -> Cow<'_, str> {
    use std::os::unix::ffi::OsStrExt;
    if let Some(s) = path.to_str() {
        return quote(s);
    }
    let mut out = String::from("$'");
    for &b in path.as_os_str().as_bytes() {
        match b {
            b'\'' | b'\\' => {
                out.push('\\');
                out.push(b as char);
            }
            0x20..=0x7e => out.push(b as char),
            _ => out.push_str(&format!("\\x{b:02x}")),
        }
    }
    out.push('\'');
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `sh` makes of `text`: its words, one per line.
    fn words(text: &str) -> Vec<String> {
        let out = std::process::Command::new("sh")
            .arg("-c")
            .arg(format!("for w in {text}; do printf '%s\\n' \"$w\"; done"))
            .current_dir(std::env::temp_dir())
            .output()
            .unwrap();
        String::from_utf8(out.stdout).unwrap().lines().map(String::from).collect()
    }

    #[test]
    fn the_shell_reads_a_quoted_word_back_as_it_was() {
        for w in ["runs/ok name", "*", "runs/*", "it's", "a\"b", "$HOME", "`id`", "tab\there", "~", "", "ünï"]
        {
            assert_eq!(words(&quote(w)), [w], "{w:?} quoted as {}", quote(w));
        }
        assert_eq!(quote("runs/quick-demo_2.5"), "runs/quick-demo_2.5", "a plain path stays as written");
    }

    #[test]
    fn a_path_that_is_not_utf8_is_quoted_so_that_bash_reads_its_bytes_back() {
        use std::os::unix::ffi::OsStrExt;
        // Issue 70, defect 14: a `next:` hint held U+FFFD where the byte 0xff was.
        let raw: &[u8] = b"runs/caf\xe9 it's\xff";
        let q = quote_path(std::path::Path::new(std::ffi::OsStr::from_bytes(raw)));
        let out =
            std::process::Command::new("bash").arg("-c").arg(format!("printf '%s' {q}")).output().unwrap();
        assert_eq!(out.stdout, raw, "{q}");
        assert_eq!(quote_path(std::path::Path::new("runs/ok name")), "'runs/ok name'");
    }
}
