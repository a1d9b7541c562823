//! A run: a student's program on the soft PLC coupled to a lab model, scan by scan, on
//! the simulated clock, with the scenario's buttons and faults and its properties
//! checked after every scan.
//!
//! One scan at simulated time `t` (the PLC's cycle apart):
//!
//! ```text
//!  model.advance_to(t)          the model's own instants up to t (1-s steps, step timers)
//!  scenario lines due by t      `press START`, `stuck H1 off`, `clear H1` (model console)
//!  model inputs -> %I image     each binding of the profile (K1 -> %IX0.0 ...)
//!  plc.run_cycle(t)             the student's PROGRAM
//!  %Q image -> model outputs    (EM1 <- %QX0.0 ...), effective at t
//!  check                        new model errors, then every property, over one table
//! ```
//!
//! The model advances on its own instants, never on the scan (see `plant::lab`), so the
//! result does not depend on the scan period beyond the PLC's own reaction time, and a
//! run at `--speed max` and one paced to real time give the same report.

use std::time::{Duration, Instant};

use plant::lab::{Binding, LabModel, LabOptions, Profile};
use plant::{Direction, Value};
use plc::task::{ClockReading, TaskConfig};
use plc::Plc;

use crate::program::Program;
use crate::report::{PropertyOutcome, Report, Violation, ViolationKind};
use crate::scenario::{Property, RuleKind, Scenario, ScenarioError, TimedLine};
use crate::timeline::{Channel, Timeline};

/// How fast simulated time runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Speed {
    /// As fast as the machine goes.
    Max,
    /// This many times real time (1 = real time).
    Times(f64),
}

impl std::str::FromStr for Speed {
    type Err = String;

    fn from_str(text: &str) -> Result<Speed, String> {
        if text.eq_ignore_ascii_case("max") {
            return Ok(Speed::Max);
        }
        match text.trim_end_matches(['x', 'X']).parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => Ok(Speed::Times(x)),
            _ => Err(format!(
                "{text:?} is no speed: write a factor (1, 10, 0.5) or max"
            )),
        }
    }
}

/// What a run needs besides the program.
#[derive(Debug, Clone)]
pub struct RunSettings {
    /// The model (`slide`, `crossroad`, `mixing`, `washing`).
    pub model: String,
    /// Its address profile.
    pub profile: Profile,
    /// Its options.
    pub options: LabOptions,
    /// Simulated time to run.
    pub duration: Duration,
    /// The PLC's cycle.
    pub scan: Duration,
    /// How fast.
    pub speed: Speed,
}

/// The PLC's cycle when neither the scenario nor the command line sets one.
pub const DEFAULT_SCAN: Duration = Duration::from_millis(10);
/// The run's length when neither the scenario nor the command line sets one.
pub const DEFAULT_DURATION: Duration = Duration::from_secs(600);

