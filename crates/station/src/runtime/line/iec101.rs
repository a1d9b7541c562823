//! IEC 101 outstations on a node's serial line: the gateway's second source.
//!
//! One task per line drives an [`iec101::Master`] (an FT1.2 primary polling every
//! outstation of the line, clock synchronisation and general interrogation each time an
//! outstation's link comes up). The outstations' monitor data update the points whose
//! source is `line:LINE/DEVICE/IOA`, through the same element-to-value mapping as a
//! concentrator's IEC 104 link ([`from_element`], [`EventCause::of_received`]); an
//! outstation that stops answering turns its points invalid and its status point TRUE.
//!
//! Commands routed to `line:LINE/DEVICE/IOA` are forwarded as they came (type, value,
//! select or execute, time tag) to the outstation's IOA; its confirmation becomes the
//! node's, its termination the node's termination ([`super::super::forwarded`]), after
//! the return information received before it.
//!
//! ```text
//!  command from above --> LineHandle::forward --> action: Master::send(address, ASDU)
//!                                 | watch (type, IOA)            | FT1.2 send/confirm
//!  ACT_CON / ACT_TERM <-- CommandWatches::answered <-- observe <-- outstation's class 1 data
//!  monitor data ----------> from_element --> NodePoints::update (line:LINE/DEVICE/IOA)
//! ```

use std::collections::HashMap;
use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Duration;

use iec60870::asdu::{Asdu, AsduParams, Cause, CommonAddress, Cot, InformationObject, Ioa};
use iec60870::ft12::io::{drive, EndpointAction};
use iec60870::ft12::PrimaryEvent;
use iec60870::iec101::{self, MasterEvent, StartUp};
use iec60870::outstation::{Command, TerminationFuture};
use tokio::sync::mpsc;

use crate::config::Iec101Settings;
use crate::store::CommandOutcome;
use points::PointId;

use super::super::field::{supervise, Ended, FieldSource};
use super::super::forwarded::CommandWatches;
use super::super::node::NodePoints;
use super::{all_down, device_link, open, LineSpec};
use super::{Answering, COMMAND_TIMEOUT};
use crate::device::DeviceError;
use iec60870::ft12::io::LineStream;
use std::pin::Pin;

/// How long an executed command waits for the outstation's termination, which the
/// standard leaves to the outstation, before it is terminated here.
const TERMINATION_TIMEOUT: Duration = Duration::from_secs(10);

/// The running IEC 101 part of a line: what forwarding a command needs.
#[derive(Clone)]
pub(super) struct Iec101Line {
    actions: mpsc::UnboundedSender<EndpointAction<iec101::Master>>,
    commands: Arc<CommandWatches>,
    params: AsduParams,
}

/// The outstations' values: (link address, IOA) -> the points they feed.
pub(crate) type ObjectPoints = HashMap<(u8, u32), Vec<PointId>>;

/// Starts the line's task.
pub(super) fn spawn(
    spec: LineSpec,
    settings: Iec101Settings,
    node: Arc<NodePoints>,
    answering: Answering,
) -> Iec101Line {
    let (actions, inbox) = mpsc::unbounded_channel();
    let commands = Arc::new(CommandWatches::default());
    let line = Iec101Line {
        actions,
        commands: Arc::clone(&commands),
        params: settings.params,
    };
    tokio::spawn(async move {
        let source = Iec101Source {
            spec,
            settings,
            node: Arc::clone(&node),
            inbox,
            commands,
            answering_now: answering,
        };
        supervise(node.name(), source).await;
    });
    line
}

/// An IEC 101 line under the field-source supervisor.
struct Iec101Source {
    spec: LineSpec,
    settings: Iec101Settings,
    node: Arc<NodePoints>,
    inbox: mpsc::UnboundedReceiver<EndpointAction<iec101::Master>>,
    commands: Arc<CommandWatches>,
    answering_now: Answering,
}

impl FieldSource for Iec101Source {
    type Line = Pin<Box<dyn LineStream>>;

    fn describe(&self) -> String {
        format!("line {}", self.spec.config.name)
    }

    async fn open(&mut self) -> Result<Self::Line, DeviceError> {
        Ok(open(&self.spec.config, &mut None).await?)
    }

