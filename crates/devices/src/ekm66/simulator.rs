//! An EKM66 board without a line, sans-IO: a lift with N floors on a virtual clock
//! answering the three queries.
//!
//! The board's calendar runs on the caller's `Instant`s, [`SimulatorConfig::speed`]
//! times faster than real time. The car parks, travels floor by floor (the trip counter
//! of the destination counts on arrival), opens, holds and closes its doors; some trips
//! end in a status episode (the next code of Appendix A, so that every status shows in
//! turn) or a random fault. Faults go into a ring of [`SimulatorConfig::stack_size`]
//! slots: each into the slot after the last, wrapping to the first. The
//! [`BoardMemory`] (fault stack and counters) survives a restart when the caller keeps
//! it, as the board's non-volatile memory does.
//!
//! Console operations: [`Simulator::inject_fault`], [`Simulator::hold_status`],
//! [`Simulator::request_trip`], [`Simulator::set_silent`] (stop answering),
//! [`Simulator::clear_log`].

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use chrono::{Datelike as _, NaiveDate, NaiveDateTime, Timelike as _};
use rand::rngs::StdRng;
use rand::{RngExt as _, SeedableRng as _};
use serde::{Deserialize, Serialize};
use serial_line::{LineEndpoint, LineSettings};

use super::codec::{
    encode_reply, CodecConfig, Deframer, Direction, FaultRecord, FaultTime, Query, Reply, Status,
    StatusLayout, TimeOfDay,
};
use super::tables::{DoorState, FAULT_CODES, STATUS_CODES};

/// The simulator's settings.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct SimulatorConfig {
    /// Floors, numbered 1..=floors (2..=60).
    pub floors: u8,
    /// Slots of the fault stack (1..=255).
    pub stack_size: u8,
    /// The index of the first slot (0 or 1).
    pub index_base: u8,
    /// The status reply's layout.
    pub status_layout: StatusLayout,
    /// The encoders (counter width, time coding, direction, year base).
    pub codec: CodecConfig,
    /// Speed and format of the line (for the reply delay).
    pub line: LineSettings,
    /// Board seconds per real second.
    pub speed: f64,
    /// Seed of the random source.
    pub seed: u64,
    /// The board's calendar at start.
    pub start: NaiveDateTime,
    /// Probability of a random fault at the end of a trip (0..=1).
    pub fault_probability: f64,
    /// Probability of a status episode at the end of a trip (0..=1).
    pub status_probability: f64,
    /// Board seconds between two trips, at most (the least is 2).
    pub max_dwell: u32,
}

impl Default for SimulatorConfig {
    fn default() -> Self {
        SimulatorConfig {
            floors: 5,
            stack_size: 16,
            index_base: 0,
            status_layout: StatusLayout::ADOPTED,
            codec: CodecConfig::default(),
            line: LineSettings::new(9600),
            speed: 1.0,
            seed: 0,
            start: NaiveDate::from_ymd_opt(2022, 3, 14)
                .and_then(|date| date.and_hms_opt(8, 0, 0))
                .unwrap_or_default(),
            fault_probability: 0.05,
            status_probability: 0.1,
            max_dwell: 20,
        }
    }
}

/// A fault in the stack.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct StoredFault {
    /// When.
    pub time: FaultTime,
    /// Fault code.
    pub code: u8,
    /// Floor of the car.
    pub floor: u8,
    /// Target floor (0 at rest).
    pub target: u8,
}

/// The board's non-volatile memory: the fault stack and the trip counters.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct BoardMemory {
    /// The slots, first slot first.
    pub slots: Vec<Option<StoredFault>>,
    /// The position (0-based) of the last fault stored.
    pub last: Option<usize>,
    /// Trips to each floor, floor 1 first.
    pub counters: Vec<u32>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Parked,
    Travelling,
    Opening,
    Open,
    Closing,
}

/// What the simulator reports to its console.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SimEvent {
    /// A query was answered.
    Answered(Query),
    /// A fault was stored at this index.
    FaultStored(FaultRecord),
    /// The status code changed.
    StatusChanged(u8),
    /// The car arrived at a floor at the end of a trip.
    Arrived(u8),
}