/// Why a run cannot start or go on.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The model or its options.
    #[error("{0}")]
    Model(#[from] plant::lab::LabError),
    /// The scenario does not fit the model.
    #[error("{0}")]
    Scenario(#[from] ScenarioError),
    /// The PLC refused the program's task or could not start it.
    #[error("the PLC: {0}")]
    Plc(String),
    /// The model refused a step or a line (a bug of the model or a scenario line).
    #[error("the model: {0}")]
    Plant(#[from] plant::PlantError),
}

/// Virtual wall clock of a run: 2024-01-01 00:00:00 UTC, as `stanice plc run` has it.
const EPOCH_NS: i64 = 1_704_067_200_000_000_000;

/// A running program and model.
pub struct Session {
    plc: Plc,
    model: Box<dyn LabModel + Send>,
    settings: RunSettings,
    program: String,
    /// Model signal -> PLC input address.
    inputs: Vec<Binding>,
    /// PLC output address -> model signal.
    outputs: Vec<Binding>,
    /// The names conditions see: the model's signals, then its state values.
    names: Vec<String>,
    values: Vec<f64>,
    /// How many signals lead `names` (the rest are state values).
    signal_count: usize,
    properties: Vec<(Property, PropertyState)>,
    events: Vec<TimedLine>,
    next_event: usize,
    now: Duration,
    scans: u64,
    errors_seen: usize,
    violations: Vec<Violation>,
    violations_total: u64,
    faults_injected: Vec<String>,
    /// Set when the program stopped (a run-time fault).
    stopped: bool,
    wall: Duration,
    /// Every change of the table, when asked for ([`Session::record_timeline`]).
    timeline: Option<Timeline>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("model", &self.settings.model)
            .field("program", &self.program)
            .field("now", &self.now)
            .finish_non_exhaustive()
    }
}

/// At most this many violations are listed; the rest are counted.
const LISTED: usize = 100;

#[derive(Debug, Default, Clone)]
struct PropertyState {
    /// The condition's value after the last scan.
    last: bool,
    /// `never`/`always`: whether it was violated after the last scan (a violation is
    /// reported when it starts).
    violated: bool,
    /// `eventually`: it held.
    satisfied: bool,
    /// `repeats`: the start of the current window.
    window_start: Option<Duration>,
    violations: u64,
}

impl Session {
    /// Starts `program` against the model of `settings`, with `scenario`'s lines and
    /// properties (`None`: the model's errors alone decide).
    pub fn new(
        program: Program,
        settings: RunSettings,
        scenario: Option<&Scenario>,
    ) -> Result<Session, RunError> {
        let model = plant::lab::open(&settings.model, &settings.options)?;
        let bindings = plant::lab::bindings(&settings.model, settings.profile, &settings.options)?;
        let direction = |signal: &str| {
            model
                .signals()
                .iter()
                .find(|info| info.name == signal)
                .map(|info| info.direction)
        };
        let (inputs, outputs): (Vec<Binding>, Vec<Binding>) = bindings
            .into_iter()
            .partition(|binding| direction(&binding.signal) == Some(Direction::Input));
        let mut names: Vec<String> = model.signals().iter().map(|s| s.name.clone()).collect();
        let signal_count = names.len();
        for (name, _) in model.state() {
            if !names.iter().any(|n| n.eq_ignore_ascii_case(name)) {
                names.push(name.to_owned());
            }
        }
        let mut properties = Vec::new();
        let mut events = Vec::new();
        if let Some(scenario) = scenario {
            let resolve = |name: &str| names.iter().position(|n| n.eq_ignore_ascii_case(name));
            let known = || names.clone();
            for spec in &scenario.properties {
                let property = spec.resolve(&resolve, &known)?;
                let state = PropertyState {
                    window_start: Some(spec.after),
                    ..PropertyState::default()
                };
                properties.push((property, state));
            }
            events = scenario.events.clone();
            check_lines(&settings, &events)?;
        }
        let mut plc = Plc::try_new(program.compiled, program.sources)
            .map_err(|error| RunError::Plc(error.to_string()))?;
        let scan_ns = i64::try_from(settings.scan.as_nanos()).unwrap_or(i64::MAX);
        plc.add_task(TaskConfig::cyclic("lab", scan_ns, &[&program.main]))
            .map_err(|error| RunError::Plc(error.to_string()))?;
        if let Some(fault) = plc.init_fault() {
            return Err(RunError::Plc(plc.render(fault)));
        }
        let values = vec![0.0; names.len()];
        let mut session = Session {
            plc,
            model,
            settings,
            program: program.main,
            inputs,
            outputs,
            names,
            values,
            signal_count,
            properties,
            events,
            next_event: 0,
            now: Duration::ZERO,
            scans: 0,
            errors_seen: 0,
            violations: Vec::new(),
            violations_total: 0,
            faults_injected: Vec::new(),
            stopped: false,
            wall: Duration::ZERO,
            timeline: None,
        };
        session.refresh();
        Ok(session)
    }

    /// The model, for a mimic or a test.
    pub fn model(&self) -> &dyn LabModel {
        self.model.as_ref()
    }

    /// The model, to press its buttons (a mimic's RESET, START).
    pub fn model_mut(&mut self) -> &mut (dyn LabModel + Send) {
        self.model.as_mut()
    }

    /// The simulated time of the next scan.
    pub fn now(&self) -> Duration {
        self.now
    }

    /// Scans run so far.
    pub fn scans(&self) -> u64 {
        self.scans
    }

    /// Whether the program stopped on a run-time fault.
    pub fn stopped(&self) -> bool {
        self.stopped
    }

    /// The violations so far (at most the first hundred).
    pub fn violations(&self) -> &[Violation] {
        &self.violations
    }

    /// The names conditions see, and their values after the last scan.
    pub fn table(&self) -> (&[String], &[f64]) {
        (&self.names, &self.values)
    }

    /// Records every change of the table from now on (a mimic's time-line).
    pub fn record_timeline(&mut self) {
        let channels = self
            .names
            .iter()
            .enumerate()
            .map(|(index, name)| {
                let kind = match self
                    .model
                    .signals()
                    .iter()
                    .find(|info| info.name == *name)
                    .map(|info| info.direction)
                {
                    _ if index >= self.signal_count => "state",
                    Some(Direction::Output) => "output",
                    _ => "input",
                };
                Channel {
                    name: name.clone(),
                    kind,
                }
            })
            .collect();
        let mut timeline = Timeline::new(channels);
        timeline.record(self.now, &self.values);
        self.timeline = Some(timeline);
    }

    /// The time-line, when recorded.
    pub fn timeline(&self) -> Option<&Timeline> {
        self.timeline.as_ref()
    }

    /// Runs a console line of the model now (a mimic's button: `press START`, `reset`).
    pub fn console(&mut self, line: &str) -> Result<(), RunError> {
        self.model.console(line)?;
        self.refresh();
        Ok(())
    }

    /// The PLC's outputs as the model has them: (signal, value).
    pub fn outputs(&self) -> Vec<(String, String)> {
        self.outputs
            .iter()
            .map(|binding| {
                let value = self
                    .model
                    .read(&binding.signal)
                    .map_or_else(|_| "?".to_owned(), |reading| show(reading.value));
                (binding.signal.clone(), value)
            })
            .collect()
    }

    /// One scan at the current time; the next is one cycle later.
    pub fn step(&mut self) -> Result<(), RunError> {
        let t = self.now;
        self.model.advance_to(t)?;
        while let Some(event) = self.events.get(self.next_event).filter(|e| e.at <= t) {
            let event = event.clone();
            self.next_event += 1;
            self.model.console(&event.line)?;
            if event.fault {
                self.faults_injected.push(format!(
                    "{:.3} s {}",
                    event.at.as_secs_f64(),
                    event.line
                ));
            }
        }
        if !self.stopped {
            for binding in &self.inputs {
                let value = self
                    .model
                    .read(&binding.signal)
                    .map_or(0, |reading| i64::from(truth(reading.value)));
                self.plc
                    .set_io(&binding.address, value)
                    .map_err(|error| RunError::Plc(error.to_string()))?;
            }
            let ns = i64::try_from(t.as_nanos()).unwrap_or(i64::MAX);
            let now = ClockReading {
                monotonic_ns: ns,
                utc_ns: EPOCH_NS.saturating_add(ns),
                utc_offset_ns: 0,
            };
            let faults = self.plc.run_cycle(now);
            for binding in &self.outputs {
                let on = self.plc.get_io(&binding.address).unwrap_or(0) != 0;
                self.model.set_output(&binding.signal, Value::Bool(on))?;
            }
            if let Some(fault) = faults.first() {
                let detail = self.plc.render(fault);
                self.stopped = true;
                self.record(ViolationKind::PlcFault, None, detail);
            }
        }
        self.refresh();
        self.check(t);
        if let Some(timeline) = &mut self.timeline {
            timeline.record(t, &self.values);
        }
        self.scans += 1;
        self.now = t.saturating_add(self.settings.scan);
        Ok(())
    }

    /// Runs until the simulated time `end` at the settings' speed.
    pub fn run_until(&mut self, end: Duration) -> Result<(), RunError> {
        let started = Instant::now();
        let simulated_start = self.now;
        while self.now < end {
            self.step()?;
            if let Speed::Times(factor) = self.settings.speed {
                let due = (self.now - simulated_start).div_f64(factor);
                let elapsed = started.elapsed();
                // Sleep only when a millisecond ahead: a syscall per 10-ms scan at 100x
                // would cost more than the scan.
                if due > elapsed + Duration::from_millis(1) {
                    std::thread::sleep(due - elapsed);
                }
            }
        }
        self.wall += started.elapsed();
        Ok(())
    }

    /// Runs the settings' whole duration and reports.
    pub fn run(mut self) -> Result<Report, RunError> {
        let end = self.settings.duration;
        self.run_until(end)?;
        self.model.advance_to(end.max(self.model.now()))?;
        self.refresh();
        self.check(end);
        Ok(self.report())
    }

    /// What the run came to so far.
    pub fn report(&self) -> Report {
        let simulated = self.now.min(self.settings.duration.max(self.now));
        let wall = self.wall.as_secs_f64();
        Report {
            model: self.settings.model.clone(),
            profile: self.settings.profile.to_string(),
            program: self.program.clone(),
            simulated_s: simulated.as_secs_f64(),
            scans: self.scans,
            wall_s: wall,
            speedup: if wall > 0.0 {
                simulated.as_secs_f64() / wall
            } else {
                0.0
            },
            passed: self.violations_total == 0,
            violations_total: self.violations_total,
            violations: self.violations.clone(),
            properties: self
                .properties
                .iter()
                .map(|(property, state)| PropertyOutcome {
                    name: property.spec.name.clone(),
                    rule: property.spec.rule.key().to_owned(),
                    condition: property.condition.text().to_owned(),
                    violations: state.violations,
                })
                .collect(),
            faults_injected: self.faults_injected.clone(),
        }
    }

    /// The condition table from the model as it is now.
    fn refresh(&mut self) {
        for (slot, name) in self
            .values
            .iter_mut()
            .zip(&self.names)
            .take(self.signal_count)
        {
            *slot = self
                .model
                .read(name)
                .map_or(0.0, |reading| number(reading.value));
        }
        for (name, value) in self.model.state() {
            if let Some(index) = self
                .names
                .iter()
                .skip(self.signal_count)
                .position(|n| n == name)
            {
                if let Some(slot) = self.values.get_mut(self.signal_count + index) {
                    *slot = number(value);
                }
            }
        }
    }

    fn record(&mut self, kind: ViolationKind, property: Option<String>, detail: String) {
        self.record_at(self.now, kind, property, detail);
    }

    fn record_at(
        &mut self,
        time: Duration,
        kind: ViolationKind,
        property: Option<String>,
        detail: String,
    ) {
        self.violations_total += 1;
        if self.violations.len() < LISTED {
            let outputs = self.outputs();
            self.violations.push(Violation {
                time_s: time.as_secs_f64(),
                kind,
                property,
                detail,
                outputs,
            });
        }
    }

    /// New model errors, then every property, at time `t`.
    fn check(&mut self, t: Duration) {
        let errors = self.model.errors();
        if errors.len() < self.errors_seen {
            // A RESET cleared the model's list.
            self.errors_seen = 0;
        }
        let new: Vec<_> = errors.iter().skip(self.errors_seen).cloned().collect();
        self.errors_seen = errors.len();
        for error in new {
            let recovery = if error.recoverable {
                "recoverable"
            } else {
                "non-recoverable: RESET needed"
            };
            self.record_at(
                error.time,
                ViolationKind::Model(error.kind.name().to_owned()),
                None,
                format!("{} ({recovery})", error.detail),
            );
        }
        let mut found = Vec::new();
        for (property, state) in &mut self.properties {
            let holds = property.condition.holds(&self.values);
            let spec = &property.spec;
            let active = t >= spec.after;
            let rose = holds && !state.last;
            match spec.rule {
                RuleKind::Never | RuleKind::Always => {
                    let violated = active && (holds == (spec.rule == RuleKind::Never));
                    if violated && !state.violated {
                        let what = if holds { "held" } else { "did not hold" };
                        found.push((t, spec.name.clone(), format!("`{}` {what}", spec.condition)));
                    }
                    state.violated = violated;
                }
                RuleKind::Eventually if active => {
                    let within = spec.within.unwrap_or_default();
                    if holds {
                        state.satisfied = true;
                    } else if !state.satisfied && t > spec.after + within {
                        state.satisfied = true; // reported once
                        found.push((
                            spec.after + within,
                            spec.name.clone(),
                            format!(
                                "`{}` did not hold within {} s",
                                spec.condition,
                                within.as_secs_f64()
                            ),
                        ));
                    }
                }
                RuleKind::Repeats if active => {
                    let within = spec.within.unwrap_or_default();
                    let start = state.window_start.unwrap_or(spec.after);
                    if rose {
                        state.window_start = Some(t);
                    } else if t > start + within {
                        // Reported once per missed window: the next window starts now.
                        state.window_start = Some(t);
                        found.push((
                            start + within,
                            spec.name.clone(),
                            format!(
                                "`{}` did not rise within {} s after {:.3} s",
                                spec.condition,
                                within.as_secs_f64(),
                                start.as_secs_f64()
                            ),
                        ));
                    }
                }
                RuleKind::Eventually | RuleKind::Repeats => {}
            }
            if found.last().is_some_and(|(_, name, _)| *name == spec.name) {
                state.violations += 1;
            }
            state.last = holds;
        }
        for (time, name, detail) in found {
            self.record_at(time, ViolationKind::Property, Some(name), detail);
        }
    }
}

/// Checks the scenario's lines against a model of the same kind before the run, so that
/// a misspelt fault is an error at once, not after ten simulated minutes.
fn check_lines(settings: &RunSettings, events: &[TimedLine]) -> Result<(), RunError> {
    let mut scratch = plant::lab::open(&settings.model, &settings.options)?;
    for event in events {
        scratch.console(&event.line).map_err(|error| {
            RunError::Scenario(ScenarioError::Invalid(format!(
                "the line `{}` at {} s: {error}",
                event.line,
                event.at.as_secs_f64()
            )))
        })?;
    }
    Ok(())
}

fn truth(value: Value) -> bool {
    match value {
        Value::Bool(b) => b,
        Value::Real(x) => x != 0.0,
    }
}

fn number(value: Value) -> f64 {
    match value {
        Value::Bool(b) => f64::from(u8::from(b)),
        Value::Real(x) => x,
    }
}

fn show(value: Value) -> String {
    match value {
        Value::Bool(b) => u8::from(b).to_string(),
        Value::Real(x) => format!("{x}"),
    }
}
