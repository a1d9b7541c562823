//! A node's serial lines: the gateway role (the ABB COM600 of the thesis). Each line has
//! one protocol and one master polling its devices:
//!
//! - [`iec103`]: protection relays (IEC 103): indications and measurands to points,
//!   commands as general commands (ASDU 20), refused while the relay reports LOCAL.
//! - [`iec101`]: outstations (IEC 101): their monitor data to points, commands forwarded
//!   as they came and followed to their confirmation and termination.
//!
//! What every line shares is here: its handle ([`LineHandle`]), the transports (serial
//! port, terminal server over TCP, simulated relays), and the status of its devices (a
//! device that stops answering turns its points invalid and its status point TRUE; the
//! line's status point is TRUE while none answers).
//!
//! A `simulate = "ref630"` line runs the thesis's relay at each device's address inside
//! this process, on an in-memory line; the console operates it ([`LineHandle::operate`]).
//!
//! A line's spec follows from the node's points ([`LineSpec::new`]): which points each
//! device's signals (IEC 103) or objects (IEC 101) feed.

mod iec101;
mod iec103;

use super::operation::OperationError;
use std::collections::{HashMap, HashSet};
use std::ops::ControlFlow;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use iec60870::asdu::Ioa;
use iec60870::ft12::io::{drive, EndpointAction, Transport};
use iec60870::ft12::{
    AddressSize, Primary, PrimaryConfig, Secondary, SecondaryConfig, SecondaryStation, SharedLine,
};
use iec60870::outstation::{Command, TerminationFuture};
use simulators::ref630::{Device, DeviceProfile};
use tokio::sync::mpsc;

use crate::config::{LineConfig, LineProtocol, LineTransport, MeasurandScaling, PointConfig};
use crate::store::CommandOutcome;
use points::{LineSignal, PointId, PointKind, PointSource};

use super::field::CommunicationStatus;
use super::node::NodePoints;
pub(crate) use iec101::ObjectPoints;
use iec103::Simulated;

/// How long a command waits for the device's acknowledgement or confirmation.
const COMMAND_TIMEOUT: Duration = Duration::from_secs(10);

/// A point fed by an IEC 103 device, with what its conversion needs.
#[derive(Debug, Clone)]
pub(crate) struct LinePoint {
    pub id: PointId,
    pub kind: PointKind,
    pub scaling: Option<MeasurandScaling>,
}

/// What a line is configured to do.
#[derive(Debug, Clone)]
pub(crate) struct LineSpec {
    pub config: LineConfig,
    /// IEC 103: (device address, FUN, INF, index) -> the points it feeds.
    pub signals: HashMap<(u8, u8, u8, Option<u8>), Vec<LinePoint>>,
    /// IEC 101: (device address, IOA) -> the points it feeds.
    pub objects: ObjectPoints,
}

impl LineSpec {
    /// The spec of `line`: the points among `points` (the node's, in its database `node`)
    /// whose source is one of its devices' signals or objects.
    pub(crate) fn new(line: &LineConfig, points: &[PointConfig], node: &NodePoints) -> LineSpec {
        let mut signals: HashMap<(u8, u8, u8, Option<u8>), Vec<LinePoint>> = HashMap::new();
        let mut objects = ObjectPoints::new();
        {
            let db = node.lock();
            for point in points {
                let PointSource::Line {
                    line: name,
                    device,
                    signal,
                } = &point.source
                else {
                    continue;
                };
                let address = line
                    .devices
                    .iter()
                    .find(|d| &d.name == device)
                    .map(|d| d.address);
                let (true, Some(address), Some(id)) =
                    (name == &line.name, address, db.id(point.name.as_str()))
                else {
                    continue;
                };
                match signal {
                    LineSignal::Iec103 { fun, inf, index } => signals
                        .entry((address, *fun, *inf, *index))
                        .or_default()
                        .push(LinePoint {
                            id,
                            kind: point.point_type.kind,
                            scaling: point.scaling,
                        }),
                    LineSignal::Iec101 { ioa } => {
                        objects.entry((address, *ioa)).or_default().push(id)
                    }
                }
            }
        }
        LineSpec {
            config: line.clone(),
            signals,
            objects,
        }
    }

    /// The FT1.2 primary polling the line's devices, with the line's timing.
    fn primary(&self, address_size: AddressSize, now: std::time::Instant) -> Primary {
        Primary::new(
            PrimaryConfig {
                address_size,
                line: self.config.settings,
                response_timeout: self.config.timeout,
                retries: self.config.retries,
                poll_interval: self.config.poll_interval,
                ..PrimaryConfig::default()
            },
            now,
        )
    }
}

/// Why a general command did not go through.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum CommandProblem {
    /// The device reports LOCAL.
    Local,
    /// Refused by the device (negative acknowledgement).
    Refused,
    /// Not acknowledged in time, or the device is not answering.
    NoAnswer(String),
}

/// A device as the handle knows it.
#[derive(Debug, Clone)]
struct DeviceEntry {
    name: String,
    address: u8,
    common_address: u16,
    local_indication: Option<(u8, u8)>,
}

