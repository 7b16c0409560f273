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
//! Numbers are re-read from the source text as f64 (the parser reads f32); the parser
//! runs through its zero-allocation visitors (`motion/words.rs`).
//!
//! Lines are interpreted one at a time ([`Interpreter::line`]), so a program of any
//! length streams with flat memory.

use nalgebra::Vector3;

use super::words::LineWords;
use crate::error::{Error, Result};

mod arc;
mod screen;
pub use arc::plane_axes;
use screen::exponent_hint;
pub(super) use screen::{oversized_code, variable_hint};

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

    fn apply(
        &mut self,
        codes: &[(char, u32, Option<u32>)],
        words: &[(char, f64)],
        line: u64,
    ) -> Result<Option<GMove>> {
        let mut dwell = false;
        let mut machine_coords = false;
        let mut g43 = false;
        let mut m6 = false;
        for (letter, major, minor) in codes {
            match (letter, major, minor) {
                ('G', 93, None) => self.inverse_time = true,
                ('G', 94, None) => self.inverse_time = false,
                ('G', 54..=59, None) => self.work = (*major - 54) as usize,
                ('G', 59, Some(k @ 1..=3)) => self.work = 5 + *k as usize,
                ('G', 53, None) => machine_coords = true,
                ('G', 43, None) => g43 = true,
                ('G', 49, None) => self.tool_event = Some(ToolEvent::Cancel { line }),
                ('G', 40, None) => {}
                ('M', 6, None) => m6 = true,
                ('M', 7..=9, None) => {}
                ('T', t, None) => self.selected = Some(*t),
                ('M', m, None) if !matches!(m, 0..=5 | 30) => {
                    self.note(
                        line,
                        format!(
                            "M{m}: not a code pkm knows (a controller's own); no motion, ignored"
                        ),
                    );
                }
                ('G', 0..=3, None) => self.mode = Some(*major),
                ('G', 4, None) => dwell = true,
                ('G', 17, None) => self.plane = Plane::XY,
                ('G', 18, None) => self.plane = Plane::ZX,
                ('G', 19, None) => self.plane = Plane::YZ,
                ('G', 20, None) => self.inches = true,
                ('G', 21, None) => self.inches = false,
                ('G', 90, None) => self.absolute = true,
                ('G', 91, None) => self.absolute = false,
                ('G', 90, Some(1)) => self.arc_absolute = true,
                ('G', 91, Some(1)) => self.arc_absolute = false,
                ('M', 2 | 30, None) => self.ended = true,
                ('M', 0 | 1 | 3 | 4 | 5, None) => {}
                _ => {
                    let code = match minor {
                        Some(m) => format!("{letter}{major}.{m}"),
                        None => format!("{letter}{major}"),
                    };
                    return Err(err(line, format!("unsupported code {code}")));
                }
            }
        }
        let unit = if self.inches { 25.4 } else { 1.0 };
        let mut target = self.position;
        let mut axis_given = false;
        let (mut ijk, mut r, mut p) = ([None::<f64>; 3], None::<f64>, None::<f64>);
        let mut h = None::<f64>;
        let mut duration = None::<f64>;
        let mut f_word = false;
        // Program coordinates are the part's less the active work offset (none for G53).
        let offset = if machine_coords {
            [0.0; 6]
        } else {
            self.work_offsets[self.work]
        };
        for &(l, v) in words {
            match l {
                'X' | 'Y' | 'Z' => {
                    let k = (l as u8 - b'X') as usize;
                    let v = v * unit;
                    target[k] = if self.absolute {
                        v + offset[k]
                    } else {
                        self.position[k] + v
                    };
                    axis_given = true;
                }
                'A' | 'B' | 'C' => {
                    let k = 3 + (l as u8 - b'A') as usize;
                    let v = v.to_radians();
                    target[k] = if self.absolute {
                        v + offset[k]
                    } else {
                        self.position[k] + v
                    };
                    axis_given = true;
                }
                'I' | 'J' | 'K' => ijk[(l as u8 - b'I') as usize] = Some(v * unit),
                'R' => r = Some(v * unit),
                'P' => p = Some(v),
                'F' => {
                    if !(v > 0.0) {
                        return Err(err(line, format!("F{v}: the feed must be > 0")));
                    }
                    f_word = true;
                    if self.inverse_time {
                        // The move takes 1/F minutes.
                        self.feed = None;
                        duration = Some(60.0 / v);
                    } else {
                        self.feed = Some(v * unit / 60.0);
                    }
                }
                'S' | 'N' | 'D' => {}
                'H' => h = Some(v),
                _ => return Err(err(line, format!("unsupported word {l}{v}"))),
            }
        }
        if m6 {
            match self.selected {
                Some(t) => {
                    self.tool = Some(t);
                    self.note(line, format!("M6: tool {t} in the spindle"));
                }
                None => return Err(err(line, "M6 without a tool selected (T)".into())),
            }
        }
        if g43 {
            let tool = match h {
                Some(v) if v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64 => v as u32,
                Some(v) => {
                    return Err(err(line, format!("H{v}: expected a tool number")));
                }
                None => self.tool.ok_or_else(|| {
                    err(
                        line,
                        "G43 without H and no tool in the spindle (T, M6)".into(),
                    )
                })?,
            };
            self.tool_event = Some(ToolEvent::Apply { h: tool, line });
        } else if h.is_some() {
            return Err(err(line, "H without G43".into()));
        }
        if dwell {
            let seconds = p.ok_or_else(|| err(line, "G4 needs P (seconds)".into()))?;
            if !(seconds >= 0.0) {
                return Err(err(line, format!("G4 P{seconds}: expected seconds >= 0")));
            }
            return Ok(Some(GMove {
                line,
                start: self.position,
                end: self.position,
                motion: Motion::Dwell { seconds },
                feed: None,
                duration: None,
            }));
        }
        let arc_words = ijk.iter().any(Option::is_some) || r.is_some();
        if !axis_given {
            if arc_words {
                return Err(err(
                    line,
                    "arc words without an end point (give X, Y or Z)".into(),
                ));
            }
            return Ok(None);
        }
        let mode = self.mode.ok_or_else(|| {
            err(
                line,
                "axis words without a motion mode (G0, G1, G2, G3)".into(),
            )
        })?;
        let start = self.position;
        let motion = match mode {
            0 | 1 => {
                if arc_words {
                    return Err(err(line, format!("I, J, K or R given with G{mode}")));
                }
                Motion::Line { rapid: mode == 0 }
            }
            _ => self.arc(mode == 3, &start, &target, ijk, r, p, line)?,
        };
        let (feed, duration) = if mode == 0 {
            (None, None)
        } else if self.inverse_time {
            if !f_word {
                return Err(err(
                    line,
                    format!("G{mode} in inverse time (G93) needs its own F on the line"),
                ));
            }
            (None, duration)
        } else {
            (
                Some(
                    self.feed
                        .ok_or_else(|| err(line, format!("G{mode} without a feed (F)")))?,
                ),
                None,
            )
        };
        self.position = target;
        Ok(Some(GMove {
            line,
            start,
            end: target,
            motion,
            feed,
            duration,
        }))
    }
}
