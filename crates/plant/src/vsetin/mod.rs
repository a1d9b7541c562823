//! The Vsetín railway station plant: the 6 kV switchroom R6 with its by-pass RS602,
//! transformers, boards RH1.1, RH1.2, RH2, RZZ, RDA, RZS1, RZS2 (TO), RH and RZS in DT, the
//! universal source of the signalling equipment, the diesel generator set, 12 lighting
//! towers (ROV) and the OŘ-area lighting.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::time::Duration;

use crate::core::{
    ConsoleOperation, Module, Plant, PlantError, Reading, SignalInfo, SimTime, StatusLine, Value,
    ValueKind,
};
use crate::devices::{earliest, Breaker, Delayed, Generator, GeneratorConfig, GeneratorState};
use crate::sun::{Sky, SunConfig};
use crate::topology::{Network, SafetyEvent, SafetyKind, TopologySnapshot};
use fault::{resolve_device, Action, DeviceKind, Fault};

mod build;
pub mod fault;

const NANOS: i128 = 1_000_000_000;
/// Safety records kept; later ones are counted in [`VsetinPlant::safety_dropped`].
const SAFETY_LOG_CAP: usize = 100_000;

/// Parameters of the station plant. Every time is a default proposal (the thesis gives
/// none) and can be changed per test.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct StationConfig {
    /// UTC time of simulated time zero, seconds since the Unix epoch (default
    /// 2024-01-01T00:00:00Z). Used by the sun model only.
    pub start_unix_secs: i64,
    /// Motorised breaker (QF) closing time, coil edge to main contacts closed.
    pub breaker_close_time: Duration,
    /// Breaker opening time, trip coil (or emergency-off release) to contacts open. Also
    /// used for a manual breaker tripped by its protection.
    pub breaker_open_time: Duration,
    /// Contactor pick-up time (coil energised to contacts closed).
    pub contactor_pickup: Duration,
    /// Contactor drop-out time (coil de-energised to contacts open).
    pub contactor_dropout: Duration,
    /// Voltage-present relays (KHU): pick-up and drop-out time.
    pub relay_time: Duration,
    /// Lamp-circuit feedback relay `PrRele`: pick-up time after the circuit is energised
    /// (it drops out at once).
    pub feedback_pickup: Duration,
    /// Lamp warm-up: light output ramps linearly from 0 to 100 % over this time.
    pub lamp_warm_up: Duration,
    /// Diesel generator.
    pub generator: GeneratorConfig,
    /// Sky over the site.
    pub sun: SunConfig,
    /// Dusk sensors switch to "dark" below this illuminance.
    pub dusk_threshold_lux: f64,
    /// Electrical load of one lighting tower, kW.
    pub tower_power_kw: f64,
    /// Electrical load of the OŘ-area lighting, kW.
    pub or_power_kw: f64,
    /// Emergency-off of RH2/RZZ also trips QF1 through a hard-wired release (besides the
    /// LOGO! logic). RDA's emergency-off always cuts both contactor coils.
    pub estop_trips_feeder: bool,
    /// QF1 of RH2 and RZZ are closed at time zero.
    pub feeders_initially_closed: bool,
}

impl Default for StationConfig {
    fn default() -> Self {
        StationConfig {
            start_unix_secs: 1_704_067_200,
            breaker_close_time: Duration::from_millis(60),
            breaker_open_time: Duration::from_millis(40),
            contactor_pickup: Duration::from_millis(30),
            contactor_dropout: Duration::from_millis(20),
            relay_time: Duration::from_millis(20),
            feedback_pickup: Duration::from_millis(50),
            lamp_warm_up: Duration::from_secs(3),
            generator: GeneratorConfig::default(),
            sun: SunConfig::default(),
            dusk_threshold_lux: 20.0,
            tower_power_kw: 2.4,
            or_power_kw: 6.0,
            estop_trips_feeder: true,
            feeders_initially_closed: true,
        }
    }
}

#[derive(Debug, Clone)]
struct BreakerDev {
    name: String,
    dev: Breaker,
    link: Option<usize>,
    close_out: Option<usize>,
    trip_out: Option<usize>,
    board: Option<usize>,
    tripped: bool,
    both_coils: bool,
    /// A breaker that must be open before this one closes by hand (RS602 and the
    /// switchroom's transformer feeder R6_Q3 lock each other out).
    interlock: Option<usize>,
}

#[derive(Debug, Clone, Copy)]
enum Coil {
    Output(usize),
    ManualSwitch(usize),
    /// The changeover of a two-input supply (the signalling equipment's universal source):
    /// energised while the relay `own` sees its input, the relay `yields_to` (the
    /// preferred input's) does not, and the contactor `interlock` (the other input's) is
    /// open, so the two inputs are never closed together (break before make).
    Changeover {
        own: usize,
        yields_to: Option<usize>,
        interlock: usize,
    },
}

#[derive(Debug, Clone)]
struct ContactorDev {
    name: String,
    dev: Delayed,
    link: Option<usize>,
    coil: Coil,
    estop_board: Option<usize>,
}

#[derive(Debug, Clone, Copy)]
enum Sense {
    Bus(usize),
    Generator,
}

#[derive(Debug, Clone)]
struct RelayDev {
    dev: Delayed,
    sense: Sense,
}

