//! Where a command goes once the node has accepted it (authority, range and audit are
//! `runtime::command`'s): each kind of target is a [`Target`], chosen once from the
//! project's `config::CommandTarget` when the node starts ([`of`]).
//!
//! | target                | project                      | how it is executed                       |
//! |-----------------------|------------------------------|------------------------------------------|
//! | [`PlcVariable`]       | `variable = "Board.x"`       | written on the simulation thread (pulse) |
//! | [`LinkObject`]        | `link:LINK/IOA`              | forwarded to the lower node, same type   |
//! | [`LineGeneral`]       | `line:LINE/DEVICE/FUN/INF`   | an IEC 103 general command (ASDU 20)     |
//! | [`LineObject`]        | `line:LINE/DEVICE/IOA`       | forwarded to an IEC 101 outstation       |
//!
//! A target answers with an [`Executed`]: the audited outcome and detail, and for a
//! confirmed command the future that ends when its return information went out (the
//! server then sends ACT_TERM). A new kind of target (a field device's output) is one
//! more implementation and one more arm of [`of`]; the server hooks do not change.

use std::collections::HashMap;
use std::sync::{mpsc, Arc};
use std::time::Duration;

use iec60870::asdu::{DoublePointState, Element, TimeTag};
use iec60870::cs104::server::{self, TerminationFuture};
use tokio::sync::oneshot;

use crate::config::{CommandConfig, CommandTarget, Feedback};
use crate::store::CommandOutcome;

use super::line::LineHandle;
use super::link::LinkHandle;
use super::node::NodePoints;
use super::simulation::{CommandRefusal, SimRequest};

/// The pulse length of a command with QU 1 or 2 when the project sets none.
pub(crate) const DEFAULT_PULSE: Duration = Duration::from_millis(500);

/// A boxed future a target returns.
pub(crate) type TargetFuture<'a> =
    std::pin::Pin<Box<dyn std::future::Future<Output = Executed> + Send + 'a>>;

/// What executing a command at its target came to.
pub(crate) struct Executed {
    /// The audited outcome.
    pub outcome: CommandOutcome,
    /// Why, in words, for the audit.
    pub detail: String,
    /// For a command executed with return information to wait for: ends once it went
    /// out (or its wait ran out), before the server terminates the command.
    pub termination: Option<TerminationFuture>,
}

impl Executed {
    fn done(outcome: CommandOutcome, detail: impl Into<String>) -> Executed {
        Executed {
            outcome,
            detail: detail.into(),
            termination: None,
        }
    }
}

/// What a target may use: the node's points and running parts, as they are when the
/// command arrives.
pub(crate) struct TargetContext {
    pub points: Arc<NodePoints>,
    pub links: HashMap<String, LinkHandle>,
    pub lines: HashMap<String, LineHandle>,
    pub simulation: mpsc::Sender<SimRequest>,
    /// The point returning the command's effect, when the project names one and the
    /// command is an execute (a select returns nothing).
    pub feedback: Option<Feedback>,
}

impl TargetContext {
    /// Asks for the feedback point's next change before the command is executed (its
    /// change may be quick); the termination that waits for it.
    fn expect_return(&self) -> Option<TerminationFuture> {
        let feedback = self.feedback.clone()?;
        let returned = self.points.expect_return(&feedback.point);
        Some(await_return(
            returned,
            feedback,
            self.points.name().to_owned(),
        ))
    }
}

/// Where a command goes: it executes the command (or refuses it) and says how that went.
pub(crate) trait Target: Send + Sync + std::fmt::Debug {
    /// Executes `command` (a select only selects).
    fn execute<'a>(
        &'a self,
        command: &'a server::Command,
        context: TargetContext,
    ) -> TargetFuture<'a>;
}

