//! The simulation thread: the plant and every node's soft PLC on one simulated clock.
//!
//! The soft PLC is single-threaded by design (its compiled code shares `Rc`s), so the
//! PLCs live on one dedicated thread together with the plant they are wired to; the
//! network side talks to it through [`SimRequest`]s. One *step* at simulated time `t`:
//!
//! 1. the plant advances to `t` (its own deadlines are hit exactly on the way);
//! 2. command pulses that end at `t` reset their variables;
//! 3. every node whose PLC has a task due copies its bound plant inputs into PLC
//!    variables (an input of a pulled or unreachable I/O module keeps its last value and
//!    is remembered as invalid), runs the cycle, and drives the bound plant outputs (a
//!    task that stops leaves its outputs at their safe values; the stop is an event of
//!    the pseudo-point `plc-task:NAME`);
//! 4. the node's PLC-sourced points are read and handed to its point database: value
//!    changes and validity changes are reported (IV while the bound input's module is
//!    unavailable or the PLC task has stopped on a fault);
//! 5. cyclic points due at `t` are sent.
//!
//! The next step is at the earliest of: a PLC task due, a plant event, a pulse end, a
//! cyclic transmission. [`Pacing::RealTime`] maps steps onto the wall clock times a
//! speed factor; [`Pacing::Manual`] moves only on request, as fast as the CPU allows.

use super::operation::OperationError;
use std::collections::HashMap;
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use plant::registry::{PlantStart, PLANTS};
use plant::{Direction, Plant, Value, ValueKind};
use plc::check::{Lane, Ty};
use plc::task::{ClockReading, Leaf, TaskConfig as PlcTask};
use plc::vm::Val;
use plc::Plc;
use tokio::sync::oneshot;

use crate::config::{CommandTarget, IoSource, NodeConfig, PointSource, Project};
use points::{EventCause, PointDb, PointId, PointKind, PointValue, Quality};

use crate::device::{ImageValue, IoImage};

use super::s7_server::{S7Prepared, S7Served};

use super::clock::{Pacing, SimClock};
use super::node::NodePoints;
use super::RuntimeError;

/// Steps run between two looks at the request channel when running behind the wall clock.
const STEPS_PER_POLL: usize = 2_000;

/// A request to the simulation thread.
pub(crate) enum SimRequest {
    /// Leave the initial hold and follow the pacing.
    Go,
    /// Manual pacing: advance by this much; replies with the new simulated time.
    Advance {
        by: Duration,
        reply: oneshot::Sender<Duration>,
    },
    /// A command on a PLC variable of node `node`, with the value the command carries.
    Command {
        node: usize,
        ioa: u32,
        value: PointValue,
        pulse: Option<Duration>,
        select: bool,
        reply: oneshot::Sender<Result<(), CommandRefusal>>,
    },
    /// Runs a closure on the simulation (tests, fault injection, monitoring).
    With(Box<dyn FnOnce(&mut Simulation) + Send>),
    /// Ends the thread.
    Stop,
}

/// Why the simulation refused a command.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CommandRefusal {
    /// The board's Local/Remote selector is in local.
    #[error("the board is in local mode")]
    LocalMode,
    /// The node has no PLC command at that address.
    #[error("no command at this address")]
    Unknown,
    /// The PLC task has stopped on a fault.
    #[error("the PLC is stopped: {0}")]
    PlcStopped(String),
    /// The value does not suit the target variable.
    #[error("bad value: {0}")]
    BadValue(String),
}

/// Where a bound signal goes in the PLC: a variable, or the process image at a direct
/// address (`%IX0.4`, `%ID4`, `%QX1.2`), as a program written with `AT` addresses for a
/// real PLC's I/O expects (the image is copied to its `AT` variables at the cycle's start).
#[derive(Clone)]
enum IoTarget {
    Variable(Leaf),
    Image(String),
}

impl IoTarget {
    fn path(&self) -> &str {
        match self {
            IoTarget::Variable(leaf) => &leaf.path,
            IoTarget::Image(address) => address,
        }
    }

    fn write(&self, plc: &mut Plc, value: Value) {
        match self {
            IoTarget::Variable(leaf) => plc.write_leaf(leaf, to_val(&leaf.ty, value)),
            IoTarget::Image(address) => {
                let x = match value {
                    Value::Bool(b) => i64::from(b),
                    Value::Real(x) => x.round() as i64,
                };
                let _ = plc.set_io(address, x);
            }
        }
    }

    /// Writes a PLC value (a command's): a variable as it is, an image address as a
    /// whole number (taking effect at the start of the next cycle).
    fn write_val(&self, plc: &mut Plc, value: Val) {
        match self {
            IoTarget::Variable(leaf) => plc.write_leaf(leaf, value),
            IoTarget::Image(address) => {
                let x = match value {
                    Val::Int(x) => x,
                    Val::Real(x) => x.round() as i64,
                    Val::Str(_) => return,
                };
                let _ = plc.set_io(address, x);
            }
        }
    }

    /// The lane a value for it takes.
    fn lane(&self) -> Option<Lane> {
        match self {
            IoTarget::Variable(leaf) => leaf.ty.lane(),
            IoTarget::Image(address) => image_type(address).lane(),
        }
    }

    fn read(&self, plc: &Plc) -> Option<Val> {
        match self {
            IoTarget::Variable(leaf) => plc.read_leaf(leaf).ok(),
            IoTarget::Image(address) => plc.get_io(address).ok().map(Val::Int),
        }
    }
}

/// Where a PLC input comes from.
enum InputFrom {
    /// A plant input.
    Signal(String),
    /// `module-fault:MODULE`: TRUE while the plant's I/O module is unavailable.
    ModuleFault(String),
    /// A point of the node (a field device's reading).
    Point(PointId),
    /// An input item of a field device (`[[node.io]] device = ...`).
    Device { image: Arc<IoImage>, item: String },
}

struct InputBinding {
    from: InputFrom,
    target: IoTarget,
    /// Numbers are multiplied by it (`scale` of the binding).
    scale: f64,
    valid: bool,
}