/// The simulated board.
#[derive(Debug)]
pub struct Simulator {
    config: SimulatorConfig,
    memory: BoardMemory,
    rng: StdRng,
    origin: Instant,
    /// Board time since `config.start` reached so far.
    elapsed: Duration,
    phase: Phase,
    next_at: Duration,
    position: u8,
    target: u8,
    direction: Direction,
    episode: Option<(u8, Duration)>,
    held_status: Option<u8>,
    next_status: usize,
    requests: VecDeque<u8>,
    status: u8,
    silent: bool,
    deframer: Deframer,
    answer: Option<(Instant, Vec<u8>)>,
    events: VecDeque<SimEvent>,
    queries: u64,
}

impl Simulator {
    /// A board switched on at `now` with an empty memory.
    pub fn new(config: SimulatorConfig, now: Instant) -> Simulator {
        Simulator::with_memory(config, BoardMemory::default(), now)
    }

    /// A board switched on at `now` with the memory it had (a restart).
    pub fn with_memory(
        config: SimulatorConfig,
        mut memory: BoardMemory,
        now: Instant,
    ) -> Simulator {
        let mut config = config;
        config.floors = config.floors.clamp(2, 60);
        config.stack_size = config.stack_size.max(1);
        config.index_base = config.index_base.min(1);
        config.speed = if config.speed.is_finite() && config.speed > 0.0 {
            config.speed
        } else {
            1.0
        };
        memory.slots.resize(usize::from(config.stack_size), None);
        if memory.last.is_some_and(|last| last >= memory.slots.len()) {
            memory.last = None;
        }
        memory.counters.resize(usize::from(config.floors), 0);
        let rng = StdRng::seed_from_u64(config.seed);
        Simulator {
            memory,
            rng,
            origin: now,
            elapsed: Duration::ZERO,
            phase: Phase::Parked,
            next_at: Duration::from_secs(2),
            position: 1,
            target: 1,
            direction: Direction::Stopped,
            episode: None,
            held_status: None,
            next_status: 0,
            requests: VecDeque::new(),
            status: 1,
            silent: false,
            deframer: Deframer::new(),
            answer: None,
            events: VecDeque::new(),
            queries: 0,
            config,
        }
    }

    /// The settings.
    pub fn config(&self) -> &SimulatorConfig {
        &self.config
    }

    /// The non-volatile memory, to keep across a restart.
    pub fn memory(&self) -> &BoardMemory {
        &self.memory
    }

    /// The next console event.
    pub fn poll_event(&mut self) -> Option<SimEvent> {
        self.events.pop_front()
    }

    /// Queries answered so far.
    pub fn queries_answered(&self) -> u64 {
        self.queries
    }

    /// The board's calendar now.
    pub fn board_time(&self) -> NaiveDateTime {
        chrono::TimeDelta::from_std(self.elapsed)
            .ok()
            .and_then(|delta| self.config.start.checked_add_signed(delta))
            .unwrap_or(self.config.start)
    }

    /// The status the board shows.
    pub fn status(&self) -> Status {
        let now = self.board_time();
        Status {
            code: self.status,
            position: self.position,
            target: self.target,
            direction: self.direction,
            time: TimeOfDay {
                hour: u8::try_from(now.hour()).unwrap_or(0),
                minute: u8::try_from(now.minute()).unwrap_or(0),
                second: u8::try_from(now.second()).unwrap_or(0),
            },
        }
    }

    /// The door state of the simulated car (closed, partly open while opening or
    /// closing, open; the simulator has no door fault). Not in the protocol: the
    /// console shows it.
    pub fn doors(&self) -> DoorState {
        match self.phase {
            Phase::Parked | Phase::Travelling => DoorState::Closed,
            Phase::Opening | Phase::Closing => DoorState::PartlyOpen,
            Phase::Open => DoorState::Open,
        }
    }

    /// Stops or resumes answering queries (a broken cable, a board switched off).
    pub fn set_silent(&mut self, silent: bool) {
        self.silent = silent;
        if silent {
            self.answer = None;
        }
    }

    /// Shows this status until [`Simulator::release_status`] (a technician's
    /// intervention); any code, known or not.
    pub fn hold_status(&mut self, code: u8) {
        self.held_status = Some(code);
        self.update_status();
    }

    /// Back to the status the lift's operation gives.
    pub fn release_status(&mut self) {
        self.held_status = None;
        self.update_status();
    }

    /// Asks for a trip to a floor (as a call button would); out-of-range floors are
    /// ignored. Returns whether it was queued.
    pub fn request_trip(&mut self, floor: u8) -> bool {
        if (1..=self.config.floors).contains(&floor) {
            self.requests.push_back(floor);
            true
        } else {
            false
        }
    }

