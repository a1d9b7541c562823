//! `stanice iec103`: the IEC 103 tools, what PCVDEW6 and a relay test set do, from a
//! command line.
//!
//! - `master`: resets, polls and interrogates protection devices, synchronises their
//!   clocks, sends general commands and generic reads, prints every ASDU decoded (text or
//!   JSON lines); `--telegrams` sends PCVDEW6's single telegrams one by one.
//! - `relay`: a protection-relay simulator (the REF630 of the thesis) on a serial line, a
//!   pseudo-terminal or TCP, operated from its console (inject, local/remote, fault).
//! - `render`: how ASDUs are shown.

mod master;
mod relay;
mod render;

use std::process::ExitCode;

use clap::Subcommand;

/// The `stanice iec103` subcommands.
#[derive(Subcommand)]
pub(crate) enum Iec103Command {
    /// Poll, interrogate and command protection devices; print what they send.
    Master(master::MasterArgs),
    /// Simulate a protection relay (ABB REF630) answering a 103 master.
    Relay(relay::RelayArgs),
}

pub(crate) async fn run(command: Iec103Command) -> anyhow::Result<ExitCode> {
    match command {
        Iec103Command::Master(args) => master::run(args).await,
        Iec103Command::Relay(args) => relay::run(args).await,
    }
}
