//! The part every lab model shares: the signal surface, the clock (1-s flag, motion
//! timers), commanded and effective outputs, console faults, the error record, the ERR
//! LED and RESET. A model supplies only its physics through [`Sim`].

use std::collections::BTreeMap;
use std::time::Duration;

use super::{ErrLed, ErrorKind, LabModel, LabOptions, ModelError};
use crate::core::{
    ConsoleOperation, Direction, Module, Plant, PlantError, Reading, SignalInfo, SimTime,
    StatusLine, Value, ValueKind,
};

/// One second, the period of the system flag.
pub(crate) const SECOND: Duration = Duration::from_secs(1);
/// Half a second: the ERR LED's blink phase.
const HALF: Duration = Duration::from_millis(500);
/// Due timers fired at one instant before the engine gives up (a model keeping a deadline
/// at the current instant would otherwise loop).
const MAX_FIRES_PER_INSTANT: usize = 16;

/// A signal of a model: its name and meaning.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SignalSpec {
    pub(crate) name: &'static str,
    pub(crate) description: &'static str,
}

/// Shorthand for the models' signal tables.
pub(crate) const fn spec(name: &'static str, description: &'static str) -> SignalSpec {
    SignalSpec { name, description }
}

/// The outputs as the model sees them at one instant.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cmd<'a> {
    effective: &'a [bool],
    commanded: &'a [bool],
    frozen: bool,
}

impl Cmd<'_> {
    /// The output at `index` of [`Sim::OUTPUTS`] as it acts: FALSE when broken or while
    /// the model is frozen by a non-recoverable error.
    pub(crate) fn on(&self, index: usize) -> bool {
        !self.frozen && self.effective.get(index).copied().unwrap_or(false)
    }

    /// The output at `index` as the PLC commands it.
    pub(crate) fn commanded(&self, index: usize) -> bool {
        self.commanded.get(index).copied().unwrap_or(false)
    }
}

/// The errors since power-on or the last RESET.
#[derive(Debug, Clone, Default)]
pub(crate) struct ErrorLog {
    entries: Vec<ModelError>,
}

impl ErrorLog {
    /// A recoverable error of `kind` is active from `now` (nothing if it already is).
    pub(crate) fn raise(&mut self, now: SimTime, kind: ErrorKind, detail: impl FnOnce() -> String) {
        if self.open(kind).is_none() {
            self.entries.push(ModelError {
                time: now,
                kind,
                recoverable: true,
                detail: detail(),
                cleared: None,
            });
        }
    }

    /// The cause of a recoverable error of `kind` went at `now`. One that began at the
    /// same instant is dropped: two outputs written one after the other in a scan.
    pub(crate) fn clear(&mut self, now: SimTime, kind: ErrorKind) {
        if let Some(i) = self.open(kind) {
            self.close(i, now);
        }
    }

    /// A non-recoverable error at `now`: the model freezes until RESET; open recoverable
    /// errors close.
    pub(crate) fn fail(&mut self, now: SimTime, kind: ErrorKind, detail: String) {
        while let Some(i) = self
            .entries
            .iter()
            .rposition(|e| e.recoverable && e.cleared.is_none())
        {
            self.close(i, now);
        }
        self.entries.push(ModelError {
            time: now,
            kind,
            recoverable: false,
            detail,
            cleared: None,
        });
    }

    fn close(&mut self, i: usize, now: SimTime) {
        match self.entries.get_mut(i) {
            Some(e) if e.time == now => {
                self.entries.remove(i);
            }
            Some(e) => e.cleared = Some(now),
            None => {}
        }
    }

    fn open(&self, kind: ErrorKind) -> Option<usize> {
        self.entries
            .iter()
            .position(|e| e.kind == kind && e.recoverable && e.cleared.is_none())
    }

    /// A non-recoverable error happened: the model is frozen.
    pub(crate) fn frozen(&self) -> bool {
        self.entries.iter().any(|e| !e.recoverable)
    }

