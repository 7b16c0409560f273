//! One line's codes and words applied to the interpreter: the modes its codes set,
//! the end point and arc words its words give, its tool change and tool length, then
//! the move it makes.

use super::{err, GMove, Interpreter, Motion, Plane, ToolEvent};
use crate::error::Result;

/// What a line's codes ask of that line only (the others set modes).
#[derive(Default)]
struct LineCodes {
    /// G4: a dwell.
    dwell: bool,
    /// G53: machine coordinates.
    machine_coords: bool,
    /// G43: a tool length.
    g43: bool,
    /// M6: a tool change.
    m6: bool,
}

/// What a line's words give besides the feed (which they set).
struct LineWords {
    /// The end point `[X, Y, Z, A, B, C]` (mm, rad).
    target: [f64; 6],
    /// Whether an axis word was given.
    axis_given: bool,
    /// I, J, K (mm).
    ijk: [Option<f64>; 3],
    /// R (mm).
    r: Option<f64>,
    /// P: dwell seconds, or arc turns.
    p: Option<f64>,
    /// H: tool number.
    h: Option<f64>,
    /// The move's duration from an F word in inverse time (s).
    duration: Option<f64>,
    /// Whether the line gave F.
    f_word: bool,
}

impl Interpreter {
    /// Applies one line's `codes` (letter, number, decimal) and `words` (letter,
    /// value), in order: its move, if any.
    pub(super) fn apply(
        &mut self,
        codes: &[(char, u32, Option<u32>)],
        words: &[(char, f64)],
        line: u64,
    ) -> Result<Option<GMove>> {
        let c = self.apply_codes(codes, line)?;
        let w = self.read_words(words, c.machine_coords, line)?;
        if c.m6 {
            self.change_tool(line)?;
        }
        if c.g43 {
            self.apply_tool_length(w.h, line)?;
        } else if w.h.is_some() {
            return Err(err(line, "H without G43".into()));
        }
        if c.dwell {
            return self.dwell(w.p, line).map(Some);
        }
        self.motion(&w, line)
    }

