//! The ball sorter of the remote sorting lab (the sorting-lab thesis, docs/THESES.md:
//! sections 2, 3, 9 and 13 of its restatement; `BS-Axx` are its numbered
//! interpretations): eight ping-pong balls, an upper reservoir closed by the gates S1 and
//! S2, a balance held shut by the gate S3, three deflectors that send the falling ball
//! into one of four shafts, a shutter over the lower reservoir and a blower that lifts
//! the balls back up.
//!
//! The plant is the mechanism and its field wiring. Its outputs are the actuators as the
//! supervisor drives them (the student's program never reaches them directly); its inputs
//! are the five light barriers and the balance as the DP/RS 232 gateway delivers it
//! (weight and stable flag of the last record). The balance is the devices crate's
//! simulator with the thesis's measured scatter, fed with the balls this mechanism puts on
//! its pan.
//!
//! The Profibus DP exchange between the two PLCs (section 4.4: the EM 277's buffer) is
//! wiring too, so it is here: the sorting PLC drives `Cmd_A` for each actuator `A`, the
//! supervisor reads it as `DP_A` and the sorting PLC reads the actuator as driven back as
//! `Fb_A`. The supervisor samples `DP_A` with its own scan, so a pulse shorter than two of
//! its scans can be lost (section 4.5), as on the model.
//!
//! # Ball path
//!
//! ```text
//!  upper reservoir (queue) ─S1─▶ slot before S2 ─S2─▶ pan (balance, Sn5) ─S3─▶ falls past
//!        ▲   Sn1 = a ball waits at S1   Sn2            deflector 1, 2, 3 (Sn3 pulses)
//!        │                                             extended k ──▶ shaft k; none ──▶ shaft 4
//!        │ blower on ≥ 2 s, shutter closed                            │
//!        └──────────────── lower reservoir (Sn4) ◀── shutter open ────┘
//! ```
//!
//! # Kinematics (the thesis gives the working times, not the strokes; these fit them)
//!
//! - A gate passes a ball only while its solenoid is energised. S1 lets the front ball of
//!   the upper reservoir roll to S2 (0.25 s) when the place before S2 is free; S2 drops
//!   the balls before it onto the pan (0.3 s); S3 lets the balls on the pan roll off
//!   (0.2 s). A ball that arrives at an open gate goes on through it, so S1 and S2 open
//!   together dose two balls, as on the model.
//! - A falling ball passes deflector k 0.1 s × k after leaving the pan and rests in its
//!   shaft 0.3 s later; Sn3 sees it for the first 0.1 s of its fall.
//! - A deflector moves when one of its two solenoids has been energised for 0.6 s without
//!   the other (the supervisor's working time is 1 s): (S4, S5), (S6, S7), (S8, S9) are
//!   deflectors 1-3, the even solenoid extends, the odd one retracts (`BS-A1`). Their
//!   positions after power-on are unknown (drawn from the seed): a program must drive
//!   them first (section 8.4).
//! - The shutter opens after SL2 has been energised for 1.0 s without SL1 and closes
//!   after SL1 for 1.0 s (working time 1.5 s). While it is open the balls in the shafts,
//!   and any ball that reaches a shaft, fall into the lower reservoir (0.4 s).
//! - The blower lifts every ball of the lower reservoir into the upper one once it has run
//!   2 s with the shutter closed (section 13's proposal), in an order drawn from the seed;
//!   when it stops, the balance is disturbed for 30 s (its run-down air).
//! - Tare zeroes the balance on a rising edge of its relay, only when the reading is
//!   stable; the light is an output to show.
//!
//! Every movement is an absolute deadline: [`Plant::advance_to`] walks them in order, so
//! the state does not depend on the step size, and the same seed gives the same run.
//!
//! # Faults (console)
//!
//! | Line | Fault (section 13) |
//! |---|---|
//! | `miss SnN` | the light barrier misses every ball (reads FALSE) |
//! | `double-dose` | the next ball S1 releases takes the one behind it along (once) |
//! | `stuck DK` | deflector K (1-3) does not move |
//! | `balance-link-loss` | the gateway to the balance is silent: weight and stable invalid |
//! | `lose-pulse A` | the next command pulse `Cmd_A` does not reach the supervisor (once) |
//! | `dp-link-loss` | the DP exchange between the PLCs fails: `DP_*` and `Fb_*` invalid |
//! | `dust G` | dust settles on the pan at G grams a minute (0 ends it) |
//!
//! `clear FAULT` and `clear all` end them; `status` shows where every ball is.
//!
//! # The balance's serial port
//!
//! Each record the balance sends is also put on the plant's serial port [`BALANCE_PORT`]
//! (15 characters, 1200 Bd) as the balance's RS-232 would carry it, so a project can read
//! the balance with its serial driver on a pseudo-terminal instead of the gateway's
//! signals; a `balance-link-loss` silences both.

use std::any::Any;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use devices::balance::reader::BALANCE_LINE;
use devices::balance::record;
use devices::balance::simulator::{BalanceConfig, BalanceSimulator, Ball, BALLS};
use rand::rngs::StdRng;
use rand::seq::SliceRandom as _;
use rand::{RngExt as _, SeedableRng as _};

use crate::core::{
    ConsoleOperation, Direction, Module, Plant, PlantError, Reading, SerialPortInfo, SignalInfo,
    SimTime, StatusLine, Value, ValueKind,
};

