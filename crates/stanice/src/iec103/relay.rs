//! `stanice iec103 relay`: the REF630 of the thesis on a serial line, a pseudo-terminal
//! or TCP, operated from its console as a relay tester would operate the real one.

use std::ops::ControlFlow;
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use iec60870::ft12::io::drive;
use iec60870::ft12::{Secondary, SecondaryConfig, SecondaryStation};
use iec60870::iec103::dpi_text;
use simulators::ref630::{Device, DeviceEvent, DeviceProfile};

use crate::iec104::render::receipt_time;
use crate::serial_line::{report_end, LineArgs, ServedLines};

/// The console's operations.
const CONSOLE_HELP: &str = "\
Console (one operation a line):
  inject I U [P Q F]   measured values as multiples of rated (FREJA300): inject 1 1, inject 0.8 0.9
  local | remote       the LOCAL/REMOTE switch (commands are refused in LOCAL)
  open | close         operate the breaker by hand (reported with cause 11, local operation)
  earth-switch on|off  operate the earth switch by hand
  truck test|service   rack the truck out to TEST or in to SERVICE
  fault                an earth fault: protection trip (ASDU 2 with fault number), breaker opens
  restart              a warm restart: the next reset of the CU reports start/restart
  status               positions, switch, clock
  help";

type Relay = SecondaryStation<Device>;

/// Arguments of `stanice iec103 relay`.
#[derive(Args, Debug)]
pub(crate) struct RelayArgs {
    #[command(flatten)]
    line: LineArgs,
    /// The relay's link and common address (SlaveAddress, 1-31 on the REF630).
    #[arg(long, default_value_t = 1)]
    address: u8,
    /// The time between cyclic measurands (CycMeasRepTime, 1s-30m; a plain number is
    /// seconds).
    #[arg(long, value_name = "TIME", default_value = "5s", value_parser = crate::duration_arg::seconds)]
    cycle: Duration,
    /// Measured values at start, as multiples of rated: I,U (currents, voltages).
    #[arg(long, value_delimiter = ',', value_name = "I,U")]
    inject: Vec<f64>,
    /// Answer "ACK" and "no data" with the single character E5 where allowed.
    #[arg(long)]
    single_char: bool,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
}

pub(crate) async fn run(args: RelayArgs) -> anyhow::Result<ExitCode> {
    if !(Duration::from_secs(1)..=Duration::from_secs(1800)).contains(&args.cycle) {
        anyhow::bail!("--cycle must be within 1..=1800 s (CycMeasRepTime)");
    }
    let settings = args.line.settings()?;
    let mut profile = DeviceProfile::ref630(args.address);
    profile.cycle = args.cycle;
    let now = tokio::time::Instant::now().into_std();
    let mut device = Device::new(profile, now, chrono::Utc::now().naive_utc());
    if !args.inject.is_empty() {
        let words: Vec<String> = std::iter::once("inject".to_owned())
            .chain(args.inject.iter().map(f64::to_string))
            .collect();
        let words: Vec<&str> = words.iter().map(String::as_str).collect();
        device.operate(&words).map_err(anyhow::Error::msg)?;
    }
    let secondary = SecondaryConfig {
        single_character: args.single_char,
        ..SecondaryConfig::new(args.address.into())
    };
    let mut station = SecondaryStation::new(settings, Secondary::new(secondary), device);
    let mut inbox = crate::console::device_operations(CONSOLE_HELP, operate);
    let serve = async {
        let mut lines = ServedLines::new(&args.line).await?;
        while let Some(line) = lines.next().await? {
            println!(
                "REF630 relay simulator at address {} on {} ({settings}), CycMeasRepTime {} s; type `help`",
                args.address,
                line.peer,
                args.cycle.as_secs_f64()
            );
            let end = drive(line.stream, &mut station, &mut inbox, |relay| {
                while let Some(event) = relay.app().poll_event() {
                    println!("{} {}", receipt_time(), describe(&event));
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

/// One console operation on the relay: what it did, or why not.
fn operate(relay: &mut Relay, words: &[String]) -> String {
    let words: Vec<&str> = words.iter().map(String::as_str).collect();
    match relay.app().operate(&words) {
        Ok(done) => done,
        Err(error) => format!("{error}; type `help`"),
    }
}

fn describe(event: &DeviceEvent) -> String {
    match event {
        DeviceEvent::Reset(function) => format!("master: {function:?}"),
        DeviceEvent::Interrogated { scn } => format!("general interrogation, scan number {scn}"),
        DeviceEvent::ClockSynchronised { time } => {
            format!(
                "clock synchronised to {} (the master's wall-clock time; IEC 103 sends no zone)",
                time.format("%Y-%m-%d %H:%M:%S%.3f")
            )
        }
        DeviceEvent::Command {
            fun,
            inf,
            on,
            accepted,
            reason,
        } => format!(
            "general command FUN {fun} INF {inf} {}: {}",
            if *on { "ON" } else { "OFF" },
            if *accepted {
                "accepted".to_owned()
            } else {
                format!("refused, {reason}")
            }
        ),
        DeviceEvent::Changed {
            fun,
            inf,
            dpi,
            cause,
        } => {
            format!("FUN {fun} INF {inf} -> {} ({cause})", dpi_text(*dpi))
        }
        DeviceEvent::Ignored(bytes) => format!("ignored {} octets: {bytes:02X?}", bytes.len()),
    }
}
