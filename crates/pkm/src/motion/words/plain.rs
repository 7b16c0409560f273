//! The common G-code line read in one pass over its bytes, without the `gcode` crate:
//! what CAM systems and pkm's own programs write on nearly every line (`N120 G1
//! X10.5 Y-2 Z.25 A3 F800`, `G1X10Y5`, a trailing `; comment`).
//!
//! A line is *plain* when it is ASCII and made only of
//! - blanks (space, tab, carriage return) between words, or none;
//! - G, M and T codes: the letter directly followed by one to six digits, optionally
//!   a point and one digit (`G91.1`);
//! - a line number (`N` and one to nine digits) before the first code;
//! - words: any other letter but `O`, directly followed by an optional sign and a
//!   number (digits, a point, digits; at least one digit);
//! - a `;` comment to the end.
//!
//! Such a line is read to exactly what [`super::LineWords`] reads through the crate
//! (the same codes, the same words in the same order: a code's arguments, then the
//! words before the first code, which the crate keeps as the block's own), with each
//! number's value the correctly rounded f64 of its decimal text, as `str::parse`
//! gives it. Anything else (parenthesised comments, variables, blanks inside a word,
//! stray signs, `O` numbers, a line number after a code, any error) is not plain: the
//! crate reads it, and reports what is wrong.

/// The powers of ten that f64 holds exactly: a decimal of at most 2^53 units of
/// `10^-k`, `k <= 22`, is the quotient of two exact doubles, and IEEE division rounds
/// it correctly (Clinger's fast path, which `str::parse` takes for the same numbers).
const EXACT_POWERS: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Reads `text` into `codes` and `words` (both empty on entry) when it is a plain
/// line, and says whether it was; when it was not, the buffers hold an unspecified
/// part of it.
pub(super) fn read(
    text: &[u8],
    codes: &mut Vec<(char, u32, Option<u32>)>,
    words: &mut Vec<(char, f64)>,
) -> bool {
    // The number of words before the first code (the block's own words).
    let mut before_codes: Option<usize> = None;
    let mut i = 0;
    while i < text.len() {
        let c = text[i];
        if matches!(c, b' ' | b'\t' | b'\r') {
            i += 1;
            continue;
        }
        if c == b';' {
            // The crate's comment runs to the next newline: a line holding one more
            // is not one line.
            if text[i..].contains(&b'\n') {
                return false;
            }
            break;
        }
        if !c.is_ascii_alphabetic() {
            return false;
        }
        let letter = c.to_ascii_uppercase();
        let at = i + 1;
        let end = match letter {
            b'G' | b'M' | b'T' => {
                let Some((major, minor, end)) = code_number(text, at) else {
                    return false;
                };
                codes.push((char::from(letter), major, minor));
                before_codes.get_or_insert(words.len());
                end
            }
            b'N' if before_codes.is_none() => {
                let digits = digit_run(text, at);
                if !(1..=9).contains(&digits) {
                    return false;
                }
                at + digits
            }
            b'N' | b'O' => return false,
            _ => {
                let Some((value, end)) = signed_number(text, at) else {
                    return false;
                };
                words.push((char::from(letter), value));
                end
            }
        };
        // A word ends at a blank, a comment, the next word or the line's end.
        match text.get(end) {
            None | Some(b' ' | b'\t' | b'\r' | b';') => {}
            Some(c) if c.is_ascii_alphabetic() => {}
            Some(_) => return false,
        }
        i = end;
    }
    if let Some(k) = before_codes {
        words.rotate_left(k);
    }
    true
}

/// The number of ASCII digits from `at`.
fn digit_run(text: &[u8], at: usize) -> usize {
    text.get(at..)
        .unwrap_or_default()
        .iter()
        .take_while(|c| c.is_ascii_digit())
        .count()
}

/// A code's number from `at`: one to six digits, optionally a point and one digit
/// (the crate's `Number`: `G1.0` is `G1`); its major and minor parts and its end.
fn code_number(text: &[u8], at: usize) -> Option<(u32, Option<u32>, usize)> {
    let digits = digit_run(text, at);
    if !(1..=6).contains(&digits) {
        return None;
    }
    let major = text[at..at + digits]
        .iter()
        .fold(0u32, |n, d| n * 10 + u32::from(d - b'0'));
    let end = at + digits;
    if text.get(end) != Some(&b'.') {
        return Some((major, None, end));
    }
    if digit_run(text, end + 1) != 1 {
        return None;
    }
    let minor = u32::from(text[end + 1] - b'0');
    Some((major, (minor != 0).then_some(minor), end + 2))
}

/// A word's value from `at`: an optional sign, digits, a point, digits (at least one
/// digit in all), and its end; `None` when there is no such number or its value is
/// not finite.
fn signed_number(text: &[u8], at: usize) -> Option<(f64, usize)> {
    let sign = usize::from(matches!(text.get(at), Some(b'-' | b'+')));
    let start = at + sign;
    let whole = digit_run(text, start);
    let point = text.get(start + whole) == Some(&b'.');
    let fraction = if point {
        digit_run(text, start + whole + 1)
    } else {
        0
    };
    if whole + fraction == 0 {
        return None;
    }
    let end = start + whole + usize::from(point) + fraction;
    let units = if whole + fraction <= 19 {
        let fraction_digits = if point {
            &text[end - fraction..end]
        } else {
            &[]
        };
        let digits = text[start..start + whole].iter().chain(fraction_digits);
        Some(digits.fold(0u64, |n, d| n * 10 + u64::from(d - b'0')))
    } else {
        None
    };
    let magnitude = match units {
        Some(u) if u <= 1 << 53 && fraction < EXACT_POWERS.len() => {
            // Both exact: the quotient is the correctly rounded decimal.
            u as f64 / EXACT_POWERS[fraction]
        }
        // Rare (more than 15 significant digits): the standard library's reading.
        _ => std::str::from_utf8(&text[start..end]).ok()?.parse().ok()?,
    };
    let value = if text[at] == b'-' {
        -magnitude
    } else {
        magnitude
    };
    value.is_finite().then_some((value, end))
}