/// The actuators, in the order of their outputs (and of the supervisor's table 3.2).
pub const ACTUATORS: [&str; 14] = [
    "S1", "S2", "S3", "S4", "S5", "S6", "S7", "S8", "S9", "SL1", "SL2", "Blower", "Tare", "Light",
];

/// The five light barriers (`BS-A1`, `BS-A10`): Sn1 a ball waits at S1, Sn2 a ball waits
/// at S2, Sn3 a ball falls past the deflectors, Sn4 the lower reservoir holds a ball, Sn5
/// a ball lies on the balance.
pub const SENSORS: [&str; 5] = ["Sn1", "Sn2", "Sn3", "Sn4", "Sn5"];

/// The gates' and the ball path's times (see the module documentation).
/// The balance's RS-232 as a serial port of the plant ([`Plant::serial_ports`]).
pub const BALANCE_PORT: &str = "balance";
/// Records kept on the balance's port for a reader that fell behind: its newest ones.
const BALANCE_BACKLOG: usize = 4;

const S1_TO_S2: Duration = Duration::from_millis(250);
const S2_TO_PAN: Duration = Duration::from_millis(300);
const OFF_THE_PAN: Duration = Duration::from_millis(200);
const PER_DEFLECTOR: Duration = Duration::from_millis(100);
const INTO_THE_SHAFT: Duration = Duration::from_millis(300);
const SN3_PULSE: Duration = Duration::from_millis(100);
const DEFLECTOR_STROKE: Duration = Duration::from_millis(600);
const SHUTTER_STROKE: Duration = Duration::from_millis(1000);
const THROUGH_THE_SHUTTER: Duration = Duration::from_millis(400);
const BLOWER_LIFTS_AFTER: Duration = Duration::from_secs(2);

/// Outputs by index in [`ACTUATORS`].
const S1: usize = 0;
const S2: usize = 1;
const S3: usize = 2;
const SL1: usize = 9;
const SL2: usize = 10;
const BLOWER: usize = 11;
const TARE: usize = 12;

/// How the sorter starts.
#[derive(Debug, Clone, PartialEq)]
pub struct SorterConfig {
    /// Seed of the balls' order, the deflectors' positions at power-on and the balance's
    /// weighing errors.
    pub seed: u64,
    /// The balls (default: the eight of table 5.1).
    pub balls: Vec<Ball>,
    /// Balance records a second (the thesis's balance sent 2-4).
    pub records_per_second: f64,
    /// Where the balls are at power-on.
    pub start: StartState,
}

impl Default for SorterConfig {
    fn default() -> SorterConfig {
        SorterConfig {
            seed: 0,
            balls: BALLS.to_vec(),
            records_per_second: 3.0,
            start: StartState::UpperReservoir,
        }
    }
}

/// Where the balls are at power-on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartState {
    /// In the upper reservoir (the model's starting state after blowing).
    UpperReservoir,
    /// Two in each shaft, as a previous sorting left them.
    Shafts,
    /// In the lower reservoir (the shafts emptied).
    LowerReservoir,
}

/// Where a ball is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Place {
    /// In the upper reservoir's tube (its position in the queue is [`SorterPlant::upper`]).
    Upper,
    /// Rolling from S1 to S2.
    RollingToS2,
    /// Waiting at S2.
    BeforeS2,
    /// Dropping from S2 onto the pan.
    DroppingOnPan,
    /// On the balance.
    Pan,
    /// Falling past the deflectors.
    Falling,
    /// In shaft 1-4.
    Shaft(u8),
    /// In the lower reservoir (or falling into it).
    Lower,
}

