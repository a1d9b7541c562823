//! Service figures of a lift and of a fleet, from the lift's history: time in service,
//! availability, failures and callbacks, MTBF and MTTR, trips and door cycles per
//! floor, the suggested parking floor and the minimum fault log.
//!
//! Sans-IO and clock-free: the history and the period come in as data (the HMI reads
//! them from the station's event store, `hmi::web::lifts`), the figures go out as a value that
//! serialises to the HMI's JSON. Times are station time ([`DateTime<Utc>`]), not the
//! board's clock. Every figure is defined in `docs/LIFT.md`, "Service figures".
//!
//! ```text
//! Observation* (status, position, direction, answering, counters) ─┐
//! FaultAt* (the fault archive)                                     ├─> ServiceFigures::compute
//! Period [from, to), FiguresConfig                                 ┘        │
//!                                         ServiceFigures of each lift ─> FleetFigures::new
//! ```
//!
//! The history is the lift's per-point event history as the store keeps it (the lift's
//! points by `LiftSignal`): one [`Observation`] per change
//! of the status, the car position, the direction, the communication or the trip
//! counters. Include the last observation of each kind at or before `from` (the state at
//! the start of the period); observations at or after `to` are ignored. The input need
//! not be ordered: it is sorted by time first, stably, so observations with the same time
//! apply in the order given.

use std::collections::BTreeMap;
use std::fmt;

use chrono::{DateTime, TimeDelta, Utc};
use serde::{Serialize, Serializer};

use super::codec::Direction;
use super::tables::{
    door_state, fault_group, lift_mode, ColourClass, DoorState, FaultGroup, LiftMode, StatusColours,
};

/// Seconds in the year the figures extrapolate to (365.25 days).
pub const YEAR_SECONDS: f64 = 365.25 * 86_400.0;

/// Seconds in a day.
const DAY_SECONDS: f64 = 86_400.0;

/// Why figures cannot be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FiguresError {
    /// The period's end is not after its start.
    #[error("empty period: {from} is not before {to}")]
    EmptyPeriod {
        /// Start.
        from: DateTime<Utc>,
        /// End.
        to: DateTime<Utc>,
    },
}

/// The period `[from, to)` the figures cover, never empty.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub struct Period {
    from: DateTime<Utc>,
    to: DateTime<Utc>,
}

impl Period {
    /// The period `[from, to)`; `to` must be after `from`.
    pub fn try_new(from: DateTime<Utc>, to: DateTime<Utc>) -> Result<Period, FiguresError> {
        if from < to {
            Ok(Period { from, to })
        } else {
            Err(FiguresError::EmptyPeriod { from, to })
        }
    }

    /// Start (included).
    pub fn from(&self) -> DateTime<Utc> {
        self.from
    }

    /// End (excluded).
    pub fn to(&self) -> DateTime<Utc> {
        self.to
    }

    /// The length, always positive.
    pub fn length(&self) -> TimeDelta {
        self.to.signed_duration_since(self.from)
    }

    /// Whether `time` lies in `[from, to)`.
    pub fn contains(&self, time: DateTime<Utc>) -> bool {
        self.from <= time && time < self.to
    }
}

impl TryFrom<(DateTime<Utc>, DateTime<Utc>)> for Period {
    type Error = FiguresError;

    fn try_from((from, to): (DateTime<Utc>, DateTime<Utc>)) -> Result<Self, Self::Error> {
        Period::try_new(from, to)
    }
}

impl fmt::Display for Period {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[{}, {})", self.from.to_rfc3339(), self.to.to_rfc3339())
    }
}

/// What changed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Observed {
    /// The status code (Appendix A).
    Status(u8),
    /// The car position (raw floor number, EKM-A6).
    Position(u8),
    /// The direction of travel.
    Direction(Direction),
    /// The communication: `false` when the board stopped answering (the poller's
    /// `CommStatus::Lost`), `true` when it answers again. Assumed answering until told
    /// otherwise.
    Answering(bool),
    /// The trip counters, floor 1 first.
    Counters(Vec<u32>),
}

