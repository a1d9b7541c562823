//! The runtime: scan cycle, tasks, watchdog, cycle statistics, retain, forcing, I/O image
//! and variable access by path.
//!
//! A [`Plc`] never reads a clock. The caller passes the time of every cycle
//! ([`ClockReading`]) — from a virtual clock in tests and simulations, from the system
//! clock in production — and, for execution-time statistics and the watchdog, a
//! [`Stopwatch`] that says how long the cycle's work took.
//!
//! One cycle of a due task: apply forced direct addresses to the process image, copy
//! `%I`/`%M` into the variables declared `AT` those addresses, apply forced variables, run
//! the task's programs in order, apply forced variables again, copy `AT %Q`/`%M`
//! variables into the output image, apply forced direct addresses again (and to the
//! variables `AT` them), update statistics and the watchdog.
//!
//! Forcing and writing work by variable path (`Main.lights[3].Q`) or by direct address
//! (`%IX0.0`, `%QW2`, `%MD20`).
//!
//! # Faults, the watchdog and STOP: per-task isolation and safe state
//!
//! A run-time fault stops only the task it happens in; the watchdog stops only the task
//! that overran; [`Plc::stop`] stops every task. The outputs of a stopped task go to
//! their safe value (default FALSE / 0, declared per output with
//! `{attribute 'safe_value' := '...'}`, see [`safe`]); on [`Plc::stop`] every output does.
//! The other tasks keep their schedule. Each stop is a [`TaskStopped`] event (task,
//! [`StopCause`] with the fault's code and position, the outputs set safe), taken with
//! [`Plc::poll_event`] after [`Plc::run_cycle`] or [`Plc::stop`]. Forced direct
//! addresses keep their forced value.

use crate::check::{Checked, PouId, Size, Ty};
use crate::compile::Compiled;
use crate::diagnostics::{Code, Diagnostic};
use crate::syntax::{PouKind, SourceMap};
use crate::vm::{format, DirectAddress, Fault, Val, Vm};
use std::collections::{BTreeMap, HashMap, HashSet, VecDeque};
use std::path::Path;
use std::rc::Rc;

pub mod safe;

/// Errors of the runtime API.
#[derive(Debug, thiserror::Error)]
pub enum PlcError {
    /// No variable at this path.
    #[error("no variable '{0}'")]
    UnknownPath(String),
    /// The path names an aggregate where a scalar was needed.
    #[error("'{0}' is not a scalar variable")]
    NotScalar(String),
    /// The text is not a valid literal for the variable's type.
    #[error("'{text}' is not a valid {ty} value")]
    BadValue {
        /// The text.
        text: String,
        /// The type.
        ty: String,
    },
    /// Unknown program name.
    #[error("no program '{0}'")]
    UnknownProgram(String),
    /// Malformed direct address.
    #[error("malformed direct address '{0}'")]
    BadAddress(String),
    /// Persistence file I/O.
    #[error("retain file: {0}")]
    Io(#[from] std::io::Error),
    /// Setting the initial values faulted (e.g. an initial value outside a subrange);
    /// the diagnostic says where.
    #[error("{}", .0.message)]
    Init(Box<Diagnostic>),
}

/// The time of one cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ClockReading {
    /// Monotonic time since the PLC started (ns). Drives timers.
    pub monotonic_ns: i64,
    /// Wall-clock UTC (ns since 1970-01-01).
    pub utc_ns: i64,
    /// Local time offset from UTC (ns), e.g. 3 600 000 000 000 for CET.
    pub utc_offset_ns: i64,
}

/// A virtual clock: starts at a given UTC time and advances only when told.
#[derive(Debug, Clone, Copy)]
pub struct VirtualClock {
    reading: ClockReading,
}

impl VirtualClock {
    /// A clock at `utc_ns` with a fixed local offset.
    pub fn new(utc_ns: i64, utc_offset_ns: i64) -> Self {
        VirtualClock {
            reading: ClockReading {
                monotonic_ns: 0,
                utc_ns,
                utc_offset_ns,
            },
        }
    }
    /// The current reading.
    pub fn now(&self) -> ClockReading {
        self.reading
    }
    /// Advances by `ns`.
    pub fn advance(&mut self, ns: i64) {
        self.reading.monotonic_ns = self.reading.monotonic_ns.saturating_add(ns);
        self.reading.utc_ns = self.reading.utc_ns.saturating_add(ns);
    }
    /// Sets the local offset (daylight-saving changes).
    pub fn set_offset(&mut self, utc_offset_ns: i64) {
        self.reading.utc_offset_ns = utc_offset_ns;
    }
}

/// Measures how long a cycle's work took (ns). Production uses a monotonic system timer;
/// tests script it to exercise the watchdog deterministically.
pub trait Stopwatch {
    /// Starts a measurement.
    fn start(&mut self);
    /// Nanoseconds since `start`.
    fn elapsed_ns(&mut self) -> i64;
}

/// A stopwatch that always reports zero (virtual-time runs).
#[derive(Debug, Default, Clone, Copy)]
pub struct NoStopwatch;

impl Stopwatch for NoStopwatch {
    fn start(&mut self) {}
    fn elapsed_ns(&mut self) -> i64 {
        0
    }
}

/// Watchdog settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Watchdog {
    /// Maximum execution time of one cycle (ns).
    pub time_ns: i64,
    /// Consecutive overruns that make a fault (1 = the first).
    pub sensitivity: u32,
}

/// Configuration of a task.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct TaskConfig {
    /// Name.
    pub name: String,
    /// Cycle interval (ns); 0 = every `run_cycle`.
    pub interval_ns: i64,
    /// Priority: 0 is the highest; equal priorities run in configuration order.
    pub priority: u8,
    /// Programs, run in order.
    pub programs: Vec<String>,
    /// Watchdog.
    pub watchdog: Option<Watchdog>,
}

impl TaskConfig {
    /// A cyclic task running `programs` every `interval_ns`.
    pub fn cyclic(name: impl Into<String>, interval_ns: i64, programs: &[&str]) -> Self {
        TaskConfig {
            name: name.into(),
            interval_ns,
            priority: 10,
            programs: programs.iter().map(|s| s.to_string()).collect(),
            watchdog: None,
        }
    }
    /// With a priority.
    #[must_use]
    pub fn with_priority(mut self, priority: u8) -> Self {
        self.priority = priority;
        self
    }
    /// With a watchdog.
    #[must_use]
    pub fn with_watchdog(mut self, time_ns: i64, sensitivity: u32) -> Self {
        self.watchdog = Some(Watchdog {
            time_ns,
            sensitivity: sensitivity.max(1),
        });
        self
    }
}

/// Cycle statistics of a task (times in ns).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CycleStats {
    /// Cycles run.
    pub cycles: u64,
    /// Last execution time.
    pub last_ns: i64,
    /// Minimum execution time.
    pub min_ns: i64,
    /// Maximum execution time.
    pub max_ns: i64,
    /// Average execution time.
    pub avg_ns: f64,
    /// Largest deviation of a cycle start from its due time.
    pub jitter_ns: i64,
    /// Cycles whose execution exceeded the watchdog time.
    pub overruns: u64,
}

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

