//! Writing the command's report and messages without dying when nobody reads them.
//!
//! `println!` and `eprintln!` panic when their stream fails, which `vcm compare a b | head -1`
//! or `vcm render 2>&1 | head` makes happen. The renderer's product is its files; the streams
//! only report on them, so a failed write must not stop a render or lose what it made. A reader
//! that left (a broken pipe) is a normal end of the conversation and stays silent; any other
//! failure on stdout is said once on stderr. After a stream fails, later lines are not tried.

use std::fmt;
use std::io::{ErrorKind, Write};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set once a write to stdout failed.
static STDOUT_GONE: AtomicBool = AtomicBool::new(false);
/// Set once a write to stderr failed.
static STDERR_GONE: AtomicBool = AtomicBool::new(false);

/// The progress bars on screen that lines are written above, while there are some.
static BARS: Mutex<Option<indicatif::MultiProgress>> = Mutex::new(None);

/// Writes every later line above `bars` (which are drawn again below it), or, with `None`,
/// where the cursor is.
pub fn write_above(bars: Option<indicatif::MultiProgress>) {
    if let Ok(mut current) = BARS.lock() {
        *current = bars;
    }
}

/// Runs `write` with the bars on screen (if any) taken away and drawn again after it.
fn beside_bars<T>(write: impl FnOnce() -> T) -> T {
    let bars = BARS.lock().ok().and_then(|bars| bars.clone());
    match bars {
        Some(bars) => bars.suspend(write),
        None => write(),
    }
}

/// Writes one line of the report to stdout; see the module's documentation on failure.
pub fn out(args: fmt::Arguments) {
    let written = beside_bars(|| write_line(&mut std::io::stdout().lock(), &STDOUT_GONE, args));
    if let Err(error) = written
        && error.kind() != ErrorKind::BrokenPipe
    {
        err(format_args!(
            "warning: cannot write the report to stdout ({error}); going on without it"
        ));
    }
}

/// Writes one line (a warning, progress, an error) to stderr, quietly giving up if it fails.
pub fn err(args: fmt::Arguments) {
    // Nowhere is left to tell of a failure on stderr.
    let _ = beside_bars(|| write_line(&mut std::io::stderr().lock(), &STDERR_GONE, args));
}

/// Writes `args` and a newline unless `gone` says the stream failed before; a failure sets it.
fn write_line(
    stream: &mut impl Write,
    gone: &AtomicBool,
    args: fmt::Arguments,
) -> std::io::Result<()> {
    if gone.load(Ordering::Relaxed) {
        return Ok(());
    }
    let written = writeln!(stream, "{args}").and_then(|()| stream.flush());
    if written.is_err() {
        gone.store(true, Ordering::Relaxed);
    }
    written
}

/// `println!` for the command's report: formats like it and never panics (see [`out`]).
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::say::out(format_args!($($arg)*))
    };
}

/// `eprintln!` for messages: formats like it and never panics (see [`err`]).
macro_rules! tell {
    ($($arg:tt)*) => {
        $crate::say::err(format_args!($($arg)*))
    };
}
