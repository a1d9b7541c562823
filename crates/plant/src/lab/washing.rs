//! The washing machine (the teaching-lab thesis, section 6 of the lab-models spec): a
//! drum turning either way, a tub filled by `napousteni` and drained by `cerpadlo`, a
//! heater `topeni`, level sensors at 50 % and 100 % and temperature sensors at 30, 40, 60
//! and 90 °C.
//!
//! - The drum animates 8 positions (`LAB-A9`; option `drum=4`: the thesis's 4-state mask,
//!   opposite LEDs lit in pairs), turning right = increasing position. A step TON runs
//!   while exactly one of `buben_vpravo`/`buben_vlevo` is TRUE: 0.5 s a step, 0.25 s with
//!   `otacky`, restarting after each step (the period follows `otacky` as the slide's
//!   follows EM3). Both directions: ERR blinks and the drum stops; releasing one resumes.
//! - On every rising edge of the 1-s flag: the temperature steps first, from the level of
//!   the second that ended: +1.5 °C with `topeni` (`LAB-A7`; option `heating=level`:
//!   1.5 × 100 / level, nothing with an empty tub), otherwise −3 °C while above 0, clamped
//!   at 0. Then the level: +5 % with `napousteni`, −5 % with `cerpadlo`, net when both
//!   (`LAB-A6`), not below 0. A level that would exceed 100 % is an overflow (it stays at
//!   100 %); a temperature above 90 °C (61 s of heating from 0 °C) is overheating. Both
//!   light ERR steadily and freeze the machine until RESET.
//! - Sensors are TRUE while the value ≥ the threshold, both ways (`LAB-A5`): `voda_50` at
//!   50 %, `voda_100` at 100 %, `teplota_30`…`teplota_90`.

use std::time::Duration;

use super::engine::{spec, Cmd, ErrorLog, SignalSpec, Sim};
use super::{ErrorKind, LabOptions};
use crate::core::{SimTime, Value};

const RIGHT: usize = 0;
const LEFT: usize = 1;
const SPIN: usize = 2;
const HEATER: usize = 3;
const INLET: usize = 4;
const PUMP: usize = 5;

/// A drum step at washing speed.
const WASH_STEP: Duration = Duration::from_millis(500);
/// A drum step with `otacky` (spin).
const SPIN_STEP: Duration = Duration::from_millis(250);
/// Fill and drain per second, % of the tub (`LAB-A6`).
const FLOW: i32 = 5;
/// Heating per second with a full tub, °C (`LAB-A7`).
const HEATING: f64 = 1.5;
/// Cooling per second with the heater off, °C.
const COOLING: f64 = 3.0;
/// Above this the machine overheats, °C.
const MAX_TEMPERATURE: f64 = 90.0;

/// Each sensor's quantity and threshold, in the order of [`Washing::SENSORS`].
const SENSOR_MAP: [(Quantity, f64); 6] = [
    (Quantity::Temperature, 90.0),
    (Quantity::Temperature, 60.0),
    (Quantity::Temperature, 40.0),
    (Quantity::Temperature, 30.0),
    (Quantity::Level, 50.0),
    (Quantity::Level, 100.0),
];

#[derive(Debug, Clone, Copy)]
enum Quantity {
    Temperature,
    Level,
}

/// Where the drum turns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Heading {
    Right,
    Left,
}

/// The machine's state.
#[derive(Debug, Clone)]
pub(crate) struct Washing {
    /// Drum positions: 8, or 4 with `drum=4`.
    positions: u8,
    /// `heating=level`.
    heat_by_level: bool,
    /// Tub level, % (0..=100, multiples of 5).
    level: i32,
    /// Water temperature, °C.
    temperature: f64,
    /// Drum position, 0..positions.
    drum: u8,
    /// The running drum TON: its direction and start.
    run: Option<(Heading, SimTime)>,
    /// The TON's period, from `otacky`.
    period: Duration,
}

