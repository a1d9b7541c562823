//! The plant-independent core: values, signal descriptions, errors and the [`Plant`] trait.

use std::collections::BTreeMap;
use std::fmt;
use std::time::Duration;

/// Simulated time: the duration since the start of the simulation.
pub type SimTime = Duration;

/// A signal value as a PLC sees it on a terminal or in a measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// A digital signal (contact, coil).
    Bool(bool),
    /// An analog measurement or set point (volts, kWh, lux...).
    Real(f64),
}

impl Value {
    /// The kind of this value.
    pub fn kind(&self) -> ValueKind {
        match self {
            Value::Bool(_) => ValueKind::Bool,
            Value::Real(_) => ValueKind::Real,
        }
    }

    /// The boolean, if this is a digital value.
    pub fn as_bool(&self) -> Option<bool> {
        match self {
            Value::Bool(b) => Some(*b),
            Value::Real(_) => None,
        }
    }

    /// The number, if this is an analog value.
    pub fn as_real(&self) -> Option<f64> {
        match self {
            Value::Real(r) => Some(*r),
            Value::Bool(_) => None,
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Bool(true) => f.write_str("TRUE"),
            Value::Bool(false) => f.write_str("FALSE"),
            Value::Real(r) => write!(f, "{r}"),
        }
    }
}

/// The type of a signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ValueKind {
    /// Digital.
    Bool,
    /// Analog (IEEE 754 double).
    Real,
}

impl fmt::Display for ValueKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ValueKind::Bool => "BOOL",
            ValueKind::Real => "REAL",
        })
    }
}

/// Direction of a signal, seen from the PLC (as on a wiring diagram).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// The plant drives it, the PLC reads it (DI, AI): contacts, relays, measurements.
    Input,
    /// The PLC drives it, the plant obeys (DO, AO): coils, start commands.
    Output,
}

/// Static description of one signal of the I/O surface.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalInfo {
    /// Stable name (the spec's tag where it gives one).
    pub name: String,
    /// Seen from the PLC.
    pub direction: Direction,
    /// Type.
    pub kind: ValueKind,
    /// The I/O module the signal is wired to; a pulled module makes it unavailable.
    pub module: String,
    /// Unit of an analog value (`V`, `kWh`, `lx`...), empty for digital signals.
    pub unit: &'static str,
    /// One-line meaning.
    pub description: String,
}

/// A value together with its availability, for the runtime's quality handling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// The physical value (the last one seen if the module is unavailable).
    pub value: Value,
    /// `false` when the signal's I/O module is unavailable (pulled): the runtime reports
    /// the point with the IV (invalid) flag.
    pub valid: bool,
}

/// Errors of the plant API.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlantError {
    /// No signal has this name.
    #[error("unknown signal `{0}`")]
    UnknownSignal(String),
    /// The signal exists but is of another type.
    #[error("signal `{name}` is {expected}, got {got}")]
    WrongType {
        /// Signal name.
        name: String,
        /// Its type.
        expected: ValueKind,
        /// The type that was supplied.
        got: ValueKind,
    },
    /// `set_output` on a plant input (a contact the plant drives).
    #[error("signal `{0}` is a plant input (read it), not an output the PLC drives")]
    NotAnOutput(String),
    /// The module of the signal is unavailable (pulled), so no valid value exists.
    #[error("signal `{signal}` unavailable: module `{module}` is not present")]
    ModuleUnavailable {
        /// Signal name.
        signal: String,
        /// Module name.
        module: String,
    },
    /// A fault or action names a device this plant does not have, or one of the wrong kind.
    #[error("no {kind} named `{name}`")]
    UnknownDevice {
        /// What was looked for (breaker, fuse, board...).
        kind: &'static str,
        /// The name given.
        name: String,
    },
    /// A short device name that fits several devices of the kind wanted.
    #[error("`{name}` could be the {kind} {}: type one of these names", candidates.join(", "))]
    AmbiguousDevice {
        /// What was looked for (breaker, fuse, board...).
        kind: &'static str,
        /// The name given.
        name: String,
        /// Every device it fits, sorted.
        candidates: Vec<String>,
    },
    /// `advance_to` with a time before the current time.
    #[error("time {requested:?} is before the plant's time {now:?}")]
    TimeWentBackwards {
        /// The plant's current time.
        now: SimTime,
        /// The requested time.
        requested: SimTime,
    },
    /// A hand operation refused by the hardware (e.g. door pushbuttons with the selector in remote).
    #[error("operation refused: {0}")]
    Refused(String),
    /// Text that does not parse as a fault.
    #[error("cannot parse fault `{0}`")]
    BadFault(String),
    /// A console line names something this plant does not have (lab models): the error
    /// lists what it takes.
    #[error("no {kind} `{name}`; {}", names_allowed(kind, allowed))]
    UnknownName {
        /// What was looked for (sensor, actuator, button).
        kind: &'static str,
        /// The name given.
        name: String,
        /// Every name allowed there.
        allowed: Vec<String>,
    },
    /// A console line that is no operation of the plant's console language.
    #[error("cannot read `{line}`; the operations are {expected}")]
    BadConsoleLine {
        /// The line.
        line: String,
        /// The operations, as usage text.
        expected: String,
    },
}

