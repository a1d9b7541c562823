//! `stanice lift poll`: the monitor of one EKM66 board: status, trip counters and the
//! fault log, as text or JSON lines; the fault archive's cursor in a file so that a
//! restart neither repeats nor skips a record.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use clap::Args;
use devices::ekm66::codec::{FaultRecord, Status};
use devices::ekm66::io::{run_poller, Transport};
use devices::ekm66::poller::{ArchiveCursor, CommStatus, Event, IndexBase, Poller, PollerConfig};
use devices::ekm66::tables::{fault_text, status_text};
use serde_json::json;
use tokio::sync::mpsc;

use super::CodecArgs;
use crate::serial_line::{within, LineArgs};

/// Arguments of `stanice lift poll`.
#[derive(Args, Debug)]
pub(crate) struct PollArgs {
    #[command(flatten)]
    line: LineArgs,
    #[command(flatten)]
    codec: CodecArgs,
    /// One JSON object a line: kind (status, counters, fault, comm) and its fields.
    #[arg(long)]
    json: bool,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
    /// The time from one poll cycle (status, counters when due, new faults) to the next
    /// (`1s`, `250ms`; a plain number is milliseconds).
    #[arg(long, value_name = "TIME", default_value = "1s", value_parser = crate::duration_arg::millis)]
    poll_period: Duration,
    /// The time between two reads of the trip counters (`60s`, `5m`; a plain number is
    /// seconds).
    #[arg(long, value_name = "TIME", default_value = "60s", value_parser = crate::duration_arg::seconds)]
    counters_period: Duration,
    /// How long to wait for a reply after the query has left (`500ms`; a plain number is
    /// milliseconds).
    #[arg(long, value_name = "TIME", default_value = "500ms", value_parser = crate::duration_arg::millis)]
    timeout: Duration,
    /// Repeats of an unanswered query before the lift counts as lost.
    #[arg(long, default_value_t = 3)]
    retries: u8,
    /// The fault stack's first index: detect (read 0, then 1), 0 or 1.
    #[arg(long, default_value = "detect", value_parser = ["detect", "0", "1"])]
    index_base: String,
    /// The fault archive's cursor (JSON), read at start and written after each new
    /// fault: a restarted monitor reads on where it stopped.
    #[arg(long, value_name = "FILE")]
    archive: Option<PathBuf>,
    /// Print every status reply, not only changes (of code, floor, target, direction).
    #[arg(long)]
    every_status: bool,
}

pub(crate) async fn run(args: PollArgs) -> anyhow::Result<ExitCode> {
    let transport = args.line.transport()?;
    let mut config = PollerConfig::default();
    config.line = args.line.settings()?;
    config.codec = args.codec.codec()?;
    config.poll_period = within(
        args.poll_period,
        Duration::from_millis(10)..=Duration::from_secs(3600),
        "--poll-period",
    )?;
    config.counters_period = args.counters_period.max(Duration::from_secs(1));
    config.reply_timeout = within(
        args.timeout,
        Duration::from_millis(5)..=Duration::from_secs(60),
        "--timeout",
    )?;
    config.retries = args.retries;
    config.index_base = match args.index_base.as_str() {
        "0" => IndexBase::Zero,
        "1" => IndexBase::One,
        _ => IndexBase::Detect,
    };
    let cursor = match &args.archive {
        Some(path) if path.exists() => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            serde_json::from_str(&text)
                .with_context(|| format!("{} is not an archive cursor", path.display()))?
        }
        _ => ArchiveCursor::default(),
    };
    let mut printer = Printer {
        json: args.json,
        every_status: args.every_status,
        last_status: None,
        last_counters: None,
    };
    let archive = args.archive.clone();
    // A line that closes (a converter's TCP connection dropped, an adapter unplugged) is
    // opened again, the cursor carried over, until the duration ends or Ctrl-C.
    // Why the line could not be opened, until it was once.
    let mut never_opened: Option<String> = Some("the line was not opened".to_owned());
    let poll_forever = async {
        let mut cursor = cursor;
        loop {
            let line = match args.line.open(&transport).await {
                Ok(line) => line,
                Err(error) => {
                    // A serial device that cannot be opened at the start (missing, no
                    // permission, held by another program) is a wrong argument, not a
                    // line to wait for: say the operating system's reason and stop.
                    if never_opened.is_some() && matches!(transport, Transport::Serial { .. }) {
                        return Err(error);
                    }
                    eprintln!("{error:#}; trying again in {}", seconds(REOPEN_AFTER));
                    if never_opened.is_some() {
                        never_opened = Some(format!("{error:#}"));
                    }
                    tokio::time::sleep(REOPEN_AFTER).await;
                    continue;
                }
            };
            never_opened = None;
            if !args.json {
                println!("polling the EKM66 on {} ({})", line.peer, config.line);
            }
            let mut poller = Poller::new(
                config.clone(),
                cursor.clone(),
                tokio::time::Instant::now().into_std(),
            );
            let (_actions, mut inbox) = mpsc::unbounded_channel();
            let mut failure = None;
            let mut stop = false;
            let end = run_poller(line.stream, &mut poller, &mut inbox, |event, cursor| {
                if let (Event::Fault(_), Some(path)) = (&event, &archive) {
                    if let Err(error) = store(path, cursor) {
                        failure = Some(error);
                        return std::ops::ControlFlow::Break(());
                    }
                }
                if printer.print(&event) {
                    std::ops::ControlFlow::Continue(())
                } else {
                    stop = true;
                    std::ops::ControlFlow::Break(())
                }
            })
            .await;
            cursor = poller.cursor().clone();
            if let Some(error) = failure {
                return Err(error);
            }
            if stop {
                return Ok(());
            }
            match end {
                Ok(devices::ekm66::io::DriveEnd::Stopped) => return Ok(()),
                Ok(devices::ekm66::io::DriveEnd::Closed) => eprintln!(
                    "the line closed; opening it again in {}",
                    seconds(REOPEN_AFTER)
                ),
                Err(error) => eprintln!(
                    "the line failed: {error}; opening it again in {}",
                    seconds(REOPEN_AFTER)
                ),
            }
            tokio::time::sleep(REOPEN_AFTER).await;
        }
    };
    let mut interrupt = crate::interrupt::Interrupt::listen();
    tokio::select! {
        result = poll_forever => result?,
        () = crate::console::run_for(args.duration) => {}
        () = interrupt.recv() => {}
    }
    if let Some(reason) = never_opened {
        eprintln!("never reached the board: {reason}");
        return Ok(ExitCode::from(crate::link_report::NOT_REACHED));
    }
    if printer.last_status.is_none() {
        eprintln!(
            "the board never answered on {transport} (is it powered, and the line's speed, \
             parity and coding its own?)"
        );
        return Ok(ExitCode::from(crate::link_report::NOT_REACHED));
    }
    Ok(ExitCode::SUCCESS)
}