/// A change in a lift's history at a station time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Observation {
    /// When (station time).
    pub time: DateTime<Utc>,
    /// What changed.
    pub what: Observed,
}

impl Observation {
    /// An observation.
    pub fn new(time: DateTime<Utc>, what: Observed) -> Observation {
        Observation { time, what }
    }
}

/// A fault record of the archive at its station time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaultAt {
    /// When (station time).
    pub time: DateTime<Utc>,
    /// The fault code (Appendix B).
    pub code: u8,
}

/// Settings of the figures.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct FiguresConfig {
    /// An out-of-service episode lasting at least this long is a callback (a stoppage
    /// that needs a technician). Default 5 minutes.
    pub callback_min: TimeDelta,
    /// The value at which the trip counters wrap (256 for one-octet counters), or `None`
    /// (default) to take every decrease of a counter as a reset: the counter starts again
    /// from zero, the trips counted are its new value. With a modulus a decrease is taken
    /// as a wrap (`new + modulus − old` trips); a reset then counts too many.
    pub counter_modulus: Option<u64>,
}

impl Default for FiguresConfig {
    fn default() -> Self {
        FiguresConfig {
            callback_min: TimeDelta::minutes(5),
            counter_modulus: None,
        }
    }
}

/// The figures of one lift over a period. Durations serialise as seconds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ServiceFigures {
    /// The period.
    pub period: Period,
    /// Time in normal service ([`LiftMode::NormalService`]).
    #[serde(serialize_with = "seconds")]
    pub normal_service: TimeDelta,
    /// Time out of service ([`LiftMode::OutOfService`]).
    #[serde(serialize_with = "seconds")]
    pub out_of_service: TimeDelta,
    /// Time in inspection mode ([`LiftMode::Inspection`]).
    #[serde(serialize_with = "seconds")]
    pub inspection: TimeDelta,
    /// Time in special operation ([`LiftMode::Other`]).
    #[serde(serialize_with = "seconds")]
    pub other: TimeDelta,
    /// Time unknown: no status yet, an unknown status code, communication lost.
    #[serde(serialize_with = "seconds")]
    pub unknown: TimeDelta,
    /// Normal-service time over the known time (the period less `unknown`); `None` when
    /// nothing is known.
    pub availability: Option<f64>,
    /// Normal-service time over the whole period: the availability if all unknown time
    /// was unavailable.
    pub availability_lower: f64,
    /// Normal-service and unknown time over the whole period: the availability if all
    /// unknown time was in service.
    pub availability_upper: f64,
    /// Transitions into out of service in the period (episodes that began in it).
    pub failures: u64,
    /// Failures whose episode lasted at least [`FiguresConfig::callback_min`] (an
    /// episode still open at `to` counts until `to`).
    pub callbacks: u64,
    /// Failures per year: `failures × year / period length`.
    pub failures_per_year: f64,
    /// Fault-log records per year: `faults × year / period length`.
    pub faults_per_year: f64,
    /// Callbacks per year: `callbacks × year / period length`.
    pub callbacks_per_year: f64,
    /// Out-of-service episodes in the period: the failures and an episode that began
    /// before `from`.
    pub episodes: u64,
    /// The episodes' durations clipped to the period, summed.
    #[serde(serialize_with = "seconds")]
    pub episode_time: TimeDelta,
    /// Mean time between failures: normal-service time / failures; `None` without a
    /// failure.
    #[serde(serialize_with = "seconds_opt")]
    pub mtbf: Option<TimeDelta>,
    /// Mean time to repair: `episode_time / episodes`; `None` without an episode.
    #[serde(serialize_with = "seconds_opt")]
    pub mttr: Option<TimeDelta>,
    /// Trips to each floor in the period from the board's counters, floor 1 first.
    pub trips_per_floor: Vec<u64>,
    /// All trips of `trips_per_floor`.
    pub trips: u64,
    /// Trips per day: `trips × day / period length`.
    pub trips_per_day: f64,
    /// Trips started from each floor (car position), from the observed movements.
    pub trips_started_per_floor: BTreeMap<u8, u64>,
    /// All trips started, also those from an unknown position.
    pub trips_started: u64,
    /// Door cycles at each floor (car position).
    pub door_cycles_per_floor: BTreeMap<u8, u64>,
    /// All door cycles, also those at an unknown position.
    pub door_cycles: u64,
    /// Door cycles per day: `door_cycles × day / period length`.
    pub door_cycles_per_day: f64,
    /// The floor most trips start from (ties: the lowest); `None` without trips.
    pub parking_floor: Option<u8>,
    /// Fault records in the period.
    pub faults: u64,
    /// Fault records per group of the minimum fault log (every group, zeros included).
    pub faults_by_group: BTreeMap<FaultGroup, u64>,
    /// Fault records per code.
    pub faults_by_code: BTreeMap<u8, u64>,
    /// The status at `to`, `None` when unknown (no status, communication lost).
    pub status_at_end: Option<u8>,
    /// The mode at `to`.
    pub mode_at_end: LiftMode,
}

