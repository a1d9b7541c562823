//! The hydraulic slide unit (the teaching-lab thesis, section 3 of the lab-models spec):
//! a slide on ten positions shown by a row of LEDs, four of them the position sensors
//! K1–K4.
//!
//! - EM1 moves right (forward), EM2 left (back), EM3 selects the speed: 1 = working feed,
//!   one step per second; 0 = rapid traverse, one step per 0.5 s (`LAB-A2`).
//! - A step TON runs while exactly one of EM1/EM2 is TRUE; on expiry the slide moves one
//!   step and the TON restarts, so the first step comes one period after the command.
//!   EM3 changed during a run sets the period of the running TON, measured from its start
//!   (a step already overdue by the new period happens at the change).
//! - EM1 and EM2 together: ERR blinks and the TON stops; releasing one resumes with a new
//!   TON (recoverable).
//! - K1–K4 sit at positions 1, 4, 7, 10 (`LAB-A1`; option `sensors=a,b,c,d`). A step that
//!   would leave [K1, K4] is overtravel: the slide moves into the zone if the zone is
//!   inside 1..10 (with `sensors=2,4,7,9`, positions 1 and 10), ERR is lit steadily, all
//!   of K1–K4 read TRUE and commands are ignored until RESET, which puts the slide back at
//!   K1.

use std::time::Duration;

use super::engine::{spec, Cmd, ErrorLog, SignalSpec, Sim};
use super::{ErrorKind, LabOptions};
use crate::core::{SimTime, Value};

const EM1: usize = 0;
const EM2: usize = 1;
const EM3: usize = 2;

/// Rapid traverse (EM3 = 0): one step per 0.5 s.
const RAPID: Duration = Duration::from_millis(500);
/// Working feed (EM3 = 1): one step per second.
const FEED: Duration = Duration::from_secs(1);

/// Where the slide is heading.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Heading {
    /// EM1: forward, towards position 10.
    Right,
    /// EM2: back, towards position 1.
    Left,
}

/// The slide's state.
#[derive(Debug, Clone)]
pub(crate) struct Slide {
    /// Positions of K1–K4.
    sensors: [u8; 4],
    /// 1..=10.
    position: u8,
    /// The running step TON: its direction and start.
    run: Option<(Heading, SimTime)>,
    /// The TON's period, from EM3.
    period: Duration,
    /// Stopped by overtravel until RESET.
    overtravel: bool,
}

impl Slide {
    fn k1(&self) -> u8 {
        self.sensors.first().copied().unwrap_or(1)
    }

    fn k4(&self) -> u8 {
        self.sensors.last().copied().unwrap_or(10)
    }

    /// The LEDs as a bit mask (bit 0 = position 1): the slide's LED, and in overtravel
    /// also the four K LEDs.
    fn leds(&self) -> u32 {
        let own = 1u32 << (self.position.clamp(1, 10) - 1);
        if self.overtravel {
            self.sensors
                .iter()
                .fold(own, |mask, k| mask | 1u32 << ((*k).clamp(1, 10) - 1))
        } else {
            own
        }
    }

    /// The sensor name at a position, if any (for the status).
    fn sensor_at(&self, position: u8) -> Option<usize> {
        self.sensors.iter().position(|k| *k == position)
    }
}

impl Sim for Slide {
    const NAME: &'static str = "slide";
    const OUTPUTS: &'static [SignalSpec] = &[
        spec("EM1", "move right (forward)"),
        spec("EM2", "move left (back)"),
        spec(
            "EM3",
            "speed: TRUE = working feed 1 s/step, FALSE = rapid traverse 0.5 s/step",
        ),
    ];
    const SENSORS: &'static [SignalSpec] = &[
        spec("K1", "position sensor K1 (position 1 by default)"),
        spec("K2", "position sensor K2 (position 4 by default)"),
        spec("K3", "position sensor K3 (position 7 by default)"),
        spec("K4", "position sensor K4 (position 10 by default)"),
    ];

    fn new(options: &LabOptions) -> Self {
        let sensors = options.sensors();
        let mut slide = Slide {
            sensors,
            position: 1,
            run: None,
            period: RAPID,
            overtravel: false,
        };
        slide.reset();
        slide
    }

    fn reset(&mut self) {
        self.position = self.k1();
        self.run = None;
        self.period = RAPID;
        self.overtravel = false;
    }

    fn apply(&mut self, now: SimTime, cmd: Cmd<'_>, log: &mut ErrorLog) {
        let (right, left) = (cmd.on(EM1), cmd.on(EM2));
        if right && left {
            let position = self.position;
            log.raise(now, ErrorKind::BothDirections, || {
                format!("EM1 and EM2 together at position {position}")
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
        self.period = if cmd.on(EM3) { FEED } else { RAPID };
    }

    fn deadline(&self) -> Option<SimTime> {
        self.run.map(|(_, start)| start.saturating_add(self.period))
    }

    fn on_timer(&mut self, now: SimTime, _cmd: Cmd<'_>, log: &mut ErrorLog) {
        let Some((heading, _)) = self.run else {
            return;
        };
        let from = i16::from(self.position);
        let target = match heading {
            Heading::Right => from + 1,
            Heading::Left => from - 1,
        };
        let (k1, k4) = (i16::from(self.k1()), i16::from(self.k4()));
        let to = u8::try_from(target).ok().filter(|p| (1..=10).contains(p));
        if (k1..=k4).contains(&target) {
            if let Some(to) = to {
                self.position = to;
                self.run = Some((heading, now));
                return;
            }
        }
        if let Some(to) = to {
            self.position = to;
        }
        self.overtravel = true;
        self.run = None;
        let past = match heading {
            Heading::Right => "right past K4",
            Heading::Left => "left past K1",
        };
        log.fail(
            now,
            ErrorKind::Overtravel,
            format!("step {past} from position {from}"),
        );
    }

    fn sensor(&self, index: usize) -> bool {
        self.overtravel || self.sensors.get(index) == Some(&self.position)
    }

    fn state(&self, _cmd: Cmd<'_>) -> Vec<(&'static str, Value)> {
        vec![
            ("position", Value::Real(f64::from(self.position))),
            ("leds", Value::Real(f64::from(self.leds()))),
        ]
    }

    fn describe(&self, _cmd: Cmd<'_>) -> Vec<String> {
        let at = match self.sensor_at(self.position) {
            Some(k) => format!("position {} (K{})", self.position, k + 1),
            None => format!("position {}", self.position),
        };
        let motion = if self.overtravel {
            "overtravel: stopped until RESET".to_owned()
        } else {
            match self.run {
                None => "stopped".to_owned(),
                Some((heading, _)) => format!(
                    "moving {} at {}",
                    match heading {
                        Heading::Right => "right",
                        Heading::Left => "left",
                    },
                    if self.period == FEED {
                        "working feed (1 s/step)"
                    } else {
                        "rapid traverse (0.5 s/step)"
                    }
                ),
            }
        };
        vec![at, motion]
    }
}
