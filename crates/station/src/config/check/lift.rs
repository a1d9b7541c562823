//! The checks of a node's lifts (`[[node.lift]]`) and the points each one brings.
//!
//! A lift's points are not written in the project: each lift has the same signals
//! ([`LiftSignal`]), so its points follow from its name and `ioa_base` (`L1.status` at
//! `ioa_base`, `L1.floor3_trips` at `ioa_base + 18` ...). A service firm adds a lift in
//! six lines; the IOAs still have to be free, and are checked like written ones.

use super::*;
use devices::ekm66::codec::{CounterWidth, DirectionCoding, StatusLayout, TimeEncoding};
use devices::ekm66::poller::{IndexBase, PollerConfig};
use devices::ekm66::simulator::SimulatorConfig;
use points::LiftSignal;
use simulators::registry::Speaks;

/// The floors a board reports (the simulator's and the counters' range).
const FLOORS: std::ops::RangeInclusive<i64> = 2..=60;

/// Every signal of a lift with `floors` floors, in IOA order.
pub(crate) fn lift_signals(floors: u8) -> impl Iterator<Item = LiftSignal> {
    LiftSignal::COMMON
        .into_iter()
        .chain((1..=floors).map(LiftSignal::FloorTrips))
}

/// The name of a lift's point for `signal`.
pub(crate) fn lift_point_name(lift: &str, signal: LiftSignal) -> String {
    format!("{lift}.{}", signal.suffix())
}