/// An out-of-service episode: `start` is the first and `end` the last out-of-service
/// moment; unknown time between two out-of-service stretches joins them.
#[derive(Debug, Clone, Copy)]
struct Episode {
    start: DateTime<Utc>,
    end: DateTime<Utc>,
}

/// Where the doors are in their cycle, from the door evidence (status codes, movement).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DoorPhase {
    /// Not known, or after a door fault.
    Unknown,
    Closed,
    /// Opened after being closed, at this position.
    Opened(Option<u8>),
}

/// The walk through the history.
struct Walker<'a> {
    period: Period,
    config: &'a FiguresConfig,
    status: Option<u8>,
    answering: bool,
    position: Option<u8>,
    direction: Option<Direction>,
    doors: DoorPhase,
    /// Start of the segment the current state holds for.
    since: DateTime<Utc>,
    times: BTreeMap<LiftMode, TimeDelta>,
    episode: Option<Episode>,
    episodes: Vec<Episode>,
    counters: Option<Vec<u32>>,
    trips_per_floor: Vec<u64>,
    trips_started_per_floor: BTreeMap<u8, u64>,
    trips_started: u64,
    door_cycles_per_floor: BTreeMap<u8, u64>,
    door_cycles: u64,
}

fn add(a: TimeDelta, b: TimeDelta) -> TimeDelta {
    a.checked_add(&b).unwrap_or(TimeDelta::MAX)
}

fn sub(a: TimeDelta, b: TimeDelta) -> TimeDelta {
    a.checked_sub(&b).unwrap_or(TimeDelta::MIN)
}

/// `total / count`, `None` for no count.
fn mean(total: TimeDelta, count: u64) -> Option<TimeDelta> {
    const NANOS: i128 = 1_000_000_000;
    if count == 0 {
        return None;
    }
    let nanos = i128::from(total.num_seconds())
        .saturating_mul(NANOS)
        .saturating_add(i128::from(total.subsec_nanos()));
    let mean = nanos.checked_div(i128::from(count))?;
    let seconds = i64::try_from(mean.div_euclid(NANOS)).ok()?;
    let rest = u32::try_from(mean.rem_euclid(NANOS)).ok()?;
    TimeDelta::new(seconds, rest)
}

/// `a / b` as a fraction; `None` when `b` is not positive.
fn ratio(a: TimeDelta, b: TimeDelta) -> Option<f64> {
    (b > TimeDelta::zero()).then(|| a.as_seconds_f64() / b.as_seconds_f64())
}

/// `count` per `unit` seconds over `length`.
fn rate(count: u64, unit: f64, length: TimeDelta) -> f64 {
    let seconds = length.as_seconds_f64();
    if seconds > 0.0 {
        count as f64 * unit / seconds
    } else {
        0.0
    }
}

fn bump<K: Ord>(map: &mut BTreeMap<K, u64>, key: K) {
    let entry = map.entry(key).or_insert(0);
    *entry = entry.saturating_add(1);
}

