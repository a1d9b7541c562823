//! The sorting lab on one simulated clock: the sorting PLC's program, the supervisor's
//! program and the mechanism ([`plant::sorter`]), wired as the lab wires them (the
//! sorting-lab thesis, section 4.1): the sorting program reaches the actuators only
//! through the supervisor.
//!
//! ```text
//!   sorting PLC (10-ms scans)            supervisor PLC (30-ms scans)        mechanism
//!   %IB0 Sn1-Sn5          ◀──────────────────────────────────────────────── sensors
//!   %ID4 weight µg, %IX8.0 stable, %IX8.1 link ◀──────────────────────────── balance
//!   %QB0-%QB1 ──▶ Cmd_A ─(DP)─ DP_A ──▶ %IB0-%IB1 ── SingleControl ──▶ %QB0-%QB1 ──▶ actuators
//!   %IB1-%IB2 ◀── Fb_A ◀─(DP)────────────────────── MultipleControl       │
//!                                                     %QB4-%QB17 states ◀───┘
//!   the globals of interface.st (the HMI's requests and what it shows) ◀── [`Rig::set`]
//!
//! The DP exchange is the mechanism's wiring (`plant::sorter`'s `Cmd_A`, `DP_A`,
//! `Fb_A`), so its faults (a lost pulse, a failed exchange) are the mechanism's console
//! faults, as in a station project.
//! ```
//!
//! One step is one sorting scan at simulated time `t`: the mechanism advances to `t`, the
//! sorting PLC reads its inputs and scans; when a supervisor scan is due (every 30 ms,
//! section 4.5: a command shorter than two of its scans can be lost, as on the model),
//! the supervisor takes the commands the sorting PLC last wrote, scans, and its outputs
//! drive the mechanism at `t`. Each refusal and lock-out of the supervisor becomes a
//! [`SupervisorEvent`] naming the actuator and the rule.

use std::time::Duration;

use lab::program::Program;
use plant::sorter::{SorterConfig, SorterPlant, ACTUATORS};
use plant::{Plant, Value};
use plc::task::{ClockReading, Leaf, TaskConfig};
use plc::Plc;
use serde::Serialize;

/// How the rig runs.
#[derive(Debug, Clone)]
pub struct RigSettings {
    /// The mechanism (its seed: the balls' order, the deflectors at power-on, the
    /// balance's errors).
    pub mechanism: SorterConfig,
    /// The sorting PLC's cycle (the CPU 315-2 DP's scan is about 10 ms).
    pub sorter_scan: Duration,
    /// The supervisor's cycle (the CPU 222's scan is about 30 ms).
    pub supervisor_scan: Duration,
}

impl Default for RigSettings {
    fn default() -> RigSettings {
        RigSettings {
            mechanism: SorterConfig::default(),
            sorter_scan: Duration::from_millis(10),
            supervisor_scan: Duration::from_millis(30),
        }
    }
}

/// Why a rig cannot start or go on.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// A PLC refused the program or stopped on a fault.
    #[error("{plc}: {message}")]
    Plc {
        /// `sorting PLC` or `supervisor`.
        plc: &'static str,
        /// What it said.
        message: String,
    },
    /// The mechanism refused a step.
    #[error("mechanism: {0}")]
    Plant(#[from] plant::PlantError),
}

/// What the supervisor did against a command.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SupervisorAction {
    /// A command refused (the actuator stayed off).
    Refused,
    /// An actuator switched off at its MaxOnTime: the penalty lock-out began.
    LockedOut,
}

/// A refusal or lock-out, as the station records it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SupervisorEvent {
    /// Simulated time.
    #[serde(with = "millis")]
    pub at: Duration,
    /// The actuator (`S1`, `SL2`, `Blower`).
    pub actuator: &'static str,
    /// What the supervisor did.
    pub action: SupervisorAction,
    /// The rule, in words.
    pub rule: &'static str,
}

mod millis {
    use std::time::Duration;

    pub(super) fn serialize<S: serde::Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u64(u64::try_from(d.as_millis()).unwrap_or(u64::MAX))
    }
}

