//! `stanice iec101`: the IEC 101 test tool over a serial line, a pseudo-terminal or TCP.
//!
//! - `master`: polls one or many outstations and prints every ASDU like a protocol
//!   analyser, or one JSON object per information object (the output of
//!   `stanice iec104 client`).
//! - `slave`: an outstation serving a CSV point list (the point list of
//!   `stanice iec104 server`), optionally simulating changes, confirming and logging
//!   commands.

mod master;
mod slave;

use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Args, Subcommand};
use iec60870::asdu::AsduParams;
use iec60870::ft12::AddressSize;

/// The field sizes of a line: both ends must agree, and nothing in the frames tells
/// when they do not, so they are options of every command.
#[derive(Args, Clone, Debug)]
pub(crate) struct FieldSizes {
    /// Octets of the link address: 1 or 2, or 0 on a balanced link.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=2))]
    link_address_size: u8,
    /// Balanced transmission (point to point, both stations send when they like)
    /// instead of the master polling.
    #[arg(long)]
    pub(crate) balanced: bool,
    /// Octets of the cause of transmission (2 carries the originator address).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=2))]
    cot_size: u8,
    /// Octets of the common address.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=2))]
    ca_size: u8,
    /// Octets of the information object address.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u8).range(1..=3))]
    ioa_size: u8,
}

impl FieldSizes {
    pub(crate) fn address_size(&self) -> AddressSize {
        AddressSize::from_octets(self.link_address_size).unwrap_or(AddressSize::One)
    }

    pub(crate) fn params(&self) -> anyhow::Result<AsduParams> {
        if self.link_address_size == 0 && !self.balanced {
            anyhow::bail!(
                "--link-address-size 0 needs --balanced: a polled line addresses its outstations"
            );
        }
        // An FT1.2 frame holds 255 octets of control field, link address and ASDU.
        let max_asdu = 255 - 1 - usize::from(self.link_address_size);
        AsduParams::try_new(self.cot_size, self.ca_size, self.ioa_size, max_asdu)
            .context("invalid field sizes")
    }
}

/// The `stanice iec101` subcommands.
#[derive(Subcommand)]
pub(crate) enum Iec101Command {
    /// Poll outstations and print what they send.
    Master(master::MasterArgs),
    /// Run an outstation serving the points of a CSV file.
    Slave(slave::SlaveArgs),
}

pub(crate) async fn run(command: Iec101Command) -> anyhow::Result<ExitCode> {
    match command {
        Iec101Command::Master(args) => master::run(args).await,
        Iec101Command::Slave(args) => slave::run(args).await,
    }
}