/// A pause as people write it (`2 s`).
fn seconds(pause: Duration) -> String {
    format!("{} s", pause.as_secs_f64())
}

/// The pause before a closed line is opened again.
const REOPEN_AFTER: Duration = Duration::from_secs(2);

/// Writes the cursor next to its file and renames it over, so that a crash leaves the
/// old or the new cursor, never half of one.
fn store(path: &Path, cursor: &ArchiveCursor) -> anyhow::Result<()> {
    let text = serde_json::to_string(cursor)?;
    let temporary = path.with_extension("tmp");
    std::fs::write(&temporary, text)
        .with_context(|| format!("cannot write {}", temporary.display()))?;
    std::fs::rename(&temporary, path).with_context(|| format!("cannot write {}", path.display()))
}

struct Printer {
    json: bool,
    every_status: bool,
    last_status: Option<Status>,
    last_counters: Option<Vec<u32>>,
}

impl Printer {
    /// Prints an event; false once standard output is closed.
    fn print(&mut self, event: &Event) -> bool {
        let line = match event {
            Event::Status(status) => {
                let same = self.last_status.is_some_and(|last| {
                    (last.code, last.position, last.target, last.direction)
                        == (
                            status.code,
                            status.position,
                            status.target,
                            status.direction,
                        )
                });
                self.last_status = Some(*status);
                if same && !self.every_status {
                    return true;
                }
                self.status(status)
            }
            Event::Counters(counters) => {
                if self.last_counters.as_ref() == Some(counters) {
                    return true;
                }
                self.last_counters = Some(counters.clone());
                if self.json {
                    json!({"kind": "counters", "counters": counters}).to_string()
                } else {
                    format!("trips per floor: {counters:?}")
                }
            }
            Event::Fault(record) => self.fault(record),
            Event::Comm(status) => {
                let text = match status {
                    CommStatus::Ok => "communication ok",
                    CommStatus::Lost => "communication lost",
                    CommStatus::Unknown => "communication unknown",
                };
                if self.json {
                    json!({"kind": "comm", "status": status.to_string(), "status_text": text})
                        .to_string()
                } else {
                    text.to_owned()
                }
            }
            Event::Error(error) => {
                tracing::debug!(%error, "line error");
                return true;
            }
            Event::Resync(reason) => {
                if self.json {
                    return true;
                }
                format!("fault log read again from its oldest record ({reason:?})")
            }
        };
        crate::console::print_lines(&[line])
    }

    fn status(&self, status: &Status) -> String {
        if self.json {
            json!({
                "kind": "status",
                "status": status.code,
                "status_text": status_text(status.code),
                "position": status.position,
                "target": status.target,
                "direction": status.direction.to_string(),
                "time": status.time.to_string(),
            })
            .to_string()
        } else {
            format!(
                "{} status {} {}: floor {}, target {}, {}",
                status.time,
                status.code,
                status_text(status.code),
                status.position,
                status.target,
                status.direction
            )
        }
    }

    fn fault(&self, record: &FaultRecord) -> String {
        if self.json {
            json!({
                "kind": "fault",
                "index": record.index,
                "fault_code": record.code,
                "fault_text": fault_text(record.code),
                "time": record.time.to_string(),
                "position": record.floor,
                "target": record.target,
            })
            .to_string()
        } else {
            format!(
                "fault {} at index {}: 0x{:02X} {} (floor {}, target {})",
                record.time,
                record.index,
                record.code,
                fault_text(record.code),
                record.floor,
                record.target
            )
        }
    }
}
