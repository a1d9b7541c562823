//! `stanice iec101 master`: poll outstations, print every ASDU.

use std::ops::ControlFlow;
use std::process::ExitCode;

use clap::Args;
use iec60870::asdu::{Asdu, Cause, CommonAddress, TypeId};
use iec60870::cs104::client::ClientEvent;
use iec60870::ft12::io::drive;
use iec60870::ft12::BalancedEvent;
use iec60870::ft12::{Balanced, BalancedConfig, Primary, PrimaryConfig, PrimaryEvent};
use iec60870::iec101::{Master, MasterEvent, StartUp};
use tokio::sync::mpsc;

use super::FieldSizes;
use crate::iec104::render;
use crate::link_report::{primary_event_text, Reach};
use crate::serial_line::{LineArgs, PollingArgs};

/// Arguments of `stanice iec101 master`.
#[derive(Args, Debug)]
pub(crate) struct MasterArgs {
    #[command(flatten)]
    line: LineArgs,
    /// Link addresses of the outstations on the line, separated by commas.
    #[arg(long, default_value = "1", value_delimiter = ',')]
    address: Vec<u16>,
    /// Common address of the stations (for interrogation and clock sync).
    #[arg(long, default_value_t = 1)]
    ca: u16,
    /// Send a general interrogation when an outstation's link comes up.
    #[arg(long)]
    gi: bool,
    /// Send a clock synchronisation (UTC) when an outstation's link comes up.
    #[arg(long)]
    clock_sync: bool,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
    /// One JSON object per information object instead of analyser lines.
    #[arg(long)]
    json: bool,
    /// Stop when the general interrogation has terminated (with --gi), at every station.
    #[arg(long, requires = "gi")]
    exit_after_gi: bool,
    /// The zone of the station's time tags, which printed times are shown in too (with
    /// their offset): an IANA name (`Europe/Prague`), `UTC` (the test servers' default)
    /// or `local`.
    #[arg(long, value_name = "ZONE", default_value = "UTC")]
    time_zone: iec60870::time::TimeZonePolicy,
    #[command(flatten)]
    polling: PollingArgs,
    #[command(flatten)]
    sizes: FieldSizes,
}