#[derive(Debug, Clone)]
struct Board {
    name: String,
    remote: bool,
    estop: bool,
    has_estop: bool,
    bus: usize,
    base_kw: f64,
    live_ns: u128,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ContactKind {
    Fuse,
    Arrester,
    Door,
    SupplyUnit,
    NetSwitch,
}

#[derive(Debug, Clone)]
struct Contact {
    name: String,
    kind: ContactKind,
    active: bool,
}

#[derive(Debug, Clone)]
struct Lighting {
    name: String,
    bus: usize,
    km: usize,
    km_manual: usize,
    fuse: usize,
    manual_switch: bool,
    remote: bool,
    lamp_failed: bool,
    feedback: Delayed,
    energised_since: Option<SimTime>,
    power_kw: f64,
    on_ns: u128,
    dark: bool,
    dark_next: Option<SimTime>,
}

#[derive(Debug, Clone, Copy)]
enum Src {
    Const(bool),
    BreakerClosed(usize),
    ContactorClosed(usize),
    Relay(usize),
    Selector(usize, bool),
    Estop(usize),
    Contact(usize, bool),
    BusVoltage(usize, f64),
    BoardPower(usize),
    BoardCurrent(usize),
    BoardEnergy(usize),
    GenRunning,
    GenReady,
    GenFault,
    GenVoltage,
    LightFeedback(usize),
    LightDusk(usize),
    LightRemote(usize),
    LightManual(usize),
    LightEnergy(usize),
    LightPower(usize),
    LightCurrent(usize),
    LightOutput(usize),
    Illuminance,
}

#[derive(Debug, Clone, Copy)]
enum Sig {
    In(Src),
    Out(usize),
}

#[derive(Debug, Clone)]
struct Out {
    value: bool,
    module: usize,
}

/// A breaker or contactor and its position ([`VsetinPlant::switching_devices`]).
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct SwitchingDevice {
    /// Device name (`RH2_QF1`, `RDA_KM1`).
    pub name: String,
    /// A contactor (else a breaker).
    pub contactor: bool,
    /// Main contacts closed.
    pub closed: bool,
    /// Jammed in this position by a fault (`Some(true)`: stuck closed).
    pub stuck: Option<bool>,
    /// Tripped by its protection (a fault).
    pub tripped: bool,
}

impl fmt::Display for SwitchingDevice {
    /// `RH2_QF1 closed`, `RDA_KM2 open (stuck)`, `RH2_FA1.1 open (tripped)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let position = if self.closed { "closed" } else { "open" };
        write!(f, "{} {position}", self.name)?;
        if self.stuck.is_some() {
            f.write_str(" (stuck)")?;
        }
        if self.tripped {
            f.write_str(" (tripped)")?;
        }
        Ok(())
    }
}

/// The RZS supply transfer at one instant ([`VsetinPlant::transfer`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct Transfer {
    /// `RDA_KM1` (RZS from the mains through RH1.1) closed.
    pub mains_closed: bool,
    /// `RDA_KM2` (RZS from the diesel set) closed.
    pub generator_closed: bool,
    /// The RZS busbar is energised.
    pub board_live: bool,
    /// The diesel set.
    pub generator: GeneratorState,
}

impl fmt::Display for Transfer {
    /// `RZS on the mains (RDA_KM1 closed, RDA_KM2 open), generator stopped`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let feed = match (self.mains_closed, self.generator_closed) {
            (true, false) => "on the mains",
            (false, true) => "on the generator",
            (true, true) => "on the mains AND the generator",
            (false, false) => "on neither source",
        };
        let position = |closed: bool| if closed { "closed" } else { "open" };
        let generator = match self.generator {
            GeneratorState::Stopped => "stopped",
            GeneratorState::Cranking { .. } => "cranking",
            GeneratorState::Running { .. } => "running",
            GeneratorState::CoolDown { .. } => "cooling down",
            GeneratorState::Failed => "FAILED to start",
        };
        write!(
            f,
            "RZS {feed} (RDA_KM1 {}, RDA_KM2 {}), busbar {}, generator {generator}",
            position(self.mains_closed),
            position(self.generator_closed),
            if self.board_live { "live" } else { "dead" },
        )
    }
}

#[derive(Debug, Clone, Copy)]
enum SupplyRef {
    Source(usize),
    Link(usize),
}

/// The whole station plant. See the crate documentation for the signal table.
#[derive(Debug, Clone)]
pub struct VsetinPlant {
    cfg: StationConfig,
    now: SimTime,
    net: Network,
    sky: Sky,
    illuminance_override: Option<f64>,
    gen: Generator,
    da_source: usize,
    supplies: BTreeMap<String, (SupplyRef, bool)>,
    breakers: Vec<BreakerDev>,
    contactors: Vec<ContactorDev>,
    relays: Vec<RelayDev>,
    boards: Vec<Board>,
    contacts: Vec<Contact>,
    lights: Vec<Lighting>,
    modules: Vec<Module>,
    sig_module: Vec<usize>,
    outs: Vec<Out>,
    infos: Vec<SignalInfo>,
    sigs: Vec<Sig>,
    index: BTreeMap<String, usize>,
    faults: BTreeSet<Fault>,
    safety: Vec<SafetyEvent>,
    safety_dropped: u64,
    joined: Vec<Vec<String>>,
    gen_start: Option<usize>,
}

/// Phase current (A) of a balanced three-phase load of `kw` at line voltage `volts`.
fn current(kw: f64, volts: f64) -> f64 {
    if volts < 1.0 {
        0.0
    } else {
        kw * 1000.0 / (3f64.sqrt() * volts)
    }
}

fn kwh(kw: f64, ns: u128) -> f64 {
    kw * (ns as f64 / 3.6e12)
}

