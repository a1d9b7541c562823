//! The polling state machine of spec §8, sans-IO: octets and `Instant`s in, query
//! octets and [`Event`]s out.
//!
//! A cycle starts every [`PollerConfig::poll_period`]: the status query, the trip
//! counters when [`PollerConfig::counters_period`] has passed, then the fault log until
//! nothing new is left. Each query waits [`PollerConfig::reply_timeout`] after it has
//! left the line and is repeated [`PollerConfig::retries`] times; when the last repeat
//! goes unanswered the lift's communication is lost (one [`Event::Comm`]) and the cycle
//! ends. Every time-out and every invalid frame adds to the error counter; an invalid
//! reply is never stored.
//!
//! # Fault-log synchronisation
//!
//! The board keeps its faults in a ring (the fault stack): each new fault goes to the
//! slot after the last one, the index wrapping to the first slot after the board's last
//! slot. Every fault reply carries the index of the last stored record (spec §4.3).
//! The poller keeps an [`ArchiveCursor`] — the index base, the last record archived and
//! the keys of the records archived recently — which the caller stores after each
//! [`Event::Fault`] and hands back to [`Poller::new`] after a restart:
//!
//! 1. Without a known index base, read index 0, then 1 (EKM-A7): the first that holds a
//!    record is the base (a record at 1 is confirmed by reading 0 again, in case the
//!    first fault arrived in between). Both empty: the log is empty; try again next
//!    cycle.
//! 2. Each cycle reads the slot of the last archived record. If it still holds that
//!    record, its last-index octet says what is new: read the following slots up to it,
//!    wrapping to the base when a slot past the board's end answers empty.
//! 3. Without a last record (a new archive), or when that slot now holds another record
//!    (the board wrapped past it while the monitor was away, or its log was cleared and
//!    refilled), or is empty (the log was cleared): read the whole stack, oldest first —
//!    from the slot after the last index when it holds a record (a full, wrapped stack),
//!    else from the base — and archive what the cursor does not know.
//!
//! A record is archived once: its key (index, time, code) is checked against the
//! cursor. So neither a restart of the monitor (the cursor is stored) nor a restart of
//! the board (its stack is non-volatile; a cleared stack is read again from the base)
//! nor the wrap-around of the index makes a duplicate or a gap, as long as the board
//! does not overwrite records the monitor has not read yet (more faults than the stack
//! holds while the monitor is away), which no monitor can recover.

use std::collections::VecDeque;
use std::fmt;
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};
use serial_line::{LineEndpoint, LineSettings};

use super::codec::{
    decode_reply, CodecConfig, Deframer, FaultRecord, FaultTime, FrameError, Query, Reply,
    ReplyError, Status,
};

/// How the fault stack's first index is found (EKM-A7).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum IndexBase {
    /// Read index 0, then 1: the first holding a record is the base (default).
    #[default]
    Detect,
    /// The stack starts at 0.
    Zero,
    /// The stack starts at 1.
    One,
}

/// The poller's settings; defaults per spec EKM-A1 and EKM-A7.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct PollerConfig {
    /// Speed and character format (9600 8E1), for the transmit time of a query.
    pub line: LineSettings,
    /// The reply decoders.
    pub codec: CodecConfig,
    /// From the start of one cycle to the next (1 s).
    pub poll_period: Duration,
    /// From one counter query to the next (60 s).
    pub counters_period: Duration,
    /// How long to wait for a reply once the query has left (500 ms).
    pub reply_timeout: Duration,
    /// Repeats of an unanswered query before the communication counts as lost (3).
    pub retries: u8,
    /// The fault stack's first index.
    pub index_base: IndexBase,
    /// The highest index the board may use; after it the index wraps to the base
    /// (255). A board with a smaller stack is recognised by an empty slot past its end.
    pub max_index: u8,
    /// Record keys the cursor remembers against duplicates (at least a stack's worth).
    pub remembered: usize,
}