    /// An open recoverable error that lights ERR.
    fn blinking(&self) -> bool {
        self.entries
            .iter()
            .any(|e| e.recoverable && e.cleared.is_none() && e.kind.lights_err())
    }

    fn active(&self) -> impl Iterator<Item = &ModelError> {
        self.entries.iter().filter(|e| e.cleared.is_none())
    }
}

/// The physics of one model. Every method gets the current instant and the outputs; the
/// engine never calls `apply`, `on_timer` or `on_second` while the model is frozen.
pub(crate) trait Sim: Send + 'static {
    /// The model's name (one of [`super::MODELS`]) and its I/O module.
    const NAME: &'static str;
    /// The outputs the PLC drives, without RESET (the engine adds it).
    const OUTPUTS: &'static [SignalSpec];
    /// The model's sensors the PLC reads.
    const SENSORS: &'static [SignalSpec];
    /// Extra push-buttons besides START (the crossroad's pedestrian button).
    const BUTTONS: &'static [SignalSpec] = &[];

    /// The initial state (power-on) with the options.
    fn new(options: &LabOptions) -> Self;
    /// Back to the initial state (RESET).
    fn reset(&mut self);
    /// The outputs may have changed at `now`: start or stop timers, raise or clear
    /// recoverable errors.
    fn apply(&mut self, now: SimTime, cmd: Cmd<'_>, log: &mut ErrorLog);
    /// The motion timer's expiry, if one runs.
    fn deadline(&self) -> Option<SimTime> {
        None
    }
    /// The motion timer expired at `now` (the engine calls this only when
    /// [`Sim::deadline`] is at or before `now`).
    fn on_timer(&mut self, _now: SimTime, _cmd: Cmd<'_>, _log: &mut ErrorLog) {}
    /// The 1-s system flag rose at `now`.
    fn on_second(&mut self, _now: SimTime, _cmd: Cmd<'_>, _log: &mut ErrorLog) {}
    /// The sensor at `index` of [`Sim::SENSORS`], before console faults.
    fn sensor(&self, index: usize) -> bool;
    /// ERR blinks for a reason that is not an error (the mixing unit's initial state).
    fn blinks(&self) -> bool {
        false
    }
    /// The model's own state values (see [`LabModel::state`]).
    fn state(&self, cmd: Cmd<'_>) -> Vec<(&'static str, Value)>;
    /// Items of the status line `model`.
    fn describe(&self, cmd: Cmd<'_>) -> Vec<String>;
}

/// A console fault on one signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Fault {
    /// A sensor reads this value whatever happens.
    Stuck(bool),
    /// A sensor's wire cut: it reads FALSE.
    WireOpen,
    /// An actuator does nothing whatever is commanded.
    Broken,
}

impl Fault {
    fn describe(&self, name: &str) -> String {
        match self {
            Fault::Stuck(true) => format!("stuck {name} on"),
            Fault::Stuck(false) => format!("stuck {name} off"),
            Fault::WireOpen => format!("wire-open {name}"),
            Fault::Broken => format!("broken {name}"),
        }
    }
}

/// Where a signal name points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sig {
    /// An output; `Sim::OUTPUTS.len()` is RESET.
    Out(usize),
    /// A model sensor.
    Sensor(usize),
    /// A push-button; `Sim::BUTTONS.len()` is START.
    Button(usize),
    /// The ERR indication.
    Err,
}

/// A lab model: the shared engine around a model's physics.
pub(crate) struct LabPlant<M: Sim> {
    sim: M,
    now: SimTime,
    /// The next rising edge of the 1-s flag not yet processed.
    next_second: SimTime,
    infos: Vec<SignalInfo>,
    modules: Vec<Module>,
    /// Per output (and RESET last): what the PLC wrote.
    commanded: Vec<bool>,
    /// The same, FALSE where the actuator is broken.
    effective: Vec<bool>,
    /// Per button (and START last): held down.
    pressed: Vec<bool>,
    /// Console faults by canonical signal name.
    faults: BTreeMap<&'static str, Fault>,
    log: ErrorLog,
    program_err: bool,
    reset_request: bool,
}

impl<M: Sim> LabPlant<M> {
    /// The model at power-on.
    pub(crate) fn new(options: &LabOptions) -> Self {
        let info = |spec: &SignalSpec, direction: Direction| SignalInfo {
            name: spec.name.to_owned(),
            direction,
            kind: ValueKind::Bool,
            module: M::NAME.to_owned(),
            unit: "",
            description: spec.description.to_owned(),
        };
        let mut infos: Vec<SignalInfo> = M::OUTPUTS
            .iter()
            .map(|s| info(s, Direction::Output))
            .collect();
        infos.push(info(&RESET, Direction::Output));
        infos.extend(M::SENSORS.iter().map(|s| info(s, Direction::Input)));
        infos.extend(M::BUTTONS.iter().map(|s| info(s, Direction::Input)));
        infos.push(info(&START, Direction::Input));
        infos.push(info(&ERR, Direction::Input));
        let outputs = M::OUTPUTS.len() + 1;
        LabPlant {
            sim: M::new(options),
            now: SimTime::ZERO,
            next_second: SECOND,
            infos,
            modules: vec![Module {
                name: M::NAME.to_owned(),
                present: true,
                linked: true,
            }],
            commanded: vec![false; outputs],
            effective: vec![false; outputs],
            pressed: vec![false; M::BUTTONS.len() + 1],
            faults: BTreeMap::new(),
            log: ErrorLog::default(),
            program_err: options.program_err(),
            reset_request: false,
        }
    }

    fn locate(&self, name: &str) -> Option<(Sig, &'static str)> {
        let find = |table: &'static [SignalSpec]| {
            table
                .iter()
                .position(|s| s.name.eq_ignore_ascii_case(name))
                .and_then(|i| table.get(i).map(|s| (i, s.name)))
        };
        if let Some((i, n)) = find(M::OUTPUTS) {
            return Some((Sig::Out(i), n));
        }
        if let Some((i, n)) = find(M::SENSORS) {
            return Some((Sig::Sensor(i), n));
        }
        if let Some((i, n)) = find(M::BUTTONS) {
            return Some((Sig::Button(i), n));
        }
        if RESET.name.eq_ignore_ascii_case(name) {
            return Some((Sig::Out(M::OUTPUTS.len()), RESET.name));
        }
        if START.name.eq_ignore_ascii_case(name) {
            return Some((Sig::Button(M::BUTTONS.len()), START.name));
        }
        if ERR.name.eq_ignore_ascii_case(name) {
            return Some((Sig::Err, ERR.name));
        }
        None
    }

    /// The LED's state.
    fn led(&self) -> ErrLed {
        if self.log.frozen() {
            ErrLed::Steady
        } else if self.log.blinking() || self.sim.blinks() {
            ErrLed::Blinking
        } else {
            ErrLed::Off
        }
    }

    /// An input as the PLC reads it: the physical value through any console fault.
    fn through_fault(&self, name: &str, value: bool) -> bool {
        match self.faults.get(name) {
            Some(Fault::Stuck(v)) => *v,
            Some(Fault::WireOpen) => false,
            Some(Fault::Broken) | None => value,
        }
    }

    fn value(&self, sig: Sig, name: &str) -> bool {
        match sig {
            Sig::Out(i) => self.commanded.get(i).copied().unwrap_or(false),
            Sig::Sensor(i) => self.through_fault(name, self.sim.sensor(i)),
            Sig::Button(i) => {
                self.through_fault(name, self.pressed.get(i).copied().unwrap_or(false))
            }
            Sig::Err => self.through_fault(name, self.led() != ErrLed::Off),
        }
    }

    /// Recomputes the effective outputs and lets the model react at `now`: the RESET
    /// request's edge, the model's timers and errors, then timers already due.
    fn settle(&mut self) {
        let reset_index = M::OUTPUTS.len();
        let all_outputs = M::OUTPUTS.iter().chain(std::iter::once(&RESET));
        for ((effective, commanded), spec) in self
            .effective
            .iter_mut()
            .zip(&self.commanded)
            .zip(all_outputs)
        {
            *effective = *commanded && self.faults.get(spec.name) != Some(&Fault::Broken);
        }
        let request = self.program_err && self.effective.get(reset_index).copied().unwrap_or(false);
        let rising = request && !self.reset_request;
        self.reset_request = request;
        if rising {
            self.sim.reset();
            self.log = ErrorLog::default();
        }
        if self.log.frozen() {
            return;
        }
        let cmd = Cmd {
            effective: &self.effective,
            commanded: &self.commanded,
            frozen: false,
        };
        self.sim.apply(self.now, cmd, &mut self.log);
        self.fire_due_timers();
    }

    /// Fires the model's timer while it is due at the current instant.
    fn fire_due_timers(&mut self) {
        for _ in 0..MAX_FIRES_PER_INSTANT {
            if self.log.frozen() {
                return;
            }
            match self.sim.deadline() {
                Some(d) if d <= self.now => {
                    let cmd = Cmd {
                        effective: &self.effective,
                        commanded: &self.commanded,
                        frozen: false,
                    };
                    self.sim.on_timer(self.now, cmd, &mut self.log);
                }
                _ => return,
            }
        }
    }

    /// Everything due at `e` (timers first, then the 1-s flag).
    fn fire(&mut self, e: SimTime) {
        self.now = e;
        self.fire_due_timers();
        if e >= self.next_second {
            self.next_second = self.next_second.saturating_add(SECOND);
            if !self.log.frozen() {
                let cmd = Cmd {
                    effective: &self.effective,
                    commanded: &self.commanded,
                    frozen: false,
                };
                self.sim.on_second(e, cmd, &mut self.log);
            }
        }
    }

    /// The next instant anything happens (with or without the model's timer).
    fn next_internal(&self, with_timer: bool) -> SimTime {
        let mut next = self.next_second;
        if with_timer && !self.log.frozen() {
            if let Some(d) = self.sim.deadline() {
                next = next.min(d.max(self.now));
            }
        }
        if self.led() == ErrLed::Blinking {
            let halves = self.now.as_millis() / 500 + 1;
            let half = u64::try_from(halves)
                .ok()
                .and_then(|h| HALF.checked_mul(u32::try_from(h).ok()?));
            if let Some(half) = half {
                next = next.min(half);
            }
        }
        next
    }

    fn do_reset(&mut self) {
        self.sim.reset();
        self.log = ErrorLog::default();
        self.settle();
    }

    fn sensor_names(&self) -> Vec<String> {
        self.infos
            .iter()
            .filter(|s| s.direction == Direction::Input)
            .map(|s| s.name.clone())
            .collect()
    }

    fn actuator_names() -> Vec<String> {
        M::OUTPUTS.iter().map(|s| s.name.to_owned()).collect()
    }

    fn button_names() -> Vec<String> {
        M::BUTTONS
            .iter()
            .chain(std::iter::once(&START))
            .map(|s| s.name.to_owned())
            .collect()
    }

    /// `name` as a signal of `kind` (sensor, actuator, button), or the error listing them.
    fn resolve(&self, kind: &'static str, name: &str) -> Result<(Sig, &'static str), PlantError> {
        let allowed = match kind {
            "sensor" => self.sensor_names(),
            "actuator" => Self::actuator_names(),
            _ => Self::button_names(),
        };
        match self.locate(name) {
            Some((sig, canonical)) if allowed.iter().any(|a| a == canonical) => {
                Ok((sig, canonical))
            }
            _ => Err(PlantError::UnknownName {
                kind,
                name: name.to_owned(),
                allowed,
            }),
        }
    }

    fn bad_line(line: &str) -> PlantError {
        PlantError::BadConsoleLine {
            line: line.to_owned(),
            expected: USAGES.join(", "),
        }
    }

    fn set_fault(&mut self, name: &'static str, fault: Option<Fault>) {
        match fault {
            Some(f) => self.faults.insert(name, f),
            None => self.faults.remove(name),
        };
        self.settle();
    }
}