/// Names of the lighting boards: `ROV01`..`ROV12` and `OR`.
pub fn lighting_boards() -> Vec<String> {
    let mut v: Vec<String> = (1..=12).map(|i| format!("ROV{i:02}")).collect();
    v.push("OR".to_string());
    v
}

impl VsetinPlant {
    /// Builds the station at time zero with default parameters.
    pub fn new() -> Self {
        Self::with_config(StationConfig::default())
    }

    /// Builds the station at time zero.
    pub fn with_config(cfg: StationConfig) -> Self {
        let mut p = VsetinPlant {
            sky: Sky::new(cfg.sun.clone()),
            gen: Generator::new(cfg.generator.clone()),
            cfg,
            now: Duration::ZERO,
            net: Network::default(),
            illuminance_override: None,
            da_source: 0,
            supplies: BTreeMap::new(),
            breakers: Vec::new(),
            contactors: Vec::new(),
            relays: Vec::new(),
            boards: Vec::new(),
            contacts: Vec::new(),
            lights: Vec::new(),
            modules: Vec::new(),
            sig_module: Vec::new(),
            outs: Vec::new(),
            infos: Vec::new(),
            sigs: Vec::new(),
            index: BTreeMap::new(),
            faults: BTreeSet::new(),
            safety: Vec::new(),
            safety_dropped: 0,
            joined: Vec::new(),
            gen_start: None,
        };
        p.build();
        // Start in the steady state: relays already follow what they sense, and the
        // contactors their relays drive (the universal source's changeover) have followed
        // them; the PLC-driven coils are all off at time zero, so those stay open.
        for _ in 0..2 {
            p.settle();
            for r in &mut p.relays {
                r.dev.complete();
            }
            p.settle();
            for c in &mut p.contactors {
                c.dev.complete();
            }
        }
        p.settle();
        for r in &mut p.relays {
            r.dev.complete();
        }
        for l in &mut p.lights {
            l.feedback.complete();
        }
        p
    }

    // ------------------------------------------------------------------ the step

    fn out_eff(&self, slot: Option<usize>) -> bool {
        slot.and_then(|s| self.outs.get(s))
            .is_some_and(|o| o.value && self.modules.get(o.module).is_some_and(|m| m.present))
    }

    fn board_estop(&self, b: Option<usize>) -> bool {
        b.and_then(|b| self.boards.get(b)).is_some_and(|b| b.estop)
    }

    fn unix_ns(&self, t: SimTime) -> i128 {
        i128::from(self.cfg.start_unix_secs) * NANOS + t.as_nanos() as i128
    }

    fn sim_of_unix(&self, ns: i128) -> Option<SimTime> {
        let rel = ns - i128::from(self.cfg.start_unix_secs) * NANOS;
        u64::try_from(rel).ok().map(Duration::from_nanos)
    }

    fn circuit_energised(&self, l: &Lighting) -> bool {
        let km = |i: usize| self.contactors.get(i).is_some_and(|c| c.dev.value());
        let fuse_ok = self.contacts.get(l.fuse).is_some_and(|c| !c.active);
        self.net.live(l.bus) && (km(l.km) || km(l.km_manual)) && fuse_ok && !l.lamp_failed
    }

    /// Brings every device up to date at `self.now`: fires due timers, applies coils and
    /// commands, recomputes energisation, then drives the relays that sense it.
    fn settle(&mut self) {
        let now = self.now;
        for b in &mut self.breakers {
            b.dev.fire(now);
        }
        for c in &mut self.contactors {
            c.dev.fire(now);
        }
        self.gen.fire(now);
        for r in &mut self.relays {
            r.dev.fire(now);
        }
        for l in &mut self.lights {
            l.feedback.fire(now);
        }
        self.update_dusk();

        // Coils and commands.
        let estop_trips = self.cfg.estop_trips_feeder;
        for i in 0..self.breakers.len() {
            let Some(b) = self.breakers.get(i) else {
                continue;
            };
            let close = self.out_eff(b.close_out);
            let trip_coil = self.out_eff(b.trip_out);
            let trip = trip_coil || b.tripped || (estop_trips && self.board_estop(b.board));
            let both = close && trip_coil;
            let name = b.name.clone();
            let was_both = b.both_coils;
            if let Some(b) = self.breakers.get_mut(i) {
                b.dev.drive(now, close, trip);
                b.both_coils = both;
            }
            if both && !was_both {
                self.record(SafetyKind::BothCoils { breaker: name });
            }
        }
        for i in 0..self.contactors.len() {
            let Some(c) = self.contactors.get(i) else {
                continue;
            };
            let coil = match c.coil {
                Coil::Output(o) => self.out_eff(Some(o)),
                Coil::ManualSwitch(l) => self.lights.get(l).is_some_and(|l| l.manual_switch),
                Coil::Changeover {
                    own,
                    yields_to,
                    interlock,
                } => {
                    let relay = |r: usize| self.relays.get(r).is_some_and(|r| r.dev.value());
                    relay(own)
                        && !yields_to.is_some_and(relay)
                        && !self
                            .contactors
                            .get(interlock)
                            .is_some_and(|k| k.dev.value())
                }
            } && !self.board_estop(c.estop_board);
            if let Some(c) = self.contactors.get_mut(i) {
                c.dev.drive(now, coil);
            }
        }
        let start = self.out_eff(self.gen_start);
        self.gen.drive(now, start);

        // Energisation.
        for b in &self.breakers {
            if let Some(l) = b.link {
                self.net.set_link(l, b.dev.closed());
            }
        }
        for c in &self.contactors {
            if let Some(l) = c.link {
                self.net.set_link(l, c.dev.value());
            }
        }
        for (r, lost) in self.supplies.values() {
            match *r {
                SupplyRef::Source(s) => self.net.set_source(s, !lost),
                SupplyRef::Link(l) => self.net.set_link(l, !lost),
            }
        }
        self.net.set_source(self.da_source, self.gen.live());
        let joined = self.net.energise();
        self.monitor(joined);

        // Sensing.
        for i in 0..self.relays.len() {
            let Some(r) = self.relays.get(i) else {
                continue;
            };
            let want = match r.sense {
                Sense::Bus(b) => self.net.live(b),
                Sense::Generator => self.gen.voltage_ok(now),
            };
            if let Some(r) = self.relays.get_mut(i) {
                r.dev.drive(now, want);
            }
        }
        for i in 0..self.lights.len() {
            let Some(l) = self.lights.get(i) else {
                continue;
            };
            let on = self.circuit_energised(l);
            if let Some(l) = self.lights.get_mut(i) {
                l.feedback.drive(now, on);
                l.energised_since = match (on, l.energised_since) {
                    (true, None) => Some(now),
                    (true, s) => s,
                    (false, _) => None,
                };
            }
        }
    }

