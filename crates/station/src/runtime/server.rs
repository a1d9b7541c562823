//! A node's IEC 104 server: its settings (admission slots, redundancy, TLS, command age),
//! its process image (the points' values of the first PLC scan, and the node's commands),
//! the sink that passes the node's changes to it, and its redundancy groups' status
//! points (no controlling station connected yet).

use std::net::SocketAddr;
use std::sync::Arc;

use iec60870::cs104::server::{
    spawn_server, CommandPoint, ProcessImage, ServerConfig, ServerError, ServerHandle,
};
use iec60870::time::TimeZonePolicy;

use crate::config::{NodeConfig, Project};

use super::command::NodeHandler;
use super::node::NodePoints;
use super::sink::Iec104Sink;
use super::{RuntimeError, NODE_SERVER_SLOTS};

/// Starts the node `config`'s server, if it has one, with `handler` taking its commands;
/// its image holds the current values of `points` (those of the first PLC scan).
pub(super) async fn start_server(
    project: &Project,
    config: &NodeConfig,
    points: &Arc<NodePoints>,
    handler: &Arc<NodeHandler>,
    zone: TimeZonePolicy,
) -> Result<Option<ServerHandle>, RuntimeError> {
    let (Some(settings), Some(address)) = (&config.server, config.server_address(&project.station))
    else {
        return Ok(None);
    };
    let server = server_config(config, settings, address, zone)?;
    let image = process_image(config, points, zone)?;
    let handle = spawn_server(server, image, Arc::clone(handler) as Arc<_>)
        .await
        .map_err(|error| start_error(config, error))?;
    points.attach_sink(Arc::new(Iec104Sink {
        server: handle.clone(),
        zone,
    }));
    no_clients_yet(config, settings, points);
    Ok(Some(handle))
}

/// The server's settings, its TLS files loaded.
fn server_config(
    config: &NodeConfig,
    settings: &crate::config::ServerConfig,
    address: SocketAddr,
    zone: TimeZonePolicy,
) -> Result<ServerConfig, RuntimeError> {
    let mut server = ServerConfig::new(address, config.common_address);
    server.allowed_clients = settings.allowed_clients.clone();
    server.outstation.redundancy = settings.redundancy.clone();
    // Slots for the controlling stations they are meant for: idle clients
    // cannot hold every connection (iec60870::cs104::server, admission).
    server.max_connections_per_address = Some(NODE_SERVER_SLOTS.per_address);
    server.max_connections_per_group = Some(NODE_SERVER_SLOTS.per_group);
    server.reserved_per_group = NODE_SERVER_SLOTS.reserved_per_group;
    server.start_timeout = Some(NODE_SERVER_SLOTS.start_timeout);
    server.outstation.max_command_age = settings.max_command_age;
    server.outstation.event_buffer_capacity = settings.event_buffer;
    server.outstation.time_zone = zone;
    if let Some(files) = &settings.tls {
        // Already resolved against the project folder by the configuration.
        let tls = files
            .load()
            .and_then(|pem| iec60870::cs104::tls::server_config(&pem))
            .map_err(|error| {
                RuntimeError::Setup(format!("node `{}`: TLS: {error}", config.name))
            })?;
        server.tls = Some(tls);
    }
    Ok(server)
}

/// The server's process image: the node's points as they are now, and its commands.
fn process_image(
    config: &NodeConfig,
    points: &NodePoints,
    zone: TimeZonePolicy,
) -> Result<ProcessImage, RuntimeError> {
    let setup = |error: &dyn std::fmt::Display| {
        RuntimeError::Setup(format!("node `{}`: {error}", config.name))
    };
    let mut image = points_iec::process_image(&points.lock(), zone).map_err(|e| setup(&e))?;
    for command in &config.commands {
        image
            .add_command(CommandPoint {
                ioa: command.ioa,
                command_type: command.type_id,
                select_required: command.select_required,
                max_age: command.max_age,
            })
            .map_err(|e| setup(&e))?;
    }
    Ok(image)
}

/// Why the server did not start: its port held by another program apart, as the caller
/// can say how to move the project's ports.
fn start_error(config: &NodeConfig, error: ServerError) -> RuntimeError {
    match error {
        ServerError::Listen { address, source }
            if source.kind() == std::io::ErrorKind::AddrInUse =>
        {
            RuntimeError::PortInUse {
                node: config.name.clone(),
                address,
            }
        }
        error => RuntimeError::Server {
            node: config.name.clone(),
            error,
        },
    }
}

/// Sets the status points of the server's redundancy groups: no controlling station is
/// connected yet.
fn no_clients_yet(
    config: &NodeConfig,
    settings: &crate::config::ServerConfig,
    points: &NodePoints,
) {
    let origin = config.name.clone();
    points.change_with(&origin, |db, now| {
        settings
            .redundancy_groups
            .iter()
            .filter_map(|g| g.status_point.as_deref())
            .filter_map(|p| db.set_link_status(p, false, now).ok().flatten())
            .collect()
    });
}
