//! `stanice balance`: the remote sorting lab's Sartorius balance on a serial line — a
//! reader that prints what the balance sends, and a simulator with the thesis's measured
//! behaviour and a console.

use std::ops::ControlFlow;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, Subcommand};
use devices::balance::io::{run_reader, run_simulator, DriveEnd};
use devices::balance::reader::{BalanceReader, ReaderEvent, BALANCE_LINE};
use devices::balance::simulator::{self, BalanceConfig, BalanceEvent, BalanceSimulator};
use iec60870::ft12::Parity;

use crate::serial_line::{report_end, LineArgs, ServedLines};

/// Balance subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum BalanceCommand {
    /// Print what a balance sends: one line per legal record (nothing for an illegal
    /// one; those are counted and logged at debug).
    Read(ReadArgs),
    /// A simulated balance on a serial line, a pseudo-terminal or TCP, with a console
    /// (`ball red 1`, `remove`, `blower`, `tare`).
    Simulate(SimulateArgs),
}

/// Where the balance's line is; 1200 Bd, 8 data bits (the balance's 7 and its unused
/// parity position, masked), no parity, as the thesis set it.
#[derive(Args, Clone, Debug)]
pub(crate) struct BalanceLineArgs {
    /// A serial port device, e.g. /dev/ttyUSB0.
    #[arg(long, value_name = "DEV", conflicts_with_all = ["pty", "tcp", "listen"])]
    serial: Option<String>,
    /// Open a new pseudo-terminal pair and print the path of its other end.
    #[arg(long, conflicts_with_all = ["tcp", "listen"])]
    pty: bool,
    /// Connect over TCP to HOST:PORT (a terminal server).
    #[arg(long, value_name = "HOST:PORT", conflicts_with = "listen")]
    tcp: Option<String>,
    /// Listen on ADDR:PORT for a TCP peer.
    #[arg(long, value_name = "ADDR:PORT")]
    listen: Option<String>,
    /// Line speed in baud.
    #[arg(long, default_value_t = BALANCE_LINE.baud)]
    baud: u32,
    /// Parity: none (the balance's setting), even or odd.
    #[arg(long, default_value = "none")]
    parity: Parity,
}

impl BalanceLineArgs {
    fn line(&self) -> LineArgs {
        LineArgs {
            serial: self.serial.clone(),
            pty: self.pty,
            tcp: self.tcp.clone(),
            listen: self.listen.clone(),
            baud: self.baud,
            parity: self.parity,
            stop_bits: 1,
        }
    }
}

/// `stanice balance read`
#[derive(Debug, Args)]
pub(crate) struct ReadArgs {
    #[command(flatten)]
    line: BalanceLineArgs,
    /// One JSON object a line: `{"weight_g": 2.291, "stable": false, "time": ...}`.
    #[arg(long)]
    json: bool,
    /// Stop after this long (`30s`, `10m`); runs until Ctrl-C or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<Duration>,
}

/// `stanice balance simulate`
#[derive(Debug, Args)]
pub(crate) struct SimulateArgs {
    #[command(flatten)]
    line: BalanceLineArgs,
    /// Records a second (the thesis's balance sent 2-4).
    #[arg(long, default_value_t = 3.0)]
    rate: f64,
    /// Seed of the weighing errors.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// A ball on the pan from the start (`red 1` .. `green 2`, or grams).
    #[arg(long, value_name = "BALL")]
    ball: Option<String>,
    /// Stop after this long (`30s`, `10m`); runs until Ctrl-C or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<Duration>,
}

/// Runs a `balance` subcommand.
pub(crate) async fn run(command: BalanceCommand) -> anyhow::Result<ExitCode> {
    match command {
        BalanceCommand::Read(args) => read(args).await,
        BalanceCommand::Simulate(args) => simulate(args).await,
    }
}

async fn read(args: ReadArgs) -> anyhow::Result<ExitCode> {
    let line_args = args.line.line();
    let transport = line_args.transport()?;
    let settings = line_args.settings()?;
    let mut records = 0u64;
    let mut illegal = 0u64;
    let read_forever = async {
        let line = line_args.open(&transport).await?;
        if !args.json {
            println!("reading the balance on {} ({settings})", line.peer);
        }
        let mut reader = BalanceReader::new(settings, tokio::time::Instant::now().into_std());
        let end = run_reader(line.stream, &mut reader, |event| {
            match event {
                ReaderEvent::Record(reading) => {
                    records += 1;
                    let time = crate::printed_time::stamp(chrono::Utc::now());
                    let text = if args.json {
                        serde_json::json!({
                            "weight_g": reading.weight_g,
                            "stable": reading.stable,
                            "time": time,
                        })
                        .to_string()
                    } else {
                        format!("{time}  {reading}")
                    };
                    println!("{text}");
                }
                ReaderEvent::Illegal(_) => illegal += 1,
                ReaderEvent::Answering(false) if !args.json => {
                    eprintln!("the balance is silent (no legal record for 2 s)");
                }
                ReaderEvent::Answering(_) => {}
            }
            ControlFlow::Continue(())
        })
        .await;
        if matches!(end, Ok(DriveEnd::Closed)) {
            eprintln!("the line closed");
        }
        Ok::<(), anyhow::Error>(())
    };
    let mut interrupt = crate::interrupt::Interrupt::listen();
    tokio::select! {
        result = read_forever => result?,
        () = crate::console::run_for(args.duration) => {}
        () = interrupt.recv() => {}
    }
    eprintln!("{records} legal record(s), {illegal} illegal");
    Ok(if records > 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(crate::link_report::NOT_REACHED)
    })
}

async fn simulate(args: SimulateArgs) -> anyhow::Result<ExitCode> {
    if !(args.rate.is_finite() && (0.1..=10.0).contains(&args.rate)) {
        anyhow::bail!("--rate must be within 0.1..=10 records a second");
    }
    let line_args = args.line.line();
    let settings = line_args.settings()?;
    let config = BalanceConfig {
        records_per_second: args.rate,
        seed: args.seed,
        line: settings,
        ..BalanceConfig::default()
    };
    let now = tokio::time::Instant::now().into_std();
    let mut balance = BalanceSimulator::new(config, now);
    if let Some(ball) = &args.ball {
        simulator::operate(&mut balance, now, &format!("ball {ball}"))
            .map_err(anyhow::Error::msg)?;
    }
    let mut inbox = crate::console::device_operations(&CONSOLE_HELP, operate);
    let verbose = crate::verbosity::is_on();
    let serve = async {
        let mut lines = ServedLines::new(&line_args).await?;
        while let Some(line) = lines.next().await? {
            println!(
                "Sartorius balance simulator on {} ({settings}), {} records a second; type `help`",
                line.peer, args.rate
            );
            let end = run_simulator(line.stream, &mut balance, &mut inbox, |event| {
                if verbose {
                    let BalanceEvent::Sent(reading) = event;
                    println!("sent {reading}");
                }
                ControlFlow::Continue(())
            })
            .await;
            report_end(&line.peer, end);
        }
        Ok::<(), anyhow::Error>(())
    };
    crate::console::serve_until_stopped(serve, args.duration).await?;
    Ok(ExitCode::SUCCESS)
}

/// The console's operations.
static CONSOLE_HELP: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    format!(
        "Console (one operation a line):\n{}\n  help",
        simulator::HELP
    )
});

/// One console operation on the balance, at the drive loop's time.
fn operate(balance: &mut BalanceSimulator, words: &[String]) -> String {
    let now = tokio::time::Instant::now().into_std();
    simulator::operate(balance, now, &words.join(" ")).unwrap_or_else(|error| error)
}