/// The master of a line, by protocol.
#[derive(Clone)]
enum Driver {
    Iec103(iec103::Iec103Line),
    Iec101(iec101::Iec101Line),
}

/// A running line.
#[derive(Clone)]
pub struct LineHandle {
    name: String,
    devices: Vec<DeviceEntry>,
    /// The devices answering now: a command to a silent one fails at once.
    answering: Answering,
    driver: Driver,
    simulated: Option<mpsc::UnboundedSender<EndpointAction<Simulated>>>,
}

/// The devices of a line answering now (the line's status point is TRUE while none does).
#[derive(Debug, Clone, Default)]
pub(crate) struct Answering(Arc<Mutex<HashSet<u8>>>);

impl Answering {
    /// Notes a device answering or not; whether any does now.
    fn set(&self, address: u8, up: bool) -> bool {
        let mut answering = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        if up {
            answering.insert(address);
        } else {
            answering.remove(&address);
        }
        !answering.is_empty()
    }

    fn contains(&self, address: u8) -> bool {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .contains(&address)
    }

    /// None answers (the line closed); whether any did.
    fn clear(&self) -> bool {
        let mut answering = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        let any = !answering.is_empty();
        answering.clear();
        any
    }
}

impl std::fmt::Debug for LineHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LineHandle")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

impl LineHandle {
    /// The line's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The names of the line's devices simulated in this process (none for a real line).
    pub fn simulated_devices(&self) -> Vec<&str> {
        if self.simulated.is_none() {
            return Vec::new();
        }
        self.devices
            .iter()
            .map(|device| device.name.as_str())
            .collect()
    }

    fn device(&self, name: &str) -> Option<&DeviceEntry> {
        self.devices
            .iter()
            .find(|device| device.name.eq_ignore_ascii_case(name))
    }

    /// Sends a general command (IEC 103) to a device and waits for its acknowledgement.
    pub(crate) async fn command(
        &self,
        device: &str,
        fun: u8,
        inf: u8,
        on: bool,
    ) -> Result<(), CommandProblem> {
        let Some(entry) = self.device(device) else {
            return Err(CommandProblem::NoAnswer(format!(
                "no device {device} on line {}",
                self.name
            )));
        };
        match &self.driver {
            Driver::Iec103(line) => {
                line.command(entry.address, (fun, inf, on), entry.local_indication)
                    .await
            }
            Driver::Iec101(_) => Err(CommandProblem::NoAnswer(format!(
                "line {} is IEC 101: its commands go to an IOA",
                self.name
            ))),
        }
    }

    /// Forwards a command (IEC 101) to IOA `ioa` of a device: its confirmation is the
    /// outcome, an executed command's termination waits for the device's.
    pub(crate) async fn forward(
        &self,
        device: &str,
        ioa: Ioa,
        command: &Command,
    ) -> (CommandOutcome, String, Option<TerminationFuture>) {
        let Some(entry) = self.device(device) else {
            return (
                CommandOutcome::Failed,
                format!("no device {device} on line {}", self.name),
                None,
            );
        };
        if !self.answering.contains(entry.address) {
            return (
                CommandOutcome::Failed,
                format!("{device} on line {} is not answering: not sent", self.name),
                None,
            );
        }
        match &self.driver {
            Driver::Iec101(line) => {
                line.forward(
                    (&entry.name, entry.address, entry.common_address),
                    ioa,
                    command,
                )
                .await
            }
            Driver::Iec103(_) => (
                CommandOutcome::Refused,
                format!("line {} is IEC 103: it takes general commands", self.name),
                None,
            ),
        }
    }

    /// A console operation on a simulated device ([`Device::operate`]: `local`,
    /// `remote`, `inject I U`, `open`, `close`, `fault` ...). Errors name what is wrong.
    pub fn operate(&self, device: &str, words: &[&str]) -> Result<String, OperationError> {
        // Not this line's (or not simulated here): the caller tries the other lines.
        let (Some(simulated), Some(entry)) = (&self.simulated, self.device(device)) else {
            return Err(OperationError::NoDevice(device.to_owned()));
        };
        let address = u16::from(entry.address);
        let words: Vec<String> = words.iter().map(|word| (*word).to_owned()).collect();
        let (done, answer) = std::sync::mpsc::channel();
        simulated
            .send(Box::new(move |line: &mut Simulated| {
                let result = match line.station(address) {
                    Some(station) => {
                        let words: Vec<&str> = words.iter().map(String::as_str).collect();
                        station.app().operate(&words)
                    }
                    None => Err("no such device".to_owned()),
                };
                let _ = done.send(result);
            }))
            .map_err(|_| OperationError::Stopped(format!("line {}", self.name)))?;
        // The line's loop runs the operation at once; a line being reopened may take
        // a moment.
        answer
            .recv_timeout(Duration::from_secs(5))
            .map_err(|_| OperationError::Stopped(format!("line {}", self.name)))?
            .map_err(OperationError::Refused)
    }
}