impl Default for PollerConfig {
    fn default() -> Self {
        PollerConfig {
            line: LineSettings::new(9600),
            codec: CodecConfig::default(),
            poll_period: Duration::from_secs(1),
            counters_period: Duration::from_secs(60),
            reply_timeout: Duration::from_millis(500),
            retries: 3,
            index_base: IndexBase::Detect,
            max_index: u8::MAX,
            remembered: 1024,
        }
    }
}

/// What identifies a fault record (spec §8: same index and timestamp, and the code).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct FaultKey {
    /// The slot.
    pub index: u8,
    /// The time of occurrence.
    pub time: FaultTime,
    /// The fault code.
    pub code: u8,
}

impl From<&FaultRecord> for FaultKey {
    fn from(record: &FaultRecord) -> Self {
        FaultKey {
            index: record.index,
            time: record.time,
            code: record.code,
        }
    }
}

/// Where the archive stands in the board's fault log: stored by the caller after each
/// [`Event::Fault`] (serialisable), given back to [`Poller::new`] after a restart.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ArchiveCursor {
    /// The detected index base.
    pub base: Option<u8>,
    /// The last record archived (or found archived) in the board's order.
    pub last: Option<FaultKey>,
    /// Keys of recently archived records, oldest first.
    pub known: VecDeque<FaultKey>,
}

impl ArchiveCursor {
    /// Whether the archive has this record.
    pub fn contains(&self, record: &FaultRecord) -> bool {
        let key = FaultKey::from(record);
        self.known.iter().any(|known| *known == key)
    }

    fn remember(&mut self, record: &FaultRecord, capacity: usize) {
        if !self.contains(record) {
            self.known.push_back(FaultKey::from(record));
            while self.known.len() > capacity.max(1) {
                self.known.pop_front();
            }
        }
        self.last = Some(FaultKey::from(record));
    }
}

/// The lift's communication status (a point per lift).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum CommStatus {
    /// No reply yet.
    Unknown,
    /// The last query was answered.
    Ok,
    /// A query went unanswered after all retries.
    Lost,
}

impl fmt::Display for CommStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CommStatus::Unknown => "unknown",
            CommStatus::Ok => "ok",
            CommStatus::Lost => "lost",
        })
    }
}

/// Something that went wrong on the line (each adds to the error counter).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PollError {
    /// Octets that are no frame.
    #[error("invalid frame: {0}")]
    Frame(#[from] FrameError),
    /// A frame that is not the reply to the query.
    #[error("invalid reply: {0}")]
    Reply(#[from] ReplyError),
    /// A fault record of another index than the one asked for.
    #[error("record {got} in reply to a query for {asked}")]
    WrongIndex {
        /// Requested.
        asked: u8,
        /// In the reply.
        got: u8,
    },
    /// No valid reply in time.
    #[error("no reply to the {query} query (attempt {attempt})")]
    Timeout {
        /// The query.
        query: Query,
        /// 1 for the first send.
        attempt: u8,
    },
}

/// Why the whole fault stack is read again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResyncReason {
    /// The slot of the last archived record holds another record.
    Overwritten,
    /// The slot of the last archived record is empty: the log was cleared.
    Cleared,
}

/// What the poller reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event {
    /// A status reply.
    Status(Status),
    /// The trip counters, floor 1 first.
    Counters(Vec<u32>),
    /// A fault record new to the archive, in the board's order; store
    /// [`Poller::cursor`] once it is archived.
    Fault(FaultRecord),
    /// The communication status changed.
    Comm(CommStatus),
    /// A line error (also counted in [`Poller::errors`]).
    Error(PollError),
    /// The fault stack is read again from its oldest record.
    Resync(ResyncReason),
}

/// The fault-log synchronisation step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sync {
    /// Reading index 0 or 1 to find the base.
    Detect(u8),
    /// Index 0 was empty, index 1 held this record: reading 0 again, in case faults
    /// arrived in between (a base-1 board never has a record at 0).
    Confirm(FaultRecord),
    /// Reading the slot of the last archived record (or the base).
    Probe(u8),
    /// Reading the slot after the board's last index: a record there means a full stack.
    ScanProbe(u8),
    /// Reading slots up to the board's last index.
    Read {
        next: u8,
        end: Option<u8>,
        jumped: bool,
    },
    Done,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Idle {
        until: Instant,
    },
    Ready {
        query: Query,
        attempt: u8,
        since: Instant,
    },
    Waiting {
        query: Query,
        attempt: u8,
        deadline: Instant,
    },
}