/// Who drives an output.
#[derive(Debug, Clone, PartialEq)]
enum Owner {
    /// A variable of this PROGRAM (index of the POU).
    Program(usize),
    /// A global (upper-case name): the tasks whose code names it.
    Global(String),
}

/// An output with its safe value.
#[derive(Debug, Clone)]
struct SafeOutput {
    /// `%QX0.1` or the variable path.
    name: String,
    leaf: Leaf,
    at: Option<DirectAddress>,
    owner: Owner,
    safe: Val,
}

struct Task {
    config: TaskConfig,
    programs: Vec<(usize, Size)>,
    next_due: Option<i64>,
    stats: CycleStats,
    state: TaskState,
    consecutive_overruns: u32,
    /// Last whole second and tenth of a second seen (system flags), and whether it ran.
    last_tick: Option<(i64, i64)>,
    /// Indexes of the programs it runs.
    pous: HashSet<usize>,
    /// Upper-case names its programs mention, transitively (globals it drives).
    names: HashSet<String>,
}

/// A scalar variable reached by path.
#[derive(Debug, Clone, PartialEq)]
pub struct Leaf {
    /// `Main.lights[3].Q`
    pub path: String,
    /// Type.
    pub ty: Ty,
    /// Absolute address.
    pub addr: Size,
    /// Declared RETAIN (or inside a RETAIN variable).
    pub retain: bool,
    /// Declared PERSISTENT.
    pub persistent: bool,
}

/// Loop iterations allowed per task cycle before a fault.
pub const DEFAULT_LOOP_BUDGET: u64 = 100_000_000;

/// A soft PLC: compiled program, memory, tasks.
pub struct Plc {
    compiled: Compiled,
    sources: SourceMap,
    vm: Vm,
    tasks: Vec<Task>,
    forces: BTreeMap<String, (Ty, Size, Val)>,
    /// Forced direct addresses (`%QX1.3`), by canonical spelling.
    io_forces: BTreeMap<String, (DirectAddress, i64)>,
    io_bindings: Vec<(Size, Ty, DirectAddress)>,
    /// Integer cells of System_S.R_EDGE_1SEC, R_EDGE_100MS, FIRST_SCAN.
    system_flags: Option<[usize; 3]>,
    stopwatch: Box<dyn Stopwatch>,
    /// The fault of the last cold start, if it failed; and whether `run_cycle` has yet to
    /// report it.
    init_fault: Option<(Diagnostic, bool)>,
    /// Outputs and their safe values.
    outputs: Vec<SafeOutput>,
    /// A safe value that is not a literal of its output's type (the PLC stays in STOP).
    safe_error: Option<Diagnostic>,
    /// Names mentioned by each user POU (for which task drives a global output).
    mentions: HashMap<String, HashSet<String>>,
    /// Stops not yet taken with `poll_event`.
    events: VecDeque<TaskStopped>,
    /// Loop iterations per cycle.
    pub loop_budget: u64,
}

impl Plc {
    /// A PLC for a compiled program; memory is cold-started. No tasks yet.
    ///
    /// If setting the initial values faults (an initial value outside a subrange, an
    /// array index or a division in an initial-value expression), the PLC is in STOP:
    /// [`Plc::init_fault`] says why, every task starts faulted with that diagnostic and
    /// the first [`Plc::run_cycle`] returns it. [`Plc::try_new`] returns it as an error.
    pub fn new(compiled: Compiled, sources: SourceMap) -> Self {
        let vm = Vm::new(compiled.checked.memory_size, Rc::clone(&compiled.code));
        let mut plc = Plc {
            compiled,
            sources,
            vm,
            tasks: Vec::new(),
            forces: BTreeMap::new(),
            io_forces: BTreeMap::new(),
            io_bindings: Vec::new(),
            system_flags: None,
            stopwatch: Box::new(NoStopwatch),
            init_fault: None,
            outputs: Vec::new(),
            safe_error: None,
            mentions: HashMap::new(),
            events: VecDeque::new(),
            loop_budget: DEFAULT_LOOP_BUDGET,
        };
        plc.io_bindings = plc.collect_io_bindings();
        plc.mentions = safe::mentions(&plc.compiled.checked, &plc.sources);
        plc.collect_outputs();
        plc.system_flags = [
            "System_S.R_EDGE_1SEC",
            "System_S.R_EDGE_100MS",
            "System_S.FIRST_SCAN",
        ]
        .iter()
        .map(|p| plc.leaf(p).ok().map(|l| l.addr.i))
        .collect::<Option<Vec<usize>>>()
        .and_then(|v| <[usize; 3]>::try_from(v).ok());
        // a fault is kept in `init_fault` and reported by the tasks and `run_cycle`
        let _ = plc.cold_start();
        plc
    }

    /// Like [`Plc::new`], but a fault while setting the initial values is an error.
    pub fn try_new(compiled: Compiled, sources: SourceMap) -> Result<Self, PlcError> {
        let plc = Plc::new(compiled, sources);
        match plc.init_fault() {
            Some(d) => Err(PlcError::Init(Box::new(d.clone()))),
            None => Ok(plc),
        }
    }

    /// The fault of the last cold (or warm) start, if setting the initial values failed.
    /// Tasks stay faulted until a start succeeds.
    pub fn init_fault(&self) -> Option<&Diagnostic> {
        self.init_fault.as_ref().map(|(d, _)| d)
    }

    /// The checked program (types, POUs, globals).
    pub fn checked(&self) -> &Checked {
        &self.compiled.checked
    }

    /// The source map (for rendering diagnostics).
    pub fn sources(&self) -> &SourceMap {
        &self.sources
    }

    /// Replaces the stopwatch used for statistics and the watchdog.
    pub fn set_stopwatch(&mut self, s: Box<dyn Stopwatch>) {
        self.stopwatch = s;
    }

    /// Adds a task.
    pub fn add_task(&mut self, config: TaskConfig) -> Result<(), PlcError> {
        let mut programs = Vec::new();
        for name in &config.programs {
            let key = name.to_uppercase();
            let c = &self.compiled.checked;
            let pid = c
                .pou_index
                .get(&key)
                .copied()
                .filter(|p| c.pou(*p).map(|p| p.kind) == Some(PouKind::Program))
                .ok_or_else(|| PlcError::UnknownProgram(name.clone()))?;
            let base = c.pou(pid).and_then(|p| p.base).unwrap_or_default();
            programs.push((pid.0, base));
        }
        let state = match &self.init_fault {
            Some((d, _)) => TaskState::Faulted(d.clone()),
            None => TaskState::Running,
        };
        let names = safe::reachable(&self.mentions, &config.programs);
        self.tasks.push(Task {
            pous: programs.iter().map(|(p, _)| *p).collect(),
            names,
            config,
            programs,
            next_due: None,
            stats: CycleStats::default(),
            state,
            consecutive_overruns: 0,
            last_tick: None,
        });
        // stable sort by priority keeps configuration order among equals
        self.tasks.sort_by_key(|t| t.config.priority);
        Ok(())
    }

