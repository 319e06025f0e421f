//! Messages on stderr are one line each, whatever a scene file, an extension name or a path on
//! the command line holds: every error and warning passes through [`one_line`], which escapes
//! control characters (a newline or an ANSI escape in a URI cannot print a second
//! `penumbra: error:` line or recolour the terminal).

use std::borrow::Cow;

/// `text` with each control character (C0, DEL, C1) written as Rust writes it in a string
/// literal: `\n`, `\r`, `\t`, `\u{1b}`.
pub fn one_line(text: &str) -> Cow<'_, str> {
    if !text.chars().any(char::is_control) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

/// Prints `penumbra: {kind}: {text}` on stderr as one line.
pub fn print(kind: &str, text: &str) {
    eprintln!("penumbra: {kind}: {}", one_line(text));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_and_the_rest_kept() {
        assert_eq!(one_line("plain ü π"), "plain ü π");
        assert!(matches!(one_line("plain"), Cow::Borrowed(_)));
        assert_eq!(
            one_line("a\nb\r\tc\u{1b}[31md\u{7f}\u{85}"),
            "a\\nb\\r\\tc\\u{1b}[31md\\u{7f}\\u{85}"
        );
    }
}