/// A ball that came to rest in a shaft: the sorter's result, one line per arrival.
#[derive(Debug, Clone, PartialEq)]
pub struct Arrival {
    /// When.
    pub at: SimTime,
    /// The ball's name (`red 1`).
    pub ball: &'static str,
    /// The shaft (1-4).
    pub shaft: u8,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Action {
    /// A ball rolled from S1 to S2.
    ReachS2(usize),
    /// A ball lands on the pan.
    ReachPan(usize),
    /// A ball rolls off the pan.
    LeavePan(usize),
    /// A falling ball passes deflector k (0-based).
    PassDeflector { ball: usize, deflector: usize },
    /// A ball comes to rest in a shaft (1-4).
    ReachShaft { ball: usize, shaft: u8 },
    /// A ball reaches the lower reservoir through the open shutter.
    ReachLower(usize),
    /// A solenoid energised since `since` completes its stroke.
    Stroke { output: usize, since: SimTime },
    /// The blower, on since `since`, lifts the balls.
    Lift { since: SimTime },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Due {
    at: SimTime,
    order: u64,
}

/// The mechanism.
#[derive(Debug)]
pub struct SorterPlant {
    now: SimTime,
    config: SorterConfig,
    rng: StdRng,
    signals: Vec<SignalInfo>,
    modules: Vec<Module>,
    /// The actuators as the supervisor drives them.
    commanded: [bool; ACTUATORS.len()],
    /// Since when each actuator has been effectively energised (a lost pulse is not).
    energised_since: [Option<SimTime>; ACTUATORS.len()],
    places: Vec<Place>,
    /// The upper reservoir, front ball (the one at S1) first.
    upper: Vec<usize>,
    /// Deflectors 1-3: extended.
    deflectors: [bool; 3],
    shutter_open: bool,
    agenda: BTreeMap<Due, Action>,
    next_order: u64,
    sn3_until: SimTime,
    balance: BalanceSimulator,
    /// The balance simulator counts in `Instant`s; only differences from this origin
    /// matter.
    origin: Instant,
    next_record: SimTime,
    weight_g: f64,
    stable: bool,
    /// The balance's records not yet taken from its serial port ([`BALANCE_PORT`]):
    /// whole records, at most [`BALANCE_BACKLOG`] of them.
    balance_line: Vec<u8>,
    /// The sorting PLC's commands on the DP bus.
    dp_commands: [bool; ACTUATORS.len()],
    /// Commands whose next pulse is to be lost, and those being lost until they fall.
    dp_to_lose: [bool; ACTUATORS.len()],
    dp_losing: [bool; ACTUATORS.len()],
    missed: [bool; 5],
    double_dose: bool,
    stuck: [bool; 3],
    dust_g_per_min: f64,
    arrivals: Vec<Arrival>,
    notes: Vec<String>,
}

impl SorterPlant {
    /// A sorter in its power-on state.
    pub fn new(config: SorterConfig) -> SorterPlant {
        let mut rng = StdRng::seed_from_u64(config.seed);
        let deflectors = [rng.random(), rng.random(), rng.random()];
        let count = config.balls.len();
        let mut order: Vec<usize> = (0..count).collect();
        order.shuffle(&mut rng);
        let (places, upper) = match config.start {
            StartState::UpperReservoir => (vec![Place::Upper; count], order),
            StartState::LowerReservoir => (vec![Place::Lower; count], Vec::new()),
            StartState::Shafts => {
                let mut places = vec![Place::Lower; count];
                for (index, ball) in order.iter().enumerate() {
                    if let Some(place) = places.get_mut(*ball) {
                        *place = Place::Shaft(u8::try_from(index % 4 + 1).unwrap_or(4));
                    }
                }
                (places, Vec::new())
            }
        };
        let balance = BalanceSimulator::new(
            BalanceConfig {
                records_per_second: config.records_per_second,
                seed: config.seed ^ 0x5a5a_5a5a,
                ..BalanceConfig::default()
            },
            Self::origin(),
        );
        let mut signals = Vec::new();
        for name in ACTUATORS {
            signals.push(SignalInfo {
                name: name.to_owned(),
                direction: Direction::Output,
                kind: ValueKind::Bool,
                module: "ACTUATORS".to_owned(),
                unit: "",
                description: actuator_meaning(name).to_owned(),
            });
        }
        for name in SENSORS {
            signals.push(SignalInfo {
                name: name.to_owned(),
                direction: Direction::Input,
                kind: ValueKind::Bool,
                module: "SENSORS".to_owned(),
                unit: "",
                description: sensor_meaning(name).to_owned(),
            });
        }
        signals.push(SignalInfo {
            name: "Balance_g".to_owned(),
            direction: Direction::Input,
            kind: ValueKind::Real,
            module: "BALANCE".to_owned(),
            unit: "g",
            description: "the balance's last record: weight".to_owned(),
        });
        signals.push(SignalInfo {
            name: "Balance_ug".to_owned(),
            direction: Direction::Input,
            kind: ValueKind::Real,
            module: "BALANCE".to_owned(),
            unit: "µg",
            description: "the balance's last record: weight in micrograms, a whole number as \
                          the gateway hands it to the PLC (a DINT)"
                .to_owned(),
        });
        signals.push(SignalInfo {
            name: "Balance_stable".to_owned(),
            direction: Direction::Input,
            kind: ValueKind::Bool,
            module: "BALANCE".to_owned(),
            unit: "",
            description: "the balance's last record: stable".to_owned(),
        });
        for name in ACTUATORS {
            for (prefix, direction, description) in [
                ("Cmd_", Direction::Output, "the sorting PLC's command for"),
                (
                    "DP_",
                    Direction::Input,
                    "the supervisor's input: the command for",
                ),
                (
                    "Fb_",
                    Direction::Input,
                    "back to the sorting PLC: the supervisor drives",
                ),
            ] {
                signals.push(SignalInfo {
                    name: format!("{prefix}{name}"),
                    direction,
                    kind: ValueKind::Bool,
                    module: "DP".to_owned(),
                    unit: "",
                    description: format!("{description} {name} (Profibus DP)"),
                });
            }
        }
        let modules = ["ACTUATORS", "SENSORS", "BALANCE", "DP"]
            .into_iter()
            .map(|name| Module {
                name: name.to_owned(),
                present: true,
                linked: true,
            })
            .collect();
        SorterPlant {
            now: Duration::ZERO,
            rng,
            signals,
            modules,
            commanded: [false; ACTUATORS.len()],
            energised_since: [None; ACTUATORS.len()],
            places,
            upper,
            deflectors,
            shutter_open: false,
            agenda: BTreeMap::new(),
            next_order: 0,
            sn3_until: Duration::ZERO,
            balance,
            origin: Self::origin(),
            next_record: Duration::ZERO,
            weight_g: 0.0,
            stable: true,
            balance_line: Vec::new(),
            dp_commands: [false; ACTUATORS.len()],
            dp_to_lose: [false; ACTUATORS.len()],
            dp_losing: [false; ACTUATORS.len()],
            missed: [false; 5],
            double_dose: false,
            stuck: [false; 3],
            dust_g_per_min: 0.0,
            arrivals: Vec::new(),
            notes: Vec::new(),
            config,
        }
    }

    #[allow(
        clippy::disallowed_methods,
        reason = "an origin for the balance simulator's Instants: only differences from it are used, so runs stay deterministic"
    )]
    fn origin() -> Instant {
        Instant::now()
    }