impl InputBinding {
    /// Copies the input into the PLC; a value that is not valid now leaves the PLC's last
    /// one and marks the input invalid.
    fn copy(
        &mut self,
        plc: &mut Plc,
        plant: Option<&(dyn Plant + Send + 'static)>,
        db: Option<&PointDb>,
    ) {
        let reading = match &self.from {
            InputFrom::ModuleFault(module) => plant.map(|plant| {
                let fault = !plant
                    .modules()
                    .iter()
                    .any(|m| &m.name == module && m.valid());
                (Value::Bool(fault), true)
            }),
            InputFrom::Signal(signal) => plant
                .and_then(|plant| plant.read(signal).ok())
                .map(|reading| (reading.value, reading.valid)),
            InputFrom::Point(id) => db.and_then(|db| db.get(*id)).and_then(|point| {
                let valid = point.has_value() && !point.quality.invalid;
                let value = match &point.value {
                    PointValue::Bool(on) => Value::Bool(*on),
                    PointValue::Float(x) => Value::Real(*x),
                    PointValue::Int(n) => Value::Real(*n as f64),
                    PointValue::DoublePoint(d) => Value::Real(f64::from(*d)),
                    PointValue::Bits(bits) => Value::Real(f64::from(*bits)),
                    PointValue::Text(_) => return None,
                };
                Some((value, valid))
            }),
            InputFrom::Device { image, item } => Some(match image.input(item) {
                Some(ImageValue::Bool(on)) => (Value::Bool(on), true),
                Some(ImageValue::Number(x)) => (Value::Real(x), true),
                None => (Value::Bool(false), false),
            }),
        };
        match reading {
            Some((value, true)) => {
                self.valid = true;
                let value = match value {
                    Value::Real(x) => Value::Real(x * self.scale),
                    bool @ Value::Bool(_) => bool,
                };
                self.target.write(plc, value);
            }
            Some((_, false)) | None => self.valid = false,
        }
    }
}

/// Where a PLC output goes.
enum OutputTo {
    /// A plant output (coil, command).
    Signal(String),
    /// An output item of a field device (`[[node.io]] device = ...`).
    Device {
        image: Arc<IoImage>,
        /// `DEVICE.ITEM`, for observers and the log.
        name: String,
        item: String,
    },
}

impl OutputTo {
    fn name(&self) -> &str {
        match self {
            OutputTo::Signal(signal) => signal,
            OutputTo::Device { name, .. } => name,
        }
    }
}

struct OutputBinding {
    to: OutputTo,
    target: IoTarget,
    kind: ValueKind,
    last: Option<Value>,
}

struct SourcedPoint {
    id: PointId,
    kind: PointKind,
    /// A variable, or a direct address of the process image (`%IX0.0`): a point that
    /// shows an input whatever program runs.
    source: IoTarget,
    /// The source's type.
    ty: Ty,
    /// The input binding feeding this variable, whose module validity is the point's.
    input: Option<usize>,
    /// A BOOL variable that makes the point invalid while TRUE.
    invalid_when: Option<Leaf>,
    last: Option<(PointValue, bool)>,
}

struct SimCommand {
    /// A variable, or a direct address of the image (a marker an S7 client reads).
    target: IoTarget,
    remote_enable: Option<Leaf>,
}

struct SimNode {
    points: Arc<NodePoints>,
    plc: Option<Plc>,
    /// The node's stopped tasks (a fault, the watchdog, `plc-stop`) and why: the points
    /// their programs feed are invalid and commands to them refused, while the other
    /// tasks run on (per-task isolation).
    stopped: HashMap<String, String>,
    /// Which task runs each program (by upper-case name), and every task.
    task_of_program: HashMap<String, String>,
    tasks: Vec<String>,
    /// The station is shutting down: a stop is recorded and drives the outputs, but the
    /// points are not published invalid (the servers close; an IV event per point at
    /// every shutdown would bury the history).
    shutting_down: bool,
    inputs: Vec<InputBinding>,
    outputs: Vec<OutputBinding>,
    sourced: Vec<SourcedPoint>,
    commands: HashMap<u32, SimCommand>,
    /// The PLC's memory served over S7 (`[node.s7_server]`).
    s7: Option<S7Served>,
}

struct Pulse {
    at: Duration,
    node: usize,
    target: IoTarget,
}

/// A plant output driven to a new value by a node's PLC, for observers
/// ([`Simulation::observe_outputs`]).
#[derive(Debug, Clone, PartialEq)]
pub struct OutputChange {
    /// The node whose PLC drove it.
    pub node: String,
    /// The plant signal.
    pub signal: String,
    /// The new value.
    pub value: Value,
    /// Simulated time of the change.
    pub time: Duration,
    /// Wall-clock instant it was driven (latency measurements).
    pub at: Instant,
}

/// The plant and the nodes' PLCs; owned by the simulation thread.
pub struct Simulation {
    clock: Arc<SimClock>,
    now: Duration,
    stepped: bool,
    plant: Option<Box<dyn Plant + Send>>,
    nodes: Vec<SimNode>,
    pulses: Vec<Pulse>,
    observers: Vec<mpsc::Sender<OutputChange>>,
    /// The plant's serial ports on pseudo-terminals (`plant_port`): where each one's
    /// octets go.
    serial_ports: Vec<(String, tokio::sync::mpsc::Sender<Vec<u8>>)>,
    /// The I/O images of the field devices the PLCs are bound to.
    images: DeviceImages,
}

/// The I/O image of each field device with items bound to a PLC, by (node, device).
pub(crate) type DeviceImages = HashMap<(String, String), Arc<IoImage>>;

impl Simulation {
    /// Builds the PLCs of `nodes` (index into `project.nodes`, with their shared points)
    /// and the project's plant.
    pub(crate) fn build(
        project: &Project,
        nodes: &[(usize, Arc<NodePoints>)],
        clock: Arc<SimClock>,
        images: DeviceImages,
        mut served: Vec<S7Prepared>,
    ) -> Result<Simulation, RuntimeError> {
        let start = PlantStart {
            unix_secs: clock.start().timestamp(),
        };
        let plant = match project.station.plant.as_deref() {
            None => None,
            Some(name) => Some(plant::registry::open(name, start).ok_or_else(|| {
                RuntimeError::Setup(format!(
                    "unknown plant `{name}` (known: {})",
                    PLANTS.join(", ")
                ))
            })?),
        };
        let mut built = Vec::new();
        for (index, points) in nodes {
            let Some(config) = project.nodes.get(*index) else {
                continue;
            };
            let mut node = build_node(config, Arc::clone(points), plant.as_deref(), &images)?;
            if let Some(index) = served.iter().position(|s| s.node == config.name) {
                let prepared = served.swap_remove(index);
                let plc = node.plc.as_ref().ok_or_else(|| {
                    RuntimeError::Setup(format!(
                        "node `{}`: an S7 server needs the node's PLC",
                        config.name
                    ))
                })?;
                node.s7 = Some(
                    S7Served::new(&prepared.config, prepared.memory, prepared.receiver, plc)
                        .map_err(|error| {
                            RuntimeError::Setup(format!("node `{}`: {error}", config.name))
                        })?,
                );
            }
            built.push(node);
        }
        Ok(Simulation {
            clock,
            now: Duration::ZERO,
            stepped: false,
            plant,
            nodes: built,
            pulses: Vec::new(),
            observers: Vec::new(),
            serial_ports: Vec::new(),
            images,
        })
    }

