//! A node's IEC 104 server hooks: commands travel down the hierarchy and their outcome
//! travels back; clock synchronisation sets the node's clock and is passed down.
//!
//! A command addressed to a PLC variable goes to the simulation thread, which refuses it
//! while the board's `remote_enable` variable is FALSE (Local/Remote switch in local) and
//! otherwise writes it (held for the pulse time, then reset). A command addressed to a
//! link is sent to the lower node with the same qualifier (a select stays a select) and
//! its confirmation becomes this node's. Each is audited in the store with the peer's
//! address, the time on the node's clock, the target, the value and the outcome.
//!
//! The command sequence (ACT_CON, return information, ACT_TERM) holds on every path: a
//! command with a feedback point is confirmed when the PLC took it and terminated once
//! the point's next change went out as return information (or its wait ran out); a
//! forwarded command is confirmed when the lower node confirmed it and terminated when
//! the lower node's termination arrived, after the data that came before it.
//!
//! A node's handler is built from its configuration here ([`NodeHandler::new`]): each
//! command routed by its target, the links whose lower node takes the node's time.

use std::collections::HashMap;
use std::sync::{mpsc, Arc};
use std::time::Duration;

use iec60870::asdu::{DoublePointState, Element, TimeTag};
use iec60870::cs104::server::{self, CommandFuture, StationHandler, TerminationFuture};
use iec60870::outstation::Peer;
use iec60870::time::Cp56Time2a;
use tokio::sync::oneshot;

use crate::config::{CommandConfig, CommandTarget, NodeConfig};
use crate::store::{Actor, CommandOutcome, CommandPhase, CommandRecord, PointValue};

use super::clock::LocalClocks;
use super::link::LinkHandle;
use super::node::NodePoints;
use super::simulation::{CommandRefusal, SimRequest};

/// The pulse length of a command with QU 1 or 2 when the project sets none.
pub(crate) const DEFAULT_PULSE: Duration = Duration::from_millis(500);

/// Where a command of this node goes.
#[derive(Debug, Clone)]
pub(crate) enum Route {
    /// A PLC variable of this node (simulation node index).
    Plc {
        node: usize,
        pulse: Option<Duration>,
    },
    /// Down a link, as command `ioa` of the lower node.
    Link {
        link: String,
        ioa: iec60870::asdu::Ioa,
    },
    /// To a device on a serial line, as a general command to FUN/INF (ON/OFF fixed by
    /// `value`, or the command's own).
    Line {
        line: String,
        device: String,
        fun: u8,
        inf: u8,
        value: Option<bool>,
    },
    /// To an IEC 101 outstation on a serial line, forwarded as it came to its `ioa`.
    LineObject {
        line: String,
        device: String,
        ioa: iec60870::asdu::Ioa,
    },
}

impl Route {
    /// Where `command` goes by its target; `sim_node` is the node's index on the
    /// simulation thread.
    fn of(command: &CommandConfig, sim_node: usize) -> Route {
        match &command.target {
            CommandTarget::Variable(_) => Route::Plc {
                node: sim_node,
                pulse: command.pulse,
            },
            CommandTarget::Link { link, ioa } => Route::Link {
                link: link.clone(),
                ioa: *ioa,
            },
            CommandTarget::Line {
                line,
                device,
                fun,
                inf,
                value,
            } => Route::Line {
                line: line.clone(),
                device: device.clone(),
                fun: *fun,
                inf: *inf,
                value: *value,
            },
            CommandTarget::LineObject { line, device, ioa } => Route::LineObject {
                line: line.clone(),
                device: device.clone(),
                ioa: *ioa,
            },
        }
    }
}

#[derive(Debug, Clone)]
pub(crate) struct RoutedCommand {
    pub name: String,
    pub route: Route,
    /// Only clients of these redundancy groups may send it (empty: any).
    pub from_groups: Vec<String>,
    /// The point returning its effect (commands on a PLC variable).
    pub feedback: Option<crate::config::Feedback>,
    /// The values a set-point may take.
    pub range: Option<std::ops::RangeInclusive<f64>>,
}