/// Most fault reads in one cycle: two passes over the largest stack.
const MAX_FAULT_READS: u16 = 2 * 256 + 4;

/// The master of one lift, sans-IO.
#[derive(Debug)]
pub struct Poller {
    config: PollerConfig,
    cursor: ArchiveCursor,
    deframer: Deframer,
    state: State,
    sync: Sync,
    fault_reads: u16,
    cycle_start: Instant,
    counters_due: Instant,
    comm: CommStatus,
    errors: u64,
    events: VecDeque<Event>,
}

impl Poller {
    /// A poller whose first cycle starts at `now`, with the archive's cursor (default
    /// for a new archive).
    pub fn new(config: PollerConfig, cursor: ArchiveCursor, now: Instant) -> Poller {
        Poller {
            config,
            cursor,
            deframer: Deframer::new(),
            state: State::Idle { until: now },
            sync: Sync::Done,
            fault_reads: 0,
            cycle_start: now,
            counters_due: now,
            comm: CommStatus::Unknown,
            errors: 0,
            events: VecDeque::new(),
        }
    }

    /// The settings.
    pub fn config(&self) -> &PollerConfig {
        &self.config
    }

    /// The archive's cursor, to store after each [`Event::Fault`].
    pub fn cursor(&self) -> &ArchiveCursor {
        &self.cursor
    }

    /// Time-outs and invalid frames so far.
    pub fn errors(&self) -> u64 {
        self.errors
    }

    /// The communication status.
    pub fn comm_status(&self) -> CommStatus {
        self.comm
    }

    /// The next event; poll after every `handle_*` call until `None`.
    pub fn poll_event(&mut self) -> Option<Event> {
        self.events.pop_front()
    }

