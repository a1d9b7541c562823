//! A node's IEC 104 server hooks: commands travel down the hierarchy and their outcome
//! travels back; clock synchronisation sets the node's clock and is passed down.
//!
//! A command the node accepts (its sender's redundancy group may send it, a set-point is
//! in range, the group's authority variable allows it) goes to its target
//! (`runtime::target`): a PLC variable is written on the simulation thread, which refuses
//! it while the board's `remote_enable` variable is FALSE (Local/Remote switch in local)
//! and otherwise writes it (held for the pulse time, then reset); a command addressed to
//! a link is sent to the lower node with the same qualifier (a select stays a select) and
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

use iec60870::asdu::Element;
use iec60870::cs104::server::{self, CommandFuture, StationHandler};
use iec60870::outstation::Peer;
use iec60870::time::Cp56Time2a;
use tokio::sync::oneshot;

use crate::config::NodeConfig;
use crate::store::{Actor, CommandOutcome, CommandPhase, CommandRecord, PointValue};

use super::clock::LocalClocks;
use super::link::LinkHandle;
use super::node::NodePoints;
use super::simulation::SimRequest;
use super::target::{self, Executed, Target, TargetContext};

#[derive(Debug, Clone)]
pub(crate) struct RoutedCommand {
    pub name: String,
    /// Where it goes.
    pub target: Arc<dyn Target>,
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
                    target: target::of(command, sim_node),
                    from_groups: command.from_groups.clone(),
                    feedback: command.feedback.clone(),
                    range: command.range.clone(),
                },
            )
        })
        .collect()
}

impl NodeHandler {
    /// A command through the node's routing, authority and audit, whoever sent it: its
    /// sender's redundancy group by name (`group_name`, empty for none) and that group's
    /// settings when the server has it, and the actor the audit names.
    fn route(
        &self,
        command: server::Command,
        group_name: String,
        group: Option<crate::config::RedundancyGroup>,
        actor: String,
    ) -> CommandFuture {
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
            actor,
        };
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
            let context = TargetContext {
                points: Arc::clone(&this.points),
                links: handler_links,
                lines: handler_lines,
                simulation,
                feedback: routed.feedback.filter(|_| !command.select),
            };
            let Executed {
                outcome,
                detail,
                termination,
            } = routed.target.execute(&command, context).await;
            match (this.finish(outcome, detail).await, termination) {
                (server::CommandOutcome::Executed, Some(termination)) => {
                    server::CommandOutcome::Confirmed(termination)
                }
                (reply, _) => reply,
            }
        })
    }
}

impl StationHandler for NodeHandler {
    fn handle_command(&self, command: server::Command) -> CommandFuture {
        let group = self.group_of(&command.peer).cloned();
        let group_name = group.as_ref().map(|g| g.name.clone()).unwrap_or_default();
        let actor = peer_actor(&command.peer, group.as_ref().map(|g| g.name.as_str()));
        self.route(command, group_name, group, actor)
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
            actor: peer_actor(
                &command.peer,
                self.group_of(&command.peer).map(|g| g.name.as_str()),
            ),
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
    /// Who sent it, as the audit names it (a client's address and redundancy group, an
    /// MQTT host).
    actor: String,
}

/// A controlling station as the audit names it: its address and redundancy group.
fn peer_actor(peer: &Peer, group: Option<&str>) -> String {
    match group {
        Some(group) => format!("{peer} (group {group})"),
        None => peer.to_string(),
    }
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
            node = %self.points.name(), command = %self.name, actor = %self.actor,
            select = self.command.select, ?outcome, %detail, "command"
        );
        CommandRecord {
            id: None,
            time: self.points.clock().now(),
            actor: Actor::Remote(self.actor),
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

/// A node's commands for protocols other than its IEC 104 server (an MQTT host's
/// writes): the same routing, authority by redundancy group and audit as a command from
/// a controlling station.
#[derive(Clone)]
pub struct CommandPort {
    handler: Arc<NodeHandler>,
    common_address: iec60870::asdu::CommonAddress,
    by_name: HashMap<String, (iec60870::asdu::Ioa, iec60870::asdu::TypeId)>,
}

impl std::fmt::Debug for CommandPort {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CommandPort")
            .field("node", &self.handler.points.name())
            .finish_non_exhaustive()
    }
}

/// Why a command was not carried out.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CommandError {
    /// The node has no command of this name.
    #[error("node has no command `{0}`")]
    Unknown(String),
    /// Refused (its reason is in the audit and the log).
    #[error("command `{0}` refused")]
    Refused(String),
}

impl CommandPort {
    pub(crate) fn new(config: &NodeConfig, handler: &Arc<NodeHandler>) -> CommandPort {
        CommandPort {
            handler: Arc::clone(handler),
            common_address: config.common_address,
            by_name: config
                .commands
                .iter()
                .map(|c| (c.name.clone(), (c.ioa, c.type_id)))
                .collect(),
        }
    }

    /// Audits a command refused before it reached the node (an MQTT write of a metric
    /// that is not a command, of another type, without a value), with its reason.
    pub fn audit_refusal(&self, point: &str, value: PointValue, detail: &str, actor: &str) {
        let points = &self.handler.points;
        tracing::info!(node = %points.name(), command = %point, %actor, %detail, "command refused");
        points.recorder().command(CommandRecord {
            id: None,
            time: points.clock().now(),
            actor: Actor::Remote(actor.to_owned()),
            node: points.name().to_owned(),
            point: point.to_owned(),
            ioa: self.by_name.get(point).map(|(ioa, _)| ioa.get()),
            value,
            phase: CommandPhase::Execute,
            outcome: CommandOutcome::Refused,
            detail: detail.to_owned(),
        });
    }

    /// The type of a command by name.
    pub fn command_type(&self, name: &str) -> Option<iec60870::asdu::TypeId> {
        self.by_name.get(name).map(|(_, type_id)| *type_id)
    }

    /// Carries out command `name` with `element` (an execute, no time tag) as sent by
    /// `actor` in redundancy group `group`: routed, checked against the group's authority
    /// and the command's range, and audited with `actor`, as a command from dispatch.
    pub async fn execute(
        &self,
        name: &str,
        element: Element,
        actor: &str,
        group: &str,
    ) -> Result<(), CommandError> {
        let Some((ioa, type_id)) = self.by_name.get(name).copied() else {
            return Err(CommandError::Unknown(name.to_owned()));
        };
        let command = server::Command {
            type_id,
            common_address: self.common_address,
            ioa,
            element,
            time: None,
            originator: 0,
            select: false,
            // Not a serial master: the actor names the sender in the audit and logs.
            peer: Peer::Serial {
                port: Arc::from(actor),
                link_address: 0,
            },
        };
        let settings = self
            .handler
            .groups
            .iter()
            .find(|g| g.name == group)
            .cloned();
        let outcome = self
            .handler
            .route(command, group.to_owned(), settings, actor.to_owned())
            .await;
        match outcome {
            server::CommandOutcome::Executed | server::CommandOutcome::Confirmed(_) => Ok(()),
            _ => Err(CommandError::Refused(name.to_owned())),
        }
    }
}