    /// The balls, as configured.
    pub fn balls(&self) -> &[Ball] {
        &self.config.balls
    }

    /// Where ball `index` is.
    pub fn place(&self, index: usize) -> Option<Place> {
        self.places.get(index).copied()
    }

    /// The upper reservoir's balls, the one at S1 first.
    pub fn upper(&self) -> Vec<&'static str> {
        self.upper.iter().map(|ball| self.name(*ball)).collect()
    }

    /// The balls in shaft 1-4.
    pub fn shaft(&self, shaft: u8) -> Vec<&'static str> {
        self.balls_at(Place::Shaft(shaft))
    }

    /// The balls at `place`.
    pub fn balls_at(&self, place: Place) -> Vec<&'static str> {
        (0..self.places.len())
            .filter(|ball| self.places.get(*ball) == Some(&place))
            .map(|ball| self.name(ball))
            .collect()
    }

    /// Every ball that came to rest in a shaft, in order.
    pub fn arrivals(&self) -> &[Arrival] {
        &self.arrivals
    }

    /// Deflector 1-3 extended (`None` for another number).
    pub fn deflector_extended(&self, deflector: usize) -> Option<bool> {
        self.deflectors.get(deflector.wrapping_sub(1)).copied()
    }

    /// The shutter over the lower reservoir is open.
    pub fn shutter_open(&self) -> bool {
        self.shutter_open
    }

    /// The true mass on the pan (grams), without the balance's scatter.
    pub fn mass_on_pan(&self) -> f64 {
        self.on_pan()
            .iter()
            .map(|ball| self.ball(*ball).mean_3s)
            .sum()
    }

    fn name(&self, ball: usize) -> &'static str {
        self.config.balls.get(ball).map_or("?", |ball| ball.name)
    }

    fn ball(&self, ball: usize) -> Ball {
        self.config.balls.get(ball).copied().unwrap_or(Ball {
            name: "?",
            mean_3s: 0.0,
            sd_3s: 0.0,
            mean_15s: 0.0,
            sd_15s: 0.0,
        })
    }

    fn on_pan(&self) -> Vec<usize> {
        (0..self.places.len())
            .filter(|ball| self.places.get(*ball) == Some(&Place::Pan))
            .collect()
    }

    fn set_place(&mut self, ball: usize, place: Place) {
        if let Some(slot) = self.places.get_mut(ball) {
            *slot = place;
        }
    }

    fn at(&self, t: SimTime) -> Instant {
        self.origin + t
    }

    fn schedule(&mut self, after: Duration, action: Action) {
        let due = Due {
            at: self.now + after,
            order: self.next_order,
        };
        self.next_order += 1;
        self.agenda.insert(due, action);
    }

    fn energised(&self, output: usize) -> bool {
        self.energised_since
            .get(output)
            .copied()
            .flatten()
            .is_some()
    }

    /// What the gates let through now: run after every change of an output or a place.
    fn gates(&mut self) {
        // S1: the front ball rolls to S2 when the place before S2 is free.
        let slot_free =
            !self.places.contains(&Place::BeforeS2) && !self.places.contains(&Place::RollingToS2);
        if self.energised(S1) && slot_free && !self.upper.is_empty() {
            let mut released = vec![self.upper.remove(0)];
            if self.double_dose && !self.upper.is_empty() {
                self.double_dose = false;
                released.push(self.upper.remove(0));
            }
            for ball in released {
                self.set_place(ball, Place::RollingToS2);
                self.schedule(S1_TO_S2, Action::ReachS2(ball));
            }
        }
        self.release_at_s2();
        self.release_from_pan();
    }

    /// S2 open: the balls waiting before it drop onto the pan.
    fn release_at_s2(&mut self) {
        if !self.energised(S2) {
            return;
        }
        let resting: Vec<usize> = (0..self.places.len())
            .filter(|ball| self.places.get(*ball) == Some(&Place::BeforeS2))
            .collect();
        for ball in resting {
            self.set_place(ball, Place::DroppingOnPan);
            self.schedule(S2_TO_PAN, Action::ReachPan(ball));
        }
    }

    /// S3 open: the balls on the pan roll off.
    fn release_from_pan(&mut self) {
        if !self.energised(S3) {
            return;
        }
        let leaving: Vec<usize> = self
            .agenda
            .values()
            .filter_map(|action| match action {
                Action::LeavePan(ball) => Some(*ball),
                _ => None,
            })
            .collect();
        for ball in self.on_pan() {
            if !leaving.contains(&ball) {
                self.schedule(OFF_THE_PAN, Action::LeavePan(ball));
            }
        }
    }

    /// The pan's load changed: the balance sees the balls now on it.
    fn load_changed(&mut self) {
        let on_pan = self.on_pan();
        let now = self.at(self.now);
        match on_pan.as_slice() {
            [] => self.balance.remove(now),
            [ball] => {
                let ball = self.ball(*ball);
                self.balance.put(ball, now);
            }
            several => {
                let balls: Vec<Ball> = several.iter().map(|ball| self.ball(*ball)).collect();
                let sum = |f: fn(&Ball) -> f64| balls.iter().map(f).sum::<f64>();
                let root =
                    |f: fn(&Ball) -> f64| balls.iter().map(|b| f(b) * f(b)).sum::<f64>().sqrt();
                self.balance.put(
                    Ball {
                        name: "several balls",
                        mean_3s: sum(|b| b.mean_3s),
                        sd_3s: root(|b| b.sd_3s),
                        mean_15s: sum(|b| b.mean_15s),
                        sd_15s: root(|b| b.sd_15s),
                    },
                    now,
                );
            }
        }
    }

    fn fire_due(&mut self, due: Due) {
        self.now = due.at;
        if let Some(action) = self.agenda.remove(&due) {
            self.fire(action);
        }
    }

    fn fire(&mut self, action: Action) {
        match action {
            Action::ReachS2(ball) => self.set_place(ball, Place::BeforeS2),
            Action::ReachPan(ball) => {
                self.set_place(ball, Place::Pan);
                self.load_changed();
                self.release_from_pan();
            }
            Action::LeavePan(ball) => {
                if self.place(ball) == Some(Place::Pan) {
                    self.set_place(ball, Place::Falling);
                    self.load_changed();
                    self.sn3_until = self.now + SN3_PULSE;
                    self.schedule(PER_DEFLECTOR, Action::PassDeflector { ball, deflector: 0 });
                }
            }
            Action::PassDeflector { ball, deflector } => {
                if self.deflectors.get(deflector).copied().unwrap_or(false) {
                    let shaft = u8::try_from(deflector + 1).unwrap_or(4);
                    self.schedule(INTO_THE_SHAFT, Action::ReachShaft { ball, shaft });
                } else if deflector + 1 < self.deflectors.len() {
                    self.schedule(
                        PER_DEFLECTOR,
                        Action::PassDeflector {
                            ball,
                            deflector: deflector + 1,
                        },
                    );
                } else {
                    self.schedule(INTO_THE_SHAFT, Action::ReachShaft { ball, shaft: 4 });
                }
            }
            Action::ReachShaft { ball, shaft } => {
                self.set_place(ball, Place::Shaft(shaft));
                self.arrivals.push(Arrival {
                    at: self.now,
                    ball: self.name(ball),
                    shaft,
                });
                if self.shutter_open {
                    self.schedule(THROUGH_THE_SHUTTER, Action::ReachLower(ball));
                }
            }
            Action::ReachLower(ball) => self.set_place(ball, Place::Lower),
            Action::Stroke { output, since } => {
                if self.energised_since.get(output).copied().flatten() != Some(since) {
                    return;
                }
                self.stroke(output);
            }
            Action::Lift { since } => {
                if self.energised_since.get(BLOWER).copied().flatten() != Some(since)
                    || self.shutter_open
                {
                    return;
                }
                let mut lifted: Vec<usize> = (0..self.places.len())
                    .filter(|ball| self.places.get(*ball) == Some(&Place::Lower))
                    .collect();
                lifted.shuffle(&mut self.rng);
                for ball in lifted {
                    self.set_place(ball, Place::Upper);
                    self.upper.push(ball);
                }
            }
        }
        self.gates();
    }

    /// A solenoid held for its stroke moves its deflector or the shutter, unless its
    /// partner pulls against it.
    fn stroke(&mut self, output: usize) {
        let partner = if output % 2 == 1 {
            output + 1
        } else {
            output - 1
        };
        if self.energised(partner) {
            return;
        }
        match output {
            3..=8 => {
                let deflector = (output - 3) / 2;
                if self.stuck.get(deflector).copied().unwrap_or(false) {
                    return;
                }
                if let Some(position) = self.deflectors.get_mut(deflector) {
                    *position = output % 2 == 1;
                }
            }
            SL1 => self.shutter_open = false,
            SL2 if !self.shutter_open => {
                self.shutter_open = true;
                let shafts: Vec<usize> = (0..self.places.len())
                    .filter(|ball| matches!(self.places.get(*ball), Some(Place::Shaft(_))))
                    .collect();
                for ball in shafts {
                    self.schedule(THROUGH_THE_SHUTTER, Action::ReachLower(ball));
                }
            }
            _ => {}
        }
    }

    fn output_changed(&mut self, output: usize, on: bool) {
        let was = self.commanded.get(output).copied().unwrap_or(false);
        if let Some(slot) = self.commanded.get_mut(output) {
            *slot = on;
        }
        if was == on {
            return;
        }
        if !on {
            if let Some(since) = self.energised_since.get_mut(output) {
                *since = None;
            }
            if output == BLOWER {
                let now = self.at(self.now);
                self.balance.blower_stopped(now);
            }
            return;
        }
        if let Some(since) = self.energised_since.get_mut(output) {
            *since = Some(self.now);
        }
        let since = self.now;
        match output {
            3..=8 => self.schedule(DEFLECTOR_STROKE, Action::Stroke { output, since }),
            SL1 | SL2 => self.schedule(SHUTTER_STROKE, Action::Stroke { output, since }),
            BLOWER => self.schedule(BLOWER_LIFTS_AFTER, Action::Lift { since }),
            TARE => {
                let now = self.at(self.now);
                if self.balance.tare(now).is_err() {
                    self.notes
                        .push("tare refused: the reading is not stable".to_owned());
                }
            }
            _ => {}
        }
        self.gates();
    }

    fn dp_command(&mut self, index: usize, on: bool) {
        let was = self.dp_commands.get(index).copied().unwrap_or(false);
        if let Some(command) = self.dp_commands.get_mut(index) {
            *command = on;
        }
        if on && !was && self.dp_to_lose.get(index).copied().unwrap_or(false) {
            if let Some(lose) = self.dp_to_lose.get_mut(index) {
                *lose = false;
            }
            if let Some(losing) = self.dp_losing.get_mut(index) {
                *losing = true;
            }
            self.notes.push(format!(
                "a pulse of {} lost on its way to the supervisor",
                ACTUATORS.get(index).unwrap_or(&"?")
            ));
        }
        if !on {
            if let Some(losing) = self.dp_losing.get_mut(index) {
                *losing = false;
            }
        }
    }

    fn record(&mut self) {
        let now = self.at(self.now);
        let reading = self.balance.reading(now);
        if self.modules.get(2).is_some_and(Module::valid) {
            self.weight_g = reading.weight_g;
            self.stable = reading.stable;
            // The same record on the balance's own RS-232 (a silent link sends nothing).
            let record = record::format(reading.weight_g, reading.stable);
            let excess = (self.balance_line.len() + record.len())
                .saturating_sub(BALANCE_BACKLOG * record::RECORD_LEN);
            self.balance_line
                .drain(..excess.min(self.balance_line.len()));
            self.balance_line.extend_from_slice(&record);
        }
    }

    fn record_period(&self) -> Duration {
        Duration::from_secs_f64(1.0 / self.config.records_per_second.clamp(0.1, 10.0))
    }

    fn sensor(&self, index: usize) -> bool {
        if self.missed.get(index).copied().unwrap_or(false) {
            return false;
        }
        match index {
            0 => !self.upper.is_empty(),
            1 => self.places.contains(&Place::BeforeS2),
            2 => self.now < self.sn3_until,
            3 => self.places.contains(&Place::Lower),
            _ => self.places.contains(&Place::Pan),
        }
    }

    fn bad_line(line: &str) -> PlantError {
        PlantError::BadConsoleLine {
            line: line.to_owned(),
            expected:
                "miss SnN, double-dose, stuck DK, balance-link-loss, lose-pulse A, dp-link-loss, \
                       dust G, clear FAULT, clear all"
                    .to_owned(),
        }
    }

    fn sensor_index(name: &str) -> Result<usize, PlantError> {
        SENSORS
            .iter()
            .position(|sensor| sensor.eq_ignore_ascii_case(name))
            .ok_or_else(|| PlantError::UnknownName {
                kind: "sensor",
                name: name.to_owned(),
                allowed: SENSORS.iter().map(|s| (*s).to_owned()).collect(),
            })
    }

    fn deflector_index(name: &str) -> Result<usize, PlantError> {
        ["D1", "D2", "D3"]
            .iter()
            .position(|d| d.eq_ignore_ascii_case(name))
            .ok_or_else(|| PlantError::UnknownName {
                kind: "deflector",
                name: name.to_owned(),
                allowed: vec!["D1".to_owned(), "D2".to_owned(), "D3".to_owned()],
            })
    }

    fn set_balance_link(&mut self, linked: bool) {
        if let Some(module) = self.modules.get_mut(2) {
            module.linked = linked;
        }
    }

    fn fault(&mut self, line: &str, on: bool) -> Result<(), PlantError> {
        let words: Vec<&str> = line.split_whitespace().collect();
        let op = words.first().map(|w| w.to_ascii_lowercase());
        match (op.as_deref(), words.get(1..).unwrap_or_default()) {
            (Some("miss"), [sensor]) => {
                let index = Self::sensor_index(sensor)?;
                if let Some(missed) = self.missed.get_mut(index) {
                    *missed = on;
                }
            }
            (Some("double-dose"), []) => self.double_dose = on,
            (Some("stuck"), [deflector]) => {
                let index = Self::deflector_index(deflector)?;
                if let Some(stuck) = self.stuck.get_mut(index) {
                    *stuck = on;
                }
            }
            (Some("balance-link-loss"), []) => self.set_balance_link(!on),
            (Some("dp-link-loss"), []) => {
                if let Some(module) = self.modules.get_mut(3) {
                    module.linked = !on;
                }
            }
            (Some("lose-pulse"), [actuator]) => {
                let index = ACTUATORS
                    .iter()
                    .position(|a| a.eq_ignore_ascii_case(actuator))
                    .ok_or_else(|| PlantError::UnknownName {
                        kind: "actuator",
                        name: (*actuator).to_owned(),
                        allowed: ACTUATORS.iter().map(|a| (*a).to_owned()).collect(),
                    })?;
                if let Some(lose) = self.dp_to_lose.get_mut(index) {
                    *lose = on;
                }
            }
            (Some("dust"), [rate]) if on => {
                let rate: f64 = rate
                    .parse()
                    .ok()
                    .filter(|r: &f64| r.is_finite() && *r >= 0.0)
                    .ok_or_else(|| Self::bad_line(line))?;
                self.dust_g_per_min = rate;
                self.balance.set_dust(rate);
            }
            (Some("dust"), []) if !on => {
                self.dust_g_per_min = 0.0;
                self.balance.set_dust(0.0);
            }
            _ => return Err(Self::bad_line(line)),
        }
        Ok(())
    }
}