    /// The query to write now, if any; poll after every `handle_*` call. The reply
    /// time-out runs from `now` plus the query's transmit time.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        let State::Ready { query, attempt, .. } = self.state else {
            return None;
        };
        let bytes = query.encode();
        self.deframer.abandon();
        let deadline =
            now + self.config.line.transmit_time(bytes.len()) + self.config.reply_timeout;
        self.state = State::Waiting {
            query,
            attempt,
            deadline,
        };
        tracing::trace!(target: "devices::ekm66", %query, attempt, "query");
        Some(bytes)
    }

    /// When [`Poller::handle_timeout`] is due.
    pub fn poll_timeout(&self) -> Option<Instant> {
        Some(match self.state {
            State::Idle { until } => until,
            State::Ready { since, .. } => since,
            State::Waiting { deadline, .. } => deadline,
        })
    }

    /// The clock advanced: starts a cycle, or repeats an unanswered query, or gives up.
    /// Poll events and transmits afterwards.
    pub fn handle_timeout(&mut self, now: Instant) {
        match self.state {
            State::Idle { until } if until <= now => {
                self.cycle_start = now;
                self.ready(Query::Status, now);
            }
            State::Waiting {
                query,
                attempt,
                deadline,
            } if deadline <= now => {
                self.error(PollError::Timeout {
                    query,
                    attempt: attempt.saturating_add(1),
                });
                if let Some(error) = self.deframer.abandon() {
                    self.error(PollError::Frame(error));
                }
                if attempt < self.config.retries {
                    self.state = State::Ready {
                        query,
                        attempt: attempt + 1,
                        since: now,
                    };
                } else {
                    self.set_comm(CommStatus::Lost);
                    self.end_cycle(now);
                }
            }
            _ => {}
        }
    }

    /// The line was quiet for longer than a frame may pause: a partial reply is
    /// dropped (and counted).
    pub fn handle_line_pause(&mut self, _now: Instant) {
        if let Some(error) = self.deframer.abandon() {
            self.error(PollError::Frame(error));
        }
    }

    /// Octets received. Poll events and transmits afterwards.
    pub fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        let State::Waiting { query, .. } = self.state else {
            // Nothing asked: whatever comes is not a reply.
            return;
        };
        self.deframer.push(bytes);
        while let Some(next) = self.deframer.next_frame() {
            let reply = next
                .map_err(PollError::from)
                .and_then(|frame| Ok(decode_reply(query, &frame, &self.config.codec)?))
                .and_then(|reply| match (query, &reply) {
                    (Query::FaultRecord(asked), Reply::Fault(record)) if record.index != asked => {
                        Err(PollError::WrongIndex {
                            asked,
                            got: record.index,
                        })
                    }
                    _ => Ok(reply),
                });
            match reply {
                Ok(reply) => {
                    self.deframer.abandon();
                    self.set_comm(CommStatus::Ok);
                    self.handle_reply(now, query, reply);
                    return;
                }
                Err(error) => self.error(error),
            }
        }
    }

    fn error(&mut self, error: PollError) {
        self.errors = self.errors.saturating_add(1);
        tracing::debug!(target: "devices::ekm66", %error);
        self.events.push_back(Event::Error(error));
    }

    fn set_comm(&mut self, status: CommStatus) {
        if self.comm != status {
            self.comm = status;
            self.events.push_back(Event::Comm(status));
        }
    }

    fn ready(&mut self, query: Query, now: Instant) {
        self.state = State::Ready {
            query,
            attempt: 0,
            since: now,
        };
    }

    fn end_cycle(&mut self, now: Instant) {
        self.sync = Sync::Done;
        self.state = State::Idle {
            until: (self.cycle_start + self.config.poll_period).max(now),
        };
    }

    fn base(&self) -> Option<u8> {
        match self.config.index_base {
            IndexBase::Zero => Some(0),
            IndexBase::One => Some(1),
            IndexBase::Detect => self.cursor.base,
        }
    }

    fn successor(&self, index: u8, base: u8) -> u8 {
        if index >= self.config.max_index {
            base
        } else {
            index + 1
        }
    }

    fn handle_reply(&mut self, now: Instant, query: Query, reply: Reply) {
        match (query, reply) {
            (Query::Status, Reply::Status(status)) => {
                self.events.push_back(Event::Status(status));
                if self.counters_due <= now {
                    self.ready(Query::Counters, now);
                } else {
                    self.start_fault_sync(now);
                }
            }
            (Query::Counters, Reply::Counters(counters)) => {
                // On a fixed schedule, not drifting by the cycle's own time.
                self.counters_due = (self.counters_due + self.config.counters_period).max(now);
                self.events.push_back(Event::Counters(counters));
                self.start_fault_sync(now);
            }
            (Query::FaultRecord(index), reply) => {
                let record = match reply {
                    Reply::Fault(record) => Some(record),
                    _ => None,
                };
                self.fault_reply(index, record);
                self.next_fault_query(now);
            }
            // decode_reply only gives the reply kinds of the query.
            _ => self.end_cycle(now),
        }
    }

    fn start_fault_sync(&mut self, now: Instant) {
        self.fault_reads = 0;
        self.sync = match (self.base(), self.cursor.last) {
            (None, _) => Sync::Detect(0),
            (Some(_), Some(last)) => Sync::Probe(last.index),
            (Some(base), None) => Sync::Probe(base),
        };
        self.next_fault_query(now);
    }

    fn next_fault_query(&mut self, now: Instant) {
        let index = match self.sync {
            Sync::Detect(index) | Sync::Probe(index) => Some(index),
            Sync::Confirm(_) => Some(0),
            Sync::ScanProbe(last) => self.base().map(|base| self.successor(last, base)),
            Sync::Read { next, .. } => Some(next),
            Sync::Done => None,
        };
        match index {
            Some(index) if self.fault_reads < MAX_FAULT_READS => {
                self.fault_reads += 1;
                self.ready(Query::FaultRecord(index), now);
            }
            _ => self.end_cycle(now),
        }
    }

    fn archive(&mut self, record: &FaultRecord) {
        if !self.cursor.contains(record) {
            self.events.push_back(Event::Fault(*record));
        }
        self.cursor.remember(record, self.config.remembered);
    }

    /// One fault reply: `record` is `None` for an empty slot.
    fn fault_reply(&mut self, index: u8, record: Option<FaultRecord>) {
        let sync = self.sync;
        self.sync = Sync::Done;
        match (sync, record) {
            (Sync::Detect(0), None) => self.sync = Sync::Detect(1),
            (Sync::Detect(_), None) => {}
            (Sync::Detect(0), Some(record)) => {
                self.cursor.base = Some(0);
                self.probed(index, record);
            }
            (Sync::Detect(_), Some(record)) => self.sync = Sync::Confirm(record),
            (Sync::Confirm(_), Some(record)) => {
                self.cursor.base = Some(0);
                self.probed(index, record);
            }
            (Sync::Confirm(first), None) => {
                self.cursor.base = Some(1);
                self.probed(first.index, first);
            }
            (Sync::Probe(_), Some(record)) => self.probed(index, record),
            (Sync::Probe(_), None) => {
                if self.cursor.last.is_some() {
                    self.events.push_back(Event::Resync(ResyncReason::Cleared));
                    if let Some(base) = self.base() {
                        self.sync = Sync::Read {
                            next: base,
                            end: None,
                            jumped: false,
                        };
                    }
                }
            }
            (Sync::ScanProbe(last), None) => {
                // Not wrapped yet: the oldest record is at the base.
                if let Some(base) = self.base() {
                    self.sync = Sync::Read {
                        next: base,
                        end: Some(last),
                        jumped: true,
                    };
                }
            }
            (Sync::ScanProbe(_), Some(record)) => {
                // A full stack: the oldest record is the one after the last.
                self.archive(&record);
                self.read_on(index, record.last_index, false);
            }
            (Sync::Read { jumped, .. }, Some(record)) => {
                self.archive(&record);
                self.read_on(index, record.last_index, jumped);
            }
            (Sync::Read { end, jumped, .. }, None) => {
                // Past the board's last slot: the index wraps to the base (once).
                if let (Some(end), Some(base), false) = (end, self.base(), jumped) {
                    if index != base {
                        self.sync = Sync::Read {
                            next: base,
                            end: Some(end),
                            jumped: true,
                        };
                    }
                }
            }
            (Sync::Done, _) => {}
        }
    }

    /// The record at the probed slot: is it the last one archived?
    fn probed(&mut self, index: u8, record: FaultRecord) {
        let key = FaultKey::from(&record);
        match self.cursor.last {
            Some(last) if last == key => {
                if record.last_index != index {
                    if let Some(base) = self.base() {
                        self.sync = Sync::Read {
                            next: self.successor(index, base),
                            end: Some(record.last_index),
                            jumped: false,
                        };
                    }
                }
            }
            last => {
                if last.is_some() {
                    self.events
                        .push_back(Event::Resync(ResyncReason::Overwritten));
                }
                self.sync = Sync::ScanProbe(record.last_index);
            }
        }
    }

    /// After reading slot `index` of a board whose last index is `end`.
    fn read_on(&mut self, index: u8, end: u8, jumped: bool) {
        if index == end {
            return;
        }
        if let Some(base) = self.base() {
            let next = self.successor(index, base);
            self.sync = Sync::Read {
                next,
                end: Some(end),
                jumped: jumped || next == base,
            };
        }
    }
}

impl LineEndpoint for Poller {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        Poller::handle_bytes(self, now, bytes);
    }
    fn handle_line_pause(&mut self, now: Instant) {
        Poller::handle_line_pause(self, now);
    }
    fn handle_timeout(&mut self, now: Instant) {
        Poller::handle_timeout(self, now);
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        Poller::poll_transmit(self, now)
    }
    fn next_deadline(&self) -> Option<Instant> {
        self.poll_timeout()
    }
    fn line(&self) -> LineSettings {
        self.config.line
    }
}