/// The [`StationHandler`] of a node's server.
pub(crate) struct NodeHandler {
    pub points: Arc<NodePoints>,
    pub commands: HashMap<u32, RoutedCommand>,
    /// Set once the links are up (they start after every server of the process).
    pub links: std::sync::OnceLock<HashMap<String, LinkHandle>>,
    /// Set once the serial lines are started.
    pub lines: std::sync::OnceLock<HashMap<String, super::line::LineHandle>>,
    /// Links whose lower node takes this node's time, with the lower node's clock when it
    /// runs in this process (set directly, see [`super::link`]).
    pub sync_links: Vec<(String, Option<Arc<super::clock::NodeClock>>)>,
    pub simulation: mpsc::Sender<SimRequest>,
    /// The server's redundancy groups (command authority per group).
    pub groups: Vec<crate::config::RedundancyGroup>,
    /// This node's index on the simulation thread (authority variables are read there).
    pub sim_node: usize,
    /// Connected controlling stations per redundancy group (for their status points).
    pub connected: std::sync::Mutex<HashMap<String, usize>>,
}

impl NodeHandler {
    /// The handler of the node `config`'s server: `sim_node` is the node's index on the
    /// simulation thread, `clocks` those of the nodes in this process (the lower clocks of
    /// its clock-synchronised links). Its links and lines are set once they are started.
    pub(crate) fn new(
        config: &NodeConfig,
        sim_node: usize,
        points: &Arc<NodePoints>,
        simulation: mpsc::Sender<SimRequest>,
        clocks: &LocalClocks,
    ) -> NodeHandler {
        NodeHandler {
            points: Arc::clone(points),
            commands: routed_commands(config, sim_node),
            links: std::sync::OnceLock::new(),
            lines: std::sync::OnceLock::new(),
            sync_links: config
                .links
                .iter()
                .filter(|l| l.clock_sync)
                .map(|l| (l.name.clone(), clocks.lower(l)))
                .collect(),
            simulation,
            groups: config
                .server
                .as_ref()
                .map(|s| s.redundancy_groups.clone())
                .unwrap_or_default(),
            sim_node,
            connected: std::sync::Mutex::default(),
        }
    }

    /// The redundancy group a client belongs to, chosen as the server chooses it: the
    /// first group naming its address, else the first catch-all group.
    fn group_of(&self, peer: &Peer) -> Option<&crate::config::RedundancyGroup> {
        crate::config::RedundancyGroup::of_client(&self.groups, peer.ip())
    }
}

/// The node's commands by IOA, each with its route.
fn routed_commands(config: &NodeConfig, sim_node: usize) -> HashMap<u32, RoutedCommand> {
    config
        .commands
        .iter()
        .map(|command| {
            (
                command.ioa.get(),
                RoutedCommand {
                    name: command.name.clone(),
                    route: Route::of(command, sim_node),
                    from_groups: command.from_groups.clone(),
                    feedback: command.feedback.clone(),
                    range: command.range.clone(),
                },
            )
        })
        .collect()
}