    /// Adds the tasks declared in the source (CONFIGURATION / RESOURCE / TASK) and
    /// returns how many.
    pub fn add_declared_tasks(&mut self) -> Result<usize, PlcError> {
        let specs = self.compiled.checked.tasks.clone();
        for t in &specs {
            let programs: Vec<&str> = t.programs.iter().map(String::as_str).collect();
            self.add_task(
                TaskConfig::cyclic(t.name.clone(), t.interval_ns, &programs)
                    .with_priority(t.priority),
            )?;
        }
        Ok(specs.len())
    }

    /// Cold start: every variable gets its initial value (PERSISTENT ones are restored by
    /// the caller with [`Plc::load_retain`] if desired). Faulted tasks are restarted.
    ///
    /// A fault while setting the initial values is returned, kept as [`Plc::init_fault`]
    /// and stops every task (reported once by the next [`Plc::run_cycle`]).
    pub fn cold_start(&mut self) -> Result<(), Fault> {
        let memory = self.init_memory();
        let fault = match (&memory, &self.safe_error) {
            (Err(f), _) => Some(Diagnostic::error(
                Code::RuntimeFault,
                f.span().unwrap_or_default(),
                format!("initialisation stopped: {f}"),
            )),
            (Ok(()), Some(d)) => Some(d.clone()),
            (Ok(()), None) => None,
        };
        if let Some(d) = fault {
            for t in &mut self.tasks {
                t.state = TaskState::Faulted(d.clone());
            }
            let fault = memory.err().unwrap_or_else(|| {
                crate::vm::FaultKind::Conversion {
                    span: d.primary,
                    what: d.message.clone(),
                }
                .into()
            });
            self.init_fault = Some((d, true));
            return Err(fault);
        }
        self.init_fault = None;
        for t in &mut self.tasks {
            t.state = TaskState::Running;
            t.next_due = None;
            t.consecutive_overruns = 0;
            t.last_tick = None;
        }
        Ok(())
    }

    fn init_memory(&mut self) -> Result<(), Fault> {
        let size = self.compiled.checked.memory_size;
        self.vm.ints = vec![0; size.i];
        self.vm.reals = vec![0.0; size.r];
        self.vm.strs = vec![String::new(); size.s];
        self.vm.frame = Size::default();
        self.vm.budget = self.loop_budget;
        let gi = Rc::clone(&self.compiled.global_init);
        (gi)(&mut self.vm)?;
        for (i, p) in self.compiled.checked.pous.iter().enumerate() {
            if p.kind == PouKind::Program {
                if let Some(b) = p.base {
                    self.vm.init(i, b)?;
                }
            }
        }
        Ok(())
    }

    /// Warm start: like a cold start, but RETAIN and PERSISTENT variables keep their values.
    pub fn warm_start(&mut self) -> Result<(), Fault> {
        let kept: Vec<(Leaf, Val)> = self
            .leaves()
            .into_iter()
            .filter(|l| l.retain || l.persistent)
            .filter_map(|l| {
                let v = self.read_leaf(&l).ok()?;
                Some((l, v))
            })
            .collect();
        self.cold_start()?;
        for (l, v) in kept {
            self.write_leaf(&l, v);
        }
        Ok(())
    }

    /// Program download: replaces the program by `compiled` (a new build), cold-starts it
    /// and carries over every PERSISTENT variable whose path and type still exist. Tasks
    /// are kept (their programs are looked up again by name) and statistics reset;
    /// forcing is released; references start NULL. Returns how many values were carried
    /// over.
    pub fn download(&mut self, compiled: Compiled, sources: SourceMap) -> Result<usize, PlcError> {
        let kept: Vec<(String, Ty, Val)> = self
            .leaves()
            .into_iter()
            .filter(|l| l.persistent)
            .filter_map(|l| {
                let v = self.read_leaf(&l).ok()?;
                Some((l.path, l.ty, v))
            })
            .collect();
        let configs: Vec<TaskConfig> = self.tasks.iter().map(|t| t.config.clone()).collect();
        let bound: Vec<String> = self
            .outputs
            .iter()
            .filter(|o| o.at.is_none())
            .map(|o| o.name.clone())
            .collect();
        let mut next = Plc::new(compiled, sources);
        for path in bound {
            // an output whose variable is gone is no longer bound
            match next.bind_output(&path) {
                Ok(()) | Err(PlcError::UnknownPath(_) | PlcError::NotScalar(_)) => {}
                Err(e) => return Err(e),
            }
        }
        next.loop_budget = self.loop_budget;
        next.stopwatch = std::mem::replace(&mut self.stopwatch, Box::new(NoStopwatch));
        for c in configs {
            next.add_task(c)?;
        }
        let mut n = 0;
        for (path, ty, v) in kept {
            // an address in the old memory layout means nothing in the new one
            if matches!(ty, Ty::Ref(_)) {
                continue;
            }
            if let Ok(l) = next.leaf(&path) {
                if l.ty == ty && l.persistent {
                    next.write_leaf(&l, v);
                    n += 1;
                }
            }
        }
        *self = next;
        Ok(n)
    }

