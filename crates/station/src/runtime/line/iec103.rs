//! IEC 103 protection devices on a node's serial line: the COM600 gateway role of the
//! thesis.
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

use std::collections::HashMap;
use std::ops::ControlFlow;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use iec60870::ft12::io::{drive, EndpointAction};
use iec60870::ft12::{PrimaryEvent, SharedLine};
use iec60870::iec103::{self, Body, Cause, MasterEvent, StartUp};
use points::Quality;
use simulators::ref630::Device;
use tokio::sync::{mpsc, oneshot};

use points::{normalized, EventCause, PointKind, PointValue, SourceTime};

use super::super::field::{supervise, Ended, FieldSource};
use super::super::node::NodePoints;
use super::{all_down, device_link, open, Answering, CommandProblem, LineSpec, COMMAND_TIMEOUT};
use crate::device::DeviceError;
use iec60870::ft12::io::LineStream;
use std::pin::Pin;

/// The running IEC 103 part of a line: what a general command needs.
#[derive(Clone)]
pub(super) struct Iec103Line {
    actions: mpsc::UnboundedSender<EndpointAction<iec103::Master>>,
    shared: Arc<Mutex<Shared>>,
}

/// Simulated devices on an in-memory line.
pub(super) type Simulated = SharedLine<Device>;

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

/// Starts the line's task; `simulated` receives the console's operations of simulated
/// devices.
pub(super) fn spawn(
    spec: LineSpec,
    node: Arc<NodePoints>,
    answering: Answering,
    simulated: Option<mpsc::UnboundedReceiver<EndpointAction<Simulated>>>,
) -> Iec103Line {
    let (actions, inbox) = mpsc::unbounded_channel();
    let shared = Arc::new(Mutex::new(Shared::default()));
    let source = Iec103Source {
        spec,
        node: Arc::clone(&node),
        inbox,
        shared: Arc::clone(&shared),
        answering_now: answering,
        simulated,
    };
    tokio::spawn(async move { supervise(node.name(), source).await });
    Iec103Line { actions, shared }
}

impl Iec103Line {
    /// Sends a general command to the device at `address` and waits for its
    /// acknowledgement; refused unsent while the device's `local` indication is ON.
    pub(super) async fn command(
        &self,
        address: u8,
        (fun, inf, on): (u8, u8, bool),
        local: Option<(u8, u8)>,
    ) -> Result<(), CommandProblem> {
        let (reply, answer) = oneshot::channel();
        let request = Request::Command {
            address,
            fun,
            inf,
            on,
            local,
            reply,
        };
        let shared = Arc::clone(&self.shared);
        self.actions
            .send(Box::new(move |master: &mut iec103::Master| {
                command(master, &shared, request)
            }))
            .map_err(|_| CommandProblem::NoAnswer("the line stopped".to_owned()))?;
        match tokio::time::timeout(COMMAND_TIMEOUT + Duration::from_secs(1), answer).await {
            Ok(Ok(result)) => result,
            _ => Err(CommandProblem::NoAnswer(format!(
                "no acknowledgement from address {address}"
            ))),
        }
    }
}

/// The devices' states a command needs: indications by (address, FUN, INF), and the
/// commands awaiting their acknowledgement by (address, RII).
#[derive(Default)]
struct Shared {
    indications: HashMap<(u8, u8, u8), u8>,
    pending: HashMap<(u16, u8), oneshot::Sender<Result<(), CommandProblem>>>,
}

/// An IEC 103 line under the field-source supervisor.
struct Iec103Source {
    spec: LineSpec,
    node: Arc<NodePoints>,
    inbox: mpsc::UnboundedReceiver<EndpointAction<iec103::Master>>,
    shared: Arc<Mutex<Shared>>,
    answering_now: Answering,
    /// The simulated relays' operations, until the line is first opened.
    simulated: Option<mpsc::UnboundedReceiver<EndpointAction<Simulated>>>,
}

impl FieldSource for Iec103Source {
    type Line = Pin<Box<dyn LineStream>>;

    fn describe(&self) -> String {
        format!("line {}", self.spec.config.name)
    }

    async fn open(&mut self) -> Result<Self::Line, DeviceError> {
        Ok(open(&self.spec.config, &mut self.simulated).await?)
    }

    async fn run(&mut self, stream: Self::Line) -> Ended {
        let Iec103Source {
            spec,
            node,
            inbox,
            shared,
            answering_now,
            ..
        } = self;
        let now = tokio::time::Instant::now().into_std();
        // IEC 103 link addresses are one octet.
        let mut primary = spec.primary(iec60870::ft12::AddressSize::One, now);
        for device in &spec.config.devices {
            if let Err(error) = primary.add_station(device.address.into()) {
                tracing::warn!(line = %spec.config.name, %error, "device not polled");
            }
        }
        let clock_node = Arc::clone(node);
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
        let end = drive(stream, &mut master, inbox, |master| {
            observe(master, spec, node, shared, answering_now);
            ControlFlow::Continue(())
        })
        .await;
        let pending: Vec<_> = shared
            .lock()
            .map(|mut shared| {
                shared.indications.clear();
                shared.pending.drain().map(|(_, reply)| reply).collect()
            })
            .unwrap_or_default();
        for reply in pending {
            let _ = reply.send(Err(CommandProblem::NoAnswer("the line closed".to_owned())));
        }
        Ended {
            answered: answering_now.clear(),
            reason: format!("{end:?}"),
        }
    }

    fn lost(&mut self) {
        all_down(&self.spec, &self.node);
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
    answering_now: &Answering,
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
                device_link(spec, node, answering_now, address, false);
            }
            MasterEvent::Link(PrimaryEvent::LinkUp { address }) => {
                device_link(spec, node, answering_now, address, true);
            }
            _ => {}
        }
    }
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
            let Some(points) = spec.signals.get(&(address, header.fun, header.inf, None)) else {
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
                let value = match point.kind {
                    PointKind::Double => PointValue::DoublePoint(*dpi & 0x03),
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
                let Some(points) =
                    spec.signals
                        .get(&(address, header.fun, header.inf, Some(index)))
                else {
                    continue;
                };
                for point in points {
                    let Some(scaling) = point.scaling else {
                        continue;
                    };
                    let physical = value.to_physical(scaling.limit);
                    let converted = match point.kind {
                        PointKind::Scaled => PointValue::Int(i64::from(saturating_i16(
                            physical * scaling.factor.unwrap_or(1.0),
                        ))),
                        PointKind::Normalized => {
                            let fraction = match scaling.full_scale {
                                Some(full_scale) => physical / full_scale,
                                // The engineering value as the raw integer, as the COM600
                                // sent it (100 A -> 100).
                                None => normalized::from_raw(saturating_i16(physical)),
                            };
                            PointValue::Float(fraction.clamp(-1.0, normalized::from_raw(i16::MAX)))
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

/// `x` rounded to the nearest 16-bit integer, saturating at its ends.
fn saturating_i16(x: f64) -> i16 {
    // The clamp makes the cast exact (NaN casts to 0).
    #[allow(clippy::cast_possible_truncation)]
    let value = x.round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16;
    value
}