    fn update_dusk(&mut self) {
        let now = self.now;
        let unix = self.unix_ns(now);
        let thr = self.cfg.dusk_threshold_lux;
        let forced = self.illuminance_override.map(|lux| lux < thr);
        let mut cache: Option<(bool, Option<SimTime>)> = None;
        for i in 0..self.lights.len() {
            let due = self
                .lights
                .get(i)
                .is_some_and(|l| l.dark_next.is_none_or(|t| t <= now));
            if forced.is_none() && !due {
                continue;
            }
            let (dark, next) = match forced {
                Some(d) => (d, None),
                None => *cache.get_or_insert_with(|| {
                    let (d, n) = self.sky.dark_and_next(unix, thr);
                    (d, self.sim_of_unix(n))
                }),
            };
            if let Some(l) = self.lights.get_mut(i) {
                l.dark = dark;
                l.dark_next = next;
            }
        }
    }

    fn record(&mut self, kind: SafetyKind) {
        if self.safety.len() < SAFETY_LOG_CAP {
            self.safety.push(SafetyEvent { at: self.now, kind });
        } else {
            self.safety_dropped += 1;
        }
    }

    fn monitor(&mut self, joined: Vec<(Vec<String>, Vec<String>, bool)>) {
        let current: Vec<Vec<String>> = joined.iter().map(|j| j.1.clone()).collect();
        let ended: Vec<Vec<String>> = self
            .joined
            .iter()
            .filter(|s| !current.contains(s))
            .cloned()
            .collect();
        for sources in ended {
            self.record(SafetyKind::SourcesSeparated { sources });
        }
        for (buses, sources, both_live) in joined {
            if !self.joined.contains(&sources) {
                self.record(SafetyKind::SourcesConnected {
                    buses,
                    sources,
                    both_live,
                });
            } else if both_live {
                // A joined network that becomes truly paralleled is worth a new record.
                let was_live = self.safety.iter().rev().find_map(|e| match &e.kind {
                    SafetyKind::SourcesConnected {
                        sources: s,
                        both_live,
                        ..
                    } if *s == sources => Some(*both_live),
                    _ => None,
                });
                if was_live == Some(false) {
                    self.record(SafetyKind::SourcesConnected {
                        buses,
                        sources,
                        both_live,
                    });
                }
            }
        }
        self.joined = current;
    }

    /// Integrates the meters over `[self.now, t]`: the on-time of every load is counted in
    /// whole nanoseconds (power is constant between events), so the energy does not depend
    /// on the step size.
    fn integrate(&mut self, t: SimTime) {
        let dt = t.saturating_sub(self.now).as_nanos();
        if dt == 0 {
            return;
        }
        for i in 0..self.boards.len() {
            let live = self.boards.get(i).is_some_and(|b| self.net.live(b.bus));
            if let Some(b) = self.boards.get_mut(i) {
                if live {
                    b.live_ns += dt;
                }
            }
        }
        for i in 0..self.lights.len() {
            let on = self
                .lights
                .get(i)
                .is_some_and(|l| self.circuit_energised(l));
            if let Some(l) = self.lights.get_mut(i) {
                if on {
                    l.on_ns += dt;
                }
            }
        }
    }

    fn next_internal(&self) -> Option<SimTime> {
        let now = self.now;
        earliest(
            self.breakers
                .iter()
                .map(|b| b.dev.next_event())
                .chain(self.contactors.iter().map(|c| c.dev.next_event()))
                .chain(self.relays.iter().map(|r| r.dev.next_event()))
                .chain(self.lights.iter().map(|l| l.feedback.next_event()))
                .chain(self.lights.iter().map(|l| l.dark_next))
                .chain(self.lights.iter().map(|l| {
                    l.energised_since
                        .map(|s| s.saturating_add(self.cfg.lamp_warm_up))
                        .filter(|t| *t > now)
                }))
                .chain(std::iter::once(self.gen.next_event(now))),
        )
    }

    // ------------------------------------------------------------------ values

