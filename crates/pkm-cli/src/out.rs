//! Standard output whose failures are errors: a write that fails (a full disk,
//! `pkm ... > /dev/full`) ends the command with "error: writing to standard output: ..."
//! and exit code 1, where `println!` would panic. A reader that closes the pipe still
//! ends the command by SIGPIPE, quietly (`main::quiet_on_closed_pipe`).

use std::fmt;
use std::io::{self, Write};

/// A write to standard output that failed; the I/O error is its source.
#[derive(Debug)]
pub struct StdoutError(pub io::Error);

impl fmt::Display for StdoutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("writing to standard output")
    }
}

impl std::error::Error for StdoutError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.0)
    }
}

/// Writes `args` and a newline to standard output.
pub fn line(args: fmt::Arguments) -> Result<(), StdoutError> {
    let mut out = io::stdout().lock();
    out.write_fmt(args)
        .and_then(|()| out.write_all(b"\n"))
        .map_err(StdoutError)
}

/// Flushes standard output: the end of every command, so that output still buffered
/// (a last line without its newline) is written or its failure reported.
pub fn flush() -> Result<(), StdoutError> {
    io::stdout().lock().flush().map_err(StdoutError)
}

/// `println!` that returns a [`StdoutError`] instead of panicking.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::out::line(format_args!($($arg)*))
    };
}
pub(crate) use outln;

/// What a function that only prints returns.
pub type Printed = Result<(), StdoutError>;