    /// Current simulated time.
    pub fn now(&self) -> Duration {
        self.now
    }

    /// The plant, if the project has one (`as_any_mut` reaches the plant's own type).
    pub fn plant(&mut self) -> Option<&mut (dyn Plant + Send + 'static)> {
        self.plant.as_deref_mut()
    }

    /// The PLC of a node, if it has one (monitoring, writing and forcing variables).
    pub fn plc(&mut self, node: &str) -> Option<&mut Plc> {
        self.nodes
            .iter_mut()
            .find(|n| n.points.name() == node)
            .and_then(|n| n.plc.as_mut())
    }

    /// A BOOL (or integer: non-zero) variable of the node with this simulation index.
    pub(crate) fn read_bool(&self, node: usize, path: &str) -> Option<bool> {
        let plc = self.nodes.get(node)?.plc.as_ref()?;
        match plc.read(path).ok()? {
            Val::Int(x) => Some(x != 0),
            _ => None,
        }
    }

    /// Reports every plant output a PLC drives to a new value from now on.
    pub fn observe_outputs(&mut self) -> mpsc::Receiver<OutputChange> {
        let (sender, receiver) = mpsc::channel();
        self.observers.push(sender);
        receiver
    }

    /// Stops (`run = false`) or starts a node's soft PLC (`plc-stop NODE`, `plc-start
    /// NODE`): stopped, every output it drives goes to its safe value (declared with
    /// `{attribute 'safe_value' := ...}`, else FALSE / 0), the points it feeds turn
    /// invalid, commands to it are refused and the stop is recorded as `plc-task:NAME`
    /// events; started, its tasks run again from their next cycle.
    pub fn run_plc(&mut self, node: &str, run: bool) -> Result<(), OperationError> {
        let now = self.now;
        let Simulation {
            plant,
            nodes,
            observers,
            ..
        } = self;
        let names: Vec<String> = nodes.iter().map(|n| n.points.name().to_owned()).collect();
        let found = nodes
            .iter_mut()
            .find(|candidate| candidate.points.name().eq_ignore_ascii_case(node))
            .ok_or_else(|| OperationError::NoNode {
                node: node.to_owned(),
                suggestion: plc::suggest::did_you_mean(node, names.iter().map(String::as_str)),
            })?;
        found.run_plc(run, now, plant.as_deref_mut(), observers)
    }

    /// Stops every PLC (the station is shutting down): outputs to their safe values, the
    /// stops recorded.
    pub(crate) fn stop_all(&mut self) {
        for node in &mut self.nodes {
            node.shutting_down = true;
        }
        let names: Vec<String> = self
            .nodes
            .iter()
            .filter(|node| node.plc.is_some())
            .map(|node| node.points.name().to_owned())
            .collect();
        for name in names {
            let _ = self.run_plc(&name, false);
        }
    }

    /// Sends what the plant's device on `port` sends from now on to `line` (a full
    /// `line` drops it, as a line without flow control would).
    pub(crate) fn attach_serial_port(
        &mut self,
        port: String,
        line: tokio::sync::mpsc::Sender<Vec<u8>>,
    ) {
        if let Some(plant) = self.plant.as_mut() {
            // what it sent before anyone listened is gone, as on an unplugged line
            plant.take_serial_output(&port);
        }
        self.serial_ports.push((port, line));
    }

    /// Octets a driver sent to the plant's device on `port`.
    pub(crate) fn serial_input(&mut self, port: &str, octets: &[u8]) {
        if let Some(plant) = self.plant.as_mut() {
            if let Err(error) = plant.serial_input(port, octets) {
                tracing::warn!(port, %error, "octets to the plant's serial port dropped");
            }
        }
    }

    /// Loads a new program into the running node `config.name` (`runtime::program`):
    /// the new PLC is compiled and bound as `config` says first, so a program that does
    /// not compile or bind leaves the old one running; then the old one stops (its
    /// outputs to their safe values, the stop recorded), the new one cold-starts at the
    /// next step, and `plc-program` records what was loaded and by whom.
    pub(crate) fn load_program(
        &mut self,
        config: &NodeConfig,
        files: Vec<(String, String)>,
        description: String,
    ) -> Result<(), RuntimeError> {
        let now = self.now;
        let index = self
            .nodes
            .iter()
            .position(|node| node.points.name() == config.name)
            .ok_or_else(|| RuntimeError::Setup(format!("no running node `{}`", config.name)))?;
        let points = self
            .nodes
            .get(index)
            .map(|node| Arc::clone(&node.points))
            .ok_or_else(|| RuntimeError::Setup(format!("no running node `{}`", config.name)))?;
        let files = if files.is_empty() {
            project_sources(config)?
        } else {
            files
        };
        let fresh = build_node_from(
            config,
            files,
            Arc::clone(&points),
            self.plant.as_deref(),
            &self.images,
        )?;
        let Simulation {
            plant,
            nodes,
            observers,
            pulses,
            ..
        } = self;
        let Some(old) = nodes.get_mut(index) else {
            return Err(RuntimeError::Setup(format!(
                "no running node `{}`",
                config.name
            )));
        };
        let mut fresh = fresh;
        if let (Some(served), Some(server), Some(plc)) =
            (old.s7.as_mut(), &config.s7_server, fresh.plc.as_ref())
        {
            // the new program must have the connections' status variables
            served
                .rebind(server, plc)
                .map_err(|error| RuntimeError::Setup(format!("node `{}`: {error}", config.name)))?;
        }
        fresh.s7 = old.s7.take();
        if old.plc.is_some() {
            old.run_plc(false, now, plant.as_deref_mut(), observers)
                .map_err(|error| RuntimeError::Setup(error.to_string()))?;
        }
        // A pulse's variable is the old program's.
        pulses.retain(|pulse| pulse.node != index);
        *old = fresh;
        let utc = points.clock().at(now);
        let mut record = crate::store::EventRecord::new(
            points.name(),
            "plc-program".to_owned(),
            PointValue::Text(description),
            utc,
        );
        record.cause = EventCause::Local;
        points.recorder().event(record);
        tracing::info!(node = %config.name, "program loaded");
        Ok(())
    }

