//! `--verbose`, one flag for every tool (given before or after the subcommand): the test
//! tools print every frame, ASDU and link event in words, and every tool logs at `info`
//! unless `--log` sets the filter. Read where output is decided, so the flag is not
//! threaded through every tool's arguments.

use std::sync::atomic::{AtomicBool, Ordering};

static VERBOSE: AtomicBool = AtomicBool::new(false);

/// Sets the flag (once, from the command line).
pub(crate) fn set(on: bool) {
    VERBOSE.store(on, Ordering::Relaxed);
}

/// Whether `--verbose` was given.
pub(crate) fn is_on() -> bool {
    VERBOSE.load(Ordering::Relaxed)
}