    fn value(&self, src: Src) -> Value {
        let now = self.now;
        let b = Value::Bool;
        match src {
            Src::Const(v) => b(v),
            Src::BreakerClosed(i) => b(self.breakers.get(i).is_some_and(|x| x.dev.closed())),
            Src::ContactorClosed(i) => b(self.contactors.get(i).is_some_and(|x| x.dev.value())),
            Src::Relay(i) => b(self.relays.get(i).is_some_and(|x| x.dev.value())),
            Src::Selector(i, remote) => b(self.boards.get(i).is_some_and(|x| x.remote == remote)),
            Src::Estop(i) => b(self.boards.get(i).is_some_and(|x| x.estop)),
            Src::Contact(i, active_true) => b(self
                .contacts
                .get(i)
                .is_some_and(|x| x.active == active_true)),
            Src::BusVoltage(bus, nominal) => Value::Real(self.bus_voltage(bus, nominal)),
            Src::BoardPower(i) => Value::Real(
                self.boards
                    .get(i)
                    .filter(|x| self.net.live(x.bus))
                    .map_or(0.0, |x| x.base_kw),
            ),
            Src::BoardEnergy(i) => Value::Real(
                self.boards
                    .get(i)
                    .map_or(0.0, |x| kwh(x.base_kw, x.live_ns)),
            ),
            Src::BoardCurrent(i) => Value::Real(self.boards.get(i).map_or(0.0, |x| {
                let p = self.value(Src::BoardPower(i)).as_real().unwrap_or(0.0);
                current(p, self.bus_voltage(x.bus, 400.0))
            })),
            Src::LightCurrent(i) => Value::Real(self.lights.get(i).map_or(0.0, |l| {
                let p = self.value(Src::LightPower(i)).as_real().unwrap_or(0.0);
                current(p, self.bus_voltage(l.bus, 400.0))
            })),
            Src::GenRunning => b(self.gen.running()),
            Src::GenReady => b(self.gen.ready(now)),
            Src::GenFault => b(self.gen.failed()),
            Src::GenVoltage => Value::Real(self.gen.voltage(now)),
            Src::LightFeedback(i) => b(self.lights.get(i).is_some_and(|l| l.feedback.value())),
            Src::LightDusk(i) => b(self.lights.get(i).is_some_and(|l| l.dark)),
            Src::LightRemote(i) => b(self.lights.get(i).is_some_and(|l| l.remote)),
            Src::LightManual(i) => b(self.lights.get(i).is_some_and(|l| l.manual_switch)),
            Src::LightEnergy(i) => {
                Value::Real(self.lights.get(i).map_or(0.0, |l| kwh(l.power_kw, l.on_ns)))
            }
            Src::LightPower(i) => Value::Real(
                self.lights
                    .get(i)
                    .filter(|l| self.circuit_energised(l))
                    .map_or(0.0, |l| l.power_kw),
            ),
            Src::LightOutput(i) => {
                Value::Real(self.lights.get(i).map_or(0.0, |l| match l.energised_since {
                    Some(s) => {
                        let w = self.cfg.lamp_warm_up.as_secs_f64();
                        let e = now.saturating_sub(s).as_secs_f64();
                        if w <= 0.0 || e >= w {
                            100.0
                        } else {
                            100.0 * e / w
                        }
                    }
                    None => 0.0,
                }))
            }
            Src::Illuminance => Value::Real(
                self.illuminance_override
                    .unwrap_or_else(|| self.sky.illuminance(self.unix_ns(now))),
            ),
        }
    }

    fn bus_voltage(&self, bus: usize, nominal: f64) -> f64 {
        match self.net.supply(bus) {
            None => 0.0,
            Some(s) if s == self.da_source => self.gen.voltage(self.now) * nominal / 400.0,
            Some(_) => nominal,
        }
    }

    // ------------------------------------------------------------------ public API

    /// The configuration the plant was built with.
    pub fn config(&self) -> &StationConfig {
        &self.cfg
    }

    /// Every device name of a kind, sorted: what a fault or hand operation of that kind
    /// accepts ([`crate::operation_syntax`] tells which kind each takes).
    pub fn device_names(&self, kind: DeviceKind) -> Vec<String> {
        let contacts = |wanted: ContactKind| -> Vec<String> {
            self.contacts
                .iter()
                .filter(|c| c.kind == wanted)
                .map(|c| c.name.clone())
                .collect()
        };
        let breakers = || self.breakers.iter().map(|b| b.name.clone());
        let lights = || self.lights.iter().map(|l| l.name.clone());
        let estop_boards = || {
            self.boards
                .iter()
                .filter(|b| b.has_estop)
                .map(|b| b.name.clone())
        };
        let mut names: Vec<String> = match kind {
            DeviceKind::Supply => self.supplies.keys().cloned().collect(),
            DeviceKind::SwitchingDevice => breakers()
                .chain(self.contactors.iter().map(|c| c.name.clone()))
                .collect(),
            DeviceKind::Breaker => breakers().collect(),
            DeviceKind::LightingBoard => lights().collect(),
            DeviceKind::Fuse => contacts(ContactKind::Fuse),
            DeviceKind::SurgeArrester => contacts(ContactKind::Arrester),
            DeviceKind::EmergencyOffBoard => estop_boards().collect(),
            DeviceKind::Door => contacts(ContactKind::Door),
            DeviceKind::SupplyUnit => contacts(ContactKind::SupplyUnit),
            DeviceKind::NetworkSwitch => contacts(ContactKind::NetSwitch),
            DeviceKind::Module => self.modules.iter().map(|m| m.name.clone()).collect(),
            DeviceKind::SelectorBoard => estop_boards().chain(lights()).collect(),
        };
        names.sort();
        names.dedup();
        names
    }

