//! `stanice`: the command-line tool of the Stanice telecontrol platform.
//!
//! One binary, one subcommand per capability:
//! - `stanice iec104 ...`: the IEC 60870-5-104 test tool (outstation, client, single
//!   commands, frame decoder), what CPTT and QTester104 do for commissioning engineers.
//! - `stanice iec101 ...`: the IEC 101 master and slave over serial lines,
//!   pseudo-terminals or TCP.
//! - `stanice iec103 ...`: the IEC 103 master and the REF630 relay simulator.
//! - `stanice lift ...`: the EKM66 lift controller's monitor and board simulator.
//! - `stanice run PROJECT`: runs a station project (nodes, PLCs, plant, links, store);
//!   `stanice demo` runs the Vsetín railway station.
//! - `stanice points` / `stanice events`: a node's data points; the event store.
//! - `stanice plc ...`: checks and runs Structured Text.
//! - `stanice hmi` / `stanice user`: the web HMI and its users.
//! - `stanice stats thresholds FILE.csv`: the sorting lab's class limits from weighings.

mod balance;
mod comtrade;
mod console;
mod demo;
mod duration_arg;
mod events;
mod examples;
mod hmi;
mod iec101;
mod iec103;
mod iec104;
mod interrupt;
mod lab;
mod lift;
mod link_report;
mod modbus;
mod plc;
mod points;
mod port_in_use;
mod printed_time;
mod run;
mod s7;
mod serial_line;
mod sorting;
mod stats;
mod verbosity;

use clap::{CommandFactory as _, FromArgMatches as _, Parser, Subcommand};
use tracing_subscriber::EnvFilter;

#[derive(Parser)]
#[command(
    name = "stanice",
    version,
    about = "Stanice telecontrol and SCADA platform"
)]
struct Cli {
    /// Log filter (tracing syntax, e.g. `info`, `iec60870=debug`); also `RUST_LOG`.
    #[arg(long, global = true)]
    log: Option<String>,
    /// More of what happens: the test tools print every frame, ASDU and link event in
    /// words; every tool logs at `info` (unless `--log` says otherwise).
    #[arg(long, short = 'v', global = true)]
    verbose: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// IEC 60870-5-104 test tool: outstation, client, commands, decoder.
    #[command(subcommand)]
    Iec104(iec104::Iec104Command),
    /// IEC 60870-5-101 test tool over a serial line, a pseudo-terminal or TCP: master
    /// and slave.
    #[command(subcommand)]
    Iec101(iec101::Iec101Command),
    /// IEC 60870-5-103 tools: a master for protection relays (PCVDEW6's functions) and a
    /// relay simulator (ABB REF630).
    #[command(subcommand)]
    Iec103(iec103::Iec103Command),
    /// Lift monitoring: the Rekoba EKM66 controller board over RS-232 (a monitor and a
    /// board simulator; read-only).
    #[command(subcommand)]
    Lift(lift::LiftCommand),
    /// Modbus TCP and RTU test tool: read and write a device's coils and registers, or
    /// serve them as a TCP server or an RTU slave.
    #[command(subcommand, after_help = modbus::help(modbus::EXAMPLES))]
    Modbus(modbus::ModbusCommand),
    /// The remote sorting lab's Sartorius balance on RS-232: read what it sends, or
    /// simulate it with the thesis's measured scatter.
    #[command(subcommand)]
    Balance(balance::BalanceCommand),
    /// Siemens S7 over ISO-on-TCP: read and write a PLC's memory by absolute address
    /// (DB1.DBW2, MB10, IX0.1), or serve data blocks, inputs, outputs and markers as one.
    #[command(subcommand, after_help = s7::help(s7::EXAMPLES))]
    S7(s7::S7Command),
    /// Statistics for the labs: the sorting lab's class limits from weighings of its
    /// balls (confidence intervals, coverage, decision limits, expected reliability).
    #[command(subcommand)]
    Stats(stats::StatsCommand),
    /// The remote sorting lab without the hardware: a sorting program behind the
    /// supervisor against the simulated mechanism, and its reliability.
    #[command(subcommand)]
    Sorting(sorting::SortingCommand),
    /// Run the railway-station demo (examples/vsetin).
    Demo(demo::DemoArgs),
    /// Run a station project: every node, or those named with --node.
    Run(run::RunArgs),
    /// List the data points a node serves, as CSV (ioa,type,name,description).
    Points(points::PointsArgs),
    /// Query the event store: value changes or, with --commands, the command audit.
    Events(events::EventsArgs),
    /// Web HMI for a station (browser SCADA, itself an IEC 104 controlling station).
    Hmi(hmi::HmiArgs),
    /// Manage the HMI's users (levels 0-9, argon2 password hashes).
    #[command(subcommand)]
    User(hmi::UserCommand),
    /// Soft PLC: check and run Structured Text.
    #[command(subcommand)]
    Plc(plc::PlcCommand),
    /// PLC teaching lab: a student's program against a lab model (slide, crossroad,
    /// mixing, washing), checked by a scenario; a class graded in one command.
    #[command(subcommand)]
    Lab(lab::LabCommand),
}

fn main() -> std::process::ExitCode {
    // Parsed through the command with every subcommand's Examples section added.
    let matches = examples::with_examples(Cli::command()).get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|error| error.exit());
    verbosity::set(cli.verbose);
    let quiet = if cli.verbose { "info" } else { "warn" };
    let filter = cli.log.clone().map(EnvFilter::new).unwrap_or_else(|| {
        EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(quiet))
    });
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
    {
        Ok(runtime) => runtime,
        Err(error) => {
            eprintln!("error: cannot start the async runtime: {error}");
            return std::process::ExitCode::FAILURE;
        }
    };
    let result = runtime.block_on(async {
        match cli.command {
            Command::Iec104(command) => iec104::run(command).await,
            Command::Iec101(command) => iec101::run(command).await,
            Command::Iec103(command) => iec103::run(command).await,
            Command::Lift(command) => lift::run(command).await,
            Command::Modbus(command) => modbus::run(command).await,
            Command::Balance(command) => balance::run(command).await,
            Command::S7(command) => s7::run(command).await,
            Command::Stats(command) => stats::run(command),
            Command::Sorting(command) => sorting::run(command),
            Command::Demo(args) => demo::run(args).await,
            Command::Run(args) => run::run(args).await,
            Command::Points(args) => points::run(args),
            Command::Events(args) => events::run(args).await,
            Command::Hmi(args) => hmi::run(args).await,
            Command::User(command) => hmi::user(command),
            Command::Plc(command) => plc::run(command).await,
            Command::Lab(command) => lab::run(command).await,
        }
    });
    match result {
        Ok(code) => code,
        Err(error) => {
            eprintln!("error: {error:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