    /// Passes one line of the plant's console language (faults, `clear ...`, hand
    /// operations: [`Plant::console`]) to the plant.
    pub fn operate(&mut self, text: &str) -> Result<(), OperationError> {
        let Some(plant) = self.plant.as_mut() else {
            return Err(OperationError::NoPlant);
        };
        plant
            .console(text)
            .map_err(|error| OperationError::Refused(error.to_string()))
    }

    /// The earliest time something is due after `self.now` (or at it, before the first
    /// step).
    fn next_due(&self) -> Duration {
        if !self.stepped {
            return self.now;
        }
        let mut next = Duration::MAX;
        if let Some(plant) = &self.plant {
            if let Some(t) = plant.next_event() {
                next = next.min(t);
            }
        }
        for node in &self.nodes {
            if let Some(due) = node.plc.as_ref().and_then(Plc::next_due) {
                next = next.min(Duration::from_nanos(due.max(0).unsigned_abs()));
            }
            let utc = node.points.clock().at(self.now);
            if let Some(due) = node.points.lock().next_cyclic_due(utc) {
                let ahead = (due - utc).to_std().unwrap_or(Duration::ZERO);
                next = next.min(self.now + ahead);
            }
        }
        for pulse in &self.pulses {
            next = next.min(pulse.at);
        }
        next.max(self.now + Duration::from_nanos(1))
    }

    /// Runs every step up to and including `target`, at most `max_steps` of them; returns
    /// whether `target` was reached.
    fn advance_to(&mut self, target: Duration, max_steps: usize) -> bool {
        for _ in 0..max_steps {
            let next = self.next_due();
            if next > target {
                self.set_now(target);
                return true;
            }
            self.step(next);
        }
        false
    }

    fn set_now(&mut self, t: Duration) {
        if t > self.now {
            if let Some(plant) = self.plant.as_mut() {
                if let Err(error) = plant.advance_to(t) {
                    tracing::error!(%error, "plant cannot advance");
                }
                for (port, line) in &self.serial_ports {
                    let octets = plant.take_serial_output(port);
                    if !octets.is_empty() {
                        // full: nobody reads the line; the plant's newest come next time
                        let _ = line.try_send(octets);
                    }
                }
            }
            self.now = t;
        }
        self.clock.set(self.now);
    }

    fn step(&mut self, t: Duration) {
        self.set_now(t);
        self.stepped = true;
        let now = self.now;
        // Pulses ending now.
        let mut ended = Vec::new();
        self.pulses.retain(|p| {
            if p.at <= now {
                ended.push((p.node, p.target.clone()));
                false
            } else {
                true
            }
        });
        for (node, target) in ended {
            if let Some(plc) = self.nodes.get_mut(node).and_then(|n| n.plc.as_mut()) {
                target.write_val(plc, Val::Int(0));
            }
        }
        let Simulation {
            plant,
            nodes,
            observers,
            ..
        } = self;
        for node in nodes.iter_mut() {
            node.cycle(now, plant.as_deref_mut(), observers);
        }
        for node in nodes.iter() {
            let utc = node.points.clock().at(now);
            let name = node.points.name().to_owned();
            node.points.change_with(&name, |db, _| db.due_cyclic(utc));
        }
    }

