//! `stanice iec103 master`: the PCVDEW6 functions from a command line.

use std::collections::VecDeque;
use std::ops::ControlFlow;
use std::process::ExitCode;
use std::str::FromStr;

use anyhow::bail;
use clap::Args;
use iec60870::ft12::io::drive;
use iec60870::ft12::{Answer, LineError, PrimaryConfig, PrimaryEvent, PrimaryFunction};
use iec60870::iec103::{Asdu, Body, Cause, Master, MasterEvent, StartUp, FUN_GENERIC};
use tokio::sync::mpsc;

use super::render;
use crate::iec104::render::receipt_time;
use crate::link_report::{primary_event_text, Reach};
use crate::serial_line::{LineArgs, PollingArgs};

/// A general command of `--command FUN:INF:ON|OFF`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct GeneralCommand {
    fun: u8,
    inf: u8,
    on: bool,
}

impl FromStr for GeneralCommand {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = text.split(':').collect();
        let [fun, inf, state] = parts[..] else {
            return Err(format!("{text:?}: expected FUN:INF:ON|OFF, e.g. 1:160:ON"));
        };
        let number = |part: &str, name: &str| {
            part.trim()
                .parse::<u8>()
                .map_err(|_| format!("{text:?}: {name} must be 0..=255"))
        };
        let on = match state.trim().to_ascii_uppercase().as_str() {
            "ON" | "CLOSE" | "2" => true,
            "OFF" | "OPEN" | "1" => false,
            other => return Err(format!("{text:?}: {other:?} is neither ON nor OFF")),
        };
        Ok(GeneralCommand {
            fun: number(fun, "FUN")?,
            inf: number(inf, "INF")?,
            on,
        })
    }
}

/// A single telegram of `--telegrams` (PCVDEW6's menu keys in brackets).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Telegram {
    /// Reset remote link (r).
    ResetLink,
    /// Request link status (s).
    LinkStatus,
    /// Reset (normalise) FCB (f).
    ResetFcb,
    /// Request class 1 (1).
    Class1,
    /// Request class 2 (2).
    Class2,
    /// Start general interrogation (g).
    Gi,
    /// Send the time telegram, broadcast (i).
    Time,
}

impl FromStr for Telegram {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Ok(match text.trim() {
            "reset-link" | "r" => Telegram::ResetLink,
            "link-status" | "s" => Telegram::LinkStatus,
            "reset-fcb" | "f" => Telegram::ResetFcb,
            "class1" | "1" => Telegram::Class1,
            "class2" | "2" => Telegram::Class2,
            "gi" | "g" => Telegram::Gi,
            "time" | "i" => Telegram::Time,
            other => {
                return Err(format!(
                    "unknown telegram {other:?}: reset-link (r), link-status (s), reset-fcb (f), class1 (1), class2 (2), gi (g), time (i)"
                ))
            }
        })
    }
}

/// Arguments of `stanice iec103 master`.
#[derive(Args, Debug)]
pub(crate) struct MasterArgs {
    #[command(flatten)]
    line: LineArgs,
    /// Link (and common) addresses of the devices, separated by commas.
    #[arg(long, default_value = "1", value_delimiter = ',')]
    address: Vec<u8>,
    /// Start a general interrogation when a device's link comes up.
    #[arg(long)]
    gi: bool,
    /// Synchronise each device's clock (UTC) when its link comes up.
    #[arg(long)]
    clock_sync: bool,
    /// General commands FUN:INF:ON|OFF, sent to the first device once it is started (after
    /// its interrogation with --gi); repeatable.
    #[arg(long, value_name = "FUN:INF:ON|OFF")]
    command: Vec<GeneralCommand>,
    /// Generic read of all entries of a group (ASDU 21), after the start-up.
    #[arg(long, value_name = "GROUP")]
    generic_read: Option<u8>,
    /// Single telegrams instead of automatic polling, in order, each printed with its
    /// answer; then exit. PCVDEW6's menu: reset-link (r), link-status (s), reset-fcb (f),
    /// class1 (1), class2 (2), gi (g), time (i).
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["gi", "clock_sync", "command"])]
    telegrams: Vec<Telegram>,
    /// Upload every disturbance record the devices announce (ASDU 23-31) and write it as
    /// COMTRADE (.cfg + .dat, ASCII) into DIR.
    #[arg(long, value_name = "DIR")]
    disturbance_dir: Option<std::path::PathBuf>,
    /// The COMTRADE revision of the written records.
    #[arg(long, value_enum, default_value = "1999", requires = "disturbance_dir")]
    comtrade: crate::comtrade::Revision,
    /// Stop once this many disturbance records are written.
    #[arg(long, value_name = "N", requires = "disturbance_dir")]
    exit_after_records: Option<usize>,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
    /// Stop when the general interrogation has ended at every device (with --gi).
    #[arg(long, requires = "gi")]
    exit_after_gi: bool,
    /// Stop when every --command has its result; the exit code is 1 if one was refused
    /// or unanswered.
    #[arg(long, requires = "command")]
    exit_after_commands: bool,
    /// One JSON object per ASDU instead of text lines.
    #[arg(long)]
    json: bool,
    /// The zone of the station's time tags, which printed times are shown in too (with
    /// their offset): an IANA name (`Europe/Prague`), `UTC` (the test servers' default)
    /// or `local`.
    #[arg(long, value_name = "ZONE", default_value = "UTC")]
    time_zone: iec60870::time::TimeZonePolicy,
    #[command(flatten)]
    polling: PollingArgs,
}