fn actuator_meaning(name: &str) -> &'static str {
    match name {
        "S1" => "gate S1 of the upper reservoir (energised: open)",
        "S2" => "gate S2: releases one ball onto the balance",
        "S3" => "gate S3 at the balance: releases the weighed ball",
        "S4" => "deflector 1: extend",
        "S5" => "deflector 1: retract",
        "S6" => "deflector 2: extend",
        "S7" => "deflector 2: retract",
        "S8" => "deflector 3: extend",
        "S9" => "deflector 3: retract",
        "SL1" => "shutter of the lower reservoir: close",
        "SL2" => "shutter of the lower reservoir: open",
        "Blower" => "blower: lifts the balls to the upper reservoir",
        "Tare" => "relay on the balance's Tare key",
        _ => "the model's lighting (for the camera at night)",
    }
}

fn sensor_meaning(name: &str) -> &'static str {
    match name {
        "Sn1" => "a ball waits at gate S1",
        "Sn2" => "a ball waits at gate S2",
        "Sn3" => "a ball falls past the deflectors",
        "Sn4" => "a ball is in the lower reservoir",
        _ => "a ball lies on the balance",
    }
}

impl Plant for SorterPlant {
    fn now(&self) -> SimTime {
        self.now
    }

    fn next_event(&self) -> Option<SimTime> {
        let mut next = self.next_record;
        if let Some(due) = self.agenda.keys().next() {
            next = next.min(due.at);
        }
        if self.sn3_until > self.now {
            next = next.min(self.sn3_until);
        }
        Some(next)
    }