    /// Writes RETAIN and PERSISTENT variables to `path` atomically (temporary file, then
    /// rename). One `path = value` line each, values in IEC literal syntax.
    pub fn save_retain(&self, path: &Path) -> Result<(), PlcError> {
        let mut text = String::new();
        for l in self.leaves() {
            if l.retain || l.persistent {
                let kind = if l.persistent { "PERSISTENT" } else { "RETAIN" };
                let v = self.format_leaf(&l).unwrap_or_default();
                text.push_str(&format!("{kind} {} = {v}\n", l.path));
            }
        }
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, text)?;
        std::fs::rename(&tmp, path)?;
        Ok(())
    }

    /// Restores variables saved by [`Plc::save_retain`]. With `persistent_only`, only
    /// PERSISTENT values are applied (cold start, program download). Unknown paths and
    /// values that no longer fit their type are skipped; returns how many were restored.
    pub fn load_retain(&mut self, path: &Path, persistent_only: bool) -> Result<usize, PlcError> {
        let text = std::fs::read_to_string(path)?;
        let mut n = 0;
        for line in text.lines() {
            let Some((kind, rest)) = line.split_once(' ') else {
                continue;
            };
            let Some((p, v)) = rest.split_once(" = ") else {
                continue;
            };
            if persistent_only && kind != "PERSISTENT" {
                continue;
            }
            if let Ok(l) = self.leaf(p) {
                if (l.retain || l.persistent) && self.write(p, v).is_ok() {
                    n += 1;
                }
            }
        }
        Ok(n)
    }

    /// Runs every task that is due at `now`. Returns the diagnostics of tasks that faulted
    /// in this call.
    pub fn run_cycle(&mut self, now: ClockReading) -> Vec<Diagnostic> {
        let mut faults = Vec::new();
        if let Some((d, pending)) = &mut self.init_fault {
            if *pending {
                *pending = false;
                faults.push(d.clone());
            }
        }
        self.vm.now = now.monotonic_ns;
        self.vm.utc = now.utc_ns;
        self.vm.local_offset = now.utc_offset_ns;
        for ti in 0..self.tasks.len() {
            let (due, interval) = match self.tasks.get(ti) {
                Some(t) if t.state == TaskState::Running => {
                    (t.next_due.unwrap_or(now.monotonic_ns), t.config.interval_ns)
                }
                _ => continue,
            };
            if now.monotonic_ns < due {
                continue;
            }
            self.update_system_flags(ti, now.monotonic_ns);
            self.apply_io_forces();
            self.sync_inputs();
            self.apply_forces();
            self.vm.budget = self.loop_budget;
            self.stopwatch.start();
            let programs = self
                .tasks
                .get(ti)
                .map(|t| t.programs.clone())
                .unwrap_or_default();
            let mut result = Ok(());
            for (pid, base) in programs {
                result = self.vm.call(pid, base);
                if result.is_err() {
                    break;
                }
            }
            let elapsed = self.stopwatch.elapsed_ns();
            self.apply_forces();
            self.sync_outputs();
            self.apply_io_forces();
            let Some(t) = self.tasks.get_mut(ti) else {
                continue;
            };
            // schedule
            let mut next = due.saturating_add(interval.max(0));
            if interval > 0 {
                while next <= now.monotonic_ns {
                    next = next.saturating_add(interval);
                }
            }
            t.next_due = Some(if interval > 0 { next } else { now.monotonic_ns });
            // statistics
            let s = &mut t.stats;
            s.cycles += 1;
            s.last_ns = elapsed;
            s.min_ns = if s.cycles == 1 {
                elapsed
            } else {
                s.min_ns.min(elapsed)
            };
            s.max_ns = s.max_ns.max(elapsed);
            s.avg_ns += (elapsed as f64 - s.avg_ns) / s.cycles as f64;
            s.jitter_ns = s.jitter_ns.max((now.monotonic_ns - due).abs());
            if let Err(fault) = result {
                let span = fault.span().unwrap_or_default();
                let d = Diagnostic::error(
                    Code::RuntimeFault,
                    span,
                    format!("task '{}' stopped: {fault}", t.config.name),
                );
                t.state = TaskState::Faulted(d.clone());
                faults.push(d.clone());
                self.stop_task(ti, StopCause::Fault(d), now.monotonic_ns);
                continue;
            }
            if let Some(w) = t.config.watchdog {
                if elapsed > w.time_ns {
                    s.overruns += 1;
                    t.consecutive_overruns += 1;
                    if t.consecutive_overruns >= w.sensitivity {
                        let d = Diagnostic::error(
                            Code::RuntimeFault,
                            crate::syntax::Span::default(),
                            format!(
                                "task '{}' stopped by the watchdog: {} consecutive cycle(s) over {} ns (last {} ns)",
                                t.config.name, t.consecutive_overruns, w.time_ns, elapsed
                            ),
                        );
                        t.state = TaskState::Faulted(d.clone());
                        faults.push(d.clone());
                        self.stop_task(ti, StopCause::Watchdog(d), now.monotonic_ns);
                    }
                } else {
                    t.consecutive_overruns = 0;
                }
            }
        }
        faults
    }

    /// Sets the outputs task `ti` drives to their safe values and records the stop.
    fn stop_task(&mut self, ti: usize, cause: StopCause, at_ns: i64) {
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

    /// Writes the safe value of every output driven by task `ti` (every output for
    /// `None`) into its variable and the output image; forced addresses stay forced.
    /// Returns what was set.
    fn safe_state(&mut self, ti: Option<usize>) -> Vec<(String, String)> {
        let task = ti.and_then(|i| self.tasks.get(i));
        let chosen: Vec<SafeOutput> = self
            .outputs
            .iter()
            .filter(|o| match (task, &o.owner) {
                (None, _) => true,
                (Some(t), Owner::Program(p)) => t.pous.contains(p),
                (Some(t), Owner::Global(key)) => t.names.contains(key),
            })
            .cloned()
            .collect();
        let mut set = Vec::new();
        for o in chosen {
            self.write_leaf(&o.leaf, o.safe.clone());
            if let (Some(d), Ok(v)) = (o.at, self.vm.geti(o.leaf.addr.i)) {
                self.vm.io_write(d.area, d.byte, d.bit, d.bits, v);
            }
            set.push((
                o.name.clone(),
                format_value(&self.compiled.checked, &o.leaf.ty, &o.safe),
            ));
        }
        self.apply_io_forces();
        set
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

    /// Binds the variable at `path` as an output the host drives from (a plant signal,
    /// a field device): when a task that drives it stops, it goes to its safe value
    /// (see [`safe`]). Variables declared `AT %Q...` are outputs without this.
    pub fn bind_output(&mut self, path: &str) -> Result<(), PlcError> {
        let leaf = self.leaf(path)?;
        if self
            .outputs
            .iter()
            .any(|o| o.at.is_none() && o.leaf.addr == leaf.addr && o.leaf.ty == leaf.ty)
        {
            return Ok(());
        }
        let c = &self.compiled.checked;
        let first = split_path(path)
            .and_then(|s| s.into_iter().next())
            .map(|(n, _)| n.to_uppercase())
            .unwrap_or_default();
        let (owner, name_span) =
            if let Some(g) = c.global_index.get(&first).and_then(|g| c.globals.get(*g)) {
                (Owner::Global(first), g.span)
            } else {
                let pid = c
                    .pou_index
                    .get(&first)
                    .copied()
                    .ok_or_else(|| PlcError::UnknownPath(path.to_string()))?;
                let var = split_path(path)
                    .and_then(|s| s.into_iter().nth(1))
                    .map(|(n, _)| n.to_uppercase())
                    .unwrap_or_default();
                let span = c
                    .pou(pid)
                    .and_then(|p| p.var(&var))
                    .map(|(_, v)| v.span)
                    .unwrap_or_default();
                (Owner::Program(pid.0), span)
            };
        let safe = self.safe_value(&leaf.ty, name_span)?;
        self.outputs.push(SafeOutput {
            name: path.to_string(),
            leaf,
            at: None,
            owner,
            safe,
        });
        Ok(())
    }

    /// The safe value declared before the variable named at `name` (0 / FALSE / '' when
    /// none is declared).
    fn safe_value(&self, ty: &Ty, name: crate::syntax::Span) -> Result<Val, PlcError> {
        let default = match ty.lane() {
            Some(crate::check::Lane::Real) => Val::Real(0.0),
            Some(crate::check::Lane::Str) => Val::Str(String::new()),
            _ => Val::Int(0),
        };
        let Some((text, pragma)) = safe::declared(&self.sources, name) else {
            return Ok(default);
        };
        parse_value(&self.compiled.checked, ty, &text).map_err(|_| {
            PlcError::Init(Box::new(safe::bad_value(
                &self.compiled.checked,
                ty,
                &text,
                pragma,
            )))
        })
    }

    /// The `AT %Q` outputs with their safe values; a bad safe value is kept in
    /// `safe_error` (the PLC stays in STOP).
    fn collect_outputs(&mut self) {
        let c = &self.compiled.checked;
        let mut found: Vec<(Size, Ty, DirectAddress, Owner, String, crate::syntax::Span)> =
            Vec::new();
        for g in &c.globals {
            if let Some(d) = g.at.as_deref().and_then(DirectAddress::parse) {
                found.push((
                    g.offset,
                    g.ty.clone(),
                    d,
                    Owner::Global(g.key.clone()),
                    g.name.clone(),
                    g.span,
                ));
            }
        }
        for (i, p) in c.pous.iter().enumerate() {
            if p.kind != PouKind::Program {
                continue;
            }
            let Some(base) = p.base else { continue };
            for v in &p.vars {
                if let Some(d) = v.at.as_deref().and_then(DirectAddress::parse) {
                    found.push((
                        base.plus(v.offset),
                        v.ty.clone(),
                        d,
                        Owner::Program(i),
                        format!("{}.{}", p.name, v.name),
                        v.span,
                    ));
                }
            }
        }
        for (addr, ty, d, owner, path, span) in found {
            if d.area != 'Q' {
                continue;
            }
            match self.safe_value(&ty, span) {
                Ok(safe) => self.outputs.push(SafeOutput {
                    name: direct_key(&d),
                    leaf: Leaf {
                        path,
                        ty,
                        addr,
                        retain: false,
                        persistent: false,
                    },
                    at: Some(d),
                    owner,
                    safe,
                }),
                Err(PlcError::Init(diag)) => {
                    if self.safe_error.is_none() {
                        self.safe_error = Some(*diag);
                    }
                }
                Err(_) => {}
            }
        }
    }

    fn update_system_flags(&mut self, ti: usize, now: i64) {
        let Some([sec, tenth, first]) = self.system_flags else {
            return;
        };
        let Some(t) = self.tasks.get_mut(ti) else {
            return;
        };
        let tick = (now.div_euclid(1_000_000_000), now.div_euclid(100_000_000));
        let (s, h, f) = match t.last_tick {
            None => (true, true, true),
            Some((ls, lh)) => (tick.0 != ls, tick.1 != lh, false),
        };
        t.last_tick = Some(tick);
        let _ = self.vm.seti(sec, i64::from(s));
        let _ = self.vm.seti(tenth, i64::from(h));
        let _ = self.vm.seti(first, i64::from(f));
    }

    /// Statistics of a task.
    pub fn stats(&self, task: &str) -> Option<CycleStats> {
        self.tasks
            .iter()
            .find(|t| t.config.name == task)
            .map(|t| t.stats)
    }

    /// State of a task.
    pub fn task_state(&self, task: &str) -> Option<&TaskState> {
        self.tasks
            .iter()
            .find(|t| t.config.name == task)
            .map(|t| &t.state)
    }

    /// Earliest next due time of a running task (monotonic ns).
    pub fn next_due(&self) -> Option<i64> {
        self.tasks
            .iter()
            .filter(|t| t.state == TaskState::Running)
            .map(|t| t.next_due.unwrap_or(0))
            .min()
    }

    // ------------------------------------------------------------------ paths

    /// Every scalar variable: globals by name, program variables as `Prog.var`, arrays and
    /// structs element by element, FB instances variable by variable.
    pub fn leaves(&self) -> Vec<Leaf> {
        let c = &self.compiled.checked;
        let mut out = Vec::new();
        for g in &c.globals {
            push_leaves(
                c,
                &g.name,
                &g.ty,
                g.offset,
                g.retain,
                g.persistent,
                &mut out,
            );
        }
        for p in &c.pous {
            if p.kind != PouKind::Program || p.stdlib {
                continue;
            }
            let Some(base) = p.base else { continue };
            for v in &p.vars {
                if matches!(
                    v.kind,
                    crate::syntax::VarKind::External | crate::syntax::VarKind::InOut
                ) {
                    continue;
                }
                push_leaves(
                    c,
                    &format!("{}.{}", p.name, v.name),
                    &v.ty,
                    base.plus(v.offset),
                    v.retain,
                    v.persistent,
                    &mut out,
                );
            }
        }
        out
    }

    /// Variables of one program instance.
    pub fn program_leaves(&self, program: &str) -> Result<Vec<Leaf>, PlcError> {
        let c = &self.compiled.checked;
        let pid = c
            .pou_index
            .get(&program.to_uppercase())
            .copied()
            .filter(|p| c.pou(*p).map(|p| p.kind) == Some(PouKind::Program))
            .ok_or_else(|| PlcError::UnknownProgram(program.to_string()))?;
        let prefix = format!(
            "{}.",
            c.pou(pid).map(|p| p.name.clone()).unwrap_or_default()
        );
        Ok(self
            .leaves()
            .into_iter()
            .filter(|l| l.path.starts_with(&prefix))
            .collect())
    }

    /// The scalar at `path` (`Main.lights[3].Q`, `counter`, `Main.m[1, 2]`).
    pub fn leaf(&self, path: &str) -> Result<Leaf, PlcError> {
        let c = &self.compiled.checked;
        let segs = split_path(path).ok_or_else(|| PlcError::UnknownPath(path.into()))?;
        let mut it = segs.into_iter();
        let unknown = || PlcError::UnknownPath(path.to_string());
        let (first, first_idx) = it.next().ok_or_else(unknown)?;
        let key = first.to_uppercase();
        let (mut ty, mut addr, retain, persistent, mut pending_idx) =
            if let Some(&g) = c.global_index.get(&key) {
                let g = c.globals.get(g).ok_or_else(unknown)?;
                (g.ty.clone(), g.offset, g.retain, g.persistent, first_idx)
            } else {
                let pid = c.pou_index.get(&key).copied().ok_or_else(unknown)?;
                let p = c.pou(pid).ok_or_else(unknown)?;
                let base = p
                    .base
                    .filter(|_| p.kind == PouKind::Program)
                    .ok_or_else(unknown)?;
                let (name, idx) = it.next().ok_or_else(unknown)?;
                let (_, v) = p
                    .var(&name.to_uppercase())
                    .filter(|(_, v)| v.kind != crate::syntax::VarKind::InOut)
                    .ok_or_else(unknown)?;
                (
                    v.ty.clone(),
                    base.plus(v.offset),
                    v.retain,
                    v.persistent,
                    idx,
                )
            };
        loop {
            for ix in pending_idx.drain(..) {
                let Ty::Array(a) = &ty else {
                    return Err(unknown());
                };
                if ix.len() != a.dims.len() {
                    return Err(unknown());
                }
                let mut lin = 0usize;
                for (v, (lo, hi)) in ix.iter().zip(&a.dims) {
                    if v < lo || v > hi {
                        return Err(unknown());
                    }
                    lin = lin * usize::try_from(hi - lo + 1).unwrap_or(0)
                        + usize::try_from(v - lo).unwrap_or(0);
                }
                addr = addr.plus(a.elem_size.times(lin));
                ty = a.elem.clone();
            }
            let Some((name, idx)) = it.next() else { break };
            let k = name.to_uppercase();
            let (off, t) = match &ty {
                Ty::Struct(id) => {
                    let f = c
                        .types
                        .struct_def(*id)
                        .and_then(|d| d.fields.iter().find(|f| f.key == k))
                        .ok_or_else(unknown)?;
                    (f.offset, f.ty.clone())
                }
                Ty::Fb(id) => {
                    let (_, v) = c
                        .pou(*id)
                        .and_then(|p| p.var(&k))
                        .filter(|(_, v)| v.kind != crate::syntax::VarKind::InOut)
                        .ok_or_else(unknown)?;
                    (v.offset, v.ty.clone())
                }
                _ => return Err(unknown()),
            };
            addr = addr.plus(off);
            ty = t;
            pending_idx = idx;
        }
        if ty.lane().is_none() {
            return Err(PlcError::NotScalar(path.to_string()));
        }
        Ok(Leaf {
            path: path.to_string(),
            ty,
            addr,
            retain,
            persistent,
        })
    }

    /// Reads a scalar resolved once with [`Plc::leaf`]: the fast path for runtimes that
    /// copy the same variables every cycle.
    pub fn read_leaf(&self, l: &Leaf) -> Result<Val, PlcError> {
        let bad = || PlcError::UnknownPath(l.path.clone());
        Ok(match l.ty.lane() {
            Some(crate::check::Lane::Real) => Val::Real(self.vm.getr(l.addr.r).map_err(|_| bad())?),
            Some(crate::check::Lane::Str) => Val::Str(self.vm.gets(l.addr.s).map_err(|_| bad())?),
            _ => Val::Int(self.vm.geti(l.addr.i).map_err(|_| bad())?),
        })
    }

    /// Writes a scalar resolved once with [`Plc::leaf`]. The value must be of the leaf's
    /// lane (integers, BOOL and times as [`Val::Int`], reals as [`Val::Real`]); integers
    /// are wrapped to the variable's type, as an assignment in ST would.
    pub fn write_leaf(&mut self, l: &Leaf, v: Val) {
        let v = match v {
            Val::Int(x) => Val::Int(l.ty.wrap(x)),
            other => other,
        };
        let _ = match v {
            Val::Int(x) => self.vm.seti(l.addr.i, x),
            Val::Real(x) => self.vm.setr(l.addr.r, x),
            Val::Str(x) => self.vm.sets(l.addr.s, x),
        };
    }

    /// Reads a scalar by path, or the process image by direct address (`%QX1.3`).
    pub fn read(&self, path: &str) -> Result<Val, PlcError> {
        if let Some(d) = direct_path(path) {
            let d = d?;
            return Ok(Val::Int(self.vm.io_read(d.area, d.byte, d.bit, d.bits)));
        }
        let l = self.leaf(path)?;
        self.read_leaf(&l)
    }

    fn format_leaf(&self, l: &Leaf) -> Result<String, PlcError> {
        let v = self.read_leaf(l)?;
        Ok(format_value(&self.compiled.checked, &l.ty, &v))
    }

    /// Reads a scalar by path as an IEC literal (`TRUE`, `T#5s`, `'text'`).
    pub fn read_text(&self, path: &str) -> Result<String, PlcError> {
        if let Some(d) = direct_path(path) {
            let d = d?;
            let v = Val::Int(self.vm.io_read(d.area, d.byte, d.bit, d.bits));
            return Ok(format_value(&self.compiled.checked, &direct_ty(&d), &v));
        }
        let l = self.leaf(path)?;
        self.format_leaf(&l)
    }

    /// Writes a scalar once (the program may overwrite it in the next cycle). `text` is an
    /// IEC literal of the variable's type.
    ///
    /// A direct address (`%IX0.0`, `%QW2`, `%MD20`; the `%` is required) writes the
    /// process image (a BOOL, BYTE, WORD, DWORD or LWORD literal by the address's size)
    /// and the variables declared `AT` an overlapping address.
    pub fn write(&mut self, path: &str, text: &str) -> Result<(), PlcError> {
        if let Some(d) = direct_path(path) {
            let (d, x) = self.direct_value(d?, text)?;
            self.write_io(&d, x);
            return Ok(());
        }
        let l = self.leaf(path)?;
        let v = parse_value(&self.compiled.checked, &l.ty, text)?;
        self.write_leaf(&l, v);
        Ok(())
    }

    /// Forces a variable: the value is applied before and after the programs of every
    /// cycle until [`Plc::release`].
    ///
    /// A direct address (`%IX0.0`, `%QX1.3`, `%MW10`) forces the process image: before
    /// the programs (so inputs and `AT` variables read the forced value) and after them,
    /// after the outputs were copied into the image (so programs cannot override it).
    /// After [`Plc::release`] the image keeps the forced value until the program (outputs,
    /// markers) or the field ([`Plc::set_io`], inputs) writes it again.
    pub fn force(&mut self, path: &str, text: &str) -> Result<(), PlcError> {
        if let Some(d) = direct_path(path) {
            let (d, x) = self.direct_value(d?, text)?;
            self.write_io(&d, x);
            self.io_forces.insert(direct_key(&d), (d, x));
            return Ok(());
        }
        let l = self.leaf(path)?;
        let v = parse_value(&self.compiled.checked, &l.ty, text)?;
        self.write_leaf(&l, v.clone());
        self.forces.insert(path.to_string(), (l.ty, l.addr, v));
        Ok(())
    }

    /// Releases a forced variable; returns whether it was forced.
    pub fn release(&mut self, path: &str) -> bool {
        if let Some(d) = direct_path(path) {
            return match d {
                Ok(d) => self.io_forces.remove(&direct_key(&d)).is_some(),
                Err(_) => false,
            };
        }
        self.forces.remove(path).is_some()
    }

    /// Forced paths and direct addresses (`%QX1.3`).
    pub fn forced(&self) -> Vec<String> {
        self.forces
            .keys()
            .chain(self.io_forces.keys())
            .cloned()
            .collect()
    }

    /// The value of a literal for a direct address, by the address's size.
    fn direct_value(&self, d: DirectAddress, text: &str) -> Result<(DirectAddress, i64), PlcError> {
        match parse_value(&self.compiled.checked, &direct_ty(&d), text)? {
            Val::Int(x) => Ok((d, x)),
            _ => Err(PlcError::BadValue {
                text: text.to_string(),
                ty: self.compiled.checked.type_name(&direct_ty(&d)),
            }),
        }
    }

    /// Writes the process image and every variable declared `AT` an overlapping address.
    fn write_io(&mut self, d: &DirectAddress, x: i64) {
        self.vm.io_write(d.area, d.byte, d.bit, d.bits, x);
        for (a, ty, b) in &self.io_bindings {
            if overlaps(b, d) {
                let v = self.vm.io_read(b.area, b.byte, b.bit, b.bits);
                let _ = self.vm.seti(a.i, ty.wrap(v));
            }
        }
    }

    fn apply_io_forces(&mut self) {
        if self.io_forces.is_empty() {
            return;
        }
        let forces: Vec<(DirectAddress, i64)> = self.io_forces.values().copied().collect();
        for (d, x) in forces {
            self.write_io(&d, x);
        }
    }

    fn apply_forces(&mut self) {
        let forces: Vec<(Size, Val)> = self
            .forces
            .values()
            .map(|(_, a, v)| (*a, v.clone()))
            .collect();
        for (a, v) in forces {
            let _ = match v {
                Val::Int(x) => self.vm.seti(a.i, x),
                Val::Real(x) => self.vm.setr(a.r, x),
                Val::Str(x) => self.vm.sets(a.s, x),
            };
        }
    }

    // ------------------------------------------------------------------ I/O image

    fn collect_io_bindings(&self) -> Vec<(Size, Ty, DirectAddress)> {
        let c = &self.compiled.checked;
        let mut out = Vec::new();
        for g in &c.globals {
            if let Some(d) = g.at.as_deref().and_then(DirectAddress::parse) {
                out.push((g.offset, g.ty.clone(), d));
            }
        }
        for p in &c.pous {
            if p.kind != PouKind::Program {
                continue;
            }
            let Some(base) = p.base else { continue };
            for v in &p.vars {
                if let Some(d) = v.at.as_deref().and_then(DirectAddress::parse) {
                    out.push((base.plus(v.offset), v.ty.clone(), d));
                }
            }
        }
        out
    }

    fn sync_inputs(&mut self) {
        for (a, ty, d) in &self.io_bindings {
            if d.area == 'I' || d.area == 'M' {
                let v = self.vm.io_read(d.area, d.byte, d.bit, d.bits);
                let _ = self.vm.seti(a.i, ty.wrap(v));
            }
        }
    }

    fn sync_outputs(&mut self) {
        for (a, _, d) in &self.io_bindings {
            if d.area == 'Q' || d.area == 'M' {
                if let Ok(v) = self.vm.geti(a.i) {
                    self.vm.io_write(d.area, d.byte, d.bit, d.bits, v);
                }
            }
        }
    }

    /// Sets an input (or marker) in the process image by direct address (`%IX0.3`,
    /// `IW4`). Takes effect at the start of the next cycle.
    pub fn set_io(&mut self, address: &str, value: i64) -> Result<(), PlcError> {
        let d = DirectAddress::parse(address.trim_start_matches('%'))
            .ok_or_else(|| PlcError::BadAddress(address.to_string()))?;
        self.vm.io_write(d.area, d.byte, d.bit, d.bits, value);
        Ok(())
    }

    /// Reads the process image by direct address (`%QX0.0`, `%QW2`).
    pub fn get_io(&self, address: &str) -> Result<i64, PlcError> {
        let d = DirectAddress::parse(address.trim_start_matches('%'))
            .ok_or_else(|| PlcError::BadAddress(address.to_string()))?;
        Ok(self.vm.io_read(d.area, d.byte, d.bit, d.bits))
    }

    /// Renders a diagnostic against this PLC's sources.
    pub fn render(&self, d: &Diagnostic) -> String {
        d.render(&self.sources)
    }
}

/// A direct address written as a path (`%QX1.3`, any case): `None` for variable paths.
fn direct_path(path: &str) -> Option<Result<DirectAddress, PlcError>> {
    let rest = path.trim().strip_prefix('%')?;
    Some(
        DirectAddress::parse(&rest.to_ascii_uppercase())
            .ok_or_else(|| PlcError::BadAddress(path.to_string())),
    )
}

/// The type of a direct address by its size.
fn direct_ty(d: &DirectAddress) -> Ty {
    match d.bits {
        1 => Ty::Bool,
        8 => Ty::Byte,
        16 => Ty::Word,
        32 => Ty::DWord,
        _ => Ty::LWord,
    }
}

/// Canonical spelling: `%QX1.3`, `%MW10`.
fn direct_key(d: &DirectAddress) -> String {
    match d.bits {
        1 => format!("%{}X{}.{}", d.area, d.byte, d.bit),
        n => {
            let size = match n {
                8 => 'B',
                16 => 'W',
                32 => 'D',
                _ => 'L',
            };
            format!("%{}{size}{}", d.area, d.byte)
        }
    }
}

/// Whether two direct addresses share a bit.
fn overlaps(a: &DirectAddress, b: &DirectAddress) -> bool {
    if a.area != b.area {
        return false;
    }
    let end = |d: &DirectAddress| d.byte + (d.bits as usize / 8).max(1);
    if a.byte >= end(b) || b.byte >= end(a) {
        return false;
    }
    !(a.bits == 1 && b.bits == 1 && a.bit != b.bit)
}

type Seg = (String, Vec<Vec<i64>>);

fn split_path(path: &str) -> Option<Vec<Seg>> {
    let mut out: Vec<Seg> = Vec::new();
    let mut rest = path.trim();
    while !rest.is_empty() {
        let end = rest.find(['.', '[']).unwrap_or(rest.len());
        let name = rest.get(..end)?.trim().to_string();
        rest = rest.get(end..)?;
        let mut idx = Vec::new();
        while let Some(r) = rest.strip_prefix('[') {
            let close = r.find(']')?;
            let inner = r.get(..close)?;
            let v: Option<Vec<i64>> = inner.split(',').map(|x| x.trim().parse().ok()).collect();
            idx.push(v?);
            rest = r.get(close + 1..)?;
        }
        let name = name.trim_start_matches('#').trim_matches('"').to_string();
        if name.is_empty() {
            return None;
        }
        out.push((name, idx));
        if let Some(r) = rest.strip_prefix('.') {
            rest = r;
        } else if !rest.is_empty() {
            return None;
        }
    }
    Some(out)
}

fn push_leaves(
    c: &Checked,
    path: &str,
    ty: &Ty,
    addr: Size,
    retain: bool,
    persistent: bool,
    out: &mut Vec<Leaf>,
) {
    match ty {
        Ty::Array(a) => {
            let n = a.len();
            for k in 0..n {
                // multi-dimensional index from linear k
                let mut rem = k;
                let mut idx = vec![0i64; a.dims.len()];
                for (d, (lo, hi)) in a.dims.iter().enumerate().rev() {
                    let span = usize::try_from(hi - lo + 1).unwrap_or(1).max(1);
                    if let Some(s) = idx.get_mut(d) {
                        *s = lo + (rem % span) as i64;
                    }
                    rem /= span;
                }
                let ix: Vec<String> = idx.iter().map(i64::to_string).collect();
                push_leaves(
                    c,
                    &format!("{path}[{}]", ix.join(", ")),
                    &a.elem,
                    addr.plus(a.elem_size.times(k)),
                    retain,
                    persistent,
                    out,
                );
            }
        }
        Ty::Struct(id) => {
            if let Some(d) = c.types.struct_def(*id) {
                for f in &d.fields {
                    push_leaves(
                        c,
                        &format!("{path}.{}", f.name),
                        &f.ty,
                        addr.plus(f.offset),
                        retain,
                        persistent,
                        out,
                    );
                }
            }
        }
        Ty::Fb(id) => {
            if let Some(p) = c.pou(PouId(id.0)) {
                for v in &p.vars {
                    if matches!(
                        v.kind,
                        crate::syntax::VarKind::External
                            | crate::syntax::VarKind::Temp
                            | crate::syntax::VarKind::InOut
                    ) {
                        continue;
                    }
                    push_leaves(
                        c,
                        &format!("{path}.{}", v.name),
                        &v.ty,
                        addr.plus(v.offset),
                        retain || v.retain,
                        persistent || v.persistent,
                        out,
                    );
                }
            }
        }
        Ty::Void => {}
        _ => out.push(Leaf {
            path: path.to_string(),
            ty: ty.clone(),
            addr,
            retain,
            persistent,
        }),
    }
}

/// Formats a scalar value of `ty` as an IEC literal.
pub fn format_value(c: &Checked, ty: &Ty, v: &Val) -> String {
    match (ty, v) {
        (Ty::Bool, Val::Int(x)) => if *x != 0 { "TRUE" } else { "FALSE" }.into(),
        (Ty::Time, Val::Int(x)) => format::time(*x, false),
        (Ty::LTime, Val::Int(x)) => format::time(*x, true),
        (Ty::Tod, Val::Int(x)) => format::tod(*x),
        (Ty::Date, Val::Int(x)) => format::date(*x),
        (Ty::Dt, Val::Int(x)) => format::dt(*x),
        (Ty::ULInt | Ty::LWord, Val::Int(x)) => (*x as u64).to_string(),
        (Ty::Ref(_), Val::Int(0)) => "NULL".into(),
        (Ty::Ref(_), Val::Int(x)) => {
            // the cells referred to, per lane (see `compile::expr::pack`)
            let at = crate::compile::unpack(x.wrapping_sub(1));
            format!("REF({}, {}, {})", at.i, at.r, at.s)
        }
        (Ty::Enum(id), Val::Int(x)) => match c.types.enum_def(*id) {
            Some(d) => match d.values.iter().find(|(_, v)| v == x) {
                Some((n, _)) => format!("{}#{n}", d.name),
                None => x.to_string(),
            },
            None => x.to_string(),
        },
        (_, Val::Int(x)) => x.to_string(),
        (t, Val::Real(x)) => format::real(*x, *t == Ty::Real),
        (Ty::WString(_), Val::Str(s)) => format::string(s, true),
        (_, Val::Str(s)) => format::string(s, false),
    }
}

/// Parses an IEC literal (`TRUE`, `42`, `16#FF`, `1.5`, `T#5s`, `'text'`, `Color#Red`) as a
/// value of `ty`.
pub fn parse_value(c: &Checked, ty: &Ty, text: &str) -> Result<Val, PlcError> {
    let bad = || PlcError::BadValue {
        text: text.to_string(),
        ty: c.type_name(ty),
    };
    if let Ty::Ref(_) = ty {
        // an address comes from REF() in the program; from outside only NULL
        return if text.trim().eq_ignore_ascii_case("NULL") {
            Ok(Val::Int(0))
        } else {
            Err(bad())
        };
    }
    let mut diags = Vec::new();
    let toks = crate::syntax::lexer::lex(crate::syntax::FileId(0), text.trim(), &mut diags);
    if !diags.is_empty() {
        return Err(bad());
    }
    use crate::syntax::lexer::Tok;
    let kinds: Vec<&Tok> = toks
        .iter()
        .map(|t| &t.tok)
        .filter(|t| !matches!(t, Tok::Eof))
        .collect();
    let (neg, rest) = match kinds.first() {
        Some(Tok::Punct("-")) => (true, kinds.get(1..).unwrap_or(&[])),
        _ => (false, kinds.as_slice()),
    };
    let rest: Vec<&Tok> = match rest.first() {
        Some(Tok::TypePrefix(_)) => rest.get(1..).unwrap_or(&[]).to_vec(),
        _ => rest.to_vec(),
    };
    let one = match rest.as_slice() {
        [t] => *t,
        [Tok::Ident(_), Tok::HashIdent(v)] => {
            if let Ty::Enum(id) = ty {
                let d = c.types.enum_def(*id).ok_or_else(bad)?;
                let (_, x) = d
                    .values
                    .iter()
                    .find(|(n, _)| n.eq_ignore_ascii_case(v))
                    .ok_or_else(bad)?;
                return Ok(Val::Int(*x));
            }
            return Err(bad());
        }
        [Tok::Punct("-"), t] if !neg => *t,
        _ => return Err(bad()),
    };
    let sign = |x: i128| if neg { -x } else { x };
    let v = match (ty.lane(), one) {
        (Some(crate::check::Lane::Int), Tok::Ident(s)) if *ty == Ty::Bool => {
            match s.to_ascii_uppercase().as_str() {
                "TRUE" => Val::Int(1),
                "FALSE" => Val::Int(0),
                _ => return Err(bad()),
            }
        }
        (Some(crate::check::Lane::Int), Tok::Ident(s)) => {
            let Ty::Enum(id) = ty else { return Err(bad()) };
            let d = c.types.enum_def(*id).ok_or_else(bad)?;
            let (_, x) = d
                .values
                .iter()
                .find(|(n, _)| n.eq_ignore_ascii_case(s))
                .ok_or_else(bad)?;
            Val::Int(*x)
        }
        (Some(crate::check::Lane::Int), Tok::Int(x)) => {
            let x = sign(i128::try_from(*x).map_err(|_| bad())?);
            if let Some((lo, hi)) = ty.int_range() {
                if x < lo || x > hi {
                    return Err(bad());
                }
            }
            Val::Int(x as i64)
        }
        (Some(crate::check::Lane::Int), Tok::Time(ns, _)) if ty.is_duration() => {
            Val::Int(i64::try_from(sign(*ns)).map_err(|_| bad())?)
        }
        (Some(crate::check::Lane::Int), Tok::Tod(x)) if *ty == Ty::Tod => Val::Int(*x),
        (Some(crate::check::Lane::Int), Tok::Date(x)) if *ty == Ty::Date => Val::Int(*x),
        (Some(crate::check::Lane::Int), Tok::Dt(x)) if *ty == Ty::Dt => Val::Int(*x),
        (Some(crate::check::Lane::Real), Tok::Real(x)) => Val::Real(crate::stdlib::conv::fit_real(
            if neg { -*x } else { *x },
            ty,
        )),
        (Some(crate::check::Lane::Real), Tok::Int(x)) => Val::Real(crate::stdlib::conv::fit_real(
            sign(i128::try_from(*x).map_err(|_| bad())?) as f64,
            ty,
        )),
        (Some(crate::check::Lane::Str), Tok::SqString(s) | Tok::DqString(s)) => {
            let n = match ty {
                Ty::String(n) | Ty::WString(n) => *n,
                _ => u32::MAX,
            };
            Val::Str(crate::stdlib::string::truncate(s.clone(), n))
        }
        _ => return Err(bad()),
    };
    Ok(v)
}