/// The target of `command`; `sim_node` is the node's index on the simulation thread.
pub(crate) fn of(command: &CommandConfig, sim_node: usize) -> Arc<dyn Target> {
    match &command.target {
        CommandTarget::Variable(_) => Arc::new(PlcVariable {
            node: sim_node,
            pulse: command.pulse,
        }),
        CommandTarget::Link { link, ioa } => Arc::new(LinkObject {
            link: link.clone(),
            ioa: *ioa,
        }),
        CommandTarget::Line {
            line,
            device,
            fun,
            inf,
            value,
        } => Arc::new(LineGeneral {
            line: line.clone(),
            device: device.clone(),
            fun: *fun,
            inf: *inf,
            value: *value,
        }),
        CommandTarget::LineObject { line, device, ioa } => Arc::new(LineObject {
            line: line.clone(),
            device: device.clone(),
            ioa: *ioa,
        }),
    }
}

/// A PLC variable of this node, written on the simulation thread (refused there while
/// the board is in local mode), held for the pulse time of a QU 1/2 command.
#[derive(Debug)]
pub(crate) struct PlcVariable {
    /// The node's index on the simulation thread.
    node: usize,
    /// The project's pulse length.
    pulse: Option<Duration>,
}

impl Target for PlcVariable {
    fn execute<'a>(
        &'a self,
        command: &'a server::Command,
        context: TargetContext,
    ) -> TargetFuture<'a> {
        Box::pin(async move {
            let termination = context.expect_return();
            let (outcome, detail) =
                execute_on_plc(&context.simulation, self.node, command, self.pulse).await;
            Executed {
                outcome,
                detail,
                termination,
            }
        })
    }
}

/// Command `ioa` of the lower node down a link, with the same type and qualifier (a
/// select stays a select); its confirmation and termination are the lower node's.
#[derive(Debug)]
pub(crate) struct LinkObject {
    link: String,
    ioa: iec60870::asdu::Ioa,
}

impl Target for LinkObject {
    fn execute<'a>(
        &'a self,
        command: &'a server::Command,
        context: TargetContext,
    ) -> TargetFuture<'a> {
        Box::pin(async move {
            let (outcome, detail, termination) =
                forward(context.links.get(&self.link), &self.link, self.ioa, command).await;
            Executed {
                outcome,
                detail,
                termination,
            }
        })
    }
}

/// A device on a serial line, as a general command to FUN/INF (ON/OFF fixed by
/// `value`, or the command's own).
#[derive(Debug)]
pub(crate) struct LineGeneral {
    line: String,
    device: String,
    fun: u8,
    inf: u8,
    value: Option<bool>,
}

impl Target for LineGeneral {
    fn execute<'a>(
        &'a self,
        command: &'a server::Command,
        context: TargetContext,
    ) -> TargetFuture<'a> {
        Box::pin(async move {
            // As for the PLC: the return information (the relay's indication at the
            // command's FUN/INF, or the project's `feedback`) goes out before ACT_TERM;
            // the relay reports it after its acknowledgement.
            let termination = context.expect_return();
            let target = (self.device.as_str(), self.fun, self.inf, self.value);
            let (outcome, detail) =
                general_command(context.lines.get(&self.line), &self.line, target, command).await;
            Executed {
                outcome,
                detail,
                termination,
            }
        })
    }
}

/// An IEC 101 outstation on a serial line, the command forwarded as it came to `ioa`.
#[derive(Debug)]
pub(crate) struct LineObject {
    line: String,
    device: String,
    ioa: iec60870::asdu::Ioa,
}

impl Target for LineObject {
    fn execute<'a>(
        &'a self,
        command: &'a server::Command,
        context: TargetContext,
    ) -> TargetFuture<'a> {
        Box::pin(async move {
            let Some(line) = context.lines.get(&self.line) else {
                return Executed::done(
                    CommandOutcome::Failed,
                    format!("line {} is not running", self.line),
                );
            };
            let (outcome, detail, termination) =
                line.forward(&self.device, self.ioa, command).await;
            Executed {
                outcome,
                detail,
                termination,
            }
        })
    }
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
    feedback: Feedback,
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
    line: Option<&LineHandle>,
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