/// "the sensor names are K1, K2" or "there is no sensor", for [`PlantError::UnknownName`].
fn names_allowed(kind: &str, allowed: &[String]) -> String {
    if allowed.is_empty() {
        format!("there is no {kind}")
    } else {
        format!("the {kind} names are {}", allowed.join(", "))
    }
}

/// The serial line of one of a plant's field devices (the sorting lab's balance on its
/// RS-232): the device's octets come out of the plant on its simulated clock, and the
/// runtime puts them on a pseudo-terminal, so the project's driver reads the device as it
/// would read the one on the model, through a serial port.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SerialPortInfo {
    /// The port's name, as a project names it (`plant = "balance"`).
    pub name: String,
    /// What is on it.
    pub description: String,
    /// The line's speed and character format, as the device is set.
    pub line: serial_line::LineSettings,
}

/// The shape every plant simulation has: a named I/O surface and a clock-free step.
///
/// Time advances only through [`Plant::advance_to`]; every internal event (operate
/// times, delays) is hit exactly, whatever the step size. A scheduler may jump straight to
/// [`Plant::next_event`].
pub trait Plant {
    /// Current simulated time.
    fn now(&self) -> SimTime;
    /// The earliest pending internal event, if any.
    fn next_event(&self) -> Option<SimTime>;
    /// Advances to `t`, processing every internal event on the way at its exact time.
    fn advance_to(&mut self, t: SimTime) -> Result<(), PlantError>;
    /// Advances by `dt`.
    fn advance(&mut self, dt: Duration) -> Result<(), PlantError> {
        let t = self.now().saturating_add(dt);
        self.advance_to(t)
    }
    /// Every signal, in a stable order.
    fn signals(&self) -> &[SignalInfo];
    /// Reads a signal (input or output) with its availability.
    fn read(&self, name: &str) -> Result<Reading, PlantError>;
    /// Reads a plant input; fails if its module is unavailable.
    fn input(&self, name: &str) -> Result<Value, PlantError> {
        let r = self.read(name)?;
        if r.valid {
            return Ok(r.value);
        }
        let module = self
            .signals()
            .iter()
            .find(|s| s.name == name)
            .map(|s| s.module.clone())
            .unwrap_or_default();
        Err(PlantError::ModuleUnavailable {
            signal: name.to_string(),
            module,
        })
    }
    /// Drives a PLC output (coil, command). Takes effect at the current time.
    fn set_output(&mut self, name: &str, value: Value) -> Result<(), PlantError>;
    /// The plant's I/O modules and their state (a pulled or silent module makes its
    /// signals invalid).
    fn modules(&self) -> &[Module];
    /// Carries out one line of the plant's console language: a fault (stays until
    /// cleared), `clear FAULT`, `clear all`, or a hand operation. The plant owns its
    /// language: the runtime and the CLI only pass the line on.
    fn console(&mut self, line: &str) -> Result<(), PlantError>;
    /// The console language: every fault and hand operation with the names it takes now.
    fn console_operations(&self) -> Vec<ConsoleOperation>;
    /// The state worth a glance, for the console's `status`.
    fn status(&self) -> Vec<StatusLine>;
    /// The serial lines of the plant's field devices ([`SerialPortInfo`]); none by default.
    fn serial_ports(&self) -> Vec<SerialPortInfo> {
        Vec::new()
    }
    /// The octets the device on `port` sent since the last call, in order. A plant keeps
    /// only its device's newest few messages for a reader that fell behind (a line has no
    /// flow control either); an unknown port has none.
    fn take_serial_output(&mut self, _port: &str) -> Vec<u8> {
        Vec::new()
    }
    /// Octets sent to the device on `port` (from its driver, at the current time).
    fn serial_input(&mut self, port: &str, _octets: &[u8]) -> Result<(), PlantError> {
        Err(PlantError::UnknownName {
            kind: "serial port",
            name: port.to_owned(),
            allowed: self.serial_ports().into_iter().map(|p| p.name).collect(),
        })
    }
    /// The plant as `Any`, for tests and tools that know which plant they run.
    fn as_any(&self) -> &dyn std::any::Any;
    /// The plant as `Any`, mutable.
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any;
    /// All inputs with their availability.
    fn inputs(&self) -> BTreeMap<String, Reading> {
        self.signals()
            .iter()
            .filter(|s| s.direction == Direction::Input)
            .filter_map(|s| self.read(&s.name).ok().map(|r| (s.name.clone(), r)))
            .collect()
    }
    /// All outputs with the value the PLC last wrote.
    fn outputs(&self) -> BTreeMap<String, Value> {
        self.signals()
            .iter()
            .filter(|s| s.direction == Direction::Output)
            .filter_map(|s| self.read(&s.name).ok().map(|r| (s.name.clone(), r.value)))
            .collect()
    }
    /// Reads a digital signal (convenience for tests and drivers).
    fn bool(&self, name: &str) -> Result<bool, PlantError> {
        let v = self.read(name)?.value;
        v.as_bool().ok_or(PlantError::WrongType {
            name: name.to_string(),
            expected: ValueKind::Real,
            got: ValueKind::Bool,
        })
    }
    /// Reads an analog signal (convenience for tests and drivers).
    fn real(&self, name: &str) -> Result<f64, PlantError> {
        let v = self.read(name)?.value;
        v.as_real().ok_or(PlantError::WrongType {
            name: name.to_string(),
            expected: ValueKind::Bool,
            got: ValueKind::Real,
        })
    }
}