/// The supervisor's block kind per actuator, for the rules' words.
fn level_controlled(actuator: &str) -> bool {
    matches!(actuator, "S1" | "S2" | "S3" | "Blower" | "Tare")
}

/// The lab: two PLCs and the mechanism.
pub struct Rig {
    sorter: Plc,
    supervisor: Plc,
    plant: SorterPlant,
    settings: RigSettings,
    now: Duration,
    next_supervisor: Duration,
    /// The actuators as last driven (bit i = ACTUATORS[i]).
    driven: u16,
    /// The sorting PLC's commands as last put on the DP bus (bit i = ACTUATORS[i]).
    commands: u16,
    /// Per actuator: the supervisor block's `Refused`, `LockedOut` (level-controlled
    /// blocks only) and `State`, resolved once.
    flags: Vec<(&'static str, Leaf, Option<Leaf>, Leaf)>,
    events: Vec<SupervisorEvent>,
}

impl std::fmt::Debug for Rig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Rig")
            .field("now", &self.now)
            .finish_non_exhaustive()
    }
}

/// A process-image word (`%QW0`: S1-S8 in its first byte, bit 0 = S1; S9 on in the
/// second, big-endian as on an S7) as actuator bits (bit i = ACTUATORS[i]).
fn from_word(word: i64) -> u16 {
    (((word >> 8) & 0xff) | ((word & 0xff) << 8)) as u16
}

/// Actuator bits as a process-image word (the inverse of [`from_word`]).
fn to_word(bits: u16) -> i64 {
    let bits = i64::from(bits);
    ((bits & 0xff) << 8) | ((bits >> 8) & 0xff)
}

fn clock(t: Duration) -> ClockReading {
    let ns = i64::try_from(t.as_nanos()).unwrap_or(i64::MAX);
    ClockReading {
        monotonic_ns: ns,
        utc_ns: ns,
        utc_offset_ns: 0,
    }
}

fn start_plc(program: Program, scan: Duration, plc_name: &'static str) -> Result<Plc, RigError> {
    let fail = |message: String| RigError::Plc {
        plc: plc_name,
        message,
    };
    let mut plc =
        Plc::try_new(program.compiled, program.sources).map_err(|e| fail(e.to_string()))?;
    let scan_ns = i64::try_from(scan.as_nanos()).unwrap_or(i64::MAX);
    plc.add_task(TaskConfig::cyclic("main", scan_ns, &[&program.main]))
        .map_err(|e| fail(e.to_string()))?;
    if let Some(fault) = plc.init_fault() {
        return Err(fail(plc.render(fault)));
    }
    Ok(plc)
}

impl Rig {
    /// The rig with `sorter` as the sorting PLC's program and `supervisor` as the
    /// supervisor's (its PROGRAM with the instances `S1` ... `Light` of the supervisor
    /// blocks, as `examples/sorting-lab/plc/supervisor.st` has them).
    pub fn new(
        sorter: Program,
        supervisor: Program,
        settings: RigSettings,
    ) -> Result<Rig, RigError> {
        let main = supervisor.main.clone();
        let sorter = start_plc(sorter, settings.sorter_scan, "sorting PLC")?;
        let supervisor = start_plc(supervisor, settings.supervisor_scan, "supervisor")?;
        let leaf = |actuator: &str, field: &str| {
            let path = format!("{main}.{actuator}.{field}");
            supervisor.leaf(&path).map_err(|e| RigError::Plc {
                plc: "supervisor",
                message: format!(
                    "{e} (the supervisor's PROGRAM names its blocks after the actuators)"
                ),
            })
        };
        let mut flags = Vec::new();
        for actuator in ACTUATORS {
            if actuator == "Light" {
                continue;
            }
            let locked_out = if level_controlled(actuator) {
                Some(leaf(actuator, "LockedOut")?)
            } else {
                None
            };
            flags.push((
                actuator,
                leaf(actuator, "Refused")?,
                locked_out,
                leaf(actuator, "State")?,
            ));
        }
        let plant = SorterPlant::new(settings.mechanism.clone());
        Ok(Rig {
            sorter,
            supervisor,
            plant,
            now: Duration::ZERO,
            next_supervisor: Duration::ZERO,
            driven: 0,
            commands: 0,
            flags,
            events: Vec::new(),
            settings,
        })
    }