    /// The full name of the device of `kind` that `given` means: the name itself, or a
    /// unique short form of it (`QF1`-style last words, `RH11`-style first words, any
    /// case). Several fitting devices are an [`PlantError::AmbiguousDevice`] naming them.
    pub fn resolve_device(&self, kind: DeviceKind, given: &str) -> Result<String, PlantError> {
        resolve_device(kind, &self.device_names(kind), given)
    }

    /// The fault with its device's full name ([`VsetinPlant::resolve_device`]).
    pub fn resolve_fault(&self, fault: &Fault) -> Result<Fault, PlantError> {
        match (fault.device_kind(), fault.device()) {
            (Some(kind), Some(device)) => Ok(fault.with_device(self.resolve_device(kind, device)?)),
            _ => Ok(fault.clone()),
        }
    }

    /// The hand operation with its device's full name ([`VsetinPlant::resolve_device`]).
    pub fn resolve_action(&self, action: &Action) -> Result<Action, PlantError> {
        match action.device() {
            Some((kind, device)) => Ok(action.with_device(self.resolve_device(kind, device)?)),
            None => Ok(action.clone()),
        }
    }

    /// Injects a fault at the current time. Injecting an active fault again is a no-op.
    /// The device may be given by a unique short name ([`VsetinPlant::resolve_device`]);
    /// the fault is kept under the full name.
    pub fn inject(&mut self, fault: Fault) -> Result<(), PlantError> {
        let fault = self.resolve_fault(&fault)?;
        self.apply_fault(&fault, true)?;
        self.faults.insert(fault);
        self.settle();
        Ok(())
    }

    /// Clears a fault at the current time (clearing an inactive fault is a no-op). The
    /// device may be given by a unique short name, as to [`VsetinPlant::inject`].
    pub fn clear(&mut self, fault: &Fault) -> Result<(), PlantError> {
        let fault = self.resolve_fault(fault)?;
        self.apply_fault(&fault, false)?;
        self.faults.remove(&fault);
        self.settle();
        Ok(())
    }

    /// Clears every active fault.
    pub fn clear_all(&mut self) {
        let all: Vec<Fault> = self.faults.iter().cloned().collect();
        for f in all {
            let _ = self.apply_fault(&f, false);
        }
        self.faults.clear();
        self.settle();
    }

    /// The active faults, sorted.
    pub fn active_faults(&self) -> Vec<Fault> {
        self.faults.iter().cloned().collect()
    }

