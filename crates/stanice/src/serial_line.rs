//! Where an IEC 101/103 tool's line is: a serial port, a new pseudo-terminal or TCP,
//! as the same options for every serial-line command.

use std::time::Duration;

use anyhow::{bail, Context as _};
use clap::Args;
use iec60870::ft12::io::{OpenLine, Transport};
use iec60870::ft12::{LineSettings, Parity};

/// The line options shared by `stanice iec101` and `stanice iec103`.
#[derive(Args, Clone, Debug)]
pub(crate) struct LineArgs {
    /// A serial port device, e.g. /dev/ttyUSB0.
    #[arg(long, value_name = "DEV", conflicts_with_all = ["pty", "tcp", "listen"])]
    pub(crate) serial: Option<String>,
    /// Open a new pseudo-terminal pair and print the path of its other end (for a peer
    /// to open as a serial port).
    #[arg(long, conflicts_with_all = ["tcp", "listen"])]
    pub(crate) pty: bool,
    /// Connect over TCP to HOST:PORT (a terminal server, a gateway, another tool).
    #[arg(long, value_name = "HOST:PORT", conflicts_with = "listen")]
    pub(crate) tcp: Option<String>,
    /// Listen on ADDR:PORT for a TCP peer.
    #[arg(long, value_name = "ADDR:PORT")]
    pub(crate) listen: Option<String>,
    /// Line speed in baud (1200-115200).
    #[arg(long, default_value_t = 9600)]
    pub(crate) baud: u32,
    /// Parity: even (FT1.2), odd or none.
    #[arg(long, default_value = "even")]
    pub(crate) parity: Parity,
    /// Stop bits, 1 or 2.
    #[arg(long, default_value_t = 1)]
    pub(crate) stop_bits: u8,
}

impl LineArgs {
    /// Speed and character format.
    pub(crate) fn settings(&self) -> anyhow::Result<LineSettings> {
        let settings = LineSettings {
            baud: self.baud,
            parity: self.parity,
            stop_bits: self.stop_bits,
        };
        settings.validate().map_err(anyhow::Error::msg)?;
        Ok(settings)
    }

    /// The transport the options name.
    pub(crate) fn transport(&self) -> anyhow::Result<Transport> {
        let line = self.settings()?;
        Ok(match (&self.serial, self.pty, &self.tcp, &self.listen) {
            (Some(path), false, None, None) => Transport::Serial {
                path: path.clone(),
                line,
            },
            (None, true, None, None) => Transport::Pty,
            (None, false, Some(address), None) => Transport::Connect(address.clone()),
            (None, false, None, Some(address)) => Transport::Listen(address.clone()),
            (None, false, None, None) => {
                bail!("name the line: --serial DEV, --pty, --tcp HOST:PORT or --listen ADDR:PORT")
            }
            _ => bail!("name one line only: --serial, --pty, --tcp or --listen"),
        })
    }

    /// Opens the line; a pseudo-terminal's path is printed first, on a line of its own,
    /// so that a script can start the peer on it.
    pub(crate) async fn open(&self, transport: &Transport) -> anyhow::Result<OpenLine> {
        if let Transport::Listen(address) = transport {
            eprintln!("waiting for a TCP peer on {address}");
        }
        let line = transport
            .open()
            .await
            .with_context(|| format!("cannot open the line ({transport})"))?;
        if let Some(path) = &line.pty_path {
            println!("pty: {path}");
        }
        Ok(line)
    }
}

/// A duration from an option, checked against a range.
pub(crate) fn within(
    value: Duration,
    range: std::ops::RangeInclusive<Duration>,
    name: &str,
) -> anyhow::Result<Duration> {
    if !range.contains(&value) {
        bail!(
            "{name} must be within {:?}..={:?}",
            range.start(),
            range.end()
        );
    }
    Ok(value)
}

/// How a master polls its line: the options shared by `stanice iec101 master` and
/// `stanice iec103 master`.
#[derive(Args, Clone, Debug)]
pub(crate) struct PollingArgs {
    /// How long to wait for an answer after a request has left the line (`500ms`, `1s`;
    /// a plain number is milliseconds).
    #[arg(long, value_name = "TIME", default_value = "500ms", value_parser = crate::duration_arg::millis)]
    pub(crate) timeout: Duration,
    /// Repeats of an unanswered request.
    #[arg(long, default_value_t = 2)]
    pub(crate) retries: u8,
    /// The time between two class 2 polls of a device (`100ms`; a plain number is
    /// milliseconds).
    #[arg(long, value_name = "TIME", default_value = "100ms", value_parser = crate::duration_arg::millis)]
    pub(crate) poll_interval: Duration,
}

impl PollingArgs {
    /// The primary's settings for a line.
    pub(crate) fn primary_config(
        &self,
        line: iec60870::ft12::LineSettings,
    ) -> anyhow::Result<iec60870::ft12::PrimaryConfig> {
        Ok(iec60870::ft12::PrimaryConfig {
            line,
            response_timeout: within(
                self.timeout,
                Duration::from_millis(5)..=Duration::from_secs(60),
                "--timeout",
            )?,
            retries: self.retries,
            poll_interval: within(
                self.poll_interval,
                Duration::ZERO..=Duration::from_secs(3600),
                "--poll-interval",
            )?,
            ..iec60870::ft12::PrimaryConfig::default()
        })
    }
}

/// The lines a device-side tool (an IEC 101 slave, a relay simulator) serves one after
/// the other: the masters of a TCP listener as they come, or the one line of a serial
/// port or pseudo-terminal.
pub(crate) struct ServedLines<'a> {
    args: &'a LineArgs,
    transport: iec60870::ft12::io::Transport,
    listener: Option<iec60870::ft12::io::LineListener>,
    opened: bool,
}

impl<'a> ServedLines<'a> {
    /// Binds the listener of `--listen` (printing where it waits).
    pub(crate) async fn new(args: &'a LineArgs) -> anyhow::Result<ServedLines<'a>> {
        let transport = args.transport()?;
        let listener = match &transport {
            Transport::Listen(address) => {
                let listener = iec60870::ft12::io::LineListener::bind(address).await?;
                println!("waiting for a master on tcp {}", listener.local_addr()?);
                Some(listener)
            }
            _ => None,
        };
        Ok(ServedLines {
            args,
            transport,
            listener,
            opened: false,
        })
    }

    /// The next line to serve, `None` when a single line has been served.
    pub(crate) async fn next(&mut self) -> anyhow::Result<Option<OpenLine>> {
        if let Some(listener) = &self.listener {
            return Ok(Some(listener.accept().await?));
        }
        if std::mem::replace(&mut self.opened, true) {
            return Ok(None);
        }
        Ok(Some(self.args.open(&self.transport).await?))
    }
}

/// Says how serving a line ended.
pub(crate) fn report_end(peer: &str, end: std::io::Result<iec60870::ft12::io::DriveEnd>) {
    match end {
        Ok(iec60870::ft12::io::DriveEnd::Closed) => println!("master on {peer} went away"),
        Ok(iec60870::ft12::io::DriveEnd::Stopped) => {}
        Err(error) => println!("line {peer} failed: {error}"),
    }
}