impl<'a> Walker<'a> {
    fn new(period: Period, config: &'a FiguresConfig, start: DateTime<Utc>) -> Walker<'a> {
        Walker {
            period,
            config,
            status: None,
            answering: true,
            position: None,
            direction: None,
            doors: DoorPhase::Unknown,
            since: start.min(period.from),
            times: LiftMode::ALL
                .into_iter()
                .map(|mode| (mode, TimeDelta::zero()))
                .collect(),
            episode: None,
            episodes: Vec::new(),
            counters: None,
            trips_per_floor: Vec::new(),
            trips_started_per_floor: BTreeMap::new(),
            trips_started: 0,
            door_cycles_per_floor: BTreeMap::new(),
            door_cycles: 0,
        }
    }

    fn mode(&self) -> LiftMode {
        if self.answering {
            self.status.map_or(LiftMode::Unknown, lift_mode)
        } else {
            LiftMode::Unknown
        }
    }

    /// The current state held from `since` until `until` (at most `to`).
    fn hold_until(&mut self, until: DateTime<Utc>) {
        let start = self.since;
        let end = until.min(self.period.to);
        if end <= start {
            return;
        }
        self.since = end;
        let mode = self.mode();
        let clipped_start = start.max(self.period.from);
        if clipped_start < end {
            let length = end.signed_duration_since(clipped_start);
            if let Some(time) = self.times.get_mut(&mode) {
                *time = add(*time, length);
            }
        }
        match mode {
            LiftMode::OutOfService => match &mut self.episode {
                Some(episode) => episode.end = end,
                None => self.episode = Some(Episode { start, end }),
            },
            // Unknown time neither ends nor extends an episode.
            LiftMode::Unknown => {}
            _ => self.close_episode(),
        }
    }

    fn close_episode(&mut self) {
        if let Some(episode) = self.episode.take() {
            if episode.end > self.period.from {
                self.episodes.push(episode);
            }
        }
    }

    fn apply(&mut self, observation: &Observation) {
        let in_period = self.period.contains(observation.time);
        match &observation.what {
            Observed::Status(code) => {
                self.status = Some(*code);
                if let Some(state) = door_state(*code) {
                    self.door(state, in_period);
                }
            }
            Observed::Position(position) => self.position = Some(*position),
            Observed::Direction(direction) => {
                let moving = matches!(direction, Direction::Up | Direction::Down);
                if moving && self.direction == Some(Direction::Stopped) && in_period {
                    self.trips_started = self.trips_started.saturating_add(1);
                    if let Some(floor) = self.position {
                        bump(&mut self.trips_started_per_floor, floor);
                    }
                }
                if moving {
                    // A car leaves a landing with closed doors.
                    self.door(DoorState::Closed, in_period);
                }
                self.direction = Some(*direction);
            }
            Observed::Answering(answering) => self.answering = *answering,
            Observed::Counters(counters) => self.counters(observation.time, counters),
        }
    }

    fn door(&mut self, state: DoorState, in_period: bool) {
        self.doors = match (self.doors, state) {
            (DoorPhase::Opened(floor), DoorState::Closed) => {
                if in_period {
                    self.door_cycles = self.door_cycles.saturating_add(1);
                    if let Some(floor) = floor {
                        bump(&mut self.door_cycles_per_floor, floor);
                    }
                }
                DoorPhase::Closed
            }
            (_, DoorState::Closed) => DoorPhase::Closed,
            (DoorPhase::Closed, DoorState::Open) => DoorPhase::Opened(self.position),
            (phase, DoorState::Open | DoorState::PartlyOpen) => phase,
            (_, DoorState::Fault) => DoorPhase::Unknown,
        };
    }

    fn counters(&mut self, time: DateTime<Utc>, counters: &[u32]) {
        if time < self.period.from {
            // The latest reading before the period is the baseline.
            self.counters = Some(counters.to_vec());
            return;
        }
        if let Some(old) = self.counters.take() {
            if self.trips_per_floor.len() < counters.len() {
                self.trips_per_floor.resize(counters.len(), 0);
            }
            for (index, (trips, new)) in self
                .trips_per_floor
                .iter_mut()
                .zip(counters.iter())
                .enumerate()
            {
                let new = u64::from(*new);
                let delta = match old.get(index).map(|old| u64::from(*old)) {
                    Some(old) if new >= old => new - old,
                    Some(old) => match self.config.counter_modulus {
                        Some(modulus) if old < modulus && new < modulus => {
                            new.saturating_add(modulus - old)
                        }
                        _ => new,
                    },
                    // A floor the previous reading did not have starts from zero.
                    None => new,
                };
                *trips = trips.saturating_add(delta);
            }
        } else if self.trips_per_floor.len() < counters.len() {
            self.trips_per_floor.resize(counters.len(), 0);
        }
        self.counters = Some(counters.to_vec());
    }
}

impl ServiceFigures {
    /// The figures of one lift over `period` from its history (any order; see the
    /// module doc) and its fault records (those in the period count).
    pub fn compute(
        period: Period,
        observations: &[Observation],
        faults: &[FaultAt],
        config: &FiguresConfig,
    ) -> ServiceFigures {
        let mut sorted: Vec<&Observation> = observations.iter().collect();
        sorted.sort_by_key(|observation| observation.time);
        let start = sorted.first().map_or(period.from, |first| first.time);
        let mut walker = Walker::new(period, config, start);
        for observation in sorted {
            if observation.time >= period.to {
                break;
            }
            walker.hold_until(observation.time);
            walker.apply(observation);
        }
        walker.hold_until(period.to);
        walker.close_episode();

        let time = |mode| {
            walker
                .times
                .get(&mode)
                .copied()
                .unwrap_or_else(TimeDelta::zero)
        };
        let normal_service = time(LiftMode::NormalService);
        let mode_at_end = walker.mode();
        let unknown = time(LiftMode::Unknown);
        let length = period.length();

        let failures_list: Vec<&Episode> = walker
            .episodes
            .iter()
            .filter(|episode| episode.start >= period.from)
            .collect();
        let failures = failures_list.len() as u64;
        let callbacks = failures_list
            .iter()
            .filter(|episode| {
                episode.end.signed_duration_since(episode.start) >= config.callback_min
            })
            .count() as u64;
        let episodes = walker.episodes.len() as u64;
        let episode_time = walker
            .episodes
            .iter()
            .map(|episode| {
                episode
                    .end
                    .min(period.to)
                    .signed_duration_since(episode.start.max(period.from))
            })
            .fold(TimeDelta::zero(), add);

        let trips = walker
            .trips_per_floor
            .iter()
            .fold(0u64, |sum, trips| sum.saturating_add(*trips));
        let mut parking_floor: Option<(u8, u64)> = None;
        for (floor, count) in &walker.trips_started_per_floor {
            if parking_floor.is_none_or(|(_, best)| *count > best) {
                parking_floor = Some((*floor, *count));
            }
        }

        let mut faults_by_group: BTreeMap<FaultGroup, u64> = FaultGroup::ALL
            .into_iter()
            .map(|group| (group, 0))
            .collect();
        let mut faults_by_code = BTreeMap::new();
        let mut fault_count = 0u64;
        for fault in faults.iter().filter(|fault| period.contains(fault.time)) {
            fault_count = fault_count.saturating_add(1);
            bump(&mut faults_by_group, fault_group(fault.code));
            bump(&mut faults_by_code, fault.code);
        }

        ServiceFigures {
            period,
            normal_service,
            out_of_service: time(LiftMode::OutOfService),
            inspection: time(LiftMode::Inspection),
            other: time(LiftMode::Other),
            unknown,
            availability: ratio(normal_service, sub(length, unknown)),
            availability_lower: ratio(normal_service, length).unwrap_or(0.0),
            availability_upper: ratio(add(normal_service, unknown), length).unwrap_or(0.0),
            failures,
            callbacks,
            failures_per_year: rate(failures, YEAR_SECONDS, length),
            faults_per_year: rate(fault_count, YEAR_SECONDS, length),
            callbacks_per_year: rate(callbacks, YEAR_SECONDS, length),
            episodes,
            episode_time,
            mtbf: mean(normal_service, failures),
            mttr: mean(episode_time, episodes),
            trips_per_floor: walker.trips_per_floor,
            trips,
            trips_per_day: rate(trips, DAY_SECONDS, length),
            trips_started_per_floor: walker.trips_started_per_floor,
            trips_started: walker.trips_started,
            door_cycles_per_floor: walker.door_cycles_per_floor,
            door_cycles: walker.door_cycles,
            door_cycles_per_day: rate(walker.door_cycles, DAY_SECONDS, length),
            parking_floor: parking_floor.map(|(floor, _)| floor),
            faults: fault_count,
            faults_by_group,
            faults_by_code,
            status_at_end: walker.status.filter(|_| walker.answering),
            mode_at_end,
        }
    }
}

/// Lifts per colour class of their status at the end of their period.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct ClassCounts {
    /// Green statuses.
    pub green: u64,
    /// Orange statuses.
    pub orange: u64,
    /// Red statuses.
    pub red: u64,
    /// No status known (no data, communication lost).
    pub unknown: u64,
}

