//! A node's serial line to protection devices (IEC 103): the gateway role of the ABB
//! COM600 in the thesis.
//!
//! One task per line drives an [`iec103::Master`] over the line's transport: the
//! devices' indications (ASDU 1/2) and measurands (ASDU 3/9) update the points whose
//! source is `line:LINE/DEVICE/FUN/INF[/INDEX]`, converted to each point's type (a
//! measurand's fraction times its `measurand_limit`, then float, scaled or normalized);
//! a device that stops answering turns its points invalid (IV, value kept) and its
//! status point TRUE; when it answers again the master interrogates it and the values
//! come back. Commands routed to `line:` targets become general commands (ASDU 20);
//! their acknowledgement (ASDU 1, COT 20/21) is the outcome; while the device reports
//! LOCAL on its `local_indication` they are refused without being sent.
//!
//! A `simulate = "ref630"` line runs the thesis's relay at each device's address inside
//! this process, on an in-memory line; the console operates it ([`LineHandle::operate`]).

use std::collections::HashMap;
use std::ops::ControlFlow;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use iec60870::asdu::{Quality, TypeId};
use iec60870::ft12::io::{drive, EndpointAction, Transport};
use iec60870::ft12::{
    Primary, PrimaryConfig, PrimaryEvent, Secondary, SecondaryConfig, SecondaryStation, SharedLine,
};
use iec60870::iec103::{self, Body, Cause, Device, DeviceProfile, MasterEvent, StartUp};
use tokio::sync::{mpsc, oneshot};

use crate::config::{LineConfig, LineTransport, MeasurandScaling};
use crate::pointdb::{PointId, PointSource};
use crate::store::EventCause;
use crate::store::{PointValue, SourceTime};

use super::node::NodePoints;

/// How long a general command waits for the device's acknowledgement.
const COMMAND_TIMEOUT: Duration = Duration::from_secs(10);
/// The pause before a failed transport is opened again.
const REOPEN_AFTER: Duration = Duration::from_secs(5);

/// A point fed by a line device, with what its conversion needs.
#[derive(Debug, Clone)]
pub(crate) struct LinePoint {
    pub id: PointId,
    pub type_id: TypeId,
    pub scaling: Option<MeasurandScaling>,
}

/// What a line is configured to do.
#[derive(Debug, Clone)]
pub(crate) struct LineSpec {
    pub config: LineConfig,
    /// (device address, FUN, INF, index) -> the points it feeds.
    pub points: HashMap<(u8, u8, u8, Option<u8>), Vec<LinePoint>>,
}

type Simulated = SharedLine<Device>;

/// What the node asks of a line.
enum Request {
    Command {
        address: u8,
        fun: u8,
        inf: u8,
        on: bool,
        local: Option<(u8, u8)>,
        reply: oneshot::Sender<Result<(), CommandProblem>>,
    },
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

/// A device as the handle knows it: name, address, LOCAL/REMOTE indication.
type DeviceEntry = (String, u8, Option<(u8, u8)>);

/// A running line.
#[derive(Clone)]
pub struct LineHandle {
    name: String,
    devices: Vec<DeviceEntry>,
    actions: mpsc::UnboundedSender<EndpointAction<iec103::Master>>,
    shared: Arc<Mutex<Shared>>,
    simulated: Option<mpsc::UnboundedSender<EndpointAction<Simulated>>>,
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

    /// Sends a general command to a device and waits for its acknowledgement.
    pub(crate) async fn command(
        &self,
        device: &str,
        fun: u8,
        inf: u8,
        on: bool,
    ) -> Result<(), CommandProblem> {
        let Some((_, address, local)) = self.devices.iter().find(|(name, ..)| name == device)
        else {
            return Err(CommandProblem::NoAnswer(format!(
                "no device {device} on line {}",
                self.name
            )));
        };
        let (reply, answer) = oneshot::channel();
        let request = Request::Command {
            address: *address,
            fun,
            inf,
            on,
            local: *local,
            reply,
        };
        let shared = Arc::clone(&self.shared);
        self.actions
            .send(Box::new(move |master: &mut iec103::Master| {
                command(master, &shared, request)
            }))
            .map_err(|_| CommandProblem::NoAnswer(format!("line {} stopped", self.name)))?;
        match tokio::time::timeout(COMMAND_TIMEOUT + Duration::from_secs(1), answer).await {
            Ok(Ok(result)) => result,
            _ => Err(CommandProblem::NoAnswer(format!(
                "no acknowledgement from {device}"
            ))),
        }
    }

