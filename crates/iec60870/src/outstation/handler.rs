//! The hooks through which a station's application takes part: commands, clock
//! synchronisation, reset of process, and connection news.
//!
//! Every method has a default, so an application implements only what it serves. Command
//! outcomes are futures because a command often travels further (down a concentrator
//! hierarchy to the board that executes it) before its outcome is known.

use std::fmt;
use std::future::Future;
use std::pin::Pin;
use std::time::Duration;

use chrono::{DateTime, Utc};

use crate::asdu::{CommonAddress, Element, Ioa, TimeTag, TypeId};
use crate::time::Cp56Time2a;

use super::Peer;

/// A command received by the server, already checked against the process image (known
/// address, matching type, select-before-operate rules).
#[derive(Debug, Clone, PartialEq)]
pub struct Command {
    /// The command's type (`C_SC_NA_1`, `C_DC_TA_1`, ...).
    pub type_id: TypeId,
    /// The common address it was sent to.
    pub common_address: CommonAddress,
    /// The command point's address.
    pub ioa: Ioa,
    /// The command element (value and qualifier).
    pub element: Element,
    /// The time tag of a time-tagged command.
    pub time: Option<TimeTag>,
    /// The originator address of the controlling station (0 if unused).
    pub originator: u8,
    /// Whether this is the select step of a select-before-operate.
    pub select: bool,
    /// The controlling station that sent it (its TCP address, or its serial line).
    pub peer: Peer,
}

/// What became of a command.
///
/// The server keeps the standard's order on the commanding connection whichever the
/// application chooses: the confirmation (ACT_CON) first, then the return information
/// (events with cause 11 queued since the command arrived), then the termination
/// (ACT_TERM), which follows every event queued before the application terminated the
/// command.
pub enum CommandOutcome {
    /// Executed (or, for a select, the selection accepted): positive ACT_CON, and for an
    /// execute ACT_TERM after the return information queued until now.
    Executed,
    /// Accepted and under way: positive ACT_CON now; for an execute, ACT_TERM when the
    /// future resolves (the application resolves it once the return information is
    /// queued, or once it gave up waiting for it). A select ignores the future.
    Confirmed(TerminationFuture),
    /// Refused: negative ACT_CON (P/N = 1).
    Refused,
}

impl CommandOutcome {
    /// Whether the confirmation is positive.
    pub fn is_positive(&self) -> bool {
        !matches!(self, CommandOutcome::Refused)
    }
}

impl fmt::Debug for CommandOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CommandOutcome::Executed => "Executed",
            CommandOutcome::Confirmed(_) => "Confirmed",
            CommandOutcome::Refused => "Refused",
        })
    }
}

/// A command's outcome, now or later.
pub type CommandFuture = Pin<Box<dyn Future<Output = CommandOutcome> + Send + 'static>>;

/// Resolves when a confirmed command has terminated (see [`CommandOutcome::Confirmed`]).
pub type TerminationFuture = Pin<Box<dyn Future<Output = ()> + Send + 'static>>;

/// Why the server refused a command itself, before the application was asked.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum CommandRefusal {
    /// No command point has the address (negative confirmation, cause 47).
    UnknownAddress,
    /// The point takes another command type (negative ACT_CON).
    WrongType {
        /// The type the point takes.
        expected: TypeId,
    },
    /// A double command with state 0 or 3, which the standard does not permit.
    StateNotPermitted,
    /// An execute of a select-before-operate point without a matching selection.
    NoSelection,
    /// A time-tagged command older than the maximum command delay.
    Stale {
        /// How old its time tag was on arrival.
        age: Duration,
        /// The limit in force.
        limit: Duration,
    },
    /// A time-tagged command from the future, further ahead than the maximum command
    /// delay (the clocks of the stations disagree).
    FromTheFuture {
        /// How far ahead its time tag was on arrival.
        ahead: Duration,
        /// The limit in force.
        limit: Duration,
    },
    /// A time-tagged command whose time tag is marked invalid or names no real instant,
    /// where a maximum command delay is in force.
    TimeUnusable,
    /// Too many commands of the connection wait for their outcome.
    TooManyPending,
}

impl fmt::Display for CommandRefusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CommandRefusal::UnknownAddress => f.write_str("no command point at this address"),
            CommandRefusal::WrongType { expected } => {
                write!(f, "the point takes {expected}")
            }
            CommandRefusal::StateNotPermitted => {
                f.write_str("double command with a state that is not permitted")
            }
            CommandRefusal::NoSelection => f.write_str("execute without a matching selection"),
            CommandRefusal::Stale { age, limit } => write!(
                f,
                "time tag {:.3} s old, more than the {:.3} s allowed",
                age.as_secs_f64(),
                limit.as_secs_f64()
            ),
            CommandRefusal::FromTheFuture { ahead, limit } => write!(
                f,
                "time tag {:.3} s in the future, more than the {:.3} s allowed",
                ahead.as_secs_f64(),
                limit.as_secs_f64()
            ),
            CommandRefusal::TimeUnusable => {
                f.write_str("time tag invalid where a maximum command delay is in force")
            }
            CommandRefusal::TooManyPending => {
                f.write_str("too many commands waiting for their outcome")
            }
        }
    }
}

/// Wraps an outcome known at once as a [`CommandFuture`].
pub fn ready(outcome: CommandOutcome) -> CommandFuture {
    Box::pin(std::future::ready(outcome))
}

/// The application side of a controlled station.
pub trait StationHandler: Send + Sync + 'static {
    /// A command arrived (select or execute). The default refuses every command.
    fn handle_command(&self, command: Command) -> CommandFuture {
        let _ = command;
        ready(CommandOutcome::Refused)
    }

    /// The server refused a command itself (unknown address, stale time tag, ...): the
    /// application's chance to audit it. The default does nothing (the server logs it).
    fn command_refused(&self, command: &Command, refusal: &CommandRefusal) {
        let _ = (command, refusal);
    }

    /// The station's clock: what the age of a time-tagged command is measured against and
    /// what the time tags the server stamps itself say. The default reads the host's
    /// clock; a station on a simulated or synchronised clock returns that.
    #[allow(clippy::disallowed_methods)] // the application's clock: the host's by default
    fn now(&self) -> DateTime<Utc> {
        Utc::now()
    }

    /// A clock synchronisation arrived; return whether the station accepts the time.
    /// The default accepts it (and does nothing with it).
    fn handle_clock_sync(&self, time: Cp56Time2a, peer: &Peer) -> bool {
        let _ = (time, peer);
        true
    }

    /// A reset-process command (C_RP_NA_1) arrived with its qualifier; return whether it
    /// is accepted. The default refuses it.
    fn handle_reset_process(&self, qualifier: u8, peer: &Peer) -> bool {
        let _ = (qualifier, peer);
        false
    }

    /// A parameter command (P_ME_*, P_AC_NA_1) arrived; return whether it is accepted.
    /// The default refuses it.
    fn handle_parameter(&self, ioa: Ioa, element: &Element, peer: &Peer) -> bool {
        let _ = (ioa, element, peer);
        false
    }

    /// A client connected (`started = false`) or started data transfer (`started = true`).
    fn connection_changed(&self, peer: &Peer, connected: bool, started: bool) {
        let _ = (peer, connected, started);
    }
}

/// A handler that refuses every command and accepts clock synchronisation: a read-only
/// outstation.
#[derive(Debug, Default, Clone, Copy)]
pub struct ReadOnlyStation;

impl StationHandler for ReadOnlyStation {}
