//! `stanice lift simulate`: an EKM66 board on a serial line, a pseudo-terminal or TCP,
//! with a console for fault injection.

use std::process::ExitCode;

use clap::Args;
use devices::ekm66::console;
use devices::ekm66::io::run_simulator;
use devices::ekm66::simulator::{SimEvent, Simulator, SimulatorConfig};
use devices::ekm66::tables::{fault_text, status_text};

use super::CodecArgs;
use crate::serial_line::{report_end, LineArgs, ServedLines};

/// The console's operations.
static CONSOLE_HELP: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    format!("Console (one operation a line):\n{}\n  help", console::HELP)
});

/// Arguments of `stanice lift simulate`.
#[derive(Args, Debug)]
pub(crate) struct SimulateArgs {
    #[command(flatten)]
    line: LineArgs,
    #[command(flatten)]
    codec: CodecArgs,
    /// Floors, numbered 1..=N.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u8).range(2..=60))]
    floors: u8,
    /// Seed of the random trips, statuses and faults.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Slots of the fault stack; the index wraps to the first after the last.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u8).range(1..))]
    stack_size: u8,
    /// The index of the first slot, 0 or 1.
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=1))]
    index_base: u8,
    /// Board seconds per real second (the lift and its clock run faster).
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Probability of a random fault at the end of a trip (0 for injected faults only).
    #[arg(long, default_value_t = 0.05)]
    fault_probability: f64,
    /// Probability of a status episode at the end of a trip (each the next code of
    /// Appendix A, so every status shows in turn).
    #[arg(long, default_value_t = 0.1)]
    status_probability: f64,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
}

pub(crate) async fn run(args: SimulateArgs) -> anyhow::Result<ExitCode> {
    if !(args.speed.is_finite() && (0.01..=10_000.0).contains(&args.speed)) {
        anyhow::bail!("--speed must be within 0.01..=10000");
    }
    for (name, value) in [
        ("--fault-probability", args.fault_probability),
        ("--status-probability", args.status_probability),
    ] {
        if !(0.0..=1.0).contains(&value) {
            anyhow::bail!("{name} must be within 0..=1");
        }
    }
    let settings = args.line.settings()?;
    let mut config = SimulatorConfig::default();
    config.floors = args.floors;
    config.seed = args.seed;
    config.stack_size = args.stack_size;
    config.index_base = args.index_base;
    config.speed = args.speed;
    config.fault_probability = args.fault_probability;
    config.status_probability = args.status_probability;
    config.codec = args.codec.codec()?;
    config.status_layout = args.codec.layout();
    config.line = settings;
    config.start = chrono::Local::now().naive_local();
    let now = tokio::time::Instant::now().into_std();
    let mut simulator = Simulator::new(config, now);

    let mut inbox = crate::console::device_operations(&CONSOLE_HELP, operate);
    // `--verbose`: every query answered and every arrival too.
    let verbose = crate::verbosity::is_on();
    let serve = async {
        let mut lines = ServedLines::new(&args.line).await?;
        while let Some(line) = lines.next().await? {
            println!(
                "EKM66 lift simulator, {} floors, fault stack of {} from index {}, on {} ({settings}), speed {}x; type `help`",
                args.floors, args.stack_size, args.index_base, line.peer, args.speed
            );
            let end = run_simulator(line.stream, &mut simulator, &mut inbox, |event| {
                if let Some(text) = describe(&event, verbose) {
                    println!("{text}");
                }
                std::ops::ControlFlow::Continue(())
            })
            .await;
            report_end(&line.peer, end);
        }
        Ok::<(), anyhow::Error>(())
    };
    crate::console::serve_until_stopped(serve, args.duration).await?;
    Ok(ExitCode::SUCCESS)
}

fn describe(event: &SimEvent, verbose: bool) -> Option<String> {
    match event {
        SimEvent::FaultStored(record) => Some(format!(
            "fault 0x{:02X} {} stored at index {} ({}, floor {}, target {})",
            record.code,
            fault_text(record.code),
            record.index,
            record.time,
            record.floor,
            record.target
        )),
        SimEvent::StatusChanged(code) => Some(format!("status {code} {}", status_text(*code))),
        SimEvent::Arrived(floor) if verbose => Some(format!("arrived at floor {floor}")),
        SimEvent::Answered(query) if verbose => Some(format!("answered the {query} query")),
        _ => None,
    }
}

/// One console operation on the board.
fn operate(simulator: &mut Simulator, words: &[String]) -> String {
    let words: Vec<&str> = words.iter().map(String::as_str).collect();
    console::operate(simulator, &words).unwrap_or_else(|error| error)
}