impl StationHandler for NodeHandler {
    fn handle_command(&self, command: server::Command) -> CommandFuture {
        let Some(routed) = self.commands.get(&command.ioa.get()).cloned() else {
            return server::ready(server::CommandOutcome::Refused);
        };
        let points = Arc::clone(&self.points);
        let handler_links = self.links.get().cloned().unwrap_or_default();
        let handler_lines = self.lines.get().cloned().unwrap_or_default();
        let simulation = self.simulation.clone();
        let this = Recorded {
            points,
            command: command.clone(),
            name: routed.name.clone(),
        };
        let group = self.group_of(&command.peer).cloned();
        let group_name = group.as_ref().map(|g| g.name.clone()).unwrap_or_default();
        if !routed.from_groups.is_empty() && !routed.from_groups.contains(&group_name) {
            let detail = format!(
                "accepted only from {} (this client is in `{group_name}`)",
                routed.from_groups.join(", ")
            );
            return Box::pin(this.finish(CommandOutcome::Refused, detail));
        }
        if let (Some(range), Some(value)) = (&routed.range, setpoint_value(&command.element)) {
            if !range.contains(&value) {
                let detail = format!(
                    "value {value} outside the range {}..={} of the project",
                    range.start(),
                    range.end()
                );
                return Box::pin(this.finish(CommandOutcome::Refused, detail));
            }
        }
        let blocked_by = group.and_then(|g| g.refuse_commands_when);
        let sim_node = self.sim_node;
        Box::pin(async move {
            if let Some(variable) = blocked_by {
                match read_bool(&simulation, sim_node, &variable).await {
                    Some(false) => {}
                    Some(true) => {
                        let detail = format!(
                            "commands from `{group_name}` are blocked while {variable} is TRUE"
                        );
                        return this.finish(CommandOutcome::RefusedLocalMode, detail).await;
                    }
                    None => {
                        let detail = format!("command authority {variable} cannot be read");
                        return this.finish(CommandOutcome::Refused, detail).await;
                    }
                }
            }
            let (outcome, detail, termination) = match routed.route {
                Route::Plc { node, pulse } => {
                    // Asked before the PLC gets the command: its change may be quick.
                    let feedback = routed
                        .feedback
                        .filter(|_| !command.select)
                        .map(|feedback| (this.points.expect_return(&feedback.point), feedback));
                    let (outcome, detail) =
                        execute_on_plc(&simulation, node, &command, pulse).await;
                    let termination = feedback.map(|(returned, feedback)| {
                        await_return(returned, feedback, this.points.name().to_owned())
                    });
                    (outcome, detail, termination)
                }
                Route::Link { link, ioa } => {
                    forward(handler_links.get(&link), &link, ioa, &command).await
                }
                Route::Line {
                    line,
                    device,
                    fun,
                    inf,
                    value,
                } => {
                    // As for the PLC: the return information (the relay's indication at
                    // the command's FUN/INF, or the project's `feedback`) goes out before
                    // ACT_TERM; the relay reports it after its acknowledgement.
                    let feedback = routed
                        .feedback
                        .filter(|_| !command.select)
                        .map(|feedback| (this.points.expect_return(&feedback.point), feedback));
                    let target = (device.as_str(), fun, inf, value);
                    let (outcome, detail) =
                        general_command(handler_lines.get(&line), &line, target, &command).await;
                    let termination = feedback.map(|(returned, feedback)| {
                        await_return(returned, feedback, this.points.name().to_owned())
                    });
                    (outcome, detail, termination)
                }
                Route::LineObject { line, device, ioa } => match handler_lines.get(&line) {
                    Some(handle) => handle.forward(&device, ioa, &command).await,
                    None => (
                        CommandOutcome::Failed,
                        format!("line {line} is not running"),
                        None,
                    ),
                },
            };
            match (this.finish(outcome, detail).await, termination) {
                (server::CommandOutcome::Executed, Some(termination)) => {
                    server::CommandOutcome::Confirmed(termination)
                }
                (reply, _) => reply,
            }
        })
    }

    fn command_refused(&self, command: &server::Command, refusal: &server::CommandRefusal) {
        let name = self.commands.get(&command.ioa.get()).map_or_else(
            || format!("IOA {}", command.ioa),
            |routed| routed.name.clone(),
        );
        let recorded = Recorded {
            points: Arc::clone(&self.points),
            command: command.clone(),
            name,
        };
        // The reason (the age of a stale command, ...) is the audit record's detail; a
        // refusal need not wait for its commit (nothing was done).
        recorded.record(CommandOutcome::Refused, refusal.to_string());
    }

    fn now(&self) -> chrono::DateTime<chrono::Utc> {
        self.points.clock().now()
    }

