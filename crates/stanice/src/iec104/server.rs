//! `stanice iec104 server`: an outstation serving a CSV point list.
//!
//! Commands to command points are confirmed and logged on stdout; when a monitor point
//! shares the command's address and fits its value, it follows the command and is sent
//! with cause 11 (return information caused by a remote command).

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use clap::Args;
use iec60870::asdu::{Cause, CommonAddress};
use iec60870::cs104::server::{
    ready, spawn_server, Command, CommandFuture, CommandOutcome, CommandRefusal,
    RedundancyGroupConfig, RedundancyMode, ServerConfig, ServerHandle, StationHandler,
};
use iec60870::outstation::{Outstation, Peer};

use super::points_file::{self, PointList};
use super::LinkOptions;

/// Arguments of `stanice iec104 server`.
#[derive(Args, Debug)]
pub(crate) struct ServerArgs {
    /// Address to listen on.
    #[arg(long, default_value = "127.0.0.1:2404")]
    listen: SocketAddr,
    /// The station's common address.
    #[arg(long, default_value_t = 1)]
    ca: u16,
    /// CSV point list (header `ioa,type,value`).
    #[arg(long)]
    points: PathBuf,
    /// Change values over time and send them spontaneously.
    #[arg(long)]
    simulate: bool,
    /// The time between simulated changes (`1s`, `100ms`; a plain number is seconds).
    #[arg(long, value_name = "TIME", default_value = "1s", value_parser = crate::duration_arg::seconds)]
    simulate_interval: Duration,
    /// Stop after this long (`30s`, `10m`; a plain number is seconds); runs until Ctrl-C
    /// or SIGTERM otherwise.
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    duration: Option<std::time::Duration>,
    /// Connections served at once.
    #[arg(long, default_value_t = 64)]
    max_connections: usize,
    /// How clients share the data: `connection-is-group` (each connection gets every
    /// event on its own: independent masters never disturb each other), `single-group`
    /// (one started connection for all clients: a second master's STARTDT takes the data
    /// from the first, which stays connected on standby; the standard's redundancy), or
    /// `groups-by-address` (the --group groups: main and standby of each control centre).
    #[arg(long, default_value = "connection-is-group", value_parser = RedundancyMode::NAMES)]
    mode: String,
    /// A redundancy group for `--mode groups-by-address`: `NAME=IP[,IP...]`, or `NAME=`
    /// for a group that takes every client no other group names. Repeatable.
    #[arg(long = "group", value_name = "NAME=IPS")]
    groups: Vec<String>,
    /// Refuse time-tagged commands older than this, or further in the future (the
    /// maximum command delay: `30s`; a plain number is seconds); not checked unless given
    /// (a project's servers check 30 s by default).
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    max_command_age: Option<Duration>,
    /// Connections from one client address at once (no limit unless given).
    #[arg(long, value_name = "N")]
    max_per_address: Option<usize>,
    /// Connections in one redundancy group at once, with `--mode groups-by-address`.
    #[arg(long, value_name = "N")]
    max_per_group: Option<usize>,
    /// Slots kept for each `--group` that names addresses: other clients never take them.
    #[arg(long, value_name = "N", default_value_t = 0)]
    reserve_per_group: usize,
    /// Close a connection that has not started data transfer (STARTDT) within this long
    /// (`30s`; a plain number is seconds), unless a `--group` names its address (a
    /// standby may wait).
    #[arg(long, value_name = "TIME", value_parser = crate::duration_arg::seconds)]
    start_timeout: Option<Duration>,
    /// The zone of time tags: `UTC` or a zone name such as `Europe/Prague` (SU set in
    /// summer time).
    #[arg(long, default_value = "UTC")]
    time_zone: iec60870::time::TimeZonePolicy,
    #[command(flatten)]
    link: LinkOptions,
}

/// Logs commands and makes a monitor point at the same address follow them (the IEC
/// 104 server's and the IEC 101 slave's application).
pub(crate) struct CommandLogger {
    server: OnceLock<Arc<Outstation>>,
    /// Command point names by address.
    names: std::collections::HashMap<u32, String>,
}

impl CommandLogger {
    /// A logger for the command points of a point list; [`CommandLogger::serve`] gives
    /// it the outstation once it exists.
    pub(crate) fn new(names: std::collections::HashMap<u32, String>) -> Self {
        Self {
            server: OnceLock::new(),
            names,
        }
    }

    /// The outstation whose points follow the commands.
    pub(crate) fn serve(&self, outstation: Arc<Outstation>) {
        let _ = self.server.set(outstation);
    }
}

impl CommandLogger {
    /// Prints a command and what became of it, naming the command point.
    fn log(&self, command: &Command, what: &dyn std::fmt::Display) {
        let name = self
            .names
            .get(&command.ioa.get())
            .map(|name| format!(" ({name})"))
            .unwrap_or_default();
        let step = if command.select { "select" } else { "execute" };
        println!(
            "command {} ioa={}{name} {} {step} from {}: {what}",
            command.type_id, command.ioa, command.element, command.peer
        );
    }
}

