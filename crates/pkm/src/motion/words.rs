//! The codes and words of one G-code line, into buffers kept from line to line: a
//! plain line (codes, words, a trailing `;` comment: nearly every line) by the
//! one-pass reader of `words/plain.rs`, any other through the `gcode` crate's
//! zero-allocation parser (`gcode::core`'s visitors), both to the same codes and words.
//!
//! `gcode::parse` builds a syntax tree per call: a `Program`, its blocks, their codes
//! and arguments, each a vector of its own, allocated and dropped per line. The crate's
//! own AST builder is a visitor over `gcode::core`; this one records what the
//! interpreter reads (the codes, and each word's letter and source span) and nothing
//! else, with the builder's order and diagnostics: a line is read to the same codes,
//! words and first error as by `gcode::parse` (tested against it).

use gcode::core::{
    BlockVisitor, CommandVisitor, ControlFlow, Diagnostics, HasDiagnostics, Number, ProgramVisitor,
    Span, TokenType, Value,
};

use super::gcode::{err, err_at};
use crate::error::Result;

mod plain;

/// A word as the parser reported it: the letter as written and its source span, or
/// the variable (`X#1`) it names.
#[derive(Debug, Clone)]
enum Raw {
    Number { letter: char, span: Span },
    Variable { letter: char, name: String },
}

/// What one line holds, read by [`LineWords::read`]; the buffers are reused.
#[derive(Default)]
pub(crate) struct LineWords {
    /// The G, M and T codes in order: letter, major number, minor number (`G91.1`).
    pub codes: Vec<(char, u32, Option<u32>)>,
    /// The words in order (a block's code arguments, then its bare words): upper-case
    /// letter and value, re-read from the source text as f64.
    pub words: Vec<(char, f64)>,
    raw: Vec<Raw>,
    bare: Vec<Raw>,
    first_error: Option<String>,
}

// The buffers are scratch space, not state: an interpreter's copy starts empty, and two
// interpreters are equal whatever their buffers hold.
impl Clone for LineWords {
    fn clone(&self) -> Self {
        LineWords::default()
    }
}

impl PartialEq for LineWords {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for LineWords {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LineWords")
    }
}

impl LineWords {
    /// Reads `text`, one source line (1-based number `line`), into [`Self::codes`] and
    /// [`Self::words`]. Errors, naming the line: a G, M or T code number of more than
    /// six digits (`screen.rs`: the crate's `u32` would wrap it to another code), a
    /// comment left open (with its column), the parser's first diagnostic
    /// (`malformed: ...`), a variable, a word whose number is not a finite f64.
    ///
    /// A plain line (`plain.rs`: codes, words and a trailing `;` comment, nearly every
    /// line of a program) is read in one pass over its bytes to the same codes and
    /// words (its codes have at most six digits, so it needs no screen); any other is
    /// screened and goes through the crate.
    pub fn read(&mut self, text: &str, line: u64) -> Result<()> {
        self.codes.clear();
        self.words.clear();
        if plain::read(text.as_bytes(), &mut self.codes, &mut self.words) {
            return Ok(());
        }
        self.codes.clear();
        self.words.clear();
        if let Some(word) = super::gcode::oversized_code(text) {
            return Err(err(
                line,
                format!("`{word}`: a G, M or T code number has at most 6 digits"),
            ));
        }
        if let Some(column) = super::gcode::unclosed_comment(text) {
            return Err(err_at(
                line,
                column,
                "unclosed comment found: `(` without `)`".into(),
            ));
        }
        self.raw.clear();
        self.bare.clear();
        self.first_error = None;
        gcode::core::parse(text, &mut Reader(self));
        if let Some(first) = self.first_error.take() {
            let hint = super::gcode::variable_hint(text);
            return Err(err(line, format!("malformed: {first}{hint}")));
        }
        for raw in &self.raw {
            match raw {
                Raw::Variable { letter, name } => {
                    let l = letter.to_ascii_uppercase();
                    return Err(err(
                        line,
                        format!("{l}#{name}: variables are not supported"),
                    ));
                }
                Raw::Number { letter, span } => {
                    let src = text.get(span.start..span.start + span.length).unwrap_or("");
                    let num = src
                        .trim_start_matches([*letter, letter.to_ascii_lowercase()])
                        .trim();
                    let value = num.parse::<f64>().ok().filter(|v| v.is_finite());
                    let Some(v) = value else {
                        return Err(err(
                            line,
                            format!("`{src}`: expected a number after {letter}"),
                        ));
                    };
                    self.words.push((letter.to_ascii_uppercase(), v));
                }
            }
        }
        Ok(())
    }