    /// Simulated time of the next step.
    pub fn now(&self) -> Duration {
        self.now
    }

    /// The mechanism.
    pub fn plant(&self) -> &SorterPlant {
        &self.plant
    }

    /// The mechanism, for faults (`plant_mut().console("stuck D2")`).
    pub fn plant_mut(&mut self) -> &mut SorterPlant {
        &mut self.plant
    }

    /// The sorting PLC.
    pub fn sorter(&self) -> &Plc {
        &self.sorter
    }

    /// The supervisor PLC.
    pub fn supervisor(&self) -> &Plc {
        &self.supervisor
    }

    /// Every refusal and lock-out so far.
    pub fn events(&self) -> &[SupervisorEvent] {
        &self.events
    }

    /// Writes a variable of the sorting PLC as the HMI does (`StartCmd` = `TRUE`,
    /// `Colour1` = `3`): the globals of `interface.st`.
    pub fn set(&mut self, path: &str, literal: &str) -> Result<(), RigError> {
        self.sorter.write(path, literal).map_err(|e| RigError::Plc {
            plc: "sorting PLC",
            message: format!("{path}: {e}"),
        })
    }

    /// A number (or BOOL as 0/1) of the sorting PLC (`Sortings`, `StateOut`), 0 when
    /// there is none.
    pub fn value(&self, path: &str) -> f64 {
        match self.sorter.read(path) {
            Ok(plc::vm::Val::Int(x)) => x as f64,
            Ok(plc::vm::Val::Real(x)) => x,
            _ => 0.0,
        }
    }

    /// The state byte of actuator `index` as the supervisor reports it (0 ready, 1 on,
    /// 2 safety, 3 penalty).
    pub fn actuator_state(&self, index: usize) -> i64 {
        self.supervisor
            .get_io(&format!("%QB{}", 4 + index))
            .unwrap_or(0)
    }

    /// Loses the next command pulse of `actuator` on the DP bus before the supervisor
    /// sees it (the mechanism's console `lose-pulse A`).
    pub fn lose_next_pulse(&mut self, actuator: &str) -> Result<(), RigError> {
        Ok(self.plant.console(&format!("lose-pulse {actuator}"))?)
    }

    /// Reads the DP signals `{prefix}A` of every actuator as actuator bits.
    fn dp_bits(&self, prefix: &str) -> Result<u16, RigError> {
        let mut bits = 0u16;
        for (index, actuator) in ACTUATORS.iter().enumerate() {
            if self.plant.bool(&format!("{prefix}{actuator}"))? {
                bits |= 1 << index;
            }
        }
        Ok(bits)
    }

    fn sorter_inputs(&mut self) -> Result<(), RigError> {
        let mut sensors = 0i64;
        for (bit, name) in plant::sorter::SENSORS.iter().enumerate() {
            if self.plant.bool(name)? {
                sensors |= 1 << bit;
            }
        }
        let weight = self.plant.read("Balance_g")?;
        let stable = self.plant.read("Balance_stable")?;
        let micrograms = (weight.value.as_real().unwrap_or(0.0) * 1e6).round() as i64;
        let flags =
            i64::from(stable.value.as_bool().unwrap_or(false)) | (i64::from(weight.valid) << 1);
        let feedback = to_word(self.dp_bits("Fb_")?);
        let fail = |e: plc::PlcError| RigError::Plc {
            plc: "sorting PLC",
            message: e.to_string(),
        };
        self.sorter.set_io("%IB0", sensors).map_err(fail)?;
        self.sorter.set_io("%IW1", feedback).map_err(fail)?;
        self.sorter.set_io("%ID4", micrograms).map_err(fail)?;
        self.sorter.set_io("%IB8", flags).map_err(fail)?;
        Ok(())
    }

