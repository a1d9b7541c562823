//! The hooks through which a station's application takes part: commands, clock
//! synchronisation, reset of process, and connection news.
//!
//! Every method has a default, so an application implements only what it serves. Command
//! outcomes are futures because a command often travels further (down a concentrator
//! hierarchy to the board that executes it) before its outcome is known.

use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;

use crate::asdu::{CommonAddress, Element, Ioa, TimeTag, TypeId};
use crate::time::Cp56Time2a;

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
    /// The remote address of the connection that sent it.
    pub peer: SocketAddr,
}

/// What became of a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommandOutcome {
    /// Executed (or, for a select, the selection accepted): positive ACT_CON, and for an
    /// execute ACT_TERM after it.
    Executed,
    /// Refused: negative ACT_CON (P/N = 1).
    Refused,
}

/// A command's outcome, now or later.
pub type CommandFuture = Pin<Box<dyn Future<Output = CommandOutcome> + Send + 'static>>;

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

    /// A clock synchronisation arrived; return whether the station accepts the time.
    /// The default accepts it (and does nothing with it).
    fn handle_clock_sync(&self, time: Cp56Time2a, peer: SocketAddr) -> bool {
        let _ = (time, peer);
        true
    }

    /// A reset-process command (C_RP_NA_1) arrived with its qualifier; return whether it
    /// is accepted. The default refuses it.
    fn handle_reset_process(&self, qualifier: u8, peer: SocketAddr) -> bool {
        let _ = (qualifier, peer);
        false
    }

    /// A parameter command (P_ME_*, P_AC_NA_1) arrived; return whether it is accepted.
    /// The default refuses it.
    fn handle_parameter(&self, ioa: Ioa, element: &Element, peer: SocketAddr) -> bool {
        let _ = (ioa, element, peer);
        false
    }

    /// A client connected (`started = false`) or started data transfer (`started = true`).
    fn connection_changed(&self, peer: SocketAddr, connected: bool, started: bool) {
        let _ = (peer, connected, started);
    }
}

/// A handler that refuses every command and accepts clock synchronisation: a read-only
/// outstation.
#[derive(Debug, Default, Clone, Copy)]
pub struct ReadOnlyStation;

impl StationHandler for ReadOnlyStation {}