impl StationHandler for CommandLogger {
    fn handle_command(&self, command: Command) -> CommandFuture {
        self.log(&command, &"confirmed");
        if !command.select {
            let follows = (self.server.get(), command.element.commanded_value());
            if let (Some(server), Some(element)) = follows {
                if let Some(point) = server.get(command.ioa) {
                    if element.family_matches(point.event_type) {
                        if let Err(error) = server.update_with_cause(
                            command.ioa,
                            element,
                            None,
                            Cause::RETURN_REMOTE,
                        ) {
                            tracing::warn!(%error, "cannot update the point that follows the command");
                        }
                    }
                }
            }
        }
        ready(CommandOutcome::Executed)
    }

    fn command_refused(&self, command: &Command, refusal: &CommandRefusal) {
        self.log(command, &format_args!("REFUSED: {refusal}"));
    }

    fn handle_clock_sync(&self, time: iec60870::time::Cp56Time2a, peer: &Peer) -> bool {
        println!("clock synchronisation from {peer}: {time}");
        true
    }

    fn connection_changed(&self, peer: &Peer, connected: bool, started: bool) {
        let what = match (connected, started) {
            (true, false) => "connected",
            (true, true) => "started data transfer",
            (false, _) => "disconnected",
        };
        println!("client {peer} {what}");
    }
}

/// An optional option in seconds as a duration.
/// The redundancy mode of `--mode` with the groups of `--group`.
fn redundancy_mode(mode: &str, groups: &[String]) -> anyhow::Result<RedundancyMode> {
    let groups = groups
        .iter()
        .map(|group| {
            let (name, addresses) = group
                .split_once('=')
                .ok_or_else(|| anyhow::anyhow!("--group {group}: expected NAME=IP[,IP...]"))?;
            let clients = addresses
                .split(',')
                .map(str::trim)
                .filter(|address| !address.is_empty())
                .map(|address| {
                    address.parse().map_err(|_| {
                        anyhow::anyhow!("--group {group}: '{address}' is not an IP address")
                    })
                })
                .collect::<anyhow::Result<Vec<_>>>()?;
            Ok(RedundancyGroupConfig::new(name.trim(), clients))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    if !groups.is_empty() && mode != "groups-by-address" {
        anyhow::bail!("--group needs --mode groups-by-address");
    }
    let mode = RedundancyMode::from_name(mode, groups)
        .ok_or_else(|| anyhow::anyhow!("unknown --mode {mode}"))?;
    if mode == RedundancyMode::GroupsByAddress(Vec::new()) {
        anyhow::bail!("--mode groups-by-address needs at least one --group NAME=IP[,IP...]");
    }
    Ok(mode)
}

/// Starts an outstation for a loaded point list.
pub(crate) async fn serve_points(
    config: ServerConfig,
    points: PointList,
) -> anyhow::Result<ServerHandle> {
    let handler = Arc::new(CommandLogger::new(points.command_names.clone()));
    let server = spawn_server(
        config,
        points.image,
        Arc::clone(&handler) as Arc<dyn StationHandler>,
    )
    .await?;
    handler.serve(Arc::clone(server.outstation()));
    Ok(server)
}

pub(crate) async fn run(args: ServerArgs) -> anyhow::Result<ExitCode> {
    let points = points_file::load(&args.points)?;
    let mut config = ServerConfig::new(args.listen, CommonAddress::new(args.ca));
    config.apci = args.link.apci()?;
    config.max_connections = args.max_connections;
    config.max_connections_per_address = args.max_per_address;
    config.max_connections_per_group = args.max_per_group;
    config.reserved_per_group = args.reserve_per_group;
    config.start_timeout = args.start_timeout;
    config.outstation.redundancy = redundancy_mode(&args.mode, &args.groups)?;
    config.outstation.time_zone = args.time_zone;
    config.outstation.max_command_age = args.max_command_age;
    if let Some(pem) = args.link.tls()? {
        config.tls = Some(iec60870::cs104::tls::server_config(&pem)?);
    }
    let monitor_rows = points.monitor.clone();
    let summary = format!(
        "{} monitor points, {} command points, redundancy {}",
        points.monitor.len(),
        points.commands.len(),
        config.outstation.redundancy.name(),
    );
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let server = serve_points(config, points).await?;
    println!(
        "IEC 104 outstation on {} (common address {}), {summary}",
        server.local_addr(),
        args.ca
    );
    if args.simulate {
        let interval = args.simulate_interval.max(Duration::from_millis(1));
        tokio::spawn(super::simulate::run(
            Arc::clone(server.outstation()),
            monitor_rows,
            interval,
        ));
    }
    let stop = async {
        match args.duration {
            Some(duration) => tokio::time::sleep(duration).await,
            None => interrupt.recv().await,
        }
    };
    stop.await;
    server.shutdown();
    Ok(ExitCode::SUCCESS)
}