    fn supervisor_scan(&mut self) -> Result<(), RigError> {
        let commands = self.dp_bits("DP_")?;
        self.supervisor
            .set_io("%IW0", to_word(commands))
            .map_err(|e| RigError::Plc {
                plc: "supervisor",
                message: e.to_string(),
            })?;
        let faults = self.supervisor.run_cycle(clock(self.now));
        if let Some(fault) = faults.first() {
            return Err(RigError::Plc {
                plc: "supervisor",
                message: self.supervisor.render(fault),
            });
        }
        let driven = from_word(self.supervisor.get_io("%QW0").unwrap_or(0));
        for (index, actuator) in ACTUATORS.iter().enumerate() {
            let on = driven & (1 << index) != 0;
            if on != (self.driven & (1 << index) != 0) {
                self.plant.set_output(actuator, Value::Bool(on))?;
            }
        }
        self.driven = driven;
        self.collect_events();
        Ok(())
    }

    fn collect_events(&mut self) {
        let on = |plc: &Plc, leaf: &Leaf| matches!(plc.read_leaf(leaf), Ok(plc::vm::Val::Int(1)));
        for (actuator, refused, locked_out, state) in &self.flags {
            if locked_out
                .as_ref()
                .is_some_and(|leaf| on(&self.supervisor, leaf))
            {
                self.events.push(SupervisorEvent {
                    at: self.now,
                    actuator,
                    action: SupervisorAction::LockedOut,
                    rule: "on longer than MaxOnTime: switched off, PenaltyTime",
                });
            }
            if on(&self.supervisor, refused) {
                let state = match self.supervisor.read_leaf(state) {
                    Ok(plc::vm::Val::Int(state)) => state,
                    _ => 0,
                };
                let rule = match (level_controlled(actuator), state) {
                    (true, 3) => "commanded during PenaltyTime: the penalty starts again",
                    (true, _) => "commanded during SafetyTime: the safety time starts again",
                    (false, 0) => "the opposed solenoid is on: the edge is discarded",
                    (false, _) => "an edge during SafetyTime: the safety time starts again",
                };
                self.events.push(SupervisorEvent {
                    at: self.now,
                    actuator,
                    action: SupervisorAction::Refused,
                    rule,
                });
            }
        }
    }

    /// One sorting scan (and the supervisor's, when due); time moves one sorting cycle.
    pub fn step(&mut self) -> Result<(), RigError> {
        self.plant.advance_to(self.now)?;
        self.sorter_inputs()?;
        let faults = self.sorter.run_cycle(clock(self.now));
        if let Some(fault) = faults.first() {
            return Err(RigError::Plc {
                plc: "sorting PLC",
                message: self.sorter.render(fault),
            });
        }
        let commands = from_word(self.sorter.get_io("%QW0").unwrap_or(0));
        for (index, actuator) in ACTUATORS.iter().enumerate() {
            let on = commands & (1 << index) != 0;
            if on != (self.commands & (1 << index) != 0) {
                self.plant
                    .set_output(&format!("Cmd_{actuator}"), Value::Bool(on))?;
            }
        }
        self.commands = commands;
        if self.now >= self.next_supervisor {
            self.supervisor_scan()?;
            self.next_supervisor += self.settings.supervisor_scan;
        }
        self.now += self.settings.sorter_scan;
        Ok(())
    }

    /// Steps until `done` holds after a step or `limit` of simulated time has passed;
    /// whether `done` held.
    pub fn run_until(
        &mut self,
        limit: Duration,
        mut done: impl FnMut(&Rig) -> bool,
    ) -> Result<bool, RigError> {
        let until = self.now + limit;
        while self.now < until {
            self.step()?;
            if done(self) {
                return Ok(true);
            }
        }
        Ok(false)
    }
}

/// One automatic sorting as the reference program does it, from the mechanism's
/// power-on.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SortingOutcome {
    /// The sorting program reported the sorting done (`Sortings` counted it).
    pub finished: bool,
    /// Simulated time from the start command to done (or to the limit).
    #[serde(with = "millis")]
    pub took: Duration,
    /// Each ball and the shaft it rests in at the end (0: in no shaft).
    pub shafts: Vec<(&'static str, u8)>,
    /// The supervisor's refusals and lock-outs on the way.
    pub events: Vec<SupervisorEvent>,
}