    /// Stores a fault now (any code, known or not) and returns the record as the board
    /// will report it.
    pub fn inject_fault(&mut self, code: u8) -> FaultRecord {
        let now = self.board_time();
        let time = FaultTime {
            year: u16::try_from(now.year()).unwrap_or(0),
            month: u8::try_from(now.month()).unwrap_or(0),
            day: u8::try_from(now.day()).unwrap_or(0),
            time: self.status().time,
        };
        let fault = StoredFault {
            time,
            code,
            floor: self.position,
            target: if self.phase == Phase::Travelling {
                self.target
            } else {
                0
            },
        };
        let slot = self
            .memory
            .last
            .map_or(0, |last| (last + 1) % self.memory.slots.len().max(1));
        if let Some(entry) = self.memory.slots.get_mut(slot) {
            *entry = Some(fault);
        }
        self.memory.last = Some(slot);
        let record = self.record(slot, fault);
        self.events.push_back(SimEvent::FaultStored(record));
        record
    }

    /// Clears the fault log.
    pub fn clear_log(&mut self) {
        self.memory.slots.iter_mut().for_each(|slot| *slot = None);
        self.memory.last = None;
    }

    fn index_of(&self, slot: usize) -> u8 {
        u8::try_from(slot + usize::from(self.config.index_base)).unwrap_or(u8::MAX)
    }

    fn record(&self, slot: usize, fault: StoredFault) -> FaultRecord {
        FaultRecord {
            index: self.index_of(slot),
            last_index: self.memory.last.map_or(0, |last| self.index_of(last)),
            time: fault.time,
            code: fault.code,
            floor: fault.floor,
            target: fault.target,
        }
    }

    /// The reply to a query.
    pub fn reply(&self, query: Query) -> Reply {
        match query {
            Query::Status => Reply::Status(self.status()),
            Query::Counters => Reply::Counters(self.memory.counters.clone()),
            Query::FaultRecord(index) => {
                let fault = usize::from(index)
                    .checked_sub(usize::from(self.config.index_base))
                    .and_then(|slot| {
                        self.memory
                            .slots
                            .get(slot)
                            .copied()
                            .flatten()
                            .map(|fault| (slot, fault))
                    });
                match fault {
                    Some((slot, fault)) => Reply::Fault(self.record(slot, fault)),
                    None => Reply::EmptySlot { index },
                }
            }
        }
    }

    /// The reply's octets.
    pub fn reply_bytes(&self, query: Query) -> Vec<u8> {
        let index = match query {
            Query::FaultRecord(index) => index,
            _ => 0,
        };
        encode_reply(
            &self.reply(query),
            self.config.status_layout,
            &self.config.codec,
            index,
        )
    }

    fn board_elapsed(&self, now: Instant) -> Duration {
        let real = now.saturating_duration_since(self.origin).as_secs_f64();
        Duration::try_from_secs_f64(real * self.config.speed).unwrap_or(Duration::MAX)
    }

    fn real_instant(&self, board: Duration) -> Instant {
        let real = Duration::try_from_secs_f64(board.as_secs_f64() / self.config.speed)
            .unwrap_or(Duration::MAX);
        self.origin.checked_add(real).unwrap_or(self.origin)
    }

    fn secs(seconds: u64) -> Duration {
        Duration::from_secs(seconds)
    }

    fn update_status(&mut self) {
        let status = self
            .held_status
            .or(self.episode.map(|(code, _)| code))
            .unwrap_or(1);
        if status != self.status {
            self.status = status;
            self.events.push_back(SimEvent::StatusChanged(status));
        }
    }

    /// Advances the lift to the board time `now` gives.
    pub fn handle_timeout(&mut self, now: Instant) {
        let target = self.board_elapsed(now);
        // Step through every lift event up to the target time.
        let mut steps = 0;
        while self.next_at <= target && steps < 100_000 {
            steps += 1;
            self.elapsed = self.next_at;
            if let Some((_, until)) = self.episode {
                if until <= self.elapsed {
                    self.episode = None;
                    self.update_status();
                }
            }
            self.step();
        }
        self.elapsed = self.elapsed.max(target);
        if let Some((_, until)) = self.episode {
            if until <= self.elapsed {
                self.episode = None;
                self.update_status();
            }
        }
    }