pub(crate) async fn run(args: MasterArgs) -> anyhow::Result<ExitCode> {
    crate::printed_time::set_tool_zone(args.time_zone);
    let transport = args.line.transport()?;
    let params = args.sizes.params()?;
    let config = PrimaryConfig {
        address_size: args.sizes.address_size(),
        ..args.polling.primary_config(args.line.settings()?)?
    };
    let start_up = StartUp {
        clock_sync: args.clock_sync,
        interrogate: args.gi,
        originator: 0,
    };
    let clock: iec60870::iec101::Clock = Box::new(|| chrono::Utc::now().naive_utc());
    let now = tokio::time::Instant::now().into_std();
    let mut master = if args.sizes.balanced {
        let [address] = args.address[..] else {
            anyhow::bail!("a balanced link has one outstation: give one --address");
        };
        let link = Balanced::new(
            BalancedConfig {
                address_size: config.address_size,
                line: config.line,
                response_timeout: config.response_timeout,
                retries: config.retries,
                ..BalancedConfig::new(address, true)
            },
            now,
        );
        Master::balanced(
            link,
            address,
            CommonAddress::new(args.ca),
            params,
            start_up,
            clock,
        )
    } else {
        let mut master = Master::new(Primary::new(config, now), params, start_up, clock);
        for address in &args.address {
            master.add_station(*address, CommonAddress::new(args.ca))?;
        }
        master
    };
    let line = args.line.open(&transport).await?;
    if !args.json {
        println!(
            "IEC 101 master on {} ({}), outstations {:?}",
            line.peer, transport, args.address
        );
    }
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let (_keep, mut actions) = mpsc::unbounded_channel();
    let mut interrogated = std::collections::HashSet::new();
    let stations = args.address.len();
    let mut reach = Reach::new(&args.address, args.polling.retries);
    let line_name = transport.to_string();
    let run = drive(line.stream, &mut master, &mut actions, |master| {
        while let Some(event) = master.poll_event() {
            let lines = match &event {
                MasterEvent::Asdu { address, asdu } => {
                    let client_event = match Asdu::decode(asdu, master.params()) {
                        Ok(asdu) => {
                            if asdu.type_id == TypeId::C_IC_NA_1
                                && asdu.cot.cause == Cause::ACTIVATION_TERMINATION
                            {
                                interrogated.insert(*address);
                            }
                            ClientEvent::Asdu(asdu)
                        }
                        Err(error) => ClientEvent::Undecodable {
                            error: error.to_string(),
                            raw: asdu.clone(),
                        },
                    };
                    if args.json {
                        render::json_lines(&client_event)
                    } else {
                        vec![render::analyser_text(&client_event)]
                    }
                }
                MasterEvent::Link(event) => {
                    let mut lines = link_lines(event, args.json, crate::verbosity::is_on());
                    lines.extend(reach.observe(event));
                    lines
                }
                MasterEvent::Balanced(event) => {
                    let address = args.address.first().copied().unwrap_or_default();
                    let mut lines =
                        balanced_lines(event, &args.address, args.json, crate::verbosity::is_on());
                    match event {
                        BalancedEvent::LinkUp => reach.link_up(address),
                        BalancedEvent::Timeout { request, attempt } => {
                            lines.extend(reach.timed_out(address, *request, *attempt));
                        }
                        _ => {}
                    }
                    lines
                }
            };
            if !crate::console::print_lines(&lines) {
                return ControlFlow::Break(());
            }
        }
        if args.exit_after_gi && interrogated.len() == stations {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    });
    tokio::select! {
        result = run => { result?; }
        () = crate::console::run_for(args.duration) => {}
        () = interrupt.recv() => {}
    }
    Ok(reach.verdict(&line_name))
}

/// How a link-layer event is shown: link up and down always, the rest with --verbose.
fn link_lines(event: &PrimaryEvent, json: bool, verbose: bool) -> Vec<String> {
    let (name, address) = match event {
        PrimaryEvent::LinkUp { address } => ("link_up", *address),
        PrimaryEvent::LinkDown { address } => ("link_down", *address),
        PrimaryEvent::Undelivered { address, .. } => ("undelivered", *address),
        _ if verbose && !json => {
            return vec![format!(
                "{} link: {}",
                render::receipt_time(),
                primary_event_text(event)
            )]
        }
        _ => return Vec::new(),
    };
    link_news(name, address, json)
}

/// How a balanced link's event is shown, as [`link_lines`] does.
fn balanced_lines(
    event: &BalancedEvent,
    address: &[u16],
    json: bool,
    verbose: bool,
) -> Vec<String> {
    let name = match event {
        BalancedEvent::LinkUp => "link_up",
        BalancedEvent::LinkDown => "link_down",
        BalancedEvent::Undelivered(_) => "undelivered",
        _ if verbose && !json => {
            return vec![format!(
                "{} link: {}",
                render::receipt_time(),
                balanced_event_text(event)
            )]
        }
        _ => return Vec::new(),
    };
    link_news(name, address.first().copied().unwrap_or_default(), json)
}

/// A balanced link's event in words (for `--verbose`).
fn balanced_event_text(event: &BalancedEvent) -> String {
    use crate::link_report::function_name;
    match event {
        BalancedEvent::LinkUp => "link up".to_owned(),
        BalancedEvent::LinkDown => "link down".to_owned(),
        BalancedEvent::RemoteReset => "the other end reset its link (it restarted)".to_owned(),
        BalancedEvent::UserData(asdu) => format!("user data ({} octets)", asdu.len()),
        BalancedEvent::Confirmed => "user data confirmed".to_owned(),
        BalancedEvent::Undelivered(asdu) => {
            format!("user data not delivered ({} octets)", asdu.len())
        }
        BalancedEvent::Timeout { request, attempt } => format!(
            "no answer to {} (attempt {attempt})",
            function_name(*request)
        ),
        BalancedEvent::LineError(error) => format!("line error: {error}"),
    }
}

fn link_news(name: &str, address: u16, json: bool) -> Vec<String> {
    if json {
        vec![serde_json::json!({"event": name, "address": address}).to_string()]
    } else {
        vec![format!(
            "{} link {address}: {}",
            render::receipt_time(),
            name.replace('_', " ")
        )]
    }
}
