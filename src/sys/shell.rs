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
}