const RESET: SignalSpec = spec(
    "RESET",
    "the program's reset request: a rising edge resets the model (only with program-err=true)",
);
const START: SignalSpec = spec(
    "START",
    "START push-button (console press/release START); the model ignores it",
);
const ERR: SignalSpec = spec("ERR", "ERR LED blinking or lit: the model reports an error");

/// The console's operations, as `console_operations` and errors write them.
const USAGES: &[&str] = &[
    "stuck SENSOR on|off",
    "wire-open SENSOR",
    "broken ACTUATOR",
    "clear NAME",
    "clear all",
    "reset",
    "press BUTTON",
    "release BUTTON",
];

impl<M: Sim> Plant for LabPlant<M> {
    fn now(&self) -> SimTime {
        self.now
    }

    fn next_event(&self) -> Option<SimTime> {
        Some(self.next_internal(true))
    }

    fn advance_to(&mut self, t: SimTime) -> Result<(), PlantError> {
        if t < self.now {
            return Err(PlantError::TimeWentBackwards {
                now: self.now,
                requested: t,
            });
        }
        // A model keeping its timer at the current instant is skipped after a few firings.
        let mut stalls = 0;
        loop {
            let e = self.next_internal(stalls < MAX_FIRES_PER_INSTANT);
            if e > t {
                break;
            }
            if e <= self.now {
                stalls += 1;
            } else {
                stalls = 0;
            }
            self.fire(e);
        }
        self.now = t;
        Ok(())
    }