impl Rig {
    /// Sets the automatic mode and the shafts' colours (`colours[k]` for shaft k + 1,
    /// 1 red .. 4 green), presses Start and runs until the program counts a finished
    /// sorting or `limit` passes.
    pub fn automatic_sorting(
        &mut self,
        colours: [u8; 4],
        limit: Duration,
    ) -> Result<SortingOutcome, RigError> {
        self.set("Automatic", "TRUE")?;
        for (k, colour) in colours.iter().enumerate() {
            self.set(&format!("Colour{}", k + 1), &colour.to_string())?;
        }
        let before = self.value("Sortings");
        self.set("StartCmd", "TRUE")?;
        let started = self.now;
        let events_before = self.events.len();
        let finished = self.run_until(limit, |rig| rig.value("Sortings") != before)?;
        let shafts = (0..self.plant.balls().len())
            .map(|ball| {
                let name = self.plant.balls().get(ball).map_or("?", |b| b.name);
                let shaft = match self.plant.place(ball) {
                    Some(plant::sorter::Place::Shaft(shaft)) => shaft,
                    _ => 0,
                };
                (name, shaft)
            })
            .collect();
        Ok(SortingOutcome {
            finished,
            took: self.now - started,
            shafts,
            events: self
                .events
                .get(events_before..)
                .unwrap_or_default()
                .to_vec(),
        })
    }
}

/// The sortings of [`mechanism_reliability`], counted.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MechanismReliability {
    /// Balls: true colour x the colour of the shaft they ended in (0: none).
    pub confusion: crate::reliability::Confusion,
    /// Sortings run.
    pub sortings: u64,
    /// Sortings with all eight balls in the shafts of their colours.
    pub all_right: u64,
    /// Sortings the program did not finish within the limit.
    pub unfinished: u64,
    /// The supervisor's refusals and lock-outs over all sortings.
    pub supervisor_events: u64,
    /// Mean simulated time of a sorting, initialisation included.
    #[serde(with = "millis")]
    pub mean_time: Duration,
}

/// Runs `sortings` automatic sortings, each from power-on of a mechanism seeded
/// `seed + n` (the balls' order, the deflectors, the balance's errors), with the
/// programs `sorter` and `supervisor` (compiled anew each time from `build`), shafts
/// 1-4 holding red, yellow, blue, green.
pub fn mechanism_reliability(
    sortings: u64,
    seed: u64,
    mut build: impl FnMut() -> Result<(Program, Program), RigError>,
) -> Result<MechanismReliability, RigError> {
    use crate::classify::Colour;
    let colours = [1, 2, 3, 4];
    let mut counts = [[0u64; 5]; 4];
    let mut report = MechanismReliability {
        confusion: crate::reliability::Confusion { counts },
        sortings,
        all_right: 0,
        unfinished: 0,
        supervisor_events: 0,
        mean_time: Duration::ZERO,
    };
    let mut total_time = Duration::ZERO;
    for n in 0..sortings {
        let (sorter, supervisor) = build()?;
        let settings = RigSettings {
            mechanism: SorterConfig {
                seed: seed.wrapping_add(n),
                ..SorterConfig::default()
            },
            ..RigSettings::default()
        };
        let mut rig = Rig::new(sorter, supervisor, settings)?;
        let outcome = rig.automatic_sorting(colours, Duration::from_secs(600))?;
        total_time += outcome.took;
        report.unfinished += u64::from(!outcome.finished);
        report.supervisor_events += outcome.events.len() as u64;
        let mut right = 0;
        for (ball, shaft) in &outcome.shafts {
            let Some(colour) = Colour::of_ball(ball) else {
                continue;
            };
            let decided = usize::from(*shaft)
                .checked_sub(1)
                .and_then(|k| colours.get(k))
                .map_or(0, |c| usize::from(*c));
            right += usize::from(decided == usize::from(colour.code()));
            if let Some(cell) = counts
                .get_mut(usize::from(colour.code()) - 1)
                .and_then(|row| row.get_mut(decided))
            {
                *cell += 1;
            }
        }
        report.all_right += u64::from(right == outcome.shafts.len());
    }
    report.confusion = crate::reliability::Confusion { counts };
    report.mean_time = total_time
        .checked_div(u32::try_from(sortings).unwrap_or(u32::MAX).max(1))
        .unwrap_or_default();
    Ok(report)
}