/// One operation of a plant's console language.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConsoleOperation {
    /// How it is written (`supply-loss SOURCE`).
    pub usage: &'static str,
    /// A fault (stays until cleared) rather than a hand operation.
    pub fault: bool,
    /// What the placeholder of `usage` names (`breaker`, `I/O module`), if anything.
    pub names_kind: Option<String>,
    /// The names it takes now.
    pub names: Vec<String>,
}

/// One line of a plant's status: a label and its items (`breakers`: `RH2_QF1 closed`...).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StatusLine {
    /// What the line is about.
    pub label: &'static str,
    /// Its items.
    pub items: Vec<String>,
}

/// Renders signal descriptions as a Markdown table (`name | dir | type | unit | module |
/// meaning`), e.g. for `stanice` to list a plant's I/O.
pub fn signal_table_markdown(signals: &[SignalInfo]) -> String {
    let mut out = String::from(
        "| Signal | Dir | Type | Unit | Module | Meaning |\n|---|---|---|---|---|---|\n",
    );
    for s in signals {
        let dir = match s.direction {
            Direction::Input => "in",
            Direction::Output => "out",
        };
        out.push_str(&format!(
            "| `{}` | {} | {} | {} | {} | {} |\n",
            s.name, dir, s.kind, s.unit, s.module, s.description
        ));
    }
    out
}

/// An I/O module (a LOGO!, a PLC's I/O, a DI card) and its status.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Module {
    /// Module name (`RH2_LOGO`, `ROV05_PLC`, `RDRT_P9`...).
    pub name: String,
    /// Plugged in and working. A pulled module's outputs de-energise.
    pub present: bool,
    /// Its communication works. Without it the field keeps running on the last
    /// outputs, but no valid value reaches the PLC.
    pub linked: bool,
}

impl Module {
    /// Its signals carry valid values.
    pub fn valid(&self) -> bool {
        self.present && self.linked
    }
}