impl Ctx<'_> {
    /// Checks the node's lifts and returns them with the points they bring (added to
    /// `taken`).
    pub(in crate::config) fn check_lifts(
        &mut self,
        n: usize,
        raw: &RawNode,
        mut taken: TakenPoints<'_>,
    ) -> (Vec<LiftConfig>, Vec<PointConfig>) {
        let mut lifts = Vec::new();
        let mut points = Vec::new();
        let mut names = HashSet::new();
        for (l, lift) in raw.lift.iter().enumerate() {
            let at =
                |key: &'static str| -> Vec<Seg> { vec![K("node"), I(n), K("lift"), I(l), K(key)] };
            let whole = [K("node"), I(n), K("lift"), I(l)];
            if !names.insert(lift.name.clone()) {
                self.err(
                    &at("name"),
                    ConfigProblem::Duplicate {
                        what: Unique::LiftName,
                        value: lift.name.clone(),
                        other: raw.name.clone(),
                    },
                );
            }
            if lift.name.trim().is_empty() {
                self.err(&at("name"), ConfigProblem::Empty { what: "lift name" });
            }
            let floors = self
                .integer_in(Some(lift.floors), "floors", FLOORS, &at("floors"))
                .and_then(|floors| u8::try_from(floors).ok())
                .unwrap_or(2);
            let ioa_base = match ioa(lift.ioa_base) {
                Ok(base) => base,
                Err(problem) => {
                    self.err(&at("ioa_base"), problem);
                    Ioa::IRRELEVANT
                }
            };
            let settings = self.serial_settings(
                SerialKeys {
                    baud: lift.baud,
                    parity: lift.parity.as_deref(),
                    stop_bits: lift.stop_bits,
                },
                &at,
                &whole,
            );
            let mut poller = PollerConfig::default();
            poller.line = settings;
            poller.reply_timeout =
                self.millis_in(lift.timeout_ms, 500, 5..=60_000, &at("timeout_ms"));
            poller.retries = self.retries_in(lift.retries, 3, &at("retries"));
            poller.poll_period = self.millis_in(
                lift.poll_period_ms,
                1000,
                10..=3_600_000,
                &at("poll_period_ms"),
            );
            poller.counters_period = self.millis_in(
                lift.counters_period_ms,
                60_000,
                100..=86_400_000,
                &at("counters_period_ms"),
            );
            poller.index_base =
                match self.integer_in(lift.index_base, "index_base", 0..=1, &at("index_base")) {
                    Some(0) => IndexBase::Zero,
                    Some(_) => IndexBase::One,
                    None => IndexBase::Detect,
                };
            let layouts = match lift.status_layout.as_deref() {
                None | Some("any") => vec![StatusLayout::ADOPTED, StatusLayout::ALTERNATIVE],
                Some("adopted") => vec![StatusLayout::ADOPTED],
                Some("alternative") => vec![StatusLayout::ALTERNATIVE],
                Some(other) => {
                    self.err(
                        &at("status_layout"),
                        ConfigProblem::UnknownValue {
                            what: Vocabulary::StatusLayout,
                            value: other.to_owned(),
                        },
                    );
                    vec![StatusLayout::ADOPTED, StatusLayout::ALTERNATIVE]
                }
            };
            poller.codec.status_layouts = layouts;
            if let Some(width) = lift.counter_width {
                match u8::try_from(width).ok().and_then(CounterWidth::from_octets) {
                    Some(width) => poller.codec.counter_width = width,
                    None => self.err(
                        &at("counter_width"),
                        ConfigProblem::Invalid {
                            detail: format!(
                                "counter_width {width}: a trip counter is 1, 2 or 4 octets"
                            ),
                        },
                    ),
                }
            }
            match lift.time_coding.as_deref() {
                None | Some("binary") => poller.codec.time = TimeEncoding::Binary,
                Some("bcd") => poller.codec.time = TimeEncoding::Bcd,
                Some(other) => self.err(
                    &at("time_coding"),
                    ConfigProblem::UnknownValue {
                        what: Vocabulary::TimeCoding,
                        value: other.to_owned(),
                    },
                ),
            }
            if let Some(year) =
                self.integer_in(lift.year_base, "year_base", 1900..=2200, &at("year_base"))
            {
                poller.codec.year_base = u16::try_from(year).unwrap_or(2000);
            }
            if let Some(codes) = lift.direction {
                let octet = |code: i64| u8::try_from(code).ok();
                match (octet(codes[0]), octet(codes[1]), octet(codes[2])) {
                    (Some(stopped), Some(up), Some(down))
                        if stopped != up && up != down && stopped != down =>
                    {
                        poller.codec.direction = DirectionCoding { stopped, up, down };
                    }
                    _ => self.err(
                        &at("direction"),
                        ConfigProblem::Invalid {
                            detail:
                                "direction = [stopped, up, down]: three different octets 0..=255"
                                    .to_owned(),
                        },
                    ),
                }
            }
            let simulated_only = [
                ("fault_stack", lift.fault_stack.is_some()),
                ("seed", lift.seed.is_some()),
                ("speed", lift.speed.is_some()),
                ("fault_probability", lift.fault_probability.is_some()),
            ];
            let transport = match (&lift.port, &lift.tcp, &lift.simulate) {
                (Some(port), None, None) => LiftTransport::Serial(port.clone()),
                (None, Some(tcp), None) => LiftTransport::Tcp(tcp.clone()),
                (None, None, Some(board)) => {
                    if simulators::registry::find(board)
                        .is_none_or(|device| device.speaks != Speaks::Ekm66)
                    {
                        self.err(
                            &at("simulate"),
                            ConfigProblem::UnknownValue {
                                what: Vocabulary::SimulatedLift,
                                value: board.clone(),
                            },
                        );
                    }
                    LiftTransport::Simulated(self.simulated_board(lift, l, floors, &poller, &at))
                }
                _ => {
                    self.err(&whole, Conflict::LineTransport);
                    LiftTransport::Simulated(SimulatorConfig::default())
                }
            };
            if !matches!(transport, LiftTransport::Simulated(_)) {
                for (key, given) in simulated_only {
                    if given {
                        self.err(
                            &at(key),
                            ConfigProblem::Invalid {
                                detail: format!(
                                    "{key} is for simulated boards (simulate = \"ekm66\")"
                                ),
                            },
                        );
                    }
                }
            }
            let description = if lift.description.is_empty() {
                String::new()
            } else {
                format!(" ({})", lift.description)
            };
            for signal in lift_signals(floors) {
                let generated = GeneratedPoint {
                    name: lift_point_name(&lift.name, signal),
                    base: ioa_base,
                    offset: signal.offset(),
                    point_type: signal.point_type(),
                    source: PointSource::Lift {
                        lift: lift.name.clone(),
                        signal,
                    },
                    storage: signal.storage(),
                    description: format!("{} {}{description}", lift.name, signal.description()),
                };
                match self.generated_point(generated, &raw.name, &mut taken, &at) {
                    Some(point) => points.push(point),
                    None => break,
                }
            }
            lifts.push(LiftConfig {
                name: lift.name.clone(),
                description: lift.description.clone(),
                floors,
                ioa_base,
                transport,
                poller,
            });
        }
        (lifts, points)
    }

    /// The simulated board of a lift: its floors, the poller's codings, the
    /// simulation-only keys.
    fn simulated_board(
        &mut self,
        lift: &RawLift,
        index: usize,
        floors: u8,
        poller: &PollerConfig,
        at: &dyn Fn(&'static str) -> Vec<Seg>,
    ) -> SimulatorConfig {
        let mut board = SimulatorConfig::default();
        board.floors = floors;
        board.line = poller.line;
        board.codec = poller.codec.clone();
        board.status_layout = poller
            .codec
            .status_layouts
            .first()
            .copied()
            .unwrap_or(StatusLayout::ADOPTED);
        board.index_base = u8::from(poller.index_base == IndexBase::One);
        if let Some(slots) = self
            .integer_in(lift.fault_stack, "fault_stack", 1..=255, &at("fault_stack"))
            .and_then(|slots| u8::try_from(slots).ok())
        {
            board.stack_size = slots;
        }
        board.seed = match lift.seed {
            Some(seed) => seed.unsigned_abs(),
            // Lifts of one project differ unless told otherwise.
            None => u64::try_from(index).unwrap_or_default() + 1,
        };
        if let Some(speed) = lift.speed {
            if speed.is_finite() && (0.01..=10_000.0).contains(&speed) {
                board.speed = speed;
            } else {
                self.err(
                    &at("speed"),
                    ConfigProblem::Invalid {
                        detail: format!("speed {speed}: board seconds per second, 0.01..=10000"),
                    },
                );
            }
        }
        if let Some(probability) = lift.fault_probability {
            if (0.0..=1.0).contains(&probability) {
                board.fault_probability = probability;
            } else {
                self.err(
                    &at("fault_probability"),
                    ConfigProblem::Invalid {
                        detail: format!("fault_probability {probability}: a probability 0..=1"),
                    },
                );
            }
        }
        board
    }
}