/// Starts the line's task.
pub(crate) fn spawn_line(spec: LineSpec, node: Arc<NodePoints>) -> LineHandle {
    let devices = spec
        .config
        .devices
        .iter()
        .map(|device| DeviceEntry {
            name: device.name.clone(),
            address: device.address,
            common_address: device.common_address,
            local_indication: device.local_indication,
        })
        .collect();
    let name = spec.config.name.clone();
    let answering = Answering::default();
    let (driver, simulated) = match spec.config.protocol.clone() {
        LineProtocol::Iec103 => {
            let simulated = match &spec.config.transport {
                LineTransport::Simulated(_) => Some(mpsc::unbounded_channel()),
                _ => None,
            };
            let (sender, receiver) = simulated.unzip();
            let line = iec103::spawn(spec, node, answering.clone(), receiver);
            (Driver::Iec103(line), sender)
        }
        LineProtocol::Iec101(settings) => {
            let line = iec101::spawn(spec, settings, node, answering.clone());
            (Driver::Iec101(line), None)
        }
    };
    LineHandle {
        name,
        devices,
        answering,
        driver,
        simulated,
    }
}

/// Every device of the line down (its points invalid, its status point TRUE), and the
/// line's status point TRUE: at the start and whenever the line closes.
fn all_down(spec: &LineSpec, node: &NodePoints) {
    for device in &spec.config.devices {
        set_device_down(spec, node, device.address);
    }
    set_line_status(spec, node, false);
}

/// Opens the line; a simulated line starts its devices on an in-memory line.
async fn open(
    config: &LineConfig,
    simulated: &mut Option<mpsc::UnboundedReceiver<EndpointAction<Simulated>>>,
) -> std::io::Result<std::pin::Pin<Box<dyn iec60870::ft12::io::LineStream>>> {
    match &config.transport {
        LineTransport::Serial(path) => Ok(Transport::Serial {
            path: path.clone(),
            line: config.settings,
        }
        .open()
        .await?
        .stream),
        LineTransport::Tcp(address) => Ok(Transport::Connect(address.clone()).open().await?.stream),
        LineTransport::Simulated(_) => {
            let (ours, theirs) = tokio::io::duplex(4096);
            let now = tokio::time::Instant::now().into_std();
            let time = chrono::Utc::now().naive_utc();
            let stations = config
                .devices
                .iter()
                .map(|device| {
                    let mut profile = DeviceProfile::ref630(device.address);
                    profile.cycle = Duration::from_secs(5);
                    SecondaryStation::new(
                        config.settings,
                        Secondary::new(SecondaryConfig::new(device.address.into())),
                        Device::new(profile, now, time),
                    )
                })
                .collect();
            let mut line = SharedLine::new(stations);
            let mut operations = simulated
                .take()
                .unwrap_or_else(|| mpsc::unbounded_channel().1);
            tokio::spawn(async move {
                let _ = drive(Box::pin(theirs), &mut line, &mut operations, |line| {
                    // The master sees what the devices send; their own log is not needed.
                    for station in line.stations_mut() {
                        while station.app().poll_event().is_some() {}
                    }
                    ControlFlow::Continue(())
                })
                .await;
            });
            Ok(Box::pin(ours))
        }
    }
}

/// A device's link came up (`up`) or failed: its status point, its points (invalid while
/// it is silent) and the line's status point (TRUE while no device answers).
fn device_link(spec: &LineSpec, node: &NodePoints, answering: &Answering, address: u16, up: bool) {
    let Ok(address) = u8::try_from(address) else {
        return;
    };
    if up {
        tracing::info!(node = %node.name(), line = %spec.config.name, address, "device answering");
        set_device_status(spec, node, address, true);
    } else {
        tracing::warn!(node = %node.name(), line = %spec.config.name, address, "device not answering");
        set_device_down(spec, node, address);
    }
    let any = answering.set(address, up);
    set_line_status(spec, node, any);
}

fn set_line_status(spec: &LineSpec, node: &NodePoints, up: bool) {
    // The line's status point shows whether any device answers; the points are the
    // devices' own.
    let line = CommunicationStatus::new(
        format!("line {}", spec.config.name),
        spec.config.status_point.clone(),
        |_| false,
    );
    if up {
        line.up(node);
    } else {
        line.down(node);
    }
}

/// A device's status point and the points it feeds.
fn device_comm(spec: &LineSpec, address: u8) -> Option<CommunicationStatus> {
    let device = spec
        .config
        .devices
        .iter()
        .find(|device| device.address == address)?;
    let (line, name) = (spec.config.name.clone(), device.name.clone());
    Some(CommunicationStatus::new(
        format!("line {line}"),
        device.status_point.clone(),
        move |source| matches!(source, PointSource::Line { line: l, device: d, .. } if *l == line && *d == name),
    ))
}

fn set_device_status(spec: &LineSpec, node: &NodePoints, address: u8, up: bool) {
    if let Some(comm) = device_comm(spec, address) {
        if up {
            comm.up(node);
        } else {
            comm.down(node);
        }
    }
}

/// Invalidates a device's points and reports it as not answering.
fn set_device_down(spec: &LineSpec, node: &NodePoints, address: u8) {
    set_device_status(spec, node, address, false);
}