    /// Sets the modes `codes` ask for; what they ask of the line alone.
    fn apply_codes(&mut self, codes: &[(char, u32, Option<u32>)], line: u64) -> Result<LineCodes> {
        let mut c = LineCodes::default();
        for (letter, major, minor) in codes {
            match (letter, major, minor) {
                ('G', 93, None) => self.inverse_time = true,
                ('G', 94, None) => self.inverse_time = false,
                ('G', 54..=59, None) => self.work = (*major - 54) as usize,
                ('G', 59, Some(k @ 1..=3)) => self.work = 5 + *k as usize,
                ('G', 53, None) => c.machine_coords = true,
                ('G', 43, None) => c.g43 = true,
                ('G', 49, None) => self.tool_event = Some(ToolEvent::Cancel { line }),
                ('G', 40, None) => {}
                ('M', 6, None) => c.m6 = true,
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
                ('G', 4, None) => c.dwell = true,
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
        Ok(c)
    }

    /// Reads `words` in order (F sets the feed as it comes): the end point (in machine
    /// coordinates when `machine_coords`, else less the active work offset) and the
    /// other words.
    fn read_words(
        &mut self,
        words: &[(char, f64)],
        machine_coords: bool,
        line: u64,
    ) -> Result<LineWords> {
        let unit = if self.inches { 25.4 } else { 1.0 };
        let mut w = LineWords {
            target: self.position,
            axis_given: false,
            ijk: [None; 3],
            r: None,
            p: None,
            h: None,
            duration: None,
            f_word: false,
        };
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
                    w.target[k] = if self.absolute {
                        v + offset[k]
                    } else {
                        self.position[k] + v
                    };
                    w.axis_given = true;
                }
                'A' | 'B' | 'C' => {
                    let k = 3 + (l as u8 - b'A') as usize;
                    let v = v.to_radians();
                    w.target[k] = if self.absolute {
                        v + offset[k]
                    } else {
                        self.position[k] + v
                    };
                    w.axis_given = true;
                }
                'I' | 'J' | 'K' => w.ijk[(l as u8 - b'I') as usize] = Some(v * unit),
                'R' => w.r = Some(v * unit),
                'P' => w.p = Some(v),
                'F' => self.feed_word(v, unit, &mut w, line)?,
                'S' | 'N' | 'D' => {}
                'H' => w.h = Some(v),
                _ => return Err(err(line, format!("unsupported word {l}{v}"))),
            }
        }
        Ok(w)
    }

    /// Word `F` of value `v` (`unit`: mm per program unit): the feed, or in inverse
    /// time the move's duration, into `w`.
    fn feed_word(&mut self, v: f64, unit: f64, w: &mut LineWords, line: u64) -> Result<()> {
        if !(v > 0.0) {
            return Err(err(line, format!("F{v}: the feed must be > 0")));
        }
        w.f_word = true;
        if self.inverse_time {
            // The move takes 1/F minutes.
            self.feed = None;
            w.duration = Some(60.0 / v);
        } else {
            self.feed = Some(v * unit / 60.0);
        }
        Ok(())
    }

    /// M6: the tool selected goes into the spindle.
    fn change_tool(&mut self, line: u64) -> Result<()> {
        match self.selected {
            Some(t) => {
                self.tool = Some(t);
                self.note(line, format!("M6: tool {t} in the spindle"));
                Ok(())
            }
            None => Err(err(line, "M6 without a tool selected (T)".into())),
        }
    }

    /// G43: the length of tool `h` (the H word), else of the tool in the spindle, as
    /// the line's tool event.
    fn apply_tool_length(&mut self, h: Option<f64>, line: u64) -> Result<()> {
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
        Ok(())
    }

    /// G4: a dwell of `p` seconds where the tool is.
    fn dwell(&self, p: Option<f64>, line: u64) -> Result<GMove> {
        let seconds = p.ok_or_else(|| err(line, "G4 needs P (seconds)".into()))?;
        if !(seconds >= 0.0) {
            return Err(err(line, format!("G4 P{seconds}: expected seconds >= 0")));
        }
        Ok(GMove {
            line,
            start: self.position,
            end: self.position,
            motion: Motion::Dwell { seconds },
            feed: None,
            duration: None,
        })
    }

    /// The move of the modal motion to `w`'s end point, if the line gives one; the
    /// position moves there.
    fn motion(&mut self, w: &LineWords, line: u64) -> Result<Option<GMove>> {
        let arc_words = w.ijk.iter().any(Option::is_some) || w.r.is_some();
        if !w.axis_given {
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
        let target = w.target;
        let motion = match mode {
            0 | 1 => {
                if arc_words {
                    return Err(err(line, format!("I, J, K or R given with G{mode}")));
                }
                Motion::Line { rapid: mode == 0 }
            }
            _ => self.arc(mode == 3, &start, &target, w.ijk, w.r, w.p, line)?,
        };
        let (feed, duration) = self.feed_of(mode, w, line)?;
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

    /// The feed (mm/s) or duration (s) of a move in motion mode `mode`: none for a
    /// rapid, the line's duration in inverse time, else the modal feed.
    fn feed_of(&self, mode: u32, w: &LineWords, line: u64) -> Result<(Option<f64>, Option<f64>)> {
        Ok(if mode == 0 {
            (None, None)
        } else if self.inverse_time {
            if !w.f_word {
                return Err(err(
                    line,
                    format!("G{mode} in inverse time (G93) needs its own F on the line"),
                ));
            }
            (None, w.duration)
        } else {
            (
                Some(
                    self.feed
                        .ok_or_else(|| err(line, format!("G{mode} without a feed (F)")))?,
                ),
                None,
            )
        })
    }
}
