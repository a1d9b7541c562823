//! Task states and stops: a fault, the watchdog or a PLC STOP stops a task, and each stop
//! is a [`TaskStopped`] event taken with [`Plc::poll_event`].

use super::safe::Owner;
use super::{format_value, ClockReading, Plc};
use crate::diagnostics::Diagnostic;

/// State of a task.
#[derive(Debug, Clone, PartialEq)]
pub enum TaskState {
    /// Runs when due.
    Running,
    /// Stopped by a fault or the watchdog; the diagnostic says why and where.
    Faulted(Diagnostic),
    /// Stopped by [`Plc::stop`]; [`Plc::start`] resumes it.
    Stopped,
}

/// Why a task stopped.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum StopCause {
    /// A run-time fault: the diagnostic has its code (E0401) and position.
    Fault(Diagnostic),
    /// The watchdog: the diagnostic says how many cycles overran and by how much.
    Watchdog(Diagnostic),
    /// The PLC was stopped ([`Plc::stop`]).
    Stop,
}

impl StopCause {
    /// The diagnostic of a fault or watchdog stop.
    pub fn diagnostic(&self) -> Option<&Diagnostic> {
        match self {
            StopCause::Fault(d) | StopCause::Watchdog(d) => Some(d),
            StopCause::Stop => None,
        }
    }
    /// `fault`, `watchdog` or `stop`.
    pub fn kind(&self) -> &'static str {
        match self {
            StopCause::Fault(_) => "fault",
            StopCause::Watchdog(_) => "watchdog",
            StopCause::Stop => "stop",
        }
    }
}

/// A task stopped and the outputs it drives were set to their safe values.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskStopped {
    /// The task.
    pub task: String,
    /// Why.
    pub cause: StopCause,
    /// Monotonic time of the cycle (or of [`Plc::stop`]) in ns.
    pub at_ns: i64,
    /// The outputs set to their safe value: direct address (`%QX0.1`) or variable path,
    /// and the value as an IEC literal.
    pub outputs: Vec<(String, String)>,
}

impl Plc {
    /// Sets the outputs task `ti` drives to their safe values and records the stop.
    pub(super) fn stop_task(&mut self, ti: usize, cause: StopCause, at_ns: i64) {
        let Some(t) = self.tasks.get(ti) else { return };
        let task = t.config.name.clone();
        let outputs = self.safe_state(Some(ti));
        self.events.push_back(TaskStopped {
            task,
            cause,
            at_ns,
            outputs,
        });
    }

    /// PLC STOP: every running task stops, every output goes to its safe value; one
    /// [`TaskStopped`] event per task that was running ([`Plc::poll_event`]).
    /// [`Plc::start`] (or a cold or warm start) resumes.
    pub fn stop(&mut self, now: ClockReading) {
        self.safe_state(None);
        let outputs: Vec<(String, String)> = self
            .outputs
            .iter()
            .map(|o| {
                (
                    o.name.clone(),
                    format_value(&self.compiled.checked, &o.leaf.ty, &o.safe),
                )
            })
            .collect();
        for ti in 0..self.tasks.len() {
            let Some(t) = self.tasks.get_mut(ti) else {
                continue;
            };
            if t.state != TaskState::Running {
                continue;
            }
            t.state = TaskState::Stopped;
            let task = t.config.name.clone();
            let pous = t.pous.clone();
            let names = t.names.clone();
            self.events.push_back(TaskStopped {
                task,
                cause: StopCause::Stop,
                at_ns: now.monotonic_ns,
                outputs: outputs
                    .iter()
                    .zip(&self.outputs)
                    .filter(|(_, o)| match &o.owner {
                        Owner::Program(p) => pous.contains(p),
                        Owner::Global(key) => names.contains(key),
                    })
                    .map(|(x, _)| x.clone())
                    .collect(),
            });
        }
    }

    /// Resumes the tasks stopped by [`Plc::stop`] (faulted tasks stay faulted until a
    /// cold or warm start); they run at the next [`Plc::run_cycle`].
    pub fn start(&mut self) {
        for t in &mut self.tasks {
            if t.state == TaskState::Stopped {
                t.state = TaskState::Running;
                t.next_due = None;
                t.consecutive_overruns = 0;
            }
        }
    }

    /// The next task stop not yet taken (fault, watchdog or [`Plc::stop`]), oldest first.
    /// Poll after [`Plc::run_cycle`] and [`Plc::stop`].
    pub fn poll_event(&mut self) -> Option<TaskStopped> {
        self.events.pop_front()
    }
}