/// The figures of several lifts together.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FleetFigures {
    /// Lifts.
    pub lifts: u64,
    /// The lifts' periods summed (lift time).
    #[serde(serialize_with = "seconds")]
    pub lift_time: TimeDelta,
    /// Normal-service time, summed.
    #[serde(serialize_with = "seconds")]
    pub normal_service: TimeDelta,
    /// Out-of-service time, summed.
    #[serde(serialize_with = "seconds")]
    pub out_of_service: TimeDelta,
    /// Inspection time, summed.
    #[serde(serialize_with = "seconds")]
    pub inspection: TimeDelta,
    /// Special-operation time, summed.
    #[serde(serialize_with = "seconds")]
    pub other: TimeDelta,
    /// Unknown time, summed.
    #[serde(serialize_with = "seconds")]
    pub unknown: TimeDelta,
    /// Time-weighted availability: summed normal-service time over summed known time;
    /// `None` when nothing is known.
    pub availability: Option<f64>,
    /// Summed normal-service time over the summed periods.
    pub availability_lower: f64,
    /// Summed normal-service and unknown time over the summed periods.
    pub availability_upper: f64,
    /// Failures, summed.
    pub failures: u64,
    /// Callbacks, summed.
    pub callbacks: u64,
    /// Failures per lift and year: failures × year / lift time.
    pub failures_per_lift_year: f64,
    /// Fault-log records per lift and year: faults × year / lift time.
    pub faults_per_lift_year: f64,
    /// Callbacks per lift and year: callbacks × year / lift time.
    pub callbacks_per_lift_year: f64,
    /// Out-of-service episodes, summed.
    pub episodes: u64,
    /// Summed normal-service time / summed failures; `None` without a failure.
    #[serde(serialize_with = "seconds_opt")]
    pub mtbf: Option<TimeDelta>,
    /// Summed episode time / summed episodes (the mean over all episodes of all
    /// lifts); `None` without an episode.
    #[serde(serialize_with = "seconds_opt")]
    pub mttr: Option<TimeDelta>,
    /// Trips (from the counters), summed.
    pub trips: u64,
    /// Door cycles, summed.
    pub door_cycles: u64,
    /// Fault records, summed.
    pub faults: u64,
    /// Fault records per group, summed (every group).
    pub faults_by_group: BTreeMap<FaultGroup, u64>,
    /// Lifts per mode at the end of their period.
    pub lifts_by_mode: BTreeMap<LiftMode, u64>,
    /// Lifts per colour class of their status at the end of their period.
    pub lifts_by_class: ClassCounts,
}