    fn advance_to(&mut self, t: SimTime) -> Result<(), PlantError> {
        if t < self.now {
            return Err(PlantError::TimeWentBackwards {
                now: self.now,
                requested: t,
            });
        }
        loop {
            let due = self.agenda.keys().next().copied().filter(|due| due.at <= t);
            let record = (self.next_record <= t).then_some(self.next_record);
            // Movements before a record at the same instant: the record sees them.
            match (due, record) {
                (Some(due), None) => self.fire_due(due),
                (Some(due), Some(at)) if due.at <= at => self.fire_due(due),
                (_, Some(at)) => {
                    self.now = at;
                    self.record();
                    self.next_record = at + self.record_period();
                }
                (None, None) => break,
            }
        }
        self.now = t;
        Ok(())
    }

    fn signals(&self) -> &[SignalInfo] {
        &self.signals
    }

    fn read(&self, name: &str) -> Result<Reading, PlantError> {
        if let Some(index) = ACTUATORS.iter().position(|a| *a == name) {
            return Ok(Reading {
                value: Value::Bool(self.commanded.get(index).copied().unwrap_or(false)),
                valid: true,
            });
        }
        if let Some(index) = SENSORS.iter().position(|s| *s == name) {
            return Ok(Reading {
                value: Value::Bool(self.sensor(index)),
                valid: true,
            });
        }
        let dp_valid = self.modules.get(3).is_some_and(Module::valid);
        let dp = |prefix: &str| {
            name.strip_prefix(prefix)
                .and_then(|actuator| ACTUATORS.iter().position(|a| *a == actuator))
        };
        if let Some(index) = dp("Cmd_") {
            return Ok(Reading {
                value: Value::Bool(self.dp_commands.get(index).copied().unwrap_or(false)),
                valid: true,
            });
        }
        if let Some(index) = dp("DP_") {
            let on = self.dp_commands.get(index).copied().unwrap_or(false)
                && !self.dp_losing.get(index).copied().unwrap_or(false);
            return Ok(Reading {
                value: Value::Bool(on),
                valid: dp_valid,
            });
        }
        if let Some(index) = dp("Fb_") {
            return Ok(Reading {
                value: Value::Bool(self.commanded.get(index).copied().unwrap_or(false)),
                valid: dp_valid,
            });
        }
        let valid = self.modules.get(2).is_some_and(Module::valid);
        match name {
            "Balance_g" => Ok(Reading {
                value: Value::Real(self.weight_g),
                valid,
            }),
            "Balance_ug" => Ok(Reading {
                value: Value::Real((self.weight_g * 1e6).round()),
                valid,
            }),
            "Balance_stable" => Ok(Reading {
                value: Value::Bool(self.stable),
                valid,
            }),
            _ => Err(PlantError::UnknownSignal(name.to_owned())),
        }
    }