    fn handle_clock_sync(&self, time: Cp56Time2a, peer: &Peer) -> bool {
        let Some(source) = self.points.zone().from_cp56(&time) else {
            tracing::warn!(node = %self.points.name(), %peer, "clock synchronisation with an impossible date refused");
            return false;
        };
        self.points.clock().synchronise(source.time);
        tracing::info!(node = %self.points.name(), %peer, time = %source.time, "clock synchronised");
        // Pass the time down at once rather than at the next periodic synchronisation.
        // Lower nodes in this process followed already (NodeClock::synchronise).
        for (name, local) in &self.sync_links {
            if local.is_some() {
                continue;
            }
            let Some(client) = self
                .links
                .get()
                .and_then(|l| l.get(name))
                .and_then(LinkHandle::client)
            else {
                continue;
            };
            let time = self.points.zone().to_cp56(self.points.clock().now());
            tokio::spawn(async move {
                let _ = client.clock_sync(time).await;
            });
        }
        true
    }

    fn connection_changed(&self, peer: &Peer, connected: bool, started: bool) {
        tracing::info!(node = %self.points.name(), %peer, connected, started, "controlling station");
        if started {
            return;
        }
        let Some(group) = self.group_of(peer) else {
            return;
        };
        let count = {
            let mut map = self
                .connected
                .lock()
                .unwrap_or_else(|poison| poison.into_inner());
            let count = map.entry(group.name.clone()).or_insert(0);
            *count = if connected {
                count.saturating_add(1)
            } else {
                count.saturating_sub(1)
            };
            *count
        };
        if let Some(point) = &group.status_point {
            let origin = format!("clients:{}", group.name);
            self.points.change_with(&origin, |db, now| {
                db.set_link_status(point.as_str(), count > 0, now)
                    .ok()
                    .flatten()
                    .into_iter()
                    .collect()
            });
        }
    }
}

/// What the audit needs once the outcome is known.
struct Recorded {
    points: Arc<NodePoints>,
    command: server::Command,
    name: String,
}

impl Recorded {
    /// Audits the command and returns the server's outcome once the audit record is
    /// committed: a positive confirmation never leaves for a command a crash would then
    /// lose from the audit (write-ahead).
    async fn finish(self, outcome: CommandOutcome, detail: String) -> server::CommandOutcome {
        let handler_outcome = if outcome == CommandOutcome::Executed {
            server::CommandOutcome::Executed
        } else {
            server::CommandOutcome::Refused
        };
        let points = Arc::clone(&self.points);
        let record = self.audit_record(outcome, detail);
        if !points.recorder().command_committed(record).await {
            tracing::error!(node = %points.name(), "the command's audit record could not be stored");
        }
        handler_outcome
    }

    /// Audits the command without waiting for the commit.
    fn record(self, outcome: CommandOutcome, detail: String) {
        let points = Arc::clone(&self.points);
        points
            .recorder()
            .command(self.audit_record(outcome, detail));
    }

    fn audit_record(self, outcome: CommandOutcome, detail: String) -> CommandRecord {
        tracing::info!(
            node = %self.points.name(), command = %self.name, peer = %self.command.peer,
            select = self.command.select, ?outcome, %detail, "command"
        );
        CommandRecord {
            id: None,
            time: self.points.clock().now(),
            actor: Actor::Remote(self.command.peer.to_string()),
            node: self.points.name().to_owned(),
            point: self.name,
            ioa: Some(self.command.ioa.get()),
            value: command_value(&self.command.element),
            phase: if self.command.select {
                CommandPhase::Select
            } else {
                CommandPhase::Execute
            },
            outcome,
            detail,
        }
    }
}

/// Reads a BOOL variable of a node's PLC on the simulation thread.
async fn read_bool(simulation: &mpsc::Sender<SimRequest>, node: usize, path: &str) -> Option<bool> {
    let (reply, answer) = oneshot::channel();
    let path = path.to_owned();
    let request = SimRequest::With(Box::new(move |sim| {
        let _ = reply.send(sim.read_bool(node, &path));
    }));
    simulation.send(request).ok()?;
    answer.await.ok().flatten()
}

