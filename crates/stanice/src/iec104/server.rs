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
use iec60870::asdu::{Cause, CommonAddress, Element, Quality};
use iec60870::cs104::server::{
    ready, spawn_server, Command, CommandFuture, CommandOutcome, ServerConfig, ServerHandle,
    StationHandler,
};

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
    /// Seconds between simulated changes.
    #[arg(long, default_value_t = 1.0)]
    simulate_interval: f64,
    /// Stop after this many seconds (runs until Ctrl-C otherwise).
    #[arg(long)]
    duration: Option<f64>,
    /// Connections served at once.
    #[arg(long, default_value_t = 64)]
    max_connections: usize,
    #[command(flatten)]
    link: LinkOptions,
}

/// Logs commands and makes a monitor point at the same address follow them.
struct CommandLogger {
    server: OnceLock<ServerHandle>,
    names: std::collections::HashMap<u32, String>,
}

impl StationHandler for CommandLogger {
    fn handle_command(&self, command: Command) -> CommandFuture {
        let name = self
            .names
            .get(&command.ioa.get())
            .map(|name| format!(" ({name})"))
            .unwrap_or_default();
        let step = if command.select { "select" } else { "execute" };
        println!(
            "command {} ioa={}{name} {} {step} from {}: confirmed",
            command.type_id, command.ioa, command.element, command.peer
        );
        if !command.select {
            if let (Some(server), Some(element)) = (self.server.get(), follow(&command.element)) {
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

    fn handle_clock_sync(&self, time: iec60870::time::Cp56Time2a, peer: SocketAddr) -> bool {
        println!("clock synchronisation from {peer}: {time}");
        true
    }

    fn connection_changed(&self, peer: SocketAddr, connected: bool, started: bool) {
        let what = match (connected, started) {
            (true, false) => "connected",
            (true, true) => "started data transfer",
            (false, _) => "disconnected",
        };
        println!("client {peer} {what}");
    }
}

/// The monitor value a command sets.
fn follow(command: &Element) -> Option<Element> {
    let quality = Quality::default();
    Some(match command {
        Element::SingleCommand { on, .. } => Element::SinglePoint { on: *on, quality },
        Element::DoubleCommand { state, .. } => Element::DoublePoint {
            state: *state,
            quality,
        },
        Element::SetpointNormalized { raw, .. } => Element::Normalized { raw: *raw, quality },
        Element::SetpointScaled { value, .. } => Element::Scaled {
            value: *value,
            quality,
        },
        Element::SetpointFloat { value, .. } => Element::Float {
            value: *value,
            quality,
        },
        Element::BitstringCommand { bits } => Element::Bitstring {
            bits: *bits,
            quality,
        },
        _ => return None,
    })
}

/// Starts an outstation for a loaded point list.
pub(crate) async fn serve_points(
    config: ServerConfig,
    points: PointList,
) -> anyhow::Result<ServerHandle> {
    let handler = Arc::new(CommandLogger {
        server: OnceLock::new(),
        names: points.names.clone(),
    });
    let server = spawn_server(
        config,
        points.image,
        Arc::clone(&handler) as Arc<dyn StationHandler>,
    )
    .await?;
    let _ = handler.server.set(server.clone());
    Ok(server)
}

pub(crate) async fn run(args: ServerArgs) -> anyhow::Result<ExitCode> {
    let points = points_file::load(&args.points)?;
    let mut config = ServerConfig::new(args.listen, CommonAddress::new(args.ca));
    config.apci = args.link.apci()?;
    config.max_connections = args.max_connections;
    if let Some(pem) = args.link.tls()? {
        config.tls = Some(iec60870::cs104::tls::server_config(&pem)?);
    }
    let monitor_rows = points.monitor.clone();
    let summary = format!(
        "{} monitor points, {} command points",
        points.monitor.len(),
        points.commands.len()
    );
    let mut interrupt = crate::interrupt::Interrupt::listen();
    let server = serve_points(config, points).await?;
    println!(
        "IEC 104 outstation on {} (common address {}), {summary}",
        server.local_addr(),
        args.ca
    );
    if args.simulate {
        let interval = Duration::from_secs_f64(args.simulate_interval.clamp(0.001, 3600.0));
        tokio::spawn(super::simulate::run(server.clone(), monitor_rows, interval));
    }
    let stop = async {
        match args.duration {
            Some(seconds) => {
                tokio::time::sleep(Duration::from_secs_f64(seconds.clamp(0.0, 1e9))).await
            }
            None => interrupt.recv().await,
        }
    };
    stop.await;
    server.shutdown();
    Ok(ExitCode::SUCCESS)
}
