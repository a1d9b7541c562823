//! The soft PLC: a compiled program with its memory image and tasks; construction, cold
//! and warm start, program download.

use super::clock::NoStopwatch;
use super::cycle::Task;
use super::safe::{self, SafeOutput};
use super::{CycleStats, Leaf, PlcError, Stopwatch, TaskConfig, TaskState, TaskStopped};
use crate::check::{Checked, Size, Ty};
use crate::compile::Compiled;
use crate::diagnostics::{Code, Diagnostic};
use crate::syntax::{PouKind, SourceMap};
use crate::vm::{DirectAddress, Fault, Val, Vm};
use std::collections::{BTreeMap, HashMap, HashSet, VecDeque};
use std::rc::Rc;

/// Loop iterations allowed per task cycle before a fault.
pub const DEFAULT_LOOP_BUDGET: u64 = 100_000_000;

/// A soft PLC: compiled program, memory, tasks.
pub struct Plc {
    pub(super) compiled: Compiled,
    pub(super) sources: SourceMap,
    pub(super) vm: Vm,
    pub(super) tasks: Vec<Task>,
    pub(super) forces: BTreeMap<String, (Ty, Size, Val)>,
    /// Forced direct addresses (`%QX1.3`), by canonical spelling.
    pub(super) io_forces: BTreeMap<String, (DirectAddress, i64)>,
    pub(super) io_bindings: Vec<(Size, Ty, DirectAddress)>,
    /// Integer cells of System_S.R_EDGE_1SEC, R_EDGE_100MS, FIRST_SCAN.
    pub(super) system_flags: Option<[usize; 3]>,
    pub(super) stopwatch: Box<dyn Stopwatch>,
    /// The fault of the last cold start, if it failed; and whether `run_cycle` has yet to
    /// report it.
    pub(super) init_fault: Option<(Diagnostic, bool)>,
    /// Outputs and their safe values.
    pub(super) outputs: Vec<SafeOutput>,
    /// A safe value that is not a literal of its output's type (the PLC stays in STOP).
    pub(super) safe_error: Option<Diagnostic>,
    /// Names mentioned by each user POU (for which task drives a global output).
    pub(super) mentions: HashMap<String, HashSet<String>>,
    /// Stops not yet taken with `poll_event`.
    pub(super) events: VecDeque<TaskStopped>,
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

    /// The error for a program name that names none, with the nearest program's name.
    pub(super) fn unknown_program(&self, name: &str) -> PlcError {
        let programs = self
            .compiled
            .checked
            .pous
            .iter()
            .filter(|p| p.kind == PouKind::Program && !p.stdlib)
            .map(|p| p.name.as_str());
        PlcError::UnknownProgram {
            name: name.to_owned(),
            suggestion: crate::suggest::did_you_mean(name, programs),
        }
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
                .ok_or_else(|| self.unknown_program(name))?;
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

    /// Renders a diagnostic against this PLC's sources.
    pub fn render(&self, d: &Diagnostic) -> String {
        d.render(&self.sources)
    }
}
