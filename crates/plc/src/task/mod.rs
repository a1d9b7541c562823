//! The runtime: scan cycle, tasks, watchdog, cycle statistics, retain, forcing, I/O image
//! and variable access by path.
//!
//! A [`Plc`] never reads a clock. The caller passes the time of every cycle
//! ([`ClockReading`]) — from a virtual clock in tests and simulations, from the system
//! clock in production — and, for execution-time statistics and the watchdog, a
//! [`Stopwatch`] that says how long the cycle's work took.
//!
//! One cycle of a due task: apply forced direct addresses to the process image, copy
//! `%I`/`%M` into the variables declared `AT` those addresses, apply forced variables, run
//! the task's programs in order, apply forced variables again, copy `AT %Q`/`%M`
//! variables into the output image, apply forced direct addresses again (and to the
//! variables `AT` them), update statistics and the watchdog.
//!
//! Forcing and writing work by variable path (`Main.lights[3].Q`) or by direct address
//! (`%IX0.0`, `%QW2`, `%MD20`).
//!
//! # Faults, the watchdog and STOP: per-task isolation and safe state
//!
//! A run-time fault stops only the task it happens in; the watchdog stops only the task
//! that overran; [`Plc::stop`] stops every task. The outputs of a stopped task go to
//! their safe value (default FALSE / 0, declared per output with
//! `{attribute 'safe_value' := '...'}`, see [`safe`]); on [`Plc::stop`] every output does.
//! The other tasks keep their schedule. Each stop is a [`TaskStopped`] event (task,
//! [`StopCause`] with the fault's code and position, the outputs set safe), taken with
//! [`Plc::poll_event`] after [`Plc::run_cycle`] or [`Plc::stop`]. Forced direct
//! addresses keep their forced value.
//!
//! # Layout
//!
//! | file | what |
//! |------|------|
//! | `plc.rs` | [`Plc`]: construction, cold and warm start, program download |
//! | `cycle.rs` | the scan cycle ([`Plc::run_cycle`]), system flags |
//! | `config.rs` | [`TaskConfig`] |
//! | `clock.rs` | [`ClockReading`], [`VirtualClock`], [`Stopwatch`] |
//! | `watchdog.rs` | [`Watchdog`] and the overrun count |
//! | `statistics.rs` | [`CycleStats`] |
//! | `stop.rs` | [`TaskState`], [`StopCause`], [`TaskStopped`]; [`Plc::stop`], [`Plc::start`] |
//! | [`safe`] | outputs and their safe values, [`Plc::bind_output`] |
//! | `retain.rs` | RETAIN and PERSISTENT variables in a file |
//! | `path.rs` | variables by path, [`Leaf`] |
//! | `forcing.rs` | [`Plc::force`], [`Plc::release`] |
//! | `io.rs` | the I/O image and direct addresses |
//! | `format.rs` | values as IEC literals: [`format_value`], [`parse_value`] |

use crate::diagnostics::Diagnostic;

mod clock;
mod config;
mod cycle;
mod forcing;
mod format;
mod io;
mod path;
mod plc;
mod retain;
pub mod safe;
mod statistics;
mod stop;
mod watchdog;

pub use clock::{ClockReading, NoStopwatch, Stopwatch, VirtualClock};
pub use config::TaskConfig;
pub use format::{format_value, parse_value};
pub use path::Leaf;
pub use plc::{Plc, DEFAULT_LOOP_BUDGET};
pub use statistics::CycleStats;
pub use stop::{StopCause, TaskState, TaskStopped};
pub use watchdog::Watchdog;

/// Errors of the runtime API.
#[derive(Debug, thiserror::Error)]
pub enum PlcError {
    /// No variable at this path.
    #[error("no variable '{0}'")]
    UnknownPath(String),
    /// The path names an aggregate where a scalar was needed.
    #[error("'{0}' is not a scalar variable")]
    NotScalar(String),
    /// The text is not a valid literal for the variable's type.
    #[error("'{text}' is not a valid {ty} value")]
    BadValue {
        /// The text.
        text: String,
        /// The type.
        ty: String,
    },
    /// Unknown program name.
    #[error("no program '{name}'{suggestion}")]
    UnknownProgram {
        /// The name given.
        name: String,
        /// `; did you mean ...?` when a program's name is close, else empty.
        suggestion: String,
    },
    /// Malformed direct address.
    #[error("malformed direct address '{0}'")]
    BadAddress(String),
    /// Persistence file I/O.
    #[error("retain file: {0}")]
    Io(#[from] std::io::Error),
    /// Setting the initial values faulted (e.g. an initial value outside a subrange);
    /// the diagnostic says where.
    #[error("{}", .0.message)]
    Init(Box<Diagnostic>),
}