    fn apply_fault(&mut self, f: &Fault, on: bool) -> Result<(), PlantError> {
        let unknown = |kind: &'static str, name: &str| PlantError::UnknownDevice {
            kind,
            name: name.to_string(),
        };
        let now = self.now;
        match f {
            Fault::SupplyLoss(d) => {
                let s = self
                    .supplies
                    .get_mut(d.as_str())
                    .ok_or_else(|| unknown("supply", d))?;
                s.1 = on;
            }
            Fault::GeneratorFailToStart => {
                if on {
                    self.gen.fail_to_start = true;
                } else {
                    self.gen.clear_failure(now);
                }
            }
            Fault::StuckClosed(d) | Fault::StuckOpen(d) => {
                let pos = matches!(f, Fault::StuckClosed(_));
                let stuck = on.then_some(pos);
                if let Some(b) = self.breakers.iter_mut().find(|b| b.name == *d) {
                    if on || b.dev.stuck() == Some(pos) {
                        b.dev.set_stuck(stuck);
                    }
                } else if let Some(c) = self.contactors.iter_mut().find(|c| c.name == *d) {
                    if on || c.dev.stuck() == Some(pos) {
                        c.dev.set_stuck(stuck);
                    }
                } else {
                    return Err(unknown("breaker or contactor", d));
                }
            }
            Fault::BreakerTripped(d) => {
                let b = self
                    .breakers
                    .iter_mut()
                    .find(|b| b.name == *d)
                    .ok_or_else(|| unknown("breaker", d))?;
                if !on && b.tripped && b.close_out.is_none() {
                    b.tripped = false;
                    b.dev.drive(now, false, false);
                    b.dev.hand(true);
                }
                b.tripped = on;
            }
            Fault::LampFailure(d) => {
                let l = self
                    .lights
                    .iter_mut()
                    .find(|l| l.name == *d)
                    .ok_or_else(|| unknown("lighting board", d))?;
                l.lamp_failed = on;
            }
            Fault::FuseBlown(d) => self.set_contact(d, ContactKind::Fuse, on)?,
            Fault::SurgeArresterTripped(d) => self.set_contact(d, ContactKind::Arrester, on)?,
            Fault::DoorOpen(d) => self.set_contact(d, ContactKind::Door, on)?,
            Fault::SupplyUnitFault(d) => self.set_contact(d, ContactKind::SupplyUnit, on)?,
            Fault::NetworkSwitchFault(d) => self.set_contact(d, ContactKind::NetSwitch, on)?,
            Fault::EmergencyOff(d) => {
                let b = self
                    .boards
                    .iter_mut()
                    .find(|b| b.name == *d && b.has_estop)
                    .ok_or_else(|| unknown("board with emergency off", d))?;
                b.estop = on;
            }
            Fault::ModulePulled(d) | Fault::CommunicationLost(d) => {
                let m = self
                    .modules
                    .iter_mut()
                    .find(|m| m.name == *d)
                    .ok_or_else(|| unknown("module", d))?;
                if matches!(f, Fault::ModulePulled(_)) {
                    m.present = !on;
                } else {
                    m.linked = !on;
                }
            }
        }
        Ok(())
    }

    fn set_contact(&mut self, name: &str, kind: ContactKind, on: bool) -> Result<(), PlantError> {
        let c = self
            .contacts
            .iter_mut()
            .find(|c| c.name == name && c.kind == kind)
            .ok_or_else(|| PlantError::UnknownDevice {
                kind: match kind {
                    ContactKind::Fuse => "fuse",
                    ContactKind::Arrester => "surge arrester",
                    ContactKind::Door => "door",
                    ContactKind::SupplyUnit => "supply unit",
                    ContactKind::NetSwitch => "network switch",
                },
                name: name.to_string(),
            })?;
        c.active = on;
        Ok(())
    }

    /// Performs a hand operation at the current time. The device may be given by a unique
    /// short name, as to [`VsetinPlant::inject`].
    pub fn operate(&mut self, action: Action) -> Result<(), PlantError> {
        let action = self.resolve_action(&action)?;
        let unknown = |kind: &'static str, name: &str| PlantError::UnknownDevice {
            kind,
            name: name.to_string(),
        };
        match action {
            Action::SetSelector { board, remote } => {
                if let Some(b) = self
                    .boards
                    .iter_mut()
                    .find(|b| b.name == board && b.has_estop)
                {
                    b.remote = remote;
                } else if let Some(l) = self.lights.iter_mut().find(|l| l.name == board) {
                    l.remote = remote;
                } else {
                    return Err(unknown("board with a selector", &board));
                }
            }
            Action::SetManualSwitch { board, on } => {
                let l = self
                    .lights
                    .iter_mut()
                    .find(|l| l.name == board)
                    .ok_or_else(|| unknown("lighting board", &board))?;
                l.manual_switch = on;
            }
            Action::Close(name) => return self.hand_breaker(&name, true),
            Action::Open(name) => return self.hand_breaker(&name, false),
            Action::SetIlluminance(lux) => {
                self.illuminance_override = lux.filter(|x| x.is_finite());
                for l in &mut self.lights {
                    l.dark_next = None;
                }
            }
        }
        self.settle();
        Ok(())
    }

    fn hand_breaker(&mut self, name: &str, close: bool) -> Result<(), PlantError> {
        let now = self.now;
        let i = self
            .breakers
            .iter()
            .position(|b| b.name == name)
            .ok_or_else(|| PlantError::UnknownDevice {
                kind: "breaker",
                name: name.to_string(),
            })?;
        let Some(b) = self.breakers.get(i) else {
            return Ok(());
        };
        if b.close_out.is_some() {
            let board = b.board.and_then(|x| self.boards.get(x));
            if board.is_some_and(|x| x.remote) {
                return Err(PlantError::Refused(format!(
                    "{name}: board selector in remote, door pushbuttons have no effect"
                )));
            }
            if let Some(b) = self.breakers.get_mut(i) {
                if close {
                    b.dev.start_close(now);
                } else {
                    b.dev.start_open(now);
                }
            }
        } else {
            if close && b.tripped {
                return Err(PlantError::Refused(format!(
                    "{name}: tripped by its protection; clear the fault to reclose"
                )));
            }
            let locked_by = b
                .interlock
                .and_then(|x| self.breakers.get(x))
                .filter(|x| x.dev.closed());
            if let (true, Some(other)) = (close, locked_by) {
                return Err(PlantError::Refused(format!(
                    "{name}: interlocked while {} is closed; open it first",
                    other.name
                )));
            }
            if let Some(b) = self.breakers.get_mut(i) {
                b.dev.hand(close);
            }
        }
        self.settle();
        Ok(())
    }

    /// The energisation picture (buses, links, sources) at the current time.
    pub fn topology(&self) -> &TopologySnapshot {
        &self.net.snap
    }

    /// Whether a bus (by name, see [`VsetinPlant::topology`]) is energised.
    pub fn bus_live(&self, bus: &str) -> Result<bool, PlantError> {
        self.net
            .snap
            .buses
            .iter()
            .find(|b| b.name == bus)
            .map(|b| b.live)
            .ok_or_else(|| PlantError::UnknownDevice {
                kind: "bus",
                name: bus.to_string(),
            })
    }

    /// The safety monitor's records, oldest first.
    pub fn safety_log(&self) -> &[SafetyEvent] {
        &self.safety
    }

    /// Safety records not kept because the log was full.
    pub fn safety_dropped(&self) -> u64 {
        self.safety_dropped
    }

    /// Whether sources of different groups are joined right now.
    pub fn sources_joined(&self) -> bool {
        !self.joined.is_empty()
    }

    /// Number of times sources of different groups became joined.
    pub fn source_violations(&self) -> usize {
        self.safety
            .iter()
            .filter(|e| matches!(e.kind, SafetyKind::SourcesConnected { .. }))
            .count()
    }

    /// The diesel generator's state.
    pub fn generator_state(&self) -> GeneratorState {
        self.gen.state
    }

    /// Every breaker and contactor with its position, in build order (breakers first).
    pub fn switching_devices(&self) -> Vec<SwitchingDevice> {
        let breakers = self.breakers.iter().map(|b| SwitchingDevice {
            name: b.name.clone(),
            contactor: false,
            closed: b.dev.closed(),
            stuck: b.dev.stuck(),
            tripped: b.tripped,
        });
        let contactors = self.contactors.iter().map(|c| SwitchingDevice {
            name: c.name.clone(),
            contactor: true,
            closed: c.dev.value(),
            stuck: c.dev.stuck(),
            tripped: false,
        });
        breakers.chain(contactors).collect()
    }

    /// The state of the RZS supply transfer (board RDA): which contactor feeds RZS and
    /// what the diesel set does.
    pub fn transfer(&self) -> Transfer {
        let closed = |name: &str| {
            self.contactors
                .iter()
                .any(|c| c.name == name && c.dev.value())
        };
        Transfer {
            mains_closed: closed("RDA_KM1"),
            generator_closed: closed("RDA_KM2"),
            board_live: self.bus_live("RZS").unwrap_or(false),
            generator: self.gen.state,
        }
    }
}