    fn command(
        &mut self,
        node: usize,
        ioa: u32,
        value: PointValue,
        pulse: Option<Duration>,
        select: bool,
    ) -> Result<(), CommandRefusal> {
        let now = self.now;
        let sim_node = self.nodes.get_mut(node).ok_or(CommandRefusal::Unknown)?;
        let command = sim_node.commands.get(&ioa).ok_or(CommandRefusal::Unknown)?;
        if let Some(reason) = stopped_reason(
            &sim_node.stopped,
            &sim_node.task_of_program,
            &sim_node.tasks,
            command.target.path(),
        ) {
            return Err(CommandRefusal::PlcStopped(reason.to_owned()));
        }
        let plc = sim_node.plc.as_mut().ok_or(CommandRefusal::Unknown)?;
        if let Some(enable) = &command.remote_enable {
            match plc.read_leaf(enable) {
                Ok(Val::Int(0)) => return Err(CommandRefusal::LocalMode),
                Ok(_) => {}
                Err(error) => return Err(CommandRefusal::BadValue(error.to_string())),
            }
        }
        if select {
            return Ok(());
        }
        // A command's value as the PLC holds it: ON (and a double ON) is 1, OFF 0, a
        // step +1 or -1, a set-point its number, a bitstring its bits.
        let value = match value {
            PointValue::Bool(on) => Val::Int(i64::from(on)),
            PointValue::DoublePoint(2) => Val::Int(1),
            PointValue::DoublePoint(1) => Val::Int(0),
            PointValue::Int(x) => Val::Int(x),
            PointValue::Bits(bits) => Val::Int(i64::from(bits)),
            PointValue::Float(x) => Val::Real(x),
            other @ (PointValue::DoublePoint(_) | PointValue::Text(_)) => {
                return Err(CommandRefusal::BadValue(format!(
                    "{other} cannot be written to a PLC variable"
                )))
            }
        };
        let value = match (command.target.lane(), value) {
            (Some(Lane::Int), Val::Int(x)) => Val::Int(x),
            (Some(Lane::Int), Val::Real(x)) => Val::Int(x.round() as i64),
            (Some(Lane::Real), Val::Int(x)) => Val::Real(x as f64),
            (Some(Lane::Real), Val::Real(x)) => Val::Real(x),
            (lane, v) => {
                return Err(CommandRefusal::BadValue(format!(
                    "{v:?} does not suit a {lane:?} variable"
                )))
            }
        };
        let target = command.target.clone();
        target.write_val(plc, value);
        if let Some(length) = pulse {
            self.pulses
                .retain(|p| !(p.node == node && p.target.path() == target.path()));
            self.pulses.push(Pulse {
                at: now + length,
                node,
                target,
            });
        }
        Ok(())
    }
}

impl SimNode {
    fn cycle(
        &mut self,
        now: Duration,
        plant: Option<&mut (dyn Plant + Send + 'static)>,
        observers: &[mpsc::Sender<OutputChange>],
    ) {
        let Some(plc) = self.plc.as_mut() else { return };
        let due = plc
            .next_due()
            .is_some_and(|d| Duration::from_nanos(d.max(0).unsigned_abs()) <= now);
        if !due {
            return;
        }
        if let Some(served) = self.s7.as_mut() {
            served.before_cycle(plc);
        }
        {
            let reads_points = self
                .inputs
                .iter()
                .any(|input| matches!(input.from, InputFrom::Point(_)));
            let db = reads_points.then(|| self.points.lock());
            for input in &mut self.inputs {
                input.copy(plc, plant.as_deref(), db.as_deref());
            }
        }
        let clock = self.points.clock();
        let utc = clock.at(now);
        let reading = ClockReading {
            monotonic_ns: i64::try_from(now.as_nanos()).unwrap_or(i64::MAX),
            utc_ns: utc.timestamp_nanos_opt().unwrap_or(0),
            utc_offset_ns: clock.utc_offset_ns(utc),
        };
        for fault in plc.run_cycle(reading) {
            let message = plc.render(&fault);
            tracing::error!(node = %self.points.name(), "{message}");
        }
        if let Some(served) = self.s7.as_mut() {
            served.after_cycle(plc);
        }
        self.settle(now, utc, plant, observers);
    }

    /// Stops (`run = false`) or starts the node's PLC: on a stop every bound output goes
    /// to its safe value, on a start the stopped tasks run again from their next cycle.
    fn run_plc(
        &mut self,
        run: bool,
        now: Duration,
        plant: Option<&mut (dyn Plant + Send + 'static)>,
        observers: &[mpsc::Sender<OutputChange>],
    ) -> Result<(), OperationError> {
        let Some(plc) = self.plc.as_mut() else {
            return Err(OperationError::NoPlc(self.points.name().to_owned()));
        };
        let clock = self.points.clock();
        let utc = clock.at(now);
        if run {
            plc.start();
            // Faulted tasks stay faulted until a cold start (the fault is still there).
            self.stopped.retain(|task, _| {
                matches!(plc.task_state(task), Some(plc::task::TaskState::Faulted(_)))
            });
            tracing::info!(node = %self.points.name(), "PLC started");
        } else {
            plc.stop(ClockReading {
                monotonic_ns: i64::try_from(now.as_nanos()).unwrap_or(i64::MAX),
                utc_ns: utc.timestamp_nanos_opt().unwrap_or(0),
                utc_offset_ns: clock.utc_offset_ns(utc),
            });
            tracing::info!(node = %self.points.name(), "PLC stopped");
        }
        self.settle(now, utc, plant, observers);
        Ok(())
    }

    /// After a cycle or a stop: records the tasks that stopped, drives the bound outputs
    /// and publishes the points the PLC feeds.
    fn settle(
        &mut self,
        now: Duration,
        utc: chrono::DateTime<chrono::Utc>,
        plant: Option<&mut (dyn Plant + Send + 'static)>,
        observers: &[mpsc::Sender<OutputChange>],
    ) {
        let Some(plc) = self.plc.as_mut() else { return };
        // A stopped task's outputs are at their safe values now (driven below); the stop
        // goes to the event store as the text of the pseudo-point `plc-task:NAME`.
        while let Some(stop) = plc.poll_event() {
            let mut text = stop.cause.kind().to_owned();
            if let Some(d) = stop.cause.diagnostic() {
                let at = plc.sources().location(d.primary);
                text.push_str(&format!(" {} at {at}: {}", d.code, d.message));
            }
            for (output, value) in &stop.outputs {
                text.push_str(&format!("; {output} := {value}"));
            }
            self.stopped
                .insert(stop.task.clone(), format!("task {}: {text}", stop.task));
            let mut record = crate::store::EventRecord::new(
                self.points.name(),
                format!("plc-task:{}", stop.task),
                PointValue::Text(text),
                utc,
            );
            record.cause = EventCause::Local;
            self.points.recorder().event(record);
        }
        let mut plant = plant;
        {
            for output in &mut self.outputs {
                let Some(v) = output.target.read(plc) else {
                    continue;
                };
                let value = match output.kind {
                    ValueKind::Bool => Value::Bool(matches!(v, Val::Int(x) if x != 0)),
                    ValueKind::Real => Value::Real(match v {
                        Val::Int(x) => x as f64,
                        Val::Real(x) => x,
                        Val::Str(_) => 0.0,
                    }),
                };
                if output.last != Some(value) {
                    match &output.to {
                        OutputTo::Signal(signal) => {
                            if let Some(plant) = plant.as_deref_mut() {
                                if let Err(error) = plant.set_output(signal, value) {
                                    tracing::warn!(signal = %signal, %error, "output not driven");
                                }
                            }
                        }
                        OutputTo::Device { image, item, .. } => image.set_output(
                            item,
                            match value {
                                Value::Bool(on) => ImageValue::Bool(on),
                                Value::Real(x) => ImageValue::Number(x),
                            },
                        ),
                    }
                    output.last = Some(value);
                    for observer in observers.iter() {
                        let _ = observer.send(OutputChange {
                            node: self.points.name().to_owned(),
                            signal: output.to.name().to_owned(),
                            value,
                            time: now,
                            at: Instant::now(),
                        });
                    }
                }
            }
        }
        if self.shutting_down {
            return;
        }
        // Points: read everything first, then take the database lock once.
        let mut changes = Vec::new();
        for point in &mut self.sourced {
            let Some(v) = point.source.read(plc) else {
                continue;
            };
            let forced_invalid = point
                .invalid_when
                .as_ref()
                .is_some_and(|leaf| matches!(plc.read_leaf(leaf), Ok(Val::Int(x)) if x != 0));
            let stopped = stopped_reason(
                &self.stopped,
                &self.task_of_program,
                &self.tasks,
                point.source.path(),
            )
            .is_some();
            let valid = !stopped
                && !forced_invalid
                && point
                    .input
                    .and_then(|i| self.inputs.get(i))
                    .is_none_or(|input| input.valid);
            let Some(value) = point_value(point.kind, &point.ty, &v) else {
                continue;
            };
            let current = Some((value.clone(), valid));
            if point.last != current {
                point.last = current;
                changes.push((point.id, value, valid));
            }
        }
        if changes.is_empty() {
            return;
        }
        let origin = self.points.name().to_owned();
        self.points.change_with(&origin, |db, received| {
            let source_time = Some(crate::store::SourceTime {
                time: received,
                invalid: false,
            });
            changes
                .into_iter()
                .filter_map(|(id, value, valid)| {
                    let quality = Quality {
                        invalid: !valid,
                        ..Quality::GOOD
                    };
                    db.update(
                        id,
                        value,
                        quality,
                        source_time,
                        received,
                        EventCause::Spontaneous,
                    )
                    .map_err(|error| tracing::warn!(%error, "PLC value refused"))
                    .ok()
                    .flatten()
                })
                .collect()
        });
    }
}

/// Why the PLC variable at `path` is not kept current: the task of its program stopped,
/// or for a variable of no program (a global) every task; `None` while it is.
fn stopped_reason<'a>(
    stopped: &'a HashMap<String, String>,
    task_of_program: &HashMap<String, String>,
    tasks: &[String],
    path: &str,
) -> Option<&'a str> {
    let program = path.split(['.', '[']).next()?.to_ascii_uppercase();
    match task_of_program.get(&program) {
        Some(task) => stopped.get(task).map(String::as_str),
        None if !tasks.is_empty() && tasks.iter().all(|task| stopped.contains_key(task)) => {
            stopped.values().next().map(String::as_str)
        }
        None => None,
    }
}

fn to_val(ty: &Ty, value: Value) -> Val {
    match (ty.lane(), value) {
        (Some(Lane::Real), Value::Real(x)) => Val::Real(x),
        (Some(Lane::Real), Value::Bool(b)) => Val::Real(f64::from(u8::from(b))),
        (_, Value::Bool(b)) => Val::Int(i64::from(b)),
        (_, Value::Real(x)) => Val::Int(x.round() as i64),
    }
}

/// The point value of a PLC variable for a point of `kind`.
fn point_value(kind: PointKind, ty: &Ty, v: &Val) -> Option<PointValue> {
    use PointKind::*;
    let int = match v {
        Val::Int(x) => *x,
        Val::Real(x) => x.round() as i64,
        Val::Str(_) => return None,
    };
    let real = match v {
        Val::Int(x) => *x as f64,
        Val::Real(x) => *x,
        Val::Str(_) => return None,
    };
    Some(match kind {
        Single => PointValue::Bool(int != 0),
        // A BOOL drives a double point as OFF (1) / ON (2); an integer gives the state.
        Double => PointValue::DoublePoint(if *ty == Ty::Bool {
            if int != 0 {
                2
            } else {
                1
            }
        } else {
            u8::try_from(int.clamp(0, 3)).unwrap_or(0)
        }),
        Step => PointValue::Int(int.clamp(-64, 63)),
        Bitstring => PointValue::Bits(int as u32),
        Normalized => PointValue::Float(real.clamp(-1.0, 1.0)),
        Scaled => PointValue::Int(int.clamp(-32768, 32767)),
        Float => PointValue::Float(real),
        Total => PointValue::Int(int),
    })
}

/// The type of a direct address's datum (`%IX0.0` BOOL, `%IB1` BYTE, `%ID4` DWORD).
fn image_type(address: &str) -> Ty {
    match address.get(2..3) {
        Some("X" | "x") => Ty::Bool,
        Some("B" | "b") => Ty::Byte,
        Some("W" | "w") => Ty::Word,
        Some("D" | "d") => Ty::DWord,
        Some("L" | "l") => Ty::LWord,
        _ => Ty::Bool,
    }
}

/// The node's source files as its project names them: (path, text).
fn project_sources(config: &NodeConfig) -> Result<Vec<(String, String)>, RuntimeError> {
    // The configuration resolved the sources against the project folder already: joining
    // the folder again doubled a relative project path (`examples/vsetin/examples/vsetin`).
    config
        .sources
        .iter()
        .map(|path| {
            std::fs::read_to_string(path)
                .map(|text| (path.display().to_string(), text))
                .map_err(|error| {
                    RuntimeError::Setup(format!(
                        "node `{}`: cannot read {}: {error}",
                        config.name,
                        path.display()
                    ))
                })
        })
        .collect()
}

fn build_node(
    config: &NodeConfig,
    points: Arc<NodePoints>,
    plant: Option<&(dyn Plant + Send + 'static)>,
    images: &DeviceImages,
) -> Result<SimNode, RuntimeError> {
    if config.sources.is_empty() && config.tasks.is_empty() {
        return build_node_from(config, Vec::new(), points, plant, images);
    }
    build_node_from(config, project_sources(config)?, points, plant, images)
}

/// Builds the node's PLC from `files` (name, text) and binds it as `config` says.
fn build_node_from(
    config: &NodeConfig,
    files: Vec<(String, String)>,
    points: Arc<NodePoints>,
    plant: Option<&(dyn Plant + Send + 'static)>,
    images: &DeviceImages,
) -> Result<SimNode, RuntimeError> {
    let node = &config.name;
    let setup = |message: String| RuntimeError::Setup(format!("node `{node}`: {message}"));
    let mut sim = SimNode {
        points: Arc::clone(&points),
        plc: None,
        stopped: HashMap::new(),
        task_of_program: config
            .tasks
            .iter()
            .flat_map(|task| {
                task.programs
                    .iter()
                    .map(|program| (program.to_ascii_uppercase(), task.name.clone()))
            })
            .collect(),
        tasks: config.tasks.iter().map(|task| task.name.clone()).collect(),
        shutting_down: false,
        inputs: Vec::new(),
        outputs: Vec::new(),
        sourced: Vec::new(),
        commands: HashMap::new(),
        s7: None,
    };
    if files.is_empty() && config.tasks.is_empty() {
        return Ok(sim);
    }
    let (sources, result) = plc::build(&files);
    let compiled = result.map_err(|diagnostics| {
        RuntimeError::Plc(
            diagnostics
                .iter()
                .map(|d| d.render(&sources))
                .collect::<Vec<_>>()
                .join("\n"),
        )
    })?;
    let mut plc = Plc::try_new(compiled, sources)
        .map_err(|error| setup(format!("PLC cold start failed: {error}")))?;
    for (path, value) in &config.initial_values {
        plc.write(path, value)
            .map_err(|error| setup(format!("set `{path}` = `{value}`: {error}")))?;
    }
    for table in &config.tables {
        load_table(&mut plc, table).map_err(|error| setup(error.to_string()))?;
    }
    for group in config.server.iter().flat_map(|s| &s.redundancy_groups) {
        if let Some(path) = &group.refuse_commands_when {
            plc.leaf(path).map_err(|error| {
                setup(format!(
                    "redundancy group `{}` refuse_commands_when `{path}`: {error}",
                    group.name
                ))
            })?;
        }
    }
    for task in &config.tasks {
        let interval = i64::try_from(task.interval.as_nanos()).unwrap_or(i64::MAX);
        let programs: Vec<&str> = task.programs.iter().map(String::as_str).collect();
        let mut plc_task =
            PlcTask::cyclic(task.name.clone(), interval, &programs).with_priority(task.priority);
        if let Some(watchdog) = task.watchdog {
            plc_task =
                plc_task.with_watchdog(i64::try_from(watchdog.as_nanos()).unwrap_or(i64::MAX), 1);
        }
        plc.add_task(plc_task)
            .map_err(|error| setup(format!("task `{}`: {error}", task.name)))?;
    }
    // Real elapsed time would make the watchdog depend on the host's load in a
    // simulated run; the runtime measures real cycle times only in real-time pacing.
    let leaf = |plc: &Plc, path: &str, what: &str| {
        plc.leaf(path)
            .map_err(|error| setup(format!("{what} `{path}`: {error}")))
    };
    for binding in &config.io {
        let target = if binding.variable.starts_with('%') {
            plc.get_io(&binding.variable)
                .map_err(|error| setup(format!("I/O address `{}`: {error}", binding.variable)))?;
            IoTarget::Image(binding.variable.clone())
        } else {
            IoTarget::Variable(leaf(&plc, &binding.variable, "I/O variable")?)
        };
        let scale = binding.scale.unwrap_or(1.0);
        let signal = match &binding.source {
            IoSource::Point(name) => {
                let id = points
                    .lock()
                    .id(name.as_str())
                    .ok_or_else(|| setup(format!("I/O binding of the unknown point `{name}`")))?;
                sim.inputs.push(InputBinding {
                    from: InputFrom::Point(id),
                    target,
                    scale,
                    valid: false,
                });
                continue;
            }
            IoSource::Device {
                device,
                item,
                output,
            } => {
                let image = images
                    .get(&(config.name.clone(), device.clone()))
                    .cloned()
                    .ok_or_else(|| setup(format!("no I/O image of device `{device}`")))?;
                if *output {
                    // A variable the project also binds as an input (a LOGO!'s contact
                    // reported to its concentrator) is passed on, not driven: it has no
                    // safe value of its own.
                    let passed_on = config.io.iter().any(|other| {
                        other.variable == binding.variable
                            && !matches!(other.source, IoSource::Device { output: true, .. })
                    });
                    if let (IoTarget::Variable(_), false) = (&target, passed_on) {
                        plc.bind_output(&binding.variable).map_err(|error| {
                            setup(format!("output `{}`: {error}", binding.variable))
                        })?;
                    }
                    let bit = match &target {
                        IoTarget::Variable(leaf) => leaf.ty == Ty::Bool,
                        IoTarget::Image(address) => image_type(address) == Ty::Bool,
                    };
                    sim.outputs.push(OutputBinding {
                        to: OutputTo::Device {
                            image,
                            name: format!("{device}.{item}"),
                            item: item.clone(),
                        },
                        target,
                        kind: if bit {
                            ValueKind::Bool
                        } else {
                            ValueKind::Real
                        },
                        last: None,
                    });
                } else {
                    sim.inputs.push(InputBinding {
                        from: InputFrom::Device {
                            image,
                            item: item.clone(),
                        },
                        target,
                        scale,
                        valid: false,
                    });
                }
                continue;
            }
            IoSource::Signal(signal) => signal,
        };
        let Some(plant) = plant else {
            return Err(setup(format!(
                "I/O binding of `{signal}` but the project has no plant"
            )));
        };
        if let Some(module) = signal.strip_prefix("module-fault:") {
            if !plant.modules().iter().any(|m| m.name == module) {
                return Err(setup(format!("the plant has no I/O module `{module}`")));
            }
            sim.inputs.push(InputBinding {
                from: InputFrom::ModuleFault(module.to_owned()),
                target,
                scale: 1.0,
                valid: true,
            });
            continue;
        }
        let info = plant
            .signals()
            .iter()
            .find(|s| &s.name == signal)
            .ok_or_else(|| setup(format!("the plant has no signal `{signal}`")))?;
        match info.direction {
            Direction::Input => sim.inputs.push(InputBinding {
                from: InputFrom::Signal(signal.clone()),
                target,
                scale,
                valid: true,
            }),
            Direction::Output => {
                // goes to its safe value (FALSE / 0 or declared) when its task stops; an
                // image address's AT variables are the program's outputs already
                if let IoTarget::Variable(_) = target {
                    plc.bind_output(&binding.variable).map_err(|error| {
                        setup(format!("output `{}`: {error}", binding.variable))
                    })?;
                }
                if binding.scale.is_some() {
                    return Err(setup(format!(
                        "`scale` of the output `{signal}`: only inputs are scaled"
                    )));
                }
                sim.outputs.push(OutputBinding {
                    to: OutputTo::Signal(signal.clone()),
                    target,
                    kind: info.kind,
                    last: None,
                });
            }
        }
    }
    {
        let db = points.lock();
        for point in &config.points {
            let PointSource::Variable(path) = &point.source else {
                continue;
            };
            let Some(id) = db.id(point.name.as_str()) else {
                continue;
            };
            let (source, ty) = if path.starts_with('%') {
                plc.get_io(path).map_err(|error| {
                    setup(format!("point `{}` source `{path}`: {error}", point.name))
                })?;
                (IoTarget::Image(path.clone()), image_type(path))
            } else {
                let target = leaf(&plc, path, &format!("point `{}` source", point.name))?;
                let ty = target.ty.clone();
                (IoTarget::Variable(target), ty)
            };
            let input = sim
                .inputs
                .iter()
                .position(|i| i.target.path() == source.path());
            let invalid_when = point
                .invalid_when
                .as_deref()
                .map(|path| leaf(&plc, path, &format!("point `{}` invalid_when", point.name)))
                .transpose()?;
            sim.sourced.push(SourcedPoint {
                id,
                kind: point.point_type.kind,
                source,
                ty,
                input,
                invalid_when,
                last: None,
            });
        }
    }
    for command in &config.commands {
        let CommandTarget::Variable(path) = &command.target else {
            continue;
        };
        let target = if path.starts_with('%') {
            plc.get_io(path).map_err(|error| {
                setup(format!(
                    "command `{}` target `{path}`: {error}",
                    command.name
                ))
            })?;
            IoTarget::Image(path.clone())
        } else {
            IoTarget::Variable(leaf(
                &plc,
                path,
                &format!("command `{}` target", command.name),
            )?)
        };
        let remote_enable = command
            .remote_enable
            .as_deref()
            .map(|path| {
                leaf(
                    &plc,
                    path,
                    &format!("command `{}` remote_enable", command.name),
                )
            })
            .transpose()?;
        sim.commands.insert(
            command.ioa.get(),
            SimCommand {
                target,
                remote_enable,
            },
        );
    }
    sim.plc = Some(plc);
    Ok(sim)
}

/// Why a table could not be loaded into the PLC.
#[derive(Debug, thiserror::Error)]
enum TableError {
    #[error("{file}: {source}")]
    Unreadable {
        file: String,
        source: std::io::Error,
    },
    #[error("{file}: no header row")]
    NoHeader { file: String },
    #[error("{file}: no column `{column}` in the header")]
    NoColumn { file: String, column: String },
    #[error("{file}:{line}: {problem}")]
    Row {
        file: String,
        line: usize,
        problem: RowProblem,
    },
}

/// What is wrong with a row of a table.
#[derive(Debug, thiserror::Error)]
enum RowProblem {
    #[error("`{0}` is not an index")]
    NotAnIndex(String),
    #[error("missing cell")]
    MissingCell,
    #[error("{target} := {literal}: {reason}")]
    Refused {
        target: String,
        literal: String,
        reason: String,
    },
}

/// Loads a CSV table into PLC arrays; errors name the file and line.
fn load_table(plc: &mut Plc, table: &crate::config::TableConfig) -> Result<(), TableError> {
    let file = table.file.display().to_string();
    let text = std::fs::read_to_string(&table.file).map_err(|source| TableError::Unreadable {
        file: file.clone(),
        source,
    })?;
    let mut rows = text
        .lines()
        .enumerate()
        .filter(|(_, line)| !line.trim_start().starts_with('#') && !line.trim().is_empty());
    let Some((_, header)) = rows.next() else {
        return Err(TableError::NoHeader { file });
    };
    let header: Vec<&str> = header.split(',').map(str::trim).collect();
    let position = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| TableError::NoColumn {
                file: file.clone(),
                column: name.to_owned(),
            })
    };
    let index_column = position(&table.index)?;
    let columns = table
        .columns
        .iter()
        .map(|(column, path)| Ok((position(column)?, path)))
        .collect::<Result<Vec<_>, TableError>>()?;
    for (number, line) in rows {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let at = |problem: RowProblem| TableError::Row {
            file: file.clone(),
            line: number + 1,
            problem,
        };
        let index: i64 = cells
            .get(index_column)
            .and_then(|c| c.parse().ok())
            .ok_or_else(|| at(RowProblem::NotAnIndex(line.trim().to_owned())))?;
        for (column, path) in &columns {
            let cell = cells
                .get(*column)
                .ok_or_else(|| at(RowProblem::MissingCell))?;
            let literal = if !cell.contains('#')
                && cell.split(':').count() >= 2
                && cell
                    .split(':')
                    .all(|part| part.chars().all(|c| c.is_ascii_digit()))
            {
                let parts: Vec<&str> = cell.split(':').collect();
                let seconds = parts.get(2).copied().unwrap_or("00");
                format!(
                    "TOD#{:0>2}:{:0>2}:{:0>2}",
                    parts.first().copied().unwrap_or("0"),
                    parts.get(1).copied().unwrap_or("0"),
                    seconds
                )
            } else {
                (*cell).to_owned()
            };
            let target = format!("{path}[{index}]");
            plc.write(&target, &literal).map_err(|error| {
                at(RowProblem::Refused {
                    target: target.clone(),
                    literal: literal.clone(),
                    reason: error.to_string(),
                })
            })?;
        }
    }
    Ok(())
}

/// The simulation thread's loop. `started`: the wall-clock instant of simulated time zero
/// (the runtime's start) for [`Pacing::RealTime`].
pub(crate) fn run(
    mut sim: Simulation,
    pacing: Pacing,
    started: Instant,
    requests: mpsc::Receiver<SimRequest>,
) {
    // Hold at time zero until the servers are up; then catch up with the wall clock from
    // `started`, so that the start-up's seconds are not missing from simulated time (a
    // station at speed 1 started at `now` would otherwise run that much behind the wall
    // clock, and hand the lag on to the nodes it synchronises).
    sim.advance_to(Duration::ZERO, 1);
    let mut going = false;
    let (real0, sim0) = (started, Duration::ZERO);
    loop {
        let request = match (pacing, going) {
            (Pacing::RealTime { speed }, true) => {
                let target = sim0
                    + Duration::try_from_secs_f64(real0.elapsed().as_secs_f64() * speed)
                        .unwrap_or(Duration::MAX / 2);
                let caught_up = sim.advance_to(target, STEPS_PER_POLL);
                let wait = if caught_up {
                    let next = sim.next_due();
                    // Nothing due at all (a project without PLC tasks and plant, such as
                    // a gateway) makes the wait infinite: look again after the cap.
                    Duration::try_from_secs_f64(
                        (next.saturating_sub(sim.now)).as_secs_f64() / speed,
                    )
                    .unwrap_or(Duration::MAX)
                    .min(Duration::from_millis(100))
                } else {
                    Duration::ZERO
                };
                match requests.recv_timeout(wait) {
                    Ok(request) => request,
                    Err(mpsc::RecvTimeoutError::Timeout) => continue,
                    Err(mpsc::RecvTimeoutError::Disconnected) => break,
                }
            }
            _ => match requests.recv() {
                Ok(request) => request,
                Err(_) => break,
            },
        };
        match request {
            SimRequest::Go => going = true,
            SimRequest::Advance { by, reply } => {
                let target = sim.now + by;
                while !sim.advance_to(target, usize::MAX) {}
                let _ = reply.send(sim.now);
            }
            SimRequest::Command {
                node,
                ioa,
                value,
                pulse,
                select,
                reply,
            } => {
                let _ = reply.send(sim.command(node, ioa, value, pulse, select));
            }
            SimRequest::With(f) => f(&mut sim),
            SimRequest::Stop => {
                sim.stop_all();
                break;
            }
        }
    }
    tracing::debug!("simulation thread ends");
}