/// What the run is waiting for.
struct Progress {
    gi_done: Vec<u16>,
    commands: VecDeque<GeneralCommand>,
    results: Vec<bool>,
    started: bool,
    generic_read_sent: bool,
    telegrams: VecDeque<Telegram>,
    telegram_open: bool,
    records: usize,
    /// Which devices answered (not kept for single telegrams, which a device may leave
    /// unanswered on purpose).
    reach: Option<Reach>,
}

pub(crate) async fn run(args: MasterArgs) -> anyhow::Result<ExitCode> {
    crate::printed_time::set_tool_zone(args.time_zone);
    let transport = args.line.transport()?;
    let manual = !args.telegrams.is_empty();
    let polling = args.polling.primary_config(args.line.settings()?)?;
    let config = PrimaryConfig {
        // PCVDEW6's single telegrams are not repeated: a timeout is what they show.
        retries: if manual { 0 } else { polling.retries },
        automatic: !manual,
        ..polling
    };
    let config_retries = config.retries;
    if args.address.is_empty() {
        bail!("--address: name at least one device");
    }
    let now = tokio::time::Instant::now().into_std();
    let mut master = Master::new(
        iec60870::ft12::Primary::new(config, now),
        StartUp {
            clock_sync: args.clock_sync,
            interrogate: args.gi,
            disturbances: args.disturbance_dir.is_some(),
        },
        Box::new(|| chrono::Utc::now().naive_utc()),
        now,
    );
    for address in &args.address {
        master.add_device(*address)?;
    }
    let line = args.line.open(&transport).await?;
    if !args.json {
        println!(
            "IEC 103 master on {} ({transport}), devices {:?}{}",
            line.peer,
            args.address,
            if manual { ", single telegrams" } else { "" }
        );
    }
    let first = args.address.first().copied().unwrap_or(1);
    let mut progress = Progress {
        gi_done: Vec::new(),
        commands: args.command.iter().copied().collect(),
        results: Vec::new(),
        started: false,
        generic_read_sent: false,
        telegrams: args.telegrams.iter().copied().collect(),
        telegram_open: false,
        records: 0,
        reach: (!manual).then(|| {
            let addresses: Vec<u16> = args.address.iter().map(|&a| u16::from(a)).collect();
            Reach::new(&addresses, config_retries)
        }),
    };
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let (_keep, mut actions) = mpsc::unbounded_channel();
    let run = drive(line.stream, &mut master, &mut actions, |master| {
        observe(master, &args, first, &mut progress)
    });
    tokio::select! {
        result = run => { result?; }
        () = crate::console::run_for(args.duration) => {}
        () = interrupt.recv() => {}
    }
    if let Some(reach) = &progress.reach {
        let verdict = reach.verdict(&transport.to_string());
        if verdict != ExitCode::SUCCESS {
            return Ok(verdict);
        }
    }
    let failed = progress.results.iter().any(|positive| !positive);
    Ok(if failed {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

fn observe(
    master: &mut Master,
    args: &MasterArgs,
    first: u8,
    progress: &mut Progress,
) -> ControlFlow<()> {
    while let Some(event) = master.poll_event() {
        let lines = match &event {
            MasterEvent::Asdu { address, asdu } => asdu_lines(*address, asdu, args.json),
            MasterEvent::Undecodable {
                address,
                error,
                raw,
            } => {
                let hex: String = raw.iter().map(|byte| format!("{byte:02X} ")).collect();
                if args.json {
                    vec![serde_json::json!({"address": address, "event": "undecodable", "error": error.to_string(), "raw": hex.trim()}).to_string()]
                } else {
                    vec![format!(
                        "{} undecodable ASDU from {address} ({error}): {}",
                        receipt_time(),
                        hex.trim()
                    )]
                }
            }
            MasterEvent::InterrogationComplete { address, scn } => {
                progress.gi_done.push(*address);
                news(
                    args.json,
                    "gi_complete",
                    *address,
                    &format!("GI cycle No: {scn} complete"),
                )
            }
            MasterEvent::CommandResult {
                address,
                fun,
                inf,
                rii,
                positive,
                timed_out,
            } => {
                progress.results.push(*positive);
                let what = match (positive, timed_out) {
                    (true, _) => "positive acknowledgement",
                    (false, true) => "no acknowledgement (timed out)",
                    (false, false) => "negative acknowledgement",
                };
                if args.json {
                    vec![serde_json::json!({"address": address, "event": "command", "fun": fun, "inf": inf, "rii": rii, "positive": positive, "timed_out": timed_out}).to_string()]
                } else {
                    vec![format!(
                        "{} command FUN {fun} INF {inf} (RII {rii}) to {address}: {what}",
                        receipt_time()
                    )]
                }
            }
            MasterEvent::Disturbance { address, record } => {
                progress.records += 1;
                disturbance_lines(*address, record, args)
            }
            MasterEvent::Link(event) => {
                let mut lines = link_lines(event, args, progress);
                if let Some(reach) = &mut progress.reach {
                    lines.extend(reach.observe(event));
                }
                lines
            }
        };
        if !crate::console::print_lines(&lines) {
            return ControlFlow::Break(());
        }
    }
    if !args.telegrams.is_empty() {
        return next_telegram(master, first, progress);
    }
    let started = if args.gi {
        progress.gi_done.contains(&u16::from(first))
    } else {
        master.primary().link_state(first.into()) == Some(iec60870::ft12::LinkState::Up)
    };
    if started && !progress.started {
        progress.started = true;
        while let Some(command) = progress.commands.pop_front() {
            if let Err(error) = master.general_command(first, command.fun, command.inf, command.on)
            {
                eprintln!("cannot send the command: {error}");
            }
        }
        if let Some(group) = args.generic_read {
            if !progress.generic_read_sent {
                progress.generic_read_sent = true;
                let read = Asdu::new(
                    21,
                    Cause::GENERIC_READ_VALID,
                    first,
                    FUN_GENERIC,
                    241,
                    Body::GenericCommand {
                        rii: 1,
                        items: vec![(u16::from(group), 1)],
                    },
                );
                if let Err(error) = master.send_asdu(first, &read) {
                    eprintln!("cannot send the generic read: {error}");
                }
            }
        }
    }
    if args.exit_after_gi
        && args
            .address
            .iter()
            .all(|address| progress.gi_done.contains(&u16::from(*address)))
    {
        return ControlFlow::Break(());
    }
    if args
        .exit_after_records
        .is_some_and(|count| progress.records >= count)
    {
        return ControlFlow::Break(());
    }
    if args.exit_after_commands && progress.started && progress.results.len() == args.command.len()
    {
        return ControlFlow::Break(());
    }
    ControlFlow::Continue(())
}

/// Sends the next single telegram once the last one is answered (or timed out).
fn next_telegram(master: &mut Master, first: u8, progress: &mut Progress) -> ControlFlow<()> {
    if progress.telegram_open {
        return ControlFlow::Continue(());
    }
    let Some(telegram) = progress.telegrams.pop_front() else {
        return if master.primary().is_idle() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        };
    };
    let address = u16::from(first);
    let sent = match telegram {
        Telegram::ResetLink => master
            .primary()
            .request(address, PrimaryFunction::ResetRemoteLink),
        Telegram::LinkStatus => master
            .primary()
            .request(address, PrimaryFunction::RequestLinkStatus),
        Telegram::ResetFcb => master.primary().request(address, PrimaryFunction::ResetFcb),
        Telegram::Class1 => master
            .primary()
            .request(address, PrimaryFunction::RequestClass1),
        Telegram::Class2 => master
            .primary()
            .request(address, PrimaryFunction::RequestClass2),
        Telegram::Gi => master.general_interrogation(first).map(|scn| {
            println!("{} start GI, GI cycle No: {scn}", receipt_time());
        }),
        Telegram::Time => {
            let now = chrono::Utc::now().naive_utc();
            println!(
                "{} Send time: {} UTC (broadcast)",
                receipt_time(),
                now.format("%Y-%m-%d %H:%M:%S%.3f")
            );
            // Nobody answers a broadcast: nothing to wait for.
            return match master.clock_sync(None, now) {
                Ok(()) => ControlFlow::Continue(()),
                Err(error) => {
                    eprintln!("cannot send the time: {error}");
                    ControlFlow::Break(())
                }
            };
        }
    };
    match sent {
        Ok(()) => {
            progress.telegram_open = true;
            ControlFlow::Continue(())
        }
        Err(error) => {
            eprintln!("cannot send {telegram:?}: {error}");
            ControlFlow::Break(())
        }
    }
}

/// Writes an uploaded record as COMTRADE and says where.
fn disturbance_lines(
    address: u16,
    record: &iec60870::iec103::DisturbanceRecord,
    args: &MasterArgs,
) -> Vec<String> {
    let Some(directory) = &args.disturbance_dir else {
        return Vec::new();
    };
    let name = format!("device{address}_fault{}", record.fan);
    let written = crate::comtrade::write(
        directory,
        &name,
        record,
        "stanice iec103 master",
        &format!("103 device {address}"),
        args.comtrade,
    );
    let summary = format!(
        "disturbance record FAN {} of device {address}: {} channels x {} samples at {} us, {} tags",
        record.fan,
        record.channels.len(),
        record.elements(),
        record.interval_us,
        record.tags.len()
    );
    match written {
        Ok((cfg, dat)) if args.json => vec![serde_json::json!({
            "event": "disturbance", "address": address, "fan": record.fan,
            "channels": record.channels.len(), "samples": record.elements(),
            "cfg": cfg.display().to_string(), "dat": dat.display().to_string(),
        })
        .to_string()],
        Ok((cfg, dat)) => vec![format!(
            "{} {summary} -> {} + {}",
            receipt_time(),
            cfg.display(),
            dat.display()
        )],
        Err(error) => {
            eprintln!("{summary}: {error:#}");
            Vec::new()
        }
    }
}

fn asdu_lines(address: u16, asdu: &Asdu, json: bool) -> Vec<String> {
    if json {
        vec![render::json(address, asdu).to_string()]
    } else {
        vec![format!("{} {}", receipt_time(), render::text(asdu))]
    }
}

fn news(json: bool, event: &str, address: u16, text: &str) -> Vec<String> {
    if json {
        vec![serde_json::json!({"event": event, "address": address}).to_string()]
    } else {
        vec![format!("{} device {address}: {text}", receipt_time())]
    }
}

/// Link-layer events: link up/down always; in single-telegram mode every answer in
/// PCVDEW6's words; the rest with --verbose.
fn link_lines(event: &PrimaryEvent, args: &MasterArgs, progress: &mut Progress) -> Vec<String> {
    let manual = !args.telegrams.is_empty();
    match event {
        PrimaryEvent::LinkUp { address } => news(args.json, "link_up", *address, "link up"),
        PrimaryEvent::LinkDown { address } => {
            news(args.json, "link_down", *address, "link down (no answer)")
        }
        PrimaryEvent::Exchange {
            address,
            request,
            answer,
            acd,
            dfc,
        } if manual => {
            progress.telegram_open = false;
            let said = match answer {
                Answer::Ack => "fixed CON Ack",
                Answer::Busy => "fixed CON Nack (busy)",
                Answer::NoData => "fixed RES Nodata",
                Answer::LinkStatus => "fixed RES link status",
                Answer::NotFunctioning => "fixed RES link not functioning",
                Answer::NotImplemented => "fixed RES not implemented",
                Answer::UserData(_) => "var RES UserData",
            };
            let state = if *acd {
                "AD"
            } else if *dfc {
                "OU"
            } else {
                "-"
            };
            if args.json {
                vec![serde_json::json!({"event": "answer", "address": address, "request": format!("{request:?}"), "answer": said, "acd": acd, "dfc": dfc}).to_string()]
            } else {
                vec![format!(
                    "{} {request:?} to {address}: {said}  LINK state <OU,AD>= {state}",
                    receipt_time()
                )]
            }
        }
        PrimaryEvent::Timeout {
            address, request, ..
        } if manual => {
            progress.telegram_open = false;
            if args.json {
                vec![serde_json::json!({"event": "timeout", "address": address, "request": format!("{request:?}")}).to_string()]
            } else {
                vec![format!(
                    "{} {request:?} to {address}: Error: dataReceiveTimeOut",
                    receipt_time()
                )]
            }
        }
        PrimaryEvent::LineError(LineError::Frame(error))
            if crate::verbosity::is_on() && !args.json =>
        {
            vec![format!("{} line error: {error}", receipt_time())]
        }
        _ if crate::verbosity::is_on() && !args.json => {
            vec![format!(
                "{} link: {}",
                receipt_time(),
                primary_event_text(event)
            )]
        }
        _ => Vec::new(),
    }
}