    fn set_output(&mut self, name: &str, value: Value) -> Result<(), PlantError> {
        if let Some(index) = name
            .strip_prefix("Cmd_")
            .and_then(|actuator| ACTUATORS.iter().position(|a| *a == actuator))
        {
            let Value::Bool(on) = value else {
                return Err(PlantError::WrongType {
                    name: name.to_owned(),
                    expected: ValueKind::Bool,
                    got: value.kind(),
                });
            };
            self.dp_command(index, on);
            return Ok(());
        }
        let Some(index) = ACTUATORS.iter().position(|a| *a == name) else {
            return Err(if self.signals.iter().any(|s| s.name == name) {
                PlantError::NotAnOutput(name.to_owned())
            } else {
                PlantError::UnknownSignal(name.to_owned())
            });
        };
        let Value::Bool(on) = value else {
            return Err(PlantError::WrongType {
                name: name.to_owned(),
                expected: ValueKind::Bool,
                got: value.kind(),
            });
        };
        self.output_changed(index, on);
        Ok(())
    }

    fn modules(&self) -> &[Module] {
        &self.modules
    }

    fn serial_ports(&self) -> Vec<SerialPortInfo> {
        vec![SerialPortInfo {
            name: BALANCE_PORT.to_owned(),
            description: "the balance's RS-232: its 15-character records, 2-4 a second".to_owned(),
            line: BALANCE_LINE,
        }]
    }

