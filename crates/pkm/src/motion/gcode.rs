//! A modal G-code interpreter over the `gcode` crate's parser.
//!
//! Supported (any other G code or word is an error naming its line, never skipped):
//! G0, G1, G2, G3 (I J K and R forms, full circles, helical arcs, P turns), G4 (dwell,
//! P seconds), G17/G18/G19, G20/G21, G90/G91, G90.1/G91.1, G93 (inverse time: `F` is
//! the reciprocal of the move's duration in minutes, on every feed move) and G94 (F
//! per minute), X Y Z A B C, N line numbers, comments, `%` delimiters (a second `%`
//! ends the program), G54-G59, G59.1-G59.3 (work offsets, added to the program's
//! coordinates; zero unless [`Interpreter::work_offsets`] sets them), G53 (machine
//! coordinates for its line), G43 H / G43 (tool length of tool H, or of the tool in
//! the spindle) and G49 (cancel; reported as [`ToolEvent`]s for the caller to apply),
//! G40 (cutter compensation off), T and M6 (tool change), M0/M1/M2/M30/M3/M4/M5/M7/
//! M8/M9 with S (no kinematic effect). Other M codes (a controller's own, such as
//! LinuxCNC's remapped M428) are accepted with a note ([`Interpreter::notes`]).
//! A line LinuxCNC refuses is refused with its line and column: a word twice, two
//! codes of one modal group, a comment left open (`gcode/groups.rs`, `screen.rs`).
//! Numbers are re-read from the source text as f64 (the parser reads f32); the parser
//! runs through its zero-allocation visitors (`motion/words.rs`).
//!
//! Lines are interpreted one at a time ([`Interpreter::line`]), so a program of any
//! length streams with flat memory.

use nalgebra::Vector3;

use super::words::LineWords;
use crate::error::{Error, Result};

mod apply;
mod arc;
mod groups;
mod screen;
pub use arc::plane_axes;
use screen::exponent_hint;
pub(super) use screen::{oversized_code, unclosed_comment, variable_hint};

/// Active plane for arcs: in-plane axes `(e1, e2)` and normal `e1 x e2`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    /// G17: X, Y; normal Z.
    XY,
    /// G18: Z, X; normal Y.
    ZX,
    /// G19: Y, Z; normal X.
    YZ,
}

impl Plane {
    /// Indices of the first in-plane axis, second in-plane axis and normal.
    pub fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::XY => (0, 1, 2),
            Plane::ZX => (2, 0, 1),
            Plane::YZ => (1, 2, 0),
        }
    }
}

/// What a line asks the machine to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// G0 or G1 to `end`.
    Line {
        /// G0.
        rapid: bool,
    },
    /// G2/G3 about `centre` in `plane`, signed sweep (rad; positive = G3).
    Arc {
        /// Centre (mm), in the plane of the start point.
        centre: Vector3<f64>,
        /// Plane.
        plane: Plane,
        /// Signed sweep (rad).
        sweep: f64,
    },
    /// G4: stay for `seconds`.
    Dwell {
        /// Duration (s).
        seconds: f64,
    },
}

/// One move of the program, in mm, rad and mm/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GMove {
    /// 1-based source line.
    pub line: u64,
    /// Start `[X, Y, Z, A, B, C]` (mm, rad).
    pub start: [f64; 6],
    /// End `[X, Y, Z, A, B, C]`.
    pub end: [f64; 6],
    /// What kind of move.
    pub motion: Motion,
    /// Programmed feed (mm/s), for G1-G3 in G94.
    pub feed: Option<f64>,
    /// Programmed duration (s), for G1-G3 in G93 (inverse time).
    pub duration: Option<f64>,
}

/// A change of the tool length a program asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ToolEvent {
    /// G43: apply the length of tool `h` (`H` word, or the tool in the spindle).
    Apply {
        /// Tool number.
        h: u32,
        /// Line.
        line: u64,
    },
    /// G49: no tool length.
    Cancel {
        /// Line.
        line: u64,
    },
}

/// The most notes an interpreter keeps ([`Interpreter::notes`]); later ones are counted.
pub const MAX_NOTES: usize = 100;