impl Default for VsetinPlant {
    fn default() -> Self {
        Self::new()
    }
}

impl Plant for VsetinPlant {
    fn now(&self) -> SimTime {
        self.now
    }

    fn next_event(&self) -> Option<SimTime> {
        self.next_internal()
    }

    fn advance_to(&mut self, t: SimTime) -> Result<(), PlantError> {
        if t < self.now {
            return Err(PlantError::TimeWentBackwards {
                now: self.now,
                requested: t,
            });
        }
        // Guards against a device that keeps a deadline at the current instant.
        let mut stalls = 0u32;
        loop {
            match self.next_internal().filter(|e| *e <= t) {
                Some(e) if e > self.now || stalls < 64 => {
                    if e <= self.now {
                        stalls += 1;
                    } else {
                        stalls = 0;
                    }
                    let e = e.max(self.now);
                    self.integrate(e);
                    self.now = e;
                    self.settle();
                }
                _ => {
                    self.integrate(t);
                    self.now = t;
                    self.settle();
                    return Ok(());
                }
            }
        }
    }

    fn signals(&self) -> &[SignalInfo] {
        &self.infos
    }

    fn read(&self, name: &str) -> Result<Reading, PlantError> {
        let i = *self
            .index
            .get(name)
            .ok_or_else(|| PlantError::UnknownSignal(name.to_string()))?;
        let valid = self
            .sig_module
            .get(i)
            .and_then(|&m| self.modules.get(m))
            .is_some_and(Module::valid);
        match self.sigs.get(i) {
            Some(Sig::In(src)) => Ok(Reading {
                value: self.value(*src),
                valid,
            }),
            Some(Sig::Out(o)) => Ok(Reading {
                value: Value::Bool(self.outs.get(*o).is_some_and(|x| x.value)),
                valid,
            }),
            None => Err(PlantError::UnknownSignal(name.to_string())),
        }
    }

    fn set_output(&mut self, name: &str, value: Value) -> Result<(), PlantError> {
        let i = *self
            .index
            .get(name)
            .ok_or_else(|| PlantError::UnknownSignal(name.to_string()))?;
        let Some(Sig::Out(o)) = self.sigs.get(i).copied() else {
            return Err(PlantError::NotAnOutput(name.to_string()));
        };
        let Value::Bool(v) = value else {
            return Err(PlantError::WrongType {
                name: name.to_string(),
                expected: ValueKind::Bool,
                got: value.kind(),
            });
        };
        if let Some(out) = self.outs.get_mut(o) {
            if out.value == v {
                return Ok(());
            }
            out.value = v;
        }
        self.settle();
        Ok(())
    }

    fn modules(&self) -> &[Module] {
        &self.modules
    }

    fn console(&mut self, line: &str) -> Result<(), PlantError> {
        let line = line.trim();
        if line == "clear all" {
            self.clear_all();
            return Ok(());
        }
        if let Some(rest) = line.strip_prefix("clear ") {
            let fault: Fault = rest.parse()?;
            return self.clear(&fault);
        }
        if let Some(action) = Action::parse(line) {
            return self.operate(action?);
        }
        let fault: Fault = line.parse()?;
        self.inject(fault)
    }

    fn console_operations(&self) -> Vec<ConsoleOperation> {
        fault::operation_syntax()
            .iter()
            .map(|syntax| ConsoleOperation {
                usage: syntax.usage,
                fault: syntax.fault,
                names_kind: syntax.device.map(|kind| kind.to_string()),
                names: syntax
                    .device
                    .map(|kind| self.device_names(kind))
                    .unwrap_or_default(),
            })
            .collect()
    }

    fn status(&self) -> Vec<StatusLine> {
        let faults: Vec<String> = self
            .active_faults()
            .iter()
            .map(ToString::to_string)
            .collect();
        let devices = self.switching_devices();
        let (contactors, breakers): (Vec<&SwitchingDevice>, Vec<&SwitchingDevice>) =
            devices.iter().partition(|d| d.contactor);
        let (shown, others): (Vec<&SwitchingDevice>, Vec<&SwitchingDevice>) = contactors
            .into_iter()
            .partition(|d| d.closed || d.stuck.is_some());
        let mut contactors: Vec<String> = shown.iter().map(ToString::to_string).collect();
        contactors.push(format!("{} other(s) open", others.len()));
        vec![
            StatusLine {
                label: "faults",
                items: if faults.is_empty() {
                    vec!["none".to_owned()]
                } else {
                    faults
                },
            },
            StatusLine {
                label: "transfer",
                items: vec![self.transfer().to_string()],
            },
            StatusLine {
                label: "breakers",
                items: breakers.iter().map(ToString::to_string).collect(),
            },
            StatusLine {
                label: "contactors",
                items: contactors,
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