    fn take_serial_output(&mut self, port: &str) -> Vec<u8> {
        if port == BALANCE_PORT {
            std::mem::take(&mut self.balance_line)
        } else {
            Vec::new()
        }
    }

    fn serial_input(&mut self, port: &str, _octets: &[u8]) -> Result<(), PlantError> {
        if port == BALANCE_PORT {
            // The balance's RxD is not connected (the thesis's balance only sends).
            Ok(())
        } else {
            Err(PlantError::UnknownName {
                kind: "serial port",
                name: port.to_owned(),
                allowed: vec![BALANCE_PORT.to_owned()],
            })
        }
    }

    fn console(&mut self, line: &str) -> Result<(), PlantError> {
        let trimmed = line.trim();
        if trimmed.eq_ignore_ascii_case("clear all") {
            self.missed = [false; 5];
            self.double_dose = false;
            self.stuck = [false; 3];
            self.set_balance_link(true);
            if let Some(module) = self.modules.get_mut(3) {
                module.linked = true;
            }
            self.dp_to_lose = [false; ACTUATORS.len()];
            self.dust_g_per_min = 0.0;
            self.balance.set_dust(0.0);
            return Ok(());
        }
        if let Some(rest) = trimmed
            .strip_prefix("clear ")
            .or_else(|| trimmed.strip_prefix("CLEAR "))
        {
            return self.fault(rest, false);
        }
        self.fault(trimmed, true)
    }

    fn console_operations(&self) -> Vec<ConsoleOperation> {
        let names = |kind: &str, names: &[&str]| {
            (
                Some(kind.to_owned()),
                names.iter().map(|n| (*n).to_owned()).collect(),
            )
        };
        let mut operations = Vec::new();
        for (usage, (names_kind, names)) in [
            ("miss SENSOR", names("sensor", &SENSORS)),
            ("double-dose", (None, Vec::new())),
            ("stuck DEFLECTOR", names("deflector", &["D1", "D2", "D3"])),
            ("balance-link-loss", (None, Vec::new())),
            ("lose-pulse ACTUATOR", names("actuator", &ACTUATORS)),
            ("dp-link-loss", (None, Vec::new())),
        ] {
            operations.push(ConsoleOperation {
                usage,
                fault: true,
                names_kind,
                names,
            });
        }
        operations.push(ConsoleOperation {
            usage: "dust G_PER_MIN",
            fault: true,
            names_kind: None,
            names: Vec::new(),
        });
        operations
    }

    fn status(&self) -> Vec<StatusLine> {
        let list = |balls: Vec<&'static str>| {
            if balls.is_empty() {
                "empty".to_owned()
            } else {
                balls.join(", ")
            }
        };
        let mut places = vec![format!("upper: {}", list(self.upper()))];
        places.push(format!("at S2: {}", list(self.balls_at(Place::BeforeS2))));
        places.push(format!("pan: {}", list(self.balls_at(Place::Pan))));
        for shaft in 1..=4 {
            places.push(format!("shaft {shaft}: {}", list(self.shaft(shaft))));
        }
        places.push(format!("lower: {}", list(self.balls_at(Place::Lower))));
        let deflectors = self
            .deflectors
            .iter()
            .enumerate()
            .map(|(k, extended)| {
                format!(
                    "D{} {}",
                    k + 1,
                    if *extended { "extended" } else { "retracted" }
                )
            })
            .chain(std::iter::once(format!(
                "shutter {}",
                if self.shutter_open { "open" } else { "closed" }
            )))
            .collect();
        let energised = ACTUATORS
            .iter()
            .zip(self.commanded)
            .filter(|(_, on)| *on)
            .map(|(name, _)| (*name).to_owned())
            .collect();
        let mut faults = Vec::new();
        for (sensor, missed) in SENSORS.iter().zip(self.missed) {
            if missed {
                faults.push(format!("miss {sensor}"));
            }
        }
        if self.double_dose {
            faults.push("double-dose".to_owned());
        }
        for (k, stuck) in self.stuck.iter().enumerate() {
            if *stuck {
                faults.push(format!("stuck D{}", k + 1));
            }
        }
        if !self.modules.get(2).is_some_and(Module::valid) {
            faults.push("balance-link-loss".to_owned());
        }
        if !self.modules.get(3).is_some_and(Module::valid) {
            faults.push("dp-link-loss".to_owned());
        }
        for (actuator, lose) in ACTUATORS.iter().zip(self.dp_to_lose) {
            if lose {
                faults.push(format!("lose-pulse {actuator}"));
            }
        }
        if self.dust_g_per_min > 0.0 {
            faults.push(format!("dust {}", self.dust_g_per_min));
        }
        vec![
            StatusLine {
                label: "balls",
                items: places,
            },
            StatusLine {
                label: "deflectors",
                items: deflectors,
            },
            StatusLine {
                label: "energised",
                items: energised,
            },
            StatusLine {
                label: "balance",
                items: vec![format!(
                    "{:.3} g{}",
                    self.weight_g,
                    if self.stable { " stable" } else { "" }
                )],
            },
            StatusLine {
                label: "faults",
                items: faults,
            },
            StatusLine {
                label: "notes",
                items: self.notes.iter().rev().take(5).cloned().collect(),
            },
        ]
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
