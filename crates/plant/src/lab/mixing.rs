//! The mixing unit (the teaching-lab thesis, section 5 of the lab-models spec): three
//! 84-L tanks filled by SV1–SV3, drained together by SV4 into a 253-L mixing vessel,
//! which SV5 empties; a mixer MIX.
//!
//! On every rising edge of the 1-s flag, in this order: +6 L into each tank whose fill
//! valve is open; with SV4 open, min(6 L, level) from each tank into the vessel; with SV5
//! open, −18 L from the vessel (not below 0). Then a tank above 84 L (the 15th second of
//! filling from empty) or the vessel above 253 L is an overflow: ERR lit steadily, the
//! model frozen until RESET.
//!
//! The level sensors are TRUE while the level ≥ their threshold, rising and falling
//! (`LAB-A5`): minimum 10 L (H3, H5, H8), half 42 L (H2, H7; tank 2 has none), full 84 L
//! (H1, H4, H6).
//!
//! From power-on or RESET ERR blinks until the first instant any of SV1–SV5 is TRUE
//! (section 5.2); that is an indication, not an error record.

use super::engine::{spec, Cmd, ErrorLog, SignalSpec, Sim};
use super::{ErrorKind, LabOptions};
use crate::core::{SimTime, Value};

const SV4: usize = 3;
const SV5: usize = 4;
const MIX: usize = 5;

/// Tank capacity, L.
const TANK: u32 = 84;
/// Mixing vessel capacity, L.
const VESSEL: u32 = 253;
/// Fill per second per valve, and transfer per second per tank, L.
const STEP: u32 = 6;
/// SV5's drain per second, L.
const DRAIN: u32 = 18;

/// Each sensor's tank (0..3) and threshold, in the order of [`Mixing::SENSORS`].
const SENSOR_MAP: [(usize, u32); 8] = [
    (0, 84),
    (0, 42),
    (0, 10),
    (1, 84),
    (1, 10),
    (2, 84),
    (2, 42),
    (2, 10),
];

/// Levels and the initial indication.
#[derive(Debug, Clone, Default)]
pub(crate) struct Mixing {
    /// Tanks 1–3, L.
    tanks: [u32; 3],
    /// The mixing vessel, L.
    vessel: u32,
    /// A solenoid has been TRUE since power-on or RESET.
    solenoid_seen: bool,
}

impl Sim for Mixing {
    const NAME: &'static str = "mixing";
    const OUTPUTS: &'static [SignalSpec] = &[
        spec("SV1", "valve filling tank 1 (6 L/s)"),
        spec("SV2", "valve filling tank 2 (6 L/s)"),
        spec("SV3", "valve filling tank 3 (6 L/s)"),
        spec(
            "SV4",
            "valve draining all tanks into the mixing vessel (6 L/s from each)",
        ),
        spec("SV5", "valve draining the mixing vessel (18 L/s)"),
        spec("MIX", "mixer on"),
    ];
    const SENSORS: &'static [SignalSpec] = &[
        spec("H1", "tank 1 full (84 L)"),
        spec("H2", "tank 1 half (42 L)"),
        spec("H3", "tank 1 minimum (10 L)"),
        spec("H4", "tank 2 full (84 L)"),
        spec("H5", "tank 2 minimum (10 L)"),
        spec("H6", "tank 3 full (84 L)"),
        spec("H7", "tank 3 half (42 L)"),
        spec("H8", "tank 3 minimum (10 L)"),
    ];

    fn new(_options: &LabOptions) -> Self {
        Mixing::default()
    }

    fn reset(&mut self) {
        *self = Mixing::default();
    }

    fn apply(&mut self, _now: SimTime, cmd: Cmd<'_>, _log: &mut ErrorLog) {
        if (0..=SV5).any(|i| cmd.on(i)) {
            self.solenoid_seen = true;
        }
    }

    fn on_second(&mut self, now: SimTime, cmd: Cmd<'_>, log: &mut ErrorLog) {
        for (i, tank) in self.tanks.iter_mut().enumerate() {
            if cmd.on(i) {
                *tank = tank.saturating_add(STEP);
            }
        }
        if cmd.on(SV4) {
            for tank in &mut self.tanks {
                let moved = STEP.min(*tank);
                *tank -= moved;
                self.vessel = self.vessel.saturating_add(moved);
            }
        }
        if cmd.on(SV5) {
            self.vessel = self.vessel.saturating_sub(DRAIN);
        }
        let mut over: Vec<String> = self
            .tanks
            .iter()
            .enumerate()
            .filter(|(_, level)| **level > TANK)
            .map(|(i, level)| format!("tank {} above {TANK} L ({level} L)", i + 1))
            .collect();
        if self.vessel > VESSEL {
            over.push(format!(
                "mixing vessel above {VESSEL} L ({} L)",
                self.vessel
            ));
        }
        if !over.is_empty() {
            log.fail(now, ErrorKind::Overflow, over.join("; "));
        }
    }

    fn sensor(&self, index: usize) -> bool {
        SENSOR_MAP
            .get(index)
            .and_then(|(tank, threshold)| self.tanks.get(*tank).map(|l| l >= threshold))
            .unwrap_or(false)
    }

    fn blinks(&self) -> bool {
        !self.solenoid_seen
    }

    fn state(&self, cmd: Cmd<'_>) -> Vec<(&'static str, Value)> {
        let [t1, t2, t3] = self.tanks;
        vec![
            ("tank1", Value::Real(f64::from(t1))),
            ("tank2", Value::Real(f64::from(t2))),
            ("tank3", Value::Real(f64::from(t3))),
            ("vessel", Value::Real(f64::from(self.vessel))),
            ("mixing", Value::Bool(cmd.on(MIX))),
        ]
    }

    fn describe(&self, cmd: Cmd<'_>) -> Vec<String> {
        let [t1, t2, t3] = self.tanks;
        let open: Vec<&str> = Self::OUTPUTS
            .iter()
            .enumerate()
            .take(SV5 + 1)
            .filter(|(i, _)| cmd.on(*i))
            .map(|(_, s)| s.name)
            .collect();
        let mut items = vec![
            format!("tanks {t1} / {t2} / {t3} L"),
            format!("vessel {} L", self.vessel),
            if open.is_empty() {
                "valves closed".to_owned()
            } else {
                format!("open {}", open.join(", "))
            },
            format!("mixer {}", if cmd.on(MIX) { "on" } else { "off" }),
        ];
        if !self.solenoid_seen {
            items.push("no solenoid yet (ERR blinks)".to_owned());
        }
        items
    }
}
