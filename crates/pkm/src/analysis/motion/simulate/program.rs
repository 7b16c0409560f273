//! The steps of a G-code program, read line by line as the runner asks for them.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::io::BufRead;

use super::invalid;
use crate::analysis::motion::{ProgramSetup, SampleSink};
use crate::error::Result;
use crate::machine::Analysable;
use crate::mechanism::PoseSpace;
use crate::motion::gcode::{Interpreter, ToolEvent};
use crate::motion::program::{to_move, wrap_note, FeedOptions};
use crate::motion::{Move, Step};

/// A program's moves and tool changes, in order, read one line at a time: each move is
/// handed on one line late (the last is known at the end), the progress of every line
/// read goes to the caller's sink.
pub(super) struct ProgramSteps<'r, 'b, 's, M, const P: usize, const A: usize> {
    /// The machine run.
    m: &'r M,
    /// Feeds and time laws of the moves.
    feed: &'r FeedOptions,
    /// Tool lengths and work offsets.
    setup: Box<ProgramSetup>,
    /// The program text.
    reader: Box<dyn BufRead + 'b>,
    /// The G-code state.
    interp: Interpreter,
    /// The line being read: one buffer for every line (`BufRead::lines` would
    /// allocate a string per line), the same lines, the same errors.
    buf: String,
    /// Lines read.
    lines: usize,
    /// The last move read, not yet handed on.
    pending: Option<Move<P>>,
    /// Steps ready to hand on.
    queue: VecDeque<Step<P>>,
    /// Nothing more is read: the program ended or failed.
    done: bool,
    /// The caller's sink, for progress.
    out: &'r RefCell<&'s mut dyn SampleSink>,
}

impl<'r, 'b, 's, M: Analysable<P, A>, const P: usize, const A: usize>
    ProgramSteps<'r, 'b, 's, M, P, A>
{
    /// The steps of the program in `reader` on `m`, from pose `from` (home when
    /// `None`); refuses a machine whose pose G-code does not address.
    pub(super) fn new(
        m: &'r M,
        feed: &'r FeedOptions,
        reader: Box<dyn BufRead + 'b>,
        from: Option<Vec<f64>>,
        setup: Box<ProgramSetup>,
        out: &'r RefCell<&'s mut dyn SampleSink>,
    ) -> Result<Self> {
        if m.info().pose_space() == PoseSpace::Own {
            return Err(invalid(
                "G-code",
                "needs a machine whose pose is X, Y, Z[, A, B, C] or tool-centre-point \
                 coordinates",
            ));
        }
        let x = match from {
            Some(x) => crate::dynamic::fixed::<P>("start pose", &x)?,
            None => m.info().home(),
        };
        let mut interp = Interpreter::new(crate::motion::run::to_spatial(m, &x));
        interp.work_offsets = setup.work_offsets;
        Ok(ProgramSteps {
            m,
            feed,
            setup,
            reader,
            interp,
            buf: String::new(),
            lines: 0,
            pending: None,
            queue: VecDeque::new(),
            done: false,
            out,
        })
    }

    /// What the program asked for that was noted (line, text), and the notes beyond
    /// those kept.
    pub(super) fn into_notes(mut self) -> (Vec<(u64, String)>, u64) {
        (
            std::mem::take(&mut self.interp.notes),
            self.interp.notes_dropped,
        )
    }

    /// Hands on the move pending, as not the last.
    fn hand_on_pending(&mut self) {
        if let Some(p) = self.pending.take() {
            self.queue.push_back(Step::Move { mv: p, last: false });
        }
    }

    /// Queues the tool change `ev`, after the moves before it (they run with the tool
    /// they had).
    fn tool_event(&mut self, ev: ToolEvent) {
        self.hand_on_pending();
        let (line, length) = match ev {
            ToolEvent::Apply { h, line } => {
                let (l, given) = self.setup.length(h);
                let what = if given {
                    format!("G43 H{h}: tool length {l} mm")
                } else {
                    format!(
                        "G43 H{h}: no length given for tool {h} (--tool-table, \
                         --tool-length): taken as 0, the machine file's tool"
                    )
                };
                self.interp.note(line, what);
                (line, l)
            }
            ToolEvent::Cancel { line } => (line, 0.0),
        };
        self.queue.push_back(Step::ToolLength { length, line });
    }

    /// Reads and interprets the next line, queueing what it makes; `false` at the end
    /// of the text or of the program.
    fn next_line(&mut self) -> Result<bool> {
        self.buf.clear();
        let read = self
            .reader
            .read_line(&mut self.buf)
            .map_err(|e| invalid("G-code", format!("reading line {}: {e}", self.lines + 1)))?;
        if read == 0 {
            return Ok(false);
        }
        self.lines += 1;
        let text = match self.buf.strip_suffix('\n') {
            Some(t) => t.strip_suffix('\r').unwrap_or(t),
            None => &self.buf,
        };
        self.out.borrow_mut().progress(text.len() as u64 + 1);
        if self.interp.ended {
            return Ok(false);
        }
        let g = self.interp.line(text, self.lines as u64)?;
        let mv = match &g {
            Some(g) => {
                if let Some(note) = wrap_note(self.m, g) {
                    self.interp.note(g.line, note);
                }
                Some(to_move(self.m, g, self.feed)?)
            }
            None => None,
        };
        if let Some(ev) = self.interp.tool_event.take() {
            self.tool_event(ev);
        }
        if let Some(mv) = mv {
            if let Some(p) = self.pending.replace(mv) {
                self.queue.push_back(Step::Move { mv: p, last: false });
            }
        }
        Ok(true)
    }
}

impl<M: Analysable<P, A>, const P: usize, const A: usize> Iterator
    for ProgramSteps<'_, '_, '_, M, P, A>
{
    type Item = Result<Step<P>>;

    fn next(&mut self) -> Option<Result<Step<P>>> {
        loop {
            if let Some(s) = self.queue.pop_front() {
                return Some(Ok(s));
            }
            if self.done {
                return None;
            }
            match self.next_line() {
                Ok(true) => {}
                Ok(false) => {
                    self.done = true;
                    if let Some(p) = self.pending.take() {
                        return Some(Ok(Step::Move { mv: p, last: true }));
                    }
                }
                Err(e) => {
                    self.done = true;
                    return Some(Err(e));
                }
            }
        }
    }
}