/// Modal state.
#[derive(Debug, Clone, PartialEq)]
pub struct Interpreter {
    /// Current `[X, Y, Z, A, B, C]` (mm, rad).
    pub position: [f64; 6],
    /// Active plane.
    pub plane: Plane,
    /// G90 (true) or G91.
    pub absolute: bool,
    /// G90.1 (true) or G91.1 (default) for I, J, K.
    pub arc_absolute: bool,
    /// G20 (true: inches) or G21.
    pub inches: bool,
    /// Feed (mm/s).
    pub feed: Option<f64>,
    /// Modal motion: 0, 1, 2 or 3.
    pub mode: Option<u32>,
    /// M2/M30 seen, or the closing `%`.
    pub ended: bool,
    /// G93 (true: inverse time) or G94.
    pub inverse_time: bool,
    /// Work offsets of G54, G55, ..., G59, G59.1, G59.2, G59.3 (mm, rad), added to the
    /// program's coordinates.
    pub work_offsets: [[f64; 6]; 9],
    /// The active work offset (0 = G54).
    pub work: usize,
    /// The tool in the spindle (last `T` before `M6`).
    pub tool: Option<u32>,
    /// `T` selected, not yet changed.
    pub selected: Option<u32>,
    /// A tool length change of the last line, for the caller to apply.
    pub tool_event: Option<ToolEvent>,
    /// What the program asked for that pkm took note of without acting on (line,
    /// text): unknown M codes, tool changes. At most [`MAX_NOTES`].
    pub notes: Vec<(u64, String)>,
    /// Notes beyond [`MAX_NOTES`].
    pub notes_dropped: u64,
    percents: u32,
    /// The last line's codes and words (buffers reused from line to line).
    words: LineWords,
}

/// The error of G-code line `line`: `message` under "G-code line N".
pub(super) fn err(line: u64, message: String) -> Error {
    Error::InvalidInput {
        what: format!("G-code line {line}"),
        message,
    }
}

/// The error of G-code line `line` at `column` (1-based, in characters): `message`
/// under "G-code line N, column C".
pub(super) fn err_at(line: u64, column: usize, message: String) -> Error {
    Error::InvalidInput {
        what: format!("G-code line {line}, column {column}"),
        message,
    }
}

const TWO_PI: f64 = std::f64::consts::TAU;

impl Interpreter {
    /// A program starting at `position` (mm, rad), G17 G21 G90 G91.1, no feed.
    pub fn new(position: [f64; 6]) -> Self {
        Interpreter {
            position,
            plane: Plane::XY,
            absolute: true,
            arc_absolute: false,
            inches: false,
            feed: None,
            mode: None,
            ended: false,
            inverse_time: false,
            work_offsets: [[0.0; 6]; 9],
            work: 0,
            tool: None,
            selected: None,
            tool_event: None,
            notes: Vec::new(),
            notes_dropped: 0,
            percents: 0,
            words: LineWords::default(),
        }
    }

    /// Adds a note (line, text), at most [`MAX_NOTES`] (later ones are counted).
    pub fn note(&mut self, line: u64, text: String) {
        if self.notes.len() < MAX_NOTES {
            self.notes.push((line, text));
        } else {
            self.notes_dropped += 1;
        }
    }

    /// Interprets one source line (1-based number `line`); returns its move, if any.
    pub fn line(&mut self, text: &str, line: u64) -> Result<Option<GMove>> {
        // A UTF-8 byte-order mark (editors on Windows write one) is not content.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        self.tool_event = None;
        if text.trim_start().starts_with('%') {
            // The program is between two `%` lines; the second ends it.
            self.percents += 1;
            if self.percents >= 2 {
                self.ended = true;
            }
            return Ok(None);
        }
        if text.trim().is_empty() {
            return Ok(None);
        }
        let mut read = std::mem::take(&mut self.words);
        let r = read.read(text, line).and_then(|()| {
            let glued_exponent =
                read.words.iter().any(|w| w.0 == 'E') && !exponent_hint(text).is_empty();
            groups::check(&read.codes, &read.words, text, line)?;
            self.apply(&read.codes, &read.words, line)
                .map_err(|e| match e {
                    Error::InvalidInput { what, message }
                        if glued_exponent && message.starts_with("unsupported word E") =>
                    {
                        Error::InvalidInput {
                            what,
                            message: format!("{message}{}", exponent_hint(text)),
                        }
                    }
                    e => e,
                })
        });
        self.words = read;
        r
    }
}