impl Sim for Washing {
    const NAME: &'static str = "washing";
    const OUTPUTS: &'static [SignalSpec] = &[
        spec("buben_vpravo", "drum rotation right (BUBEN →)"),
        spec("buben_vlevo", "drum rotation left (BUBEN ←)"),
        spec(
            "otacky",
            "spin (OTÁČKY): drum steps every 0.25 s instead of 0.5 s",
        ),
        spec("topeni", "water heating (TOPENÍ), +1.5 °C/s"),
        spec("napousteni", "water inlet (VODA), +5 %/s"),
        spec("cerpadlo", "drain pump (ČERPADLO), −5 %/s"),
    ];
    const SENSORS: &'static [SignalSpec] = &[
        spec("teplota_90", "90 °C reached"),
        spec("teplota_60", "60 °C reached"),
        spec("teplota_40", "40 °C reached"),
        spec("teplota_30", "30 °C reached"),
        spec("voda_50", "level 50 %"),
        spec("voda_100", "level 100 %"),
    ];

    fn new(options: &LabOptions) -> Self {
        Washing {
            positions: options.drum_positions(),
            heat_by_level: options.heating_by_level(),
            level: 0,
            temperature: 0.0,
            drum: 0,
            run: None,
            period: WASH_STEP,
        }
    }

    fn reset(&mut self) {
        self.level = 0;
        self.temperature = 0.0;
        self.drum = 0;
        self.run = None;
        self.period = WASH_STEP;
    }

    fn apply(&mut self, now: SimTime, cmd: Cmd<'_>, log: &mut ErrorLog) {
        let (right, left) = (cmd.on(RIGHT), cmd.on(LEFT));
        if right && left {
            log.raise(now, ErrorKind::BothDirections, || {
                "buben_vpravo and buben_vlevo together".to_owned()
            });
        } else {
            log.clear(now, ErrorKind::BothDirections);
        }
        let heading = match (right, left) {
            (true, false) => Some(Heading::Right),
            (false, true) => Some(Heading::Left),
            _ => None,
        };
        if self.run.map(|(h, _)| h) != heading {
            self.run = heading.map(|h| (h, now));
        }
        self.period = if cmd.on(SPIN) { SPIN_STEP } else { WASH_STEP };
    }

    fn deadline(&self) -> Option<SimTime> {
        self.run.map(|(_, start)| start.saturating_add(self.period))
    }

    fn on_timer(&mut self, now: SimTime, _cmd: Cmd<'_>, _log: &mut ErrorLog) {
        let Some((heading, _)) = self.run else {
            return;
        };
        let n = self.positions.max(1);
        self.drum = match heading {
            Heading::Right => (self.drum % n + 1) % n,
            Heading::Left => (self.drum % n + n - 1) % n,
        };
        self.run = Some((heading, now));
    }

    fn on_second(&mut self, now: SimTime, cmd: Cmd<'_>, log: &mut ErrorLog) {
        if cmd.on(HEATER) {
            let rate = if !self.heat_by_level {
                HEATING
            } else if self.level > 0 {
                HEATING * 100.0 / f64::from(self.level)
            } else {
                0.0
            };
            self.temperature += rate;
        } else if self.temperature > 0.0 {
            self.temperature = (self.temperature - COOLING).max(0.0);
        }
        let inflow = if cmd.on(INLET) { FLOW } else { 0 };
        let outflow = if cmd.on(PUMP) { FLOW } else { 0 };
        let level = self.level + inflow - outflow;
        self.level = level.clamp(0, 100);
        if self.temperature > MAX_TEMPERATURE {
            log.fail(
                now,
                ErrorKind::Overheat,
                format!(
                    "water above {MAX_TEMPERATURE:.0} °C ({:.1} °C)",
                    self.temperature
                ),
            );
        }
        if level > 100 {
            log.fail(
                now,
                ErrorKind::Overflow,
                format!("tub filled beyond 100 % ({level} %)"),
            );
        }
    }

    fn sensor(&self, index: usize) -> bool {
        match SENSOR_MAP.get(index) {
            Some((Quantity::Temperature, threshold)) => self.temperature >= *threshold,
            Some((Quantity::Level, threshold)) => f64::from(self.level) >= *threshold,
            None => false,
        }
    }

    fn state(&self, cmd: Cmd<'_>) -> Vec<(&'static str, Value)> {
        vec![
            ("level", Value::Real(f64::from(self.level))),
            ("temperature", Value::Real(self.temperature)),
            ("drum", Value::Real(f64::from(self.drum))),
            ("drum_turning", Value::Bool(cmd.on(RIGHT) != cmd.on(LEFT))),
        ]
    }

    fn describe(&self, cmd: Cmd<'_>) -> Vec<String> {
        let on: Vec<&str> = Self::OUTPUTS
            .iter()
            .enumerate()
            .filter(|(i, _)| cmd.on(*i))
            .map(|(_, s)| s.name)
            .collect();
        let drum = match (cmd.on(RIGHT), cmd.on(LEFT)) {
            (true, false) => "turning right",
            (false, true) => "turning left",
            (true, true) => "stopped (both directions)",
            (false, false) => "stopped",
        };
        vec![
            format!("level {} %", self.level),
            format!("temperature {:.1} °C", self.temperature),
            format!("drum at {} of {}, {drum}", self.drum, self.positions),
            if on.is_empty() {
                "all outputs off".to_owned()
            } else {
                format!("on: {}", on.join(", "))
            },
        ]
    }
}