    fn signals(&self) -> &[SignalInfo] {
        &self.infos
    }

    fn read(&self, name: &str) -> Result<Reading, PlantError> {
        let (sig, canonical) = self
            .locate(name)
            .ok_or_else(|| PlantError::UnknownSignal(name.to_owned()))?;
        Ok(Reading {
            value: Value::Bool(self.value(sig, canonical)),
            valid: true,
        })
    }

    fn set_output(&mut self, name: &str, value: Value) -> Result<(), PlantError> {
        let (sig, canonical) = self
            .locate(name)
            .ok_or_else(|| PlantError::UnknownSignal(name.to_owned()))?;
        let Sig::Out(i) = sig else {
            return Err(PlantError::NotAnOutput(canonical.to_owned()));
        };
        let Value::Bool(v) = value else {
            return Err(PlantError::WrongType {
                name: canonical.to_owned(),
                expected: ValueKind::Bool,
                got: value.kind(),
            });
        };
        match self.commanded.get_mut(i) {
            Some(c) if *c != v => *c = v,
            _ => return Ok(()),
        }
        self.settle();
        Ok(())
    }

    fn modules(&self) -> &[Module] {
        &self.modules
    }

    fn console(&mut self, line: &str) -> Result<(), PlantError> {
        let words: Vec<&str> = line.split_whitespace().collect();
        let op = words.first().map(|w| w.to_ascii_lowercase());
        match (op.as_deref(), words.get(1..).unwrap_or_default()) {
            (Some("stuck"), [name, state]) => {
                let (_, canonical) = self.resolve("sensor", name)?;
                let on = match state.to_ascii_lowercase().as_str() {
                    "on" | "true" | "1" => true,
                    "off" | "false" | "0" => false,
                    _ => return Err(Self::bad_line(line)),
                };
                self.set_fault(canonical, Some(Fault::Stuck(on)));
            }
            (Some("wire-open"), [name]) => {
                let (_, canonical) = self.resolve("sensor", name)?;
                self.set_fault(canonical, Some(Fault::WireOpen));
            }
            (Some("broken"), [name]) => {
                let (_, canonical) = self.resolve("actuator", name)?;
                self.set_fault(canonical, Some(Fault::Broken));
            }
            (Some("clear"), [name]) if name.eq_ignore_ascii_case("all") => {
                self.faults.clear();
                self.settle();
            }
            (Some("clear"), [name]) => {
                let faulted = self
                    .faults
                    .keys()
                    .copied()
                    .find(|n| n.eq_ignore_ascii_case(name));
                let Some(canonical) = faulted else {
                    return Err(PlantError::UnknownName {
                        kind: "faulted signal",
                        name: (*name).to_owned(),
                        allowed: self.faults.keys().map(|n| (*n).to_owned()).collect(),
                    });
                };
                self.set_fault(canonical, None);
            }
            (Some("reset"), []) => self.do_reset(),
            (Some(op @ ("press" | "release")), [name]) => {
                let (sig, _) = self.resolve("button", name)?;
                if let Sig::Button(i) = sig {
                    if let Some(held) = self.pressed.get_mut(i) {
                        *held = op == "press";
                    }
                }
            }
            _ => return Err(Self::bad_line(line)),
        }
        Ok(())
    }