    fn step(&mut self) {
        let at = self.next_at;
        match self.phase {
            Phase::Parked => {
                let floors = self.config.floors;
                let target = match self.requests.pop_front() {
                    Some(floor) => floor,
                    None => {
                        let pick = self.rng.random_range(1..floors);
                        if pick >= self.position {
                            pick + 1
                        } else {
                            pick
                        }
                    }
                };
                if target == self.position {
                    self.phase = Phase::Opening;
                    self.next_at = at.saturating_add(Self::secs(2));
                } else {
                    self.target = target;
                    self.direction = if target > self.position {
                        Direction::Up
                    } else {
                        Direction::Down
                    };
                    self.phase = Phase::Travelling;
                    self.next_at = at.saturating_add(Self::secs(3));
                }
            }
            Phase::Travelling => {
                self.position = match self.direction {
                    Direction::Up => self.position.saturating_add(1),
                    Direction::Down => self.position.saturating_sub(1),
                    _ => self.target,
                };
                if self.position == self.target {
                    self.direction = Direction::Stopped;
                    if let Some(counter) = self
                        .memory
                        .counters
                        .get_mut(usize::from(self.target).saturating_sub(1))
                    {
                        *counter = counter.saturating_add(1);
                    }
                    self.events.push_back(SimEvent::Arrived(self.target));
                    self.end_of_trip(at);
                    self.phase = Phase::Opening;
                    self.next_at = at.saturating_add(Self::secs(2));
                } else {
                    self.next_at = at.saturating_add(Self::secs(3));
                }
            }
            Phase::Opening => {
                self.phase = Phase::Open;
                self.next_at = at.saturating_add(Self::secs(4));
            }
            Phase::Open => {
                self.phase = Phase::Closing;
                self.next_at = at.saturating_add(Self::secs(2));
            }
            Phase::Closing => {
                self.phase = Phase::Parked;
                let dwell = self.rng.random_range(2..=self.config.max_dwell.max(2));
                self.next_at = at.saturating_add(Self::secs(u64::from(dwell)));
            }
        }
    }

    fn end_of_trip(&mut self, at: Duration) {
        let status_probability = self.config.status_probability.clamp(0.0, 1.0);
        if self.episode.is_none() && self.rng.random_bool(status_probability) {
            let entry = STATUS_CODES.get(self.next_status % STATUS_CODES.len().max(1));
            self.next_status = self.next_status.wrapping_add(1);
            if let Some(entry) = entry {
                let seconds = self.rng.random_range(5..=20u64);
                self.episode = Some((entry.code, at.saturating_add(Self::secs(seconds))));
                self.update_status();
            }
        }
        let fault_probability = self.config.fault_probability.clamp(0.0, 1.0);
        if self.rng.random_bool(fault_probability) {
            let pick = self.rng.random_range(0..FAULT_CODES.len().max(1));
            if let Some(entry) = FAULT_CODES.get(pick) {
                self.inject_fault(entry.code);
            }
        }
    }

    /// Octets from the master; a complete query is answered after the line's idle time.
    pub fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.handle_timeout(now);
        self.deframer.push(bytes);
        while let Some(next) = self.deframer.next_frame() {
            let Ok(frame) = next else { continue };
            let Ok(query) = Query::from_user_data(frame.user_data()) else {
                continue;
            };
            if self.silent {
                continue;
            }
            self.queries += 1;
            self.events.push_back(SimEvent::Answered(query));
            self.answer = Some((now + self.config.line.idle_time(), self.reply_bytes(query)));
        }
    }

    /// The reply to write now.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        match &self.answer {
            Some((at, _)) if *at <= now => self.answer.take().map(|(_, bytes)| bytes),
            _ => None,
        }
    }

    /// When the lift next changes or a reply is due.
    pub fn poll_timeout(&self) -> Option<Instant> {
        let lift = self.real_instant(self.next_at);
        let episode = self.episode.map(|(_, until)| self.real_instant(until));
        let answer = self.answer.as_ref().map(|(at, _)| *at);
        [Some(lift), episode, answer].into_iter().flatten().min()
    }
}

impl LineEndpoint for Simulator {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        Simulator::handle_bytes(self, now, bytes);
    }
    fn handle_line_pause(&mut self, _now: Instant) {
        self.deframer.abandon();
    }
    fn handle_timeout(&mut self, now: Instant) {
        Simulator::handle_timeout(self, now);
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        Simulator::poll_transmit(self, now)
    }
    fn next_deadline(&self) -> Option<Instant> {
        self.poll_timeout()
    }
    fn line(&self) -> LineSettings {
        self.config.line
    }
}