impl FleetFigures {
    /// The fleet of these lifts; `colours` classes their statuses at the end.
    pub fn new<'a>(
        lifts: impl IntoIterator<Item = &'a ServiceFigures>,
        colours: &StatusColours,
    ) -> FleetFigures {
        let zero = TimeDelta::zero();
        let mut fleet = FleetFigures {
            lifts: 0,
            lift_time: zero,
            normal_service: zero,
            out_of_service: zero,
            inspection: zero,
            other: zero,
            unknown: zero,
            availability: None,
            availability_lower: 0.0,
            availability_upper: 0.0,
            failures: 0,
            callbacks: 0,
            failures_per_lift_year: 0.0,
            faults_per_lift_year: 0.0,
            callbacks_per_lift_year: 0.0,
            episodes: 0,
            mtbf: None,
            mttr: None,
            trips: 0,
            door_cycles: 0,
            faults: 0,
            faults_by_group: FaultGroup::ALL
                .into_iter()
                .map(|group| (group, 0))
                .collect(),
            lifts_by_mode: LiftMode::ALL.into_iter().map(|mode| (mode, 0)).collect(),
            lifts_by_class: ClassCounts::default(),
        };
        let mut episode_time = zero;
        for lift in lifts {
            fleet.lifts = fleet.lifts.saturating_add(1);
            fleet.lift_time = add(fleet.lift_time, lift.period.length());
            fleet.normal_service = add(fleet.normal_service, lift.normal_service);
            fleet.out_of_service = add(fleet.out_of_service, lift.out_of_service);
            fleet.inspection = add(fleet.inspection, lift.inspection);
            fleet.other = add(fleet.other, lift.other);
            fleet.unknown = add(fleet.unknown, lift.unknown);
            fleet.failures = fleet.failures.saturating_add(lift.failures);
            fleet.callbacks = fleet.callbacks.saturating_add(lift.callbacks);
            fleet.episodes = fleet.episodes.saturating_add(lift.episodes);
            episode_time = add(episode_time, lift.episode_time);
            fleet.trips = fleet.trips.saturating_add(lift.trips);
            fleet.door_cycles = fleet.door_cycles.saturating_add(lift.door_cycles);
            fleet.faults = fleet.faults.saturating_add(lift.faults);
            for (group, count) in &lift.faults_by_group {
                let entry = fleet.faults_by_group.entry(*group).or_insert(0);
                *entry = entry.saturating_add(*count);
            }
            bump(&mut fleet.lifts_by_mode, lift.mode_at_end);
            let class = &mut fleet.lifts_by_class;
            let counter = match lift.status_at_end.map(|status| colours.class(status)) {
                Some(ColourClass::Green) => &mut class.green,
                Some(ColourClass::Orange) => &mut class.orange,
                Some(ColourClass::Red) => &mut class.red,
                None => &mut class.unknown,
            };
            *counter = counter.saturating_add(1);
        }
        let known = sub(fleet.lift_time, fleet.unknown);
        fleet.availability = ratio(fleet.normal_service, known);
        fleet.availability_lower = ratio(fleet.normal_service, fleet.lift_time).unwrap_or(0.0);
        fleet.availability_upper =
            ratio(add(fleet.normal_service, fleet.unknown), fleet.lift_time).unwrap_or(0.0);
        fleet.failures_per_lift_year = rate(fleet.failures, YEAR_SECONDS, fleet.lift_time);
        fleet.faults_per_lift_year = rate(fleet.faults, YEAR_SECONDS, fleet.lift_time);
        fleet.callbacks_per_lift_year = rate(fleet.callbacks, YEAR_SECONDS, fleet.lift_time);
        fleet.mtbf = mean(fleet.normal_service, fleet.failures);
        fleet.mttr = mean(episode_time, fleet.episodes);
        fleet
    }
}

/// A duration as seconds (JSON number).
fn seconds<S: Serializer>(duration: &TimeDelta, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_f64(duration.as_seconds_f64())
}

/// An optional duration as seconds or `null`.
fn seconds_opt<S: Serializer>(
    duration: &Option<TimeDelta>,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    match duration {
        Some(duration) => serializer.serialize_some(&duration.as_seconds_f64()),
        None => serializer.serialize_none(),
    }
}