async fn execute_on_plc(
    simulation: &mpsc::Sender<SimRequest>,
    node: usize,
    command: &server::Command,
    configured_pulse: Option<Duration>,
) -> (CommandOutcome, String) {
    let Some((value, qualifier)) = points_iec::command_value(&command.element) else {
        return (
            CommandOutcome::Refused,
            format!(
                "{} cannot be written to a PLC variable",
                command.element.short_name()
            ),
        );
    };
    let pulse = match qualifier {
        Some(1 | 2) => Some(configured_pulse.unwrap_or(DEFAULT_PULSE)),
        Some(3) => None,
        Some(_) => configured_pulse,
        None => None,
    };
    let (reply, answer) = oneshot::channel();
    let request = SimRequest::Command {
        node,
        ioa: command.ioa.get(),
        value,
        pulse,
        select: command.select,
        reply,
    };
    if simulation.send(request).is_err() {
        return (CommandOutcome::Failed, "the simulation has stopped".into());
    }
    match answer.await {
        Ok(Ok(())) => (CommandOutcome::Executed, String::new()),
        Ok(Err(CommandRefusal::LocalMode)) => (
            CommandOutcome::RefusedLocalMode,
            "the board is in local mode".into(),
        ),
        Ok(Err(refusal)) => (CommandOutcome::Refused, refusal.to_string()),
        Err(_) => (CommandOutcome::Failed, "the simulation has stopped".into()),
    }
}

/// Terminates a confirmed command once its feedback point's change has gone out as
/// return information, or when the wait runs out.
fn await_return(
    returned: tokio::sync::oneshot::Receiver<()>,
    feedback: crate::config::Feedback,
    node: String,
) -> TerminationFuture {
    Box::pin(async move {
        if tokio::time::timeout(feedback.timeout, returned)
            .await
            .is_err()
        {
            tracing::info!(
                %node, point = %feedback.point, timeout_ms = feedback.timeout.as_millis(),
                "no return information: the command is terminated without it"
            );
        }
    })
}

/// A command to a line device: a general command ON/OFF, its acknowledgement the outcome.
async fn general_command(
    line: Option<&super::line::LineHandle>,
    name: &str,
    (device, fun, inf, fixed): (&str, u8, u8, Option<bool>),
    command: &server::Command,
) -> (CommandOutcome, String) {
    use super::line::CommandProblem;
    let Some(line) = line else {
        return (
            CommandOutcome::Failed,
            format!("line {name} is not running"),
        );
    };
    let on = match &command.element {
        Element::SingleCommand { on, .. } => *on,
        Element::DoubleCommand { state, .. } => *state == DoublePointState::On,
        _ => {
            return (
                CommandOutcome::Refused,
                "only single and double commands go to a line device".to_owned(),
            )
        }
    };
    let on = fixed.unwrap_or(on);
    if command.select {
        // IEC 103 has no select: the selection stays here, the execute goes to the device.
        return (
            CommandOutcome::Executed,
            format!("selected ({device} on line {name})"),
        );
    }
    match line.command(device, fun, inf, on).await {
        Ok(()) => (
            CommandOutcome::Executed,
            format!("acknowledged by {device} (FUN {fun} INF {inf})"),
        ),
        Err(CommandProblem::Local) => (
            CommandOutcome::RefusedLocalMode,
            format!("{device} is in LOCAL: not sent"),
        ),
        Err(CommandProblem::Refused) => (
            CommandOutcome::Refused,
            format!("refused by {device} (negative acknowledgement)"),
        ),
        Err(CommandProblem::NoAnswer(why)) => (CommandOutcome::Failed, why),
    }
}

