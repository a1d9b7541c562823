//! `stanice lift`: the Rekoba EKM66 lift controller board over RS-232 (read-only: the
//! lift is never controlled).
//!
//! - `simulate`: an EKM66 board on a serial port, a pseudo-terminal or TCP: trips, door
//!   cycles, status codes, trip counters and a fault stack, operated from its console.
//! - `poll`: the monitor: polls a board and prints its status, counters and new fault
//!   records (or JSON lines), keeping the fault archive's cursor in a file.

mod poll;
mod simulate;

use std::process::ExitCode;

use anyhow::bail;
use clap::{Args, Subcommand};
use devices::ekm66::codec::{
    CodecConfig, CounterWidth, DirectionCoding, StatusLayout, TimeEncoding,
};

/// How both ends code the replies (spec EKM-A2, A3, A6): the same options on the
/// simulator and the monitor.
#[derive(Args, Clone, Debug)]
pub(crate) struct CodecArgs {
    /// The status reply's layout: adopted (20 octets), alternative (21 octets) or, for
    /// the monitor, both (each chosen by its length).
    #[arg(long, default_value = "both", value_parser = ["adopted", "alternative", "both"])]
    status_layout: String,
    /// Octets per trip counter: 1, 2 or 4 (little-endian).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=4))]
    counter_width: u8,
    /// Time and date octets in BCD instead of binary.
    #[arg(long)]
    bcd_time: bool,
    /// The year of a year octet 0.
    #[arg(long, default_value_t = 2000)]
    year_base: u16,
    /// The direction octet's values for stopped, up and down.
    #[arg(
        long,
        default_value = "0,1,2",
        value_delimiter = ',',
        value_name = "STOP,UP,DOWN"
    )]
    direction: Vec<u8>,
}

impl CodecArgs {
    pub(crate) fn codec(&self) -> anyhow::Result<CodecConfig> {
        let mut codec = CodecConfig::default();
        codec.status_layouts = match self.status_layout.as_str() {
            "adopted" => vec![StatusLayout::ADOPTED],
            "alternative" => vec![StatusLayout::ALTERNATIVE],
            _ => vec![StatusLayout::ADOPTED, StatusLayout::ALTERNATIVE],
        };
        codec.counter_width = match CounterWidth::from_octets(self.counter_width) {
            Some(width) => width,
            None => bail!("--counter-width must be 1, 2 or 4"),
        };
        codec.time = if self.bcd_time {
            TimeEncoding::Bcd
        } else {
            TimeEncoding::Binary
        };
        codec.year_base = self.year_base;
        let [stopped, up, down] = self.direction[..] else {
            bail!("--direction takes three values: stopped,up,down");
        };
        if stopped == up || up == down || stopped == down {
            bail!("--direction needs three different values");
        }
        codec.direction = DirectionCoding { stopped, up, down };
        Ok(codec)
    }

    /// The layout a board sends.
    pub(crate) fn layout(&self) -> StatusLayout {
        if self.status_layout == "alternative" {
            StatusLayout::ALTERNATIVE
        } else {
            StatusLayout::ADOPTED
        }
    }
}

/// The `stanice lift` subcommands.
#[derive(Subcommand)]
pub(crate) enum LiftCommand {
    /// Simulate an EKM66 lift controller board answering on a line.
    Simulate(simulate::SimulateArgs),
    /// Poll an EKM66 board: status, trip counters and the fault log.
    Poll(poll::PollArgs),
}

pub(crate) async fn run(command: LiftCommand) -> anyhow::Result<ExitCode> {
    match command {
        LiftCommand::Simulate(args) => simulate::run(args).await,
        LiftCommand::Poll(args) => poll::run(args).await,
    }
}