    fn word(letter: char, value: Value<'_>, span: Span) -> Raw {
        match value {
            Value::Literal(_) => Raw::Number { letter, span },
            Value::Variable(v) => Raw::Variable {
                letter,
                name: v.to_string(),
            },
        }
    }

    fn code(&mut self, letter: char, number: Number) -> ControlFlow<Command<'_>> {
        self.codes
            .push((letter, number.major(), number.minor().map(|m| m.get())));
        ControlFlow::Continue(Command(self))
    }
}

/// The diagnostics `gcode::parse` collects (unknown content, unexpected tokens), the
/// first one kept in its words.
impl Diagnostics for LineWords {
    fn emit_unknown_content(&mut self, text: &str, _span: Span) {
        if self.first_error.is_none() {
            let kind = gcode::DiagnosticKind::UnknownContent {
                text: text.to_string(),
            };
            self.first_error = Some(kind.to_string());
        }
    }

    fn emit_unexpected(&mut self, actual: &str, expected: &[TokenType], _span: Span) {
        if self.first_error.is_none() {
            let kind = gcode::DiagnosticKind::Unexpected {
                actual: actual.to_string(),
                expected: expected.to_vec(),
            };
            self.first_error = Some(kind.to_string());
        }
    }
}

struct Reader<'a>(&'a mut LineWords);
struct Block<'a>(&'a mut LineWords);
struct Command<'a>(&'a mut LineWords);

impl HasDiagnostics for Reader<'_> {
    fn diagnostics(&mut self) -> &mut dyn Diagnostics {
        self.0
    }
}

impl HasDiagnostics for Block<'_> {
    fn diagnostics(&mut self) -> &mut dyn Diagnostics {
        self.0
    }
}

impl HasDiagnostics for Command<'_> {
    fn diagnostics(&mut self) -> &mut dyn Diagnostics {
        self.0
    }
}

impl ProgramVisitor for Reader<'_> {
    fn start_block(&mut self) -> ControlFlow<impl BlockVisitor + '_> {
        ControlFlow::Continue(Block(&mut *self.0))
    }
}

impl BlockVisitor for Block<'_> {
    // A comment is `;...` or `(...)`; `gcode::parse` reports anything else it is
    // handed as a comment as unexpected, and so does this.
    fn comment(&mut self, value: &str, span: Span) {
        if !value.starts_with([';', '(']) {
            self.0.emit_unexpected(value, &[TokenType::Comment], span);
        }
    }

    fn word_address(&mut self, letter: char, value: Value<'_>, span: Span) {
        self.0.bare.push(LineWords::word(letter, value, span));
    }

    fn start_general_code(&mut self, number: Number) -> ControlFlow<impl CommandVisitor + '_> {
        self.0.code('G', number)
    }

    fn start_miscellaneous_code(
        &mut self,
        number: Number,
    ) -> ControlFlow<impl CommandVisitor + '_> {
        self.0.code('M', number)
    }

    fn start_tool_change_code(&mut self, number: Number) -> ControlFlow<impl CommandVisitor + '_> {
        self.0.code('T', number)
    }

    // A block's bare words follow its codes' arguments, as `gcode::parse`'s blocks
    // are read.
    fn end_line(self, _span: Span) {
        let words = self.0;
        words.raw.append(&mut words.bare);
    }
}