    fn console_operations(&self) -> Vec<ConsoleOperation> {
        let op = |usage: &'static str, fault: bool, kind: Option<&str>, names: Vec<String>| {
            ConsoleOperation {
                usage,
                fault,
                names_kind: kind.map(str::to_owned),
                names,
            }
        };
        let faulted: Vec<String> = self.faults.keys().map(|n| (*n).to_owned()).collect();
        vec![
            op(
                "stuck SENSOR on|off",
                true,
                Some("sensor"),
                self.sensor_names(),
            ),
            op(
                "wire-open SENSOR",
                true,
                Some("sensor"),
                self.sensor_names(),
            ),
            op(
                "broken ACTUATOR",
                true,
                Some("actuator"),
                Self::actuator_names(),
            ),
            op("clear NAME", false, Some("faulted signal"), faulted),
            op("clear all", false, None, Vec::new()),
            op("reset", false, None, Vec::new()),
            op("press BUTTON", false, Some("button"), Self::button_names()),
            op(
                "release BUTTON",
                false,
                Some("button"),
                Self::button_names(),
            ),
        ]
    }

    fn status(&self) -> Vec<StatusLine> {
        let cmd = Cmd {
            effective: &self.effective,
            commanded: &self.commanded,
            frozen: self.log.frozen(),
        };
        let or_none = |items: Vec<String>| {
            if items.is_empty() {
                vec!["none".to_owned()]
            } else {
                items
            }
        };
        let led = match self.led() {
            ErrLed::Off => "off",
            ErrLed::Blinking => "blinking",
            ErrLed::Steady => "steady",
        };
        let pressed: Vec<String> = Self::button_names()
            .into_iter()
            .zip(&self.pressed)
            .filter(|(_, p)| **p)
            .map(|(n, _)| format!("{n} pressed"))
            .collect();
        vec![
            StatusLine {
                label: M::NAME,
                items: self.sim.describe(cmd),
            },
            StatusLine {
                label: "ERR",
                items: vec![led.to_owned()],
            },
            StatusLine {
                label: "errors",
                items: or_none(self.log.active().map(ToString::to_string).collect()),
            },
            StatusLine {
                label: "faults",
                items: or_none(
                    self.faults
                        .iter()
                        .map(|(name, f)| f.describe(name))
                        .collect(),
                ),
            },
            StatusLine {
                label: "buttons",
                items: or_none(pressed),
            },
        ]
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

impl<M: Sim> LabModel for LabPlant<M> {
    fn model(&self) -> &'static str {
        M::NAME
    }

    fn err_led(&self) -> ErrLed {
        self.led()
    }

    fn err_lit(&self) -> bool {
        match self.led() {
            ErrLed::Off => false,
            ErrLed::Steady => true,
            ErrLed::Blinking => self.now.subsec_nanos() < 500_000_000,
        }
    }

    fn errors(&self) -> &[ModelError] {
        &self.log.entries
    }

    fn reset(&mut self) {
        self.do_reset();
    }

    fn state(&self) -> Vec<(&'static str, Value)> {
        let cmd = Cmd {
            effective: &self.effective,
            commanded: &self.commanded,
            frozen: self.log.frozen(),
        };
        let mut state = self.sim.state(cmd);
        state.push(("err", Value::Bool(self.led() != ErrLed::Off)));
        state.push(("err_lit", Value::Bool(self.err_lit())));
        state
    }
}
