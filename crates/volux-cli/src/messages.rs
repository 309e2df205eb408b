//! The one sanitizer every error and warning line goes through before it is printed: a
//! message may quote a hostile file (a name, a header field), so it must not drive the
//! terminal, span lines or flood it.

/// The longest line printed, in characters (the ellipsis included).
pub const MAX_LINE: usize = 300;
/// Runs of more digits than this are shortened.
pub const MAX_DIGITS: usize = 24;
/// The digits kept at the start of a shortened run.
const KEPT_DIGITS: usize = 12;

/// `text` made safe to print as one line: control characters (C0 but the line breaks and
/// tabs, DEL, C1) and bidirectional overrides escaped (`\x1b`, `\u{202e}`), line breaks and
/// tabs turned into spaces, runs of more than [`MAX_DIGITS`] digits shortened
/// (`123456789012…(300 digits)`), and the whole capped at [`MAX_LINE`] characters with an
/// ellipsis.
pub fn sanitize(text: &str) -> String {
    cap(&shorten_digit_runs(&escape_controls(text)), MAX_LINE)
}

/// Whether `c` reorders text on a terminal (bidirectional embeddings, overrides, isolates,
/// marks).
fn is_bidi_control(c: char) -> bool {
    matches!(c, '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

/// Escapes control characters and turns line breaks (`\r\n` counts as one) and tabs into
/// spaces.
fn escape_controls(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\r' if chars.peek() == Some(&'\n') => {}
            '\n' | '\r' | '\t' => out.push(' '),
            c if c.is_control() => out.push_str(&format!("\\x{:02x}", u32::from(c))),
            c if is_bidi_control(c) => out.push_str(&format!("\\u{{{:x}}}", u32::from(c))),
            c => out.push(c),
        }
    }
    out
}

/// Shortens every run of more than [`MAX_DIGITS`] ASCII digits to its first digits, an
/// ellipsis and its length.
fn shorten_digit_runs(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut run = String::new();
    for c in text.chars() {
        if c.is_ascii_digit() {
            run.push(c);
            continue;
        }
        flush_digits(&mut out, &mut run);
        out.push(c);
    }
    flush_digits(&mut out, &mut run);
    out
}

/// Appends the digit run `run` to `out` (shortened if long) and empties it.
fn flush_digits(out: &mut String, run: &mut String) {
    if run.len() > MAX_DIGITS {
        out.push_str(&run[..KEPT_DIGITS]);
        out.push_str(&format!("…({} digits)", run.len()));
    } else {
        out.push_str(run);
    }
    run.clear();
}

/// `text` cut to at most `max` characters, the last being an ellipsis when it was cut.
fn cap(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        return text.to_string();
    }
    let mut out: String = text.chars().take(max.saturating_sub(1)).collect();
    out.push('…');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_messages_pass_unchanged() {
        let m = "cannot read 'a b.raw': the gradient volume needs 8.0 GiB (2^30 voxels, 42 ms)";
        assert_eq!(sanitize(m), m);
        assert_eq!(sanitize(""), "");
        assert_eq!(sanitize("Zürich ✓"), "Zürich ✓");
    }

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(sanitize("a\u{1b}[31mred"), "a\\x1b[31mred");
        assert_eq!(
            sanitize("nul\0 del\u{7f} bel\u{7}"),
            "nul\\x00 del\\x7f bel\\x07"
        );
        assert_eq!(sanitize("c1\u{9b}2J"), "c1\\x9b2J");
        assert_eq!(sanitize("evil\u{202e}txt.exe"), "evil\\u{202e}txt.exe");
    }

    #[test]
    fn line_breaks_become_spaces() {
        assert_eq!(
            sanitize("one\ntwo\r\nthree\rfour\tfive"),
            "one two three four five"
        );
        assert!(!sanitize("a\n\n\nb").contains('\n'));
    }

    #[test]
    fn long_digit_runs_are_shortened() {
        let n = "9".repeat(300);
        assert_eq!(
            sanitize(&format!("value {n} too large")),
            "value 999999999999…(300 digits) too large"
        );
        let ok = "1".repeat(MAX_DIGITS);
        assert_eq!(sanitize(&ok), ok);
        assert_eq!(sanitize(&"1".repeat(25)), "111111111111…(25 digits)");
    }

    #[test]
    fn lines_are_capped_with_an_ellipsis() {
        let long = "é".repeat(1000);
        let s = sanitize(&long);
        assert_eq!(s.chars().count(), MAX_LINE);
        assert!(s.ends_with('…'));
        let escaped = sanitize(&"\u{1b}".repeat(400));
        assert_eq!(escaped.chars().count(), MAX_LINE);
        assert_eq!(sanitize(&"x".repeat(MAX_LINE)), "x".repeat(MAX_LINE));
    }
}
