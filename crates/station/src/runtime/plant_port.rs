//! The plant's serial ports on pseudo-terminals: a field device of the plant that talks on
//! a serial line (the sorting lab's balance on its RS-232) reaches the project's driver
//! through a real pseudo-terminal, so the driver reads it as it reads the device on the
//! model, through a serial port (`[[node.device]] settings = { plant = "balance" }`).
//!
//! ```text
//!  simulation thread                         tokio task                     the device's driver
//!  plant.advance_to(t)                       (one per port)                 (field supervisor)
//!  take_serial_output(port) --try_send--> write to the pty's master  ==>  slave /dev/pts/N
//!  serial_input(port)      <--SimRequest-- read from the master       <==  (what it sends)
//! ```
//!
//! The octets leave the plant on its simulated clock: at speed 1 as on the line, faster
//! with the station. A port nobody reads keeps [`BACKLOG`] messages and drops the rest, as
//! a line without flow control does (the plant keeps only its device's newest too).

use std::collections::HashMap;
use std::sync::mpsc;

use serial_line::io::{OpenLine, Transport};
use tokio::io::{AsyncReadExt as _, AsyncWriteExt as _};
use tokio::sync::oneshot;

use super::simulation::{SimRequest, Simulation};
use super::RuntimeError;
use crate::config::{FieldDeviceConfig, Project};

/// Messages waiting for the pseudo-terminal before new ones are dropped.
pub(crate) const BACKLOG: usize = 64;

/// One port of the plant on its pseudo-terminal.
#[derive(Debug)]
pub struct PlantPortHandle {
    port: String,
    device: String,
    pty_path: String,
    task: tokio::task::AbortHandle,
}

impl PlantPortHandle {
    /// The plant's name for the port (`balance`).
    pub fn port(&self) -> &str {
        &self.port
    }

    /// The device of the project on it (`SORTER/BAL`).
    pub fn device(&self) -> &str {
        &self.device
    }

    /// The pseudo-terminal's path the device's driver opens (`/dev/pts/4`).
    pub fn pty_path(&self) -> &str {
        &self.pty_path
    }

    pub(crate) fn stop(&self) {
        self.task.abort();
    }
}

/// The ports the selected nodes' devices are on, opened: the handles, and each device's
/// settings with `serial` naming its pseudo-terminal, by (node, device).
pub(crate) struct PlantPorts {
    pub(crate) handles: Vec<PlantPortHandle>,
    settings: HashMap<(String, String), toml::Table>,
}

impl PlantPorts {
    /// `device` of `node` as its driver is to open it: on a plant port, with the
    /// pseudo-terminal in `serial`.
    pub(crate) fn device(&self, node: &str, device: &FieldDeviceConfig) -> FieldDeviceConfig {
        let mut device = device.clone();
        if let Some(settings) = self.settings.get(&(node.to_owned(), device.name.clone())) {
            device.settings = settings.clone();
        }
        device
    }
}

/// Opens a pseudo-terminal for each plant port a device of `nodes` (indices into the
/// project) is on, and connects it to the plant on the simulation thread.
pub(crate) async fn open(
    project: &Project,
    nodes: &[usize],
    simulation: &mpsc::Sender<SimRequest>,
) -> Result<PlantPorts, RuntimeError> {
    let mut ports = PlantPorts {
        handles: Vec::new(),
        settings: HashMap::new(),
    };
    let on_ports: Vec<(&str, &FieldDeviceConfig, &str)> = nodes
        .iter()
        .filter_map(|index| project.nodes.get(*index))
        .flat_map(|node| {
            node.devices.iter().filter_map(move |device| {
                let port = device.plant_port.as_deref()?;
                Some((node.name.as_str(), device, port))
            })
        })
        .collect();
    if on_ports.is_empty() {
        return Ok(ports);
    }
    let (answer, offered) = oneshot::channel();
    simulation
        .send(SimRequest::With(Box::new(move |sim: &mut Simulation| {
            let _ = answer.send(
                sim.plant()
                    .map(|plant| plant.serial_ports())
                    .unwrap_or_default(),
            );
        })))
        .map_err(|_| RuntimeError::Stopped)?;
    let offered = offered.await.map_err(|_| RuntimeError::Stopped)?;
    let mut taken: HashMap<&str, String> = HashMap::new();
    for (node, device, port) in on_ports {
        let name = format!("{node}/{}", device.name);
        let setup = |why: String| RuntimeError::Setup(format!("device `{name}`: {why}"));
        if !offered.iter().any(|offer| offer.name == port) {
            let names: Vec<&str> = offered.iter().map(|offer| offer.name.as_str()).collect();
            return Err(setup(format!(
                "the plant has no serial port `{port}` (its ports: {})",
                if names.is_empty() {
                    "none".to_owned()
                } else {
                    names.join(", ")
                }
            )));
        }
        if let Some(other) = taken.insert(port, name.clone()) {
            return Err(setup(format!(
                "the plant's serial port `{port}` is `{other}`'s already"
            )));
        }
        let line = Transport::Pty
            .open()
            .await
            .map_err(|error| setup(error.to_string()))?;
        let Some(pty_path) = line.pty_path.clone() else {
            return Err(setup("the pseudo-terminal has no path".to_owned()));
        };
        let (to_line, from_plant) = tokio::sync::mpsc::channel(BACKLOG);
        let attached = port.to_owned();
        simulation
            .send(SimRequest::With(Box::new(move |sim: &mut Simulation| {
                sim.attach_serial_port(attached, to_line);
            })))
            .map_err(|_| RuntimeError::Stopped)?;
        let task = tokio::spawn(carry(line, port.to_owned(), from_plant, simulation.clone()))
            .abort_handle();
        tracing::info!(device = %name, port, pty = %pty_path, "the plant's serial port on a pseudo-terminal");
        let mut settings = device.settings.clone();
        settings.remove(crate::config::PLANT_PORT_KEY);
        settings.insert("serial".to_owned(), toml::Value::String(pty_path.clone()));
        ports
            .settings
            .insert((node.to_owned(), device.name.clone()), settings);
        ports.handles.push(PlantPortHandle {
            port: port.to_owned(),
            device: name,
            pty_path,
            task,
        });
    }
    Ok(ports)
}

/// Carries the plant's octets to the pseudo-terminal's master and what the driver sends
/// back to the plant, until the station stops.
async fn carry(
    line: OpenLine,
    port: String,
    mut from_plant: tokio::sync::mpsc::Receiver<Vec<u8>>,
    simulation: mpsc::Sender<SimRequest>,
) {
    // `line` keeps the pseudo-terminal's other end open (the driver may close and reopen
    // its own); only its stream is used.
    let mut line = line;
    let (mut reader, mut writer) = tokio::io::split(&mut line.stream);
    let mut buffer = [0u8; 256];
    loop {
        tokio::select! {
            octets = from_plant.recv() => {
                let Some(octets) = octets else { return };
                if let Err(error) = writer.write_all(&octets).await {
                    tracing::warn!(port, %error, "the plant's serial port cannot be written");
                    return;
                }
            }
            read = reader.read(&mut buffer) => {
                let octets = match read {
                    Ok(0) => return,
                    Ok(n) => buffer.get(..n).unwrap_or_default().to_vec(),
                    Err(error) => {
                        tracing::warn!(port, %error, "the plant's serial port cannot be read");
                        return;
                    }
                };
                let port = port.clone();
                let sent = simulation.send(SimRequest::With(Box::new(move |sim: &mut Simulation| {
                    sim.serial_input(&port, &octets);
                })));
                if sent.is_err() {
                    return;
                }
            }
        }
    }
}