impl CommandVisitor for Command<'_> {
    fn argument(&mut self, letter: char, value: Value<'_>, span: Span) {
        self.0.raw.push(LineWords::word(letter, value, span));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    type Read = (Vec<(char, u32, Option<u32>)>, Vec<(char, f64)>);

    /// The line read from `gcode::parse`'s syntax tree, as the interpreter did before
    /// the visitor: the reference.
    fn from_tree(text: &str, line: u64) -> Result<Read> {
        let program = gcode::parse(text).map_err(|d| {
            let first = d.iter().next().map(|x| x.kind.to_string());
            let hint = crate::motion::gcode::variable_hint(text);
            err(
                line,
                format!("malformed: {}{hint}", first.unwrap_or_default()),
            )
        })?;
        let (mut codes, mut words) = (Vec::new(), Vec::new());
        let value = |span: Span, letter: char| -> Result<f64> {
            let raw = text.get(span.start..span.start + span.length).unwrap_or("");
            let num = raw
                .trim_start_matches([letter, letter.to_ascii_lowercase()])
                .trim();
            num.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(line, format!("`{raw}`: expected a number after {letter}")))
        };
        let word = |letter: char, v: &gcode::Value, span: Span| -> Result<(char, f64)> {
            let l = letter.to_ascii_uppercase();
            if let gcode::Value::Variable(v) = v {
                return Err(err(line, format!("{l}#{v}: variables are not supported")));
            }
            Ok((l, value(span, letter)?))
        };
        for block in &program.blocks {
            for code in &block.codes {
                let (letter, number, args) = match code {
                    gcode::Code::General(g) => ('G', g.number, &g.args),
                    gcode::Code::Miscellaneous(m) => ('M', m.number, &m.args),
                    gcode::Code::ToolChange(t) => ('T', t.number, &t.args),
                    _ => unreachable!("the parser has three kinds of code"),
                };
                codes.push((letter, number.major(), number.minor().map(|m| m.get())));
                for a in args {
                    words.push(word(a.letter, &a.value, a.span)?);
                }
            }
            for w in &block.word_addresses {
                words.push(word(w.letter, &w.value, w.span)?);
            }
        }
        Ok((codes, words))
    }

    fn check(buf: &mut LineWords, text: &str) {
        // Refused before the parser sees them (the crate's code numbers overflow, it
        // takes an open comment to the line's end); a plain line never has one.
        let screened = crate::motion::gcode::oversized_code(text).is_some()
            || crate::motion::gcode::unclosed_comment(text).is_some();
        if screened {
            let (mut c, mut w) = (Vec::new(), Vec::new());
            assert!(!plain::read(text.as_bytes(), &mut c, &mut w), "{text:?}");
            assert!(buf.read(text, 7).is_err(), "{text:?}");
            return;
        }
        let want = from_tree(text, 7).map_err(|e| e.to_string());
        let got = buf
            .read(text, 7)
            .map(|()| (buf.codes.clone(), buf.words.clone()))
            .map_err(|e| e.to_string());
        // Values compare by bits: the same text is parsed the same way.
        let bits = |r: std::result::Result<Read, String>| {
            r.map(|(c, w)| {
                let w: Vec<_> = w.iter().map(|(l, v)| (*l, v.to_bits())).collect();
                (c, w)
            })
        };
        assert_eq!(bits(got), bits(want), "line {text:?}");
    }

    /// Every line of the example programs and of the G-code fuzz corpus, and lines
    /// written to reach each diagnostic, read to the same codes, words and first error
    /// as from `gcode::parse`; the buffers are reused across all of them.
    #[test]
    fn reads_every_line_as_the_syntax_tree_does() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let mut lines: Vec<String> = [
            "G1 X10 Y-2.5 F800",
            "g01 x1.5 y.5 z-.25 a3 b-4 c5",
            "N10 G90 G91.1 G21 (comment) X1 ; end",
            "X5 Y6",
            "X5 G1 Y6",
            "G2 X1 Y0 I0.5 J0 R2 P3",
            "G43 H2 T3 M6 S12000 M3",
            "G1 X#1 Y2",
            "G1 X#<name>",
            "G1 X",
            "G1 X-",
            "G1 X+3",
            "G1 X1e5",
            "G1 X1..2",
            "G1 X99999999999999999999999999999999999999999999999",
            "G1 X3.4028236e38",
            "G1 X5 $$",
            "G1 X5 (unclosed",
            "O100 G0 X1",
            "% G0 X1",
            "N5.5 G1 X1",
            "G0 N3 X1",
            "G1 X1 X2 X3",
            "M428",
            "G1234567 X1",
            "G0000012 X1",
            "X1 M00000030",
            "G59.3 X0",
            "G1\tX1\tY2",
            "  ",
            "\u{e9}G1 X1",
        ]
        .map(String::from)
        .into();
        for dir in ["examples/paths", "fuzz/corpus/gcode"] {
            let mut files: Vec<_> = std::fs::read_dir(root.join(dir))
                .unwrap()
                .map(|e| e.unwrap().path())
                .collect();
            files.sort();
            for f in files {
                let bytes = std::fs::read(&f).unwrap();
                let text = String::from_utf8_lossy(&bytes);
                lines.extend(text.lines().map(String::from));
            }
        }
        assert!(lines.len() > 2000, "{} lines", lines.len());
        let mut buf = LineWords::default();
        for text in &lines {
            check(&mut buf, text);
        }
    }

    /// The lines of the example programs nearly all take the one-pass reading (so the
    /// comparison above is one of the two readers against the crate, not the crate
    /// against itself).
    #[test]
    fn example_programs_are_plain_lines() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paths");
        let (mut plain_lines, mut all) = (0, 0);
        for f in std::fs::read_dir(dir).unwrap() {
            let text = std::fs::read_to_string(f.unwrap().path()).unwrap();
            for l in text.lines().filter(|l| !l.trim().is_empty()) {
                all += 1;
                let (mut c, mut w) = (Vec::new(), Vec::new());
                plain_lines += usize::from(plain::read(l.as_bytes(), &mut c, &mut w));
            }
        }
        assert!(
            all > 100 && plain_lines * 10 > all * 8,
            "{plain_lines} of {all}"
        );
    }

    /// A word of a plain line: a code (`G1`, `g91.1`, `M6`), or a letter other than
    /// G, M, T, N, O with a signed number of 1 to 25 digits (beyond the exact
    /// quotient's 2^53 units and 10^22: the standard library's reading).
    fn plain_word() -> impl Strategy<Value = String> {
        let code =
            ("[GgMmTt]", "[0-9]{1,6}", proptest::option::of("[0-9]")).prop_map(|(l, n, m)| {
                format!("{l}{n}{}", m.map(|m| format!(".{m}")).unwrap_or_default())
            });
        let word = (
            "[A-FH-LPQR-SU-Za-fh-lpqr-su-z]",
            "[+-]?",
            "[0-9]{0,12}",
            proptest::option::of("[0-9]{0,13}"),
        )
            .prop_filter_map("a number has a digit", |(l, s, w, f)| {
                let has_digit = !w.is_empty() || f.as_ref().is_some_and(|f| !f.is_empty());
                let f = f.map(|f| format!(".{f}")).unwrap_or_default();
                has_digit.then(|| format!("{l}{s}{w}{f}"))
            });
        prop_oneof![code, word]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]
        /// Random plain lines (a line number, codes and words glued or apart, a
        /// comment): read in one pass, to what the crate reads.
        #[test]
        fn reads_plain_lines_as_the_syntax_tree_does(
            number in proptest::option::of("N[0-9]{1,9}[ ]?"),
            words in proptest::collection::vec((plain_word(), "[ \t\r]{0,2}"), 0..8),
            comment in proptest::option::of(";[ -~]{0,12}"),
        ) {
            let mut text = number.unwrap_or_default();
            for (w, gap) in words {
                text += &w;
                text += &gap;
            }
            text += &comment.unwrap_or_default();
            let (mut c, mut w) = (Vec::new(), Vec::new());
            prop_assert!(plain::read(text.as_bytes(), &mut c, &mut w), "{text:?}");
            check(&mut LineWords::default(), &text);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]
        /// Random lines of G-code's characters.
        #[test]
        fn reads_random_lines_as_the_syntax_tree_does(
            text in "[GgMmTtXYZABCFIJKRPHNOSEe0-9 .+\\-#;()%<>$\t]{0,40}"
        ) {
            check(&mut LineWords::default(), &text);
        }
    }
}