/// Sends a command down a link. The confirmation is the lower node's, as the link task
/// meets it; an executed command's termination waits for the lower node's termination to
/// reach the link task too (the return information before it is then published here).
async fn forward(
    link: Option<&LinkHandle>,
    name: &str,
    ioa: iec60870::asdu::Ioa,
    command: &server::Command,
) -> (CommandOutcome, String, Option<TerminationFuture>) {
    let Some(link) = link else {
        return (CommandOutcome::Failed, format!("link {name} is cut"), None);
    };
    let Some(client) = link.client() else {
        return (CommandOutcome::Failed, format!("link {name} is cut"), None);
    };
    if !link.is_up() {
        return (CommandOutcome::Failed, format!("link {name} is down"), None);
    }
    let time = match &command.time {
        Some(TimeTag::Cp56(tag)) => Some(*tag),
        _ => None,
    };
    let answers = link.watch_command(command.type_id, ioa);
    let (type_id, element) = (command.type_id, command.element.clone());
    let mut request =
        tokio::spawn(async move { client.command(type_id, ioa, element, time).await });
    let mut confirmed = answers.confirmed;
    let mut terminated = answers.terminated;
    // The answers count as the link task meets them in the lower node's stream, after the
    // data before them: the request (the client's view of the same answers) only decides
    // when it fails. Whatever the request saw, the link task meets too, or the link goes
    // down and drops the watch: no wait needs a bound of its own.
    let mut finished = None;
    let positive = tokio::select! {
        seen = &mut confirmed => seen.ok(),
        done = &mut request => {
            let answered = matches!(done, Ok(Ok(_)));
            finished = Some(done);
            if answered { (&mut confirmed).await.ok() } else { None }
        }
    };
    if positive != Some(true) {
        // Refused (or the link went away): the request's own result says why.
        let done = match finished {
            Some(done) => done,
            None => request.await,
        };
        let (outcome, detail) = request_outcome(done, name, ioa);
        return (outcome, detail, None);
    }
    let detail = format!("confirmed by {name} (IOA {ioa})");
    if command.select {
        request.abort();
        return (CommandOutcome::Executed, detail, None);
    }
    let terminated_already =
        |done: &RequestResult| matches!(done, Ok(Ok(outcome)) if outcome.terminated);
    let termination: TerminationFuture = match finished {
        // The request ended with the termination: the link task meets it too.
        Some(done) => {
            let wait = terminated_already(&done);
            Box::pin(async move {
                if wait {
                    let _ = terminated.await;
                }
            })
        }
        None => Box::pin(async move {
            tokio::select! {
                _ = &mut terminated => {}
                done = &mut request => {
                    // A request that ended without the termination (its own time-out)
                    // ends the wait; one that ended with it waits for the link task.
                    if terminated_already(&done) {
                        let _ = terminated.await;
                    }
                }
            }
        }),
    };
    (CommandOutcome::Executed, detail, Some(termination))
}

/// What a forwarded command's request task ended with.
type RequestResult = Result<
    Result<iec60870::cs104::client::RequestOutcome, iec60870::cs104::client::ClientError>,
    tokio::task::JoinError,
>;

/// The audit outcome of a forwarded command's request.
fn request_outcome(
    result: RequestResult,
    name: &str,
    ioa: iec60870::asdu::Ioa,
) -> (CommandOutcome, String) {
    let Ok(result) = result else {
        return (
            CommandOutcome::Failed,
            format!("{name}: the request was lost"),
        );
    };
    match result {
        Ok(outcome) if outcome.positive => (
            CommandOutcome::Executed,
            format!("confirmed by {name} (IOA {ioa})"),
        ),
        Ok(outcome) => (
            CommandOutcome::Refused,
            format!("refused by {name} (IOA {ioa}, cause {})", outcome.cause),
        ),
        Err(iec60870::cs104::client::ClientError::Timeout(what)) => (
            CommandOutcome::TimedOut,
            format!("no answer from {name}: timed out waiting for {what}"),
        ),
        Err(error) => (CommandOutcome::Failed, format!("{name}: {error}")),
    }
}

/// A set-point's value in engineering units (as the project's `range` is written).
fn setpoint_value(element: &Element) -> Option<f64> {
    match element {
        Element::SetpointNormalized { .. }
        | Element::SetpointScaled { .. }
        | Element::SetpointFloat { .. } => match points_iec::command_value(element)?.0 {
            PointValue::Float(x) => Some(x),
            #[allow(clippy::cast_precision_loss)]
            PointValue::Int(i) => Some(i as f64),
            _ => None,
        },
        _ => None,
    }
}

/// The audited value of a command.
fn command_value(element: &Element) -> PointValue {
    points_iec::command_value(element).map_or_else(
        || PointValue::Text(element.short_name().to_owned()),
        |(value, _)| value,
    )
}