    async fn run(&mut self, stream: Self::Line) -> Ended {
        let Iec101Source {
            spec,
            settings,
            node,
            inbox,
            commands,
            answering_now,
        } = self;
        let now = tokio::time::Instant::now().into_std();
        let primary = spec.primary(settings.address_size, now);
        let clock_node = Arc::clone(node);
        let mut master = iec101::Master::new(
            primary,
            settings.params,
            StartUp {
                clock_sync: true,
                interrogate: true,
                originator: 0,
            },
            Box::new(move || clock_node.clock().now().naive_utc()),
        );
        for device in &spec.config.devices {
            let common_address = CommonAddress::new(device.common_address);
            if let Err(error) = master.add_station(device.address.into(), common_address) {
                tracing::warn!(line = %spec.config.name, %error, "outstation not polled");
            }
        }
        let end = drive(stream, &mut master, inbox, |master| {
            observe(master, spec, settings, node, commands, answering_now);
            ControlFlow::Continue(())
        })
        .await;
        commands.abandon_all();
        Ended {
            answered: answering_now.clear(),
            reason: format!("{end:?}"),
        }
    }

    fn lost(&mut self) {
        all_down(&self.spec, &self.node);
    }
}

fn observe(
    master: &mut iec101::Master,
    spec: &LineSpec,
    settings: &Iec101Settings,
    node: &NodePoints,
    commands: &CommandWatches,
    answering_now: &Answering,
) {
    while let Some(event) = master.poll_event() {
        match event {
            MasterEvent::Asdu { address, asdu } => {
                let Ok(address) = u8::try_from(address) else {
                    continue;
                };
                match Asdu::decode(&asdu, &settings.params) {
                    Ok(asdu) if asdu.type_id.is_command() => commands.answered(&asdu),
                    Ok(asdu) => apply(spec, node, address, &asdu),
                    Err(error) => {
                        tracing::warn!(node = %node.name(), line = %spec.config.name, address, %error, "undecodable ASDU from the outstation");
                    }
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

/// An outstation's monitor data into the points they feed.
fn apply(spec: &LineSpec, node: &NodePoints, address: u8, asdu: &Asdu) {
    let origin = format!("line {}", spec.config.name);
    node.apply_received(&origin, asdu, |ioa| {
        spec.objects.get(&(address, ioa)).map(Vec::as_slice)
    });
}

impl Iec101Line {
    /// Forwards a command to IOA `ioa` of the outstation at `address` (common address
    /// `common_address`) and follows it: the outstation's confirmation is the outcome;
    /// an executed command's termination waits for the outstation's.
    pub(super) async fn forward(
        &self,
        (name, address, common_address): (&str, u8, u16),
        ioa: Ioa,
        command: &Command,
    ) -> (CommandOutcome, String, Option<TerminationFuture>) {
        let mut cot = Cot::new(Cause::ACTIVATION);
        cot.originator = command.originator;
        let mut asdu = Asdu::new(command.type_id, cot, CommonAddress::new(common_address));
        asdu.objects.push(InformationObject {
            ioa,
            element: command.element.clone(),
            time: command.time,
        });
        let bytes = match asdu.to_bytes(&self.params) {
            Ok(bytes) => bytes,
            Err(error) => {
                return (
                    CommandOutcome::Refused,
                    format!("cannot be sent to {name}: {error}"),
                    None,
                )
            }
        };
        let answers = self.commands.watch(command.type_id, ioa);
        let (sent, sent_rx) = tokio::sync::oneshot::channel();
        let action: EndpointAction<iec101::Master> = Box::new(move |master| {
            let _ = sent.send(
                master
                    .send(address.into(), bytes)
                    .map_err(|e| e.to_string()),
            );
        });
        if self.actions.send(action).is_err() {
            return (CommandOutcome::Failed, "the line stopped".to_owned(), None);
        }
        match sent_rx.await {
            Ok(Ok(())) => {}
            Ok(Err(why)) => {
                return (
                    CommandOutcome::Failed,
                    format!("not sent to {name}: {why}"),
                    None,
                )
            }
            Err(_) => return (CommandOutcome::Failed, "the line stopped".to_owned(), None),
        }
        let positive = match tokio::time::timeout(COMMAND_TIMEOUT, answers.confirmed).await {
            Ok(Ok(positive)) => positive,
            Ok(Err(_)) => {
                return (
                    CommandOutcome::Failed,
                    format!("{name} went away before confirming"),
                    None,
                )
            }
            Err(_) => {
                return (
                    CommandOutcome::TimedOut,
                    format!("no confirmation from {name} (IOA {ioa})"),
                    None,
                )
            }
        };
        if !positive {
            return (
                CommandOutcome::Refused,
                format!("refused by {name} (IOA {ioa})"),
                None,
            );
        }
        let detail = format!("confirmed by {name} (IOA {ioa})");
        if command.select {
            return (CommandOutcome::Executed, detail, None);
        }
        let terminated = answers.terminated;
        let termination: TerminationFuture = Box::pin(async move {
            // The standard leaves the termination to the outstation: without one the
            // command is terminated here after the wait.
            let _ = tokio::time::timeout(TERMINATION_TIMEOUT, terminated).await;
        });
        (CommandOutcome::Executed, detail, Some(termination))
    }
}