    /// A console operation on a simulated device ([`Device::operate`]: `local`,
    /// `remote`, `inject I U`, `open`, `close`, `fault` ...). Errors name what is wrong.
    pub fn operate(&self, device: &str, words: &[&str]) -> Result<String, String> {
        let Some(simulated) = &self.simulated else {
            return Err(format!("line {} has no simulated devices", self.name));
        };
        let Some((_, address, _)) = self
            .devices
            .iter()
            .find(|(name, ..)| name.eq_ignore_ascii_case(device))
        else {
            return Err(format!("line {} has no device {device}", self.name));
        };
        let address = u16::from(*address);
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
            .map_err(|_| format!("line {} stopped", self.name))?;
        // The line's loop runs the operation at once; a line being reopened may take
        // a moment.
        answer
            .recv_timeout(Duration::from_secs(5))
            .map_err(|_| format!("line {} did not take the operation", self.name))?
    }
}

/// Starts the line's task.
pub(crate) fn spawn_line(spec: LineSpec, node: Arc<NodePoints>) -> LineHandle {
    let (actions, inbox) = mpsc::unbounded_channel();
    let shared = Arc::new(Mutex::new(Shared::default()));
    let simulated = match &spec.config.transport {
        LineTransport::Simulated(_) => Some(mpsc::unbounded_channel()),
        _ => None,
    };
    let handle = LineHandle {
        name: spec.config.name.clone(),
        devices: spec
            .config
            .devices
            .iter()
            .map(|device| (device.name.clone(), device.address, device.local_indication))
            .collect(),
        actions,
        shared: Arc::clone(&shared),
        simulated: simulated.as_ref().map(|(sender, _)| sender.clone()),
    };
    tokio::spawn(run(
        spec,
        node,
        inbox,
        shared,
        simulated.map(|(_, receiver)| receiver),
    ));
    handle
}

/// The devices' states a command needs: indications by (address, FUN, INF), and the
/// commands awaiting their acknowledgement by (address, RII).
#[derive(Default)]
struct Shared {
    indications: HashMap<(u8, u8, u8), u8>,
    /// The devices answering now.
    answering: std::collections::HashSet<u8>,
    pending: HashMap<(u16, u8), oneshot::Sender<Result<(), CommandProblem>>>,
}

async fn run(
    spec: LineSpec,
    node: Arc<NodePoints>,
    mut inbox: mpsc::UnboundedReceiver<EndpointAction<iec103::Master>>,
    shared: Arc<Mutex<Shared>>,
    mut simulated: Option<mpsc::UnboundedReceiver<EndpointAction<Simulated>>>,
) {
    let name = spec.config.name.clone();
    for device in &spec.config.devices {
        set_device_down(&spec, &node, device.address);
    }
    set_line_status(&spec, &node, false);
    loop {
        let stream = match open(&spec.config, &mut simulated).await {
            Ok(stream) => stream,
            Err(error) => {
                tracing::warn!(node = %node.name(), line = %name, %error, "cannot open the line; trying again");
                tokio::time::sleep(REOPEN_AFTER).await;
                continue;
            }
        };
        let now = tokio::time::Instant::now().into_std();
        let mut primary = Primary::new(
            PrimaryConfig {
                line: spec.config.settings,
                response_timeout: spec.config.timeout,
                retries: spec.config.retries,
                poll_interval: spec.config.poll_interval,
                ..PrimaryConfig::default()
            },
            now,
        );
        for device in &spec.config.devices {
            if let Err(error) = primary.add_station(device.address.into()) {
                tracing::warn!(line = %name, %error, "device not polled");
            }
        }
        let clock_node = Arc::clone(&node);
        let mut master = iec103::Master::new(
            primary,
            StartUp {
                clock_sync: true,
                interrogate: true,
                disturbances: false,
            },
            Box::new(move || clock_node.clock().now().naive_utc()),
            now,
        );
        master.set_command_timeout(COMMAND_TIMEOUT);
        let end = drive(stream, &mut master, &mut inbox, |master| {
            observe(master, &spec, &node, &shared);
            ControlFlow::Continue(())
        })
        .await;
        tracing::warn!(node = %node.name(), line = %name, ?end, "line closed; opening it again");
        for device in &spec.config.devices {
            set_device_down(&spec, &node, device.address);
        }
        let pending: Vec<_> = shared
            .lock()
            .map(|mut shared| {
                shared.indications.clear();
                shared.answering.clear();
                shared.pending.drain().map(|(_, reply)| reply).collect()
            })
            .unwrap_or_default();
        for reply in pending {
            let _ = reply.send(Err(CommandProblem::NoAnswer("the line closed".to_owned())));
        }
        set_line_status(&spec, &node, false);
        tokio::time::sleep(REOPEN_AFTER).await;
    }
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

fn command(master: &mut iec103::Master, shared: &Mutex<Shared>, request: Request) {
    let Request::Command {
        address,
        fun,
        inf,
        on,
        local,
        reply,
    } = request;
    let Ok(mut shared) = shared.lock() else {
        return;
    };
    if let Some((local_fun, local_inf)) = local {
        if shared.indications.get(&(address, local_fun, local_inf)) == Some(&2) {
            let _ = reply.send(Err(CommandProblem::Local));
            return;
        }
    }
    match master.general_command(address, fun, inf, on) {
        Ok(rii) => {
            shared.pending.insert((u16::from(address), rii), reply);
        }
        Err(error) => {
            let _ = reply.send(Err(CommandProblem::NoAnswer(error.to_string())));
        }
    }
}

fn observe(
    master: &mut iec103::Master,
    spec: &LineSpec,
    node: &NodePoints,
    shared: &Mutex<Shared>,
) {
    while let Some(event) = master.poll_event() {
        match event {
            MasterEvent::Asdu { address, asdu } => {
                let Ok(address) = u8::try_from(address) else {
                    continue;
                };
                apply(spec, node, shared, address, &asdu);
            }
            MasterEvent::CommandResult {
                address,
                rii,
                positive,
                ..
            } => {
                let reply = shared
                    .lock()
                    .ok()
                    .and_then(|mut shared| shared.pending.remove(&(address, rii)));
                if let Some(reply) = reply {
                    let _ = reply.send(if positive {
                        Ok(())
                    } else {
                        Err(CommandProblem::Refused)
                    });
                }
            }
            MasterEvent::Link(PrimaryEvent::LinkDown { address }) => {
                if let Ok(address) = u8::try_from(address) {
                    tracing::warn!(node = %node.name(), line = %spec.config.name, address, "device not answering");
                    set_device_down(spec, node, address);
                    answering(spec, node, shared, address, false);
                }
            }
            MasterEvent::Link(PrimaryEvent::LinkUp { address }) => {
                if let Ok(address) = u8::try_from(address) {
                    tracing::info!(node = %node.name(), line = %spec.config.name, address, "device answering");
                    set_device_status(spec, node, address, true);
                    answering(spec, node, shared, address, true);
                }
            }
            _ => {}
        }
    }
}

/// Notes a device answering or not; the line's status point is TRUE while none does.
fn answering(spec: &LineSpec, node: &NodePoints, shared: &Mutex<Shared>, address: u8, up: bool) {
    let any = shared.lock().map(|mut shared| {
        if up {
            shared.answering.insert(address);
        } else {
            shared.answering.remove(&address);
        }
        !shared.answering.is_empty()
    });
    if let Ok(any) = any {
        set_line_status(spec, node, any);
    }
}

fn set_line_status(spec: &LineSpec, node: &NodePoints, up: bool) {
    let Some(point) = spec.config.status_point.clone() else {
        return;
    };
    node.change_with(&format!("line {}", spec.config.name), |db, now| {
        db.set_link_status(point.as_str(), up, now)
            .ok()
            .flatten()
            .into_iter()
            .collect()
    });
}

fn device_name(spec: &LineSpec, address: u8) -> Option<&str> {
    spec.config
        .devices
        .iter()
        .find(|device| device.address == address)
        .map(|device| device.name.as_str())
}

fn set_device_status(spec: &LineSpec, node: &NodePoints, address: u8, up: bool) {
    let Some(point) = spec
        .config
        .devices
        .iter()
        .find(|device| device.address == address)
        .and_then(|device| device.status_point.clone())
    else {
        return;
    };
    node.change_with(&format!("line {}", spec.config.name), |db, now| {
        db.set_link_status(point.as_str(), up, now)
            .ok()
            .flatten()
            .into_iter()
            .collect()
    });
}

/// Invalidates a device's points and reports it as not answering.
fn set_device_down(spec: &LineSpec, node: &NodePoints, address: u8) {
    let Some(device) = device_name(spec, address).map(str::to_owned) else {
        return;
    };
    let line = spec.config.name.clone();
    node.change_with(&format!("line {line}"), |db, now| {
        db.invalidate_where(
            |point| matches!(&point.source, PointSource::Line { line: l, device: d, .. } if *l == line && *d == device),
            now,
        )
    });
    set_device_status(spec, node, address, false);
}

fn apply(
    spec: &LineSpec,
    node: &NodePoints,
    shared: &Mutex<Shared>,
    address: u8,
    asdu: &iec103::Asdu,
) {
    let origin = format!("line {}", spec.config.name);
    let header = &asdu.header;
    match &asdu.body {
        Body::TimeTagged { dpi, time, .. } | Body::TimeTaggedRelative { dpi, time, .. } => {
            if matches!(header.cause, Cause::COMMAND_ACK | Cause::COMMAND_NACK) {
                // An acknowledgement says what was commanded, not what the device is.
                return;
            }
            if let Ok(mut shared) = shared.lock() {
                shared
                    .indications
                    .insert((address, header.fun, header.inf), *dpi);
            }
            let Some(points) = spec.points.get(&(address, header.fun, header.inf, None)) else {
                return;
            };
            let now = node.clock().now();
            let source_time = time.resolve(now.naive_utc()).map(|naive| SourceTime {
                time: naive.and_utc(),
                invalid: time.is_invalid(),
            });
            let (cause, event) = match header.cause {
                Cause::LOCAL_OPERATION => (EventCause::ReturnLocal, true),
                Cause::REMOTE_OPERATION => (EventCause::ReturnRemote, true),
                Cause::SPONTANEOUS => (EventCause::Spontaneous, true),
                _ => (EventCause::Spontaneous, false),
            };
            for point in points {
                let value = match point.type_id {
                    TypeId::M_DP_NA_1 | TypeId::M_DP_TB_1 => PointValue::DoublePoint(*dpi & 0x03),
                    _ => PointValue::Bool(*dpi & 0x03 == 2),
                };
                if let Err(error) = node.update(
                    point.id,
                    value,
                    Quality::GOOD,
                    source_time,
                    cause,
                    &origin,
                    event,
                ) {
                    tracing::warn!(node = %node.name(), line = %spec.config.name, %error, "value from the line refused");
                }
            }
        }
        Body::Measurands(values) => {
            for (index, value) in values.iter().enumerate() {
                let Ok(index) = u8::try_from(index) else {
                    continue;
                };
                let Some(points) = spec
                    .points
                    .get(&(address, header.fun, header.inf, Some(index)))
                else {
                    continue;
                };
                for point in points {
                    let Some(scaling) = point.scaling else {
                        continue;
                    };
                    let physical = value.to_physical(scaling.limit);
                    let converted = match point.type_id {
                        TypeId::M_ME_NB_1 | TypeId::M_ME_TB_1 | TypeId::M_ME_TE_1 => {
                            let scaled = physical * scaling.factor.unwrap_or(1.0);
                            PointValue::Int(scaled.round().clamp(-32768.0, 32767.0) as i64)
                        }
                        TypeId::M_ME_NA_1
                        | TypeId::M_ME_TA_1
                        | TypeId::M_ME_TD_1
                        | TypeId::M_ME_ND_1 => {
                            let fraction = match scaling.full_scale {
                                Some(full_scale) => physical / full_scale,
                                // The engineering value as the raw integer, as the COM600
                                // sent it (100 A -> 100).
                                None => physical.round() / 32768.0,
                            };
                            PointValue::Float(fraction.clamp(-1.0, 32767.0 / 32768.0))
                        }
                        _ => PointValue::Float(physical),
                    };
                    let quality = Quality {
                        invalid: value.error(),
                        overflow: value.overflow(),
                        ..Quality::GOOD
                    };
                    if let Err(error) = node.update(
                        point.id,
                        converted,
                        quality,
                        None,
                        EventCause::Spontaneous,
                        &origin,
                        false,
                    ) {
                        tracing::warn!(node = %node.name(), line = %spec.config.name, %error, "value from the line refused");
                    }
                }
            }
        }
        _ => {}
    }
}
