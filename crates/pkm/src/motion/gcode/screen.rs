//! What the program's text is checked for around the `gcode` crate's reading: code
//! numbers too long for the crate's `u32` (which would wrap to another code), a
//! comment left open (which the crate takes to the line's end), and the hints for a
//! number written with an exponent and for a variable.

/// When a word `E` follows a digit directly (`F1e300`), the writer meant an exponent,
/// which G-code numbers do not have: the hint to add to the "unsupported word" error.
pub(super) fn exponent_hint(text: &str) -> &'static str {
    let b = text.as_bytes();
    let glued = (1..b.len()).any(|i| {
        b[i].eq_ignore_ascii_case(&b'e') && b[i - 1].is_ascii_digit() && {
            let next = b.get(i + 1).copied().unwrap_or(b' ');
            next.is_ascii_digit() || next == b'-' || next == b'+'
        }
    });
    if glued {
        " (G-code numbers have no exponent: `1e300` reads as 1 and a word E300; write the \
         number out)"
    } else {
        ""
    }
}

/// When a word's letter is followed by `#` (`X#1`, `Z#<depth>`), outside comments,
/// the writer used a variable, which the parser reports only as a letter without a
/// number: the hint to add to that error, naming the first such word as written.
pub(crate) fn variable_hint(text: &str) -> String {
    let b = text.as_bytes();
    let mut depth = 0usize;
    for (i, &c) in b.iter().enumerate() {
        match c {
            b';' if depth == 0 => break,
            b'(' => depth += 1,
            b')' => depth = depth.saturating_sub(1),
            b'#' if depth == 0 && i > 0 && b[i - 1].is_ascii_alphabetic() => {
                // The word: its letter, `#` and what follows up to a blank or comment.
                let end = b[i..]
                    .iter()
                    .position(|c| matches!(c, b' ' | b'\t' | b'\r' | b';' | b'('))
                    .map_or(b.len(), |k| i + k);
                let word = String::from_utf8_lossy(&b[i - 1..end]);
                return format!(
                    " (`{word}` is a variable: G-code variables are not supported; write the \
                     value)"
                );
            }
            _ => {}
        }
    }
    String::new()
}

/// The first G, M or T code whose number has more than six digits before its point
/// (leading zeros aside), outside comments. The `gcode` crate multiplies the number by
/// ten in a `u32`: `G2147483649` wraps to `G1` in a release build (a silent move) and
/// panics in a checked one, so such a word is refused before it gets there.
pub(crate) fn oversized_code(text: &str) -> Option<String> {
    let b = text.as_bytes();
    // Such a number is a run of seven digits or more: a line without one (nearly every
    // line) is settled by one pass over its bytes.
    let mut run = 0u32;
    let mut longest = 0u32;
    for &c in b {
        run = if c.is_ascii_digit() { run + 1 } else { 0 };
        longest = longest.max(run);
    }
    if longest <= 6 {
        return None;
    }
    let mut i = 0;
    let mut depth = 0usize;
    while i < b.len() {
        match b[i] {
            b';' if depth == 0 => return None,
            b'(' => depth += 1,
            b')' => depth = depth.saturating_sub(1),
            c if depth == 0 && matches!(c.to_ascii_uppercase(), b'G' | b'M' | b'T') => {
                let start = i;
                let mut j = i + 1;
                while j < b.len() && (b[j] == b' ' || b[j] == b'\t' || b[j] == b'+') {
                    j += 1;
                }
                while j < b.len() && b[j] == b'0' {
                    j += 1;
                }
                let digits = b[j..].iter().take_while(|c| c.is_ascii_digit()).count();
                if digits > 6 {
                    let end = j + digits;
                    return Some(text[start..end].to_string());
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// The 1-based column (in characters) of a `(` that opens a comment the line never
/// closes, outside a `;` comment. The crate reads `G1 X1 (feed` as a move with a
/// comment; a controller refuses it (LinuxCNC: "Unclosed comment found"), since the
/// writer meant something the line lost.
pub(crate) fn unclosed_comment(text: &str) -> Option<usize> {
    let mut open = None;
    for (i, c) in text.char_indices() {
        match c {
            ';' if open.is_none() => return None,
            '(' if open.is_none() => open = Some(i),
            ')' => open = None,
            _ => {}
        }
    }
    open.map(|i| text[..i].chars().count() + 1)
}
