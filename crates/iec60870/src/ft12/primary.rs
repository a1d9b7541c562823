//! The unbalanced primary station (the master polling a line), sans-IO.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use serial_line::LineSettings;
use thiserror::Error;

use super::deframer::{DeframeError, Deframer};
use super::frame::{AddressSize, Control, Frame, PrimaryFunction, SecondaryFunction};

/// Settings of a primary station.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PrimaryConfig {
    /// The link address field size of the line.
    pub address_size: AddressSize,
    /// Speed and character format: the primary times its frames as the line does.
    pub line: LineSettings,
    /// How long to wait for an answer once the request has left the line (PCVDEW6:
    /// 5-1000 ms).
    pub response_timeout: Duration,
    /// Repeats of an unanswered request before the secondary counts as failed.
    pub retries: u8,
    /// Poll the secondaries on its own (reset, class 2 polling, class 1 on ACD); off
    /// for a test tool that sends single telegrams with [`Primary::request`].
    pub automatic: bool,
    /// Poll class 2 when no class 1 data is waiting (IEC 103 measurands, IEC 101
    /// cyclic data); otherwise class 1 only.
    pub poll_class2: bool,
    /// The least time between two class 2 polls of one secondary; zero polls as fast as
    /// the line allows.
    pub poll_interval: Duration,
    /// Class 1 polls of one secondary in a row while it keeps ACD set, before the
    /// others get their turn.
    pub class1_burst: u8,
    /// How long a failed secondary waits before it is tried again; the others are
    /// polled meanwhile.
    pub failed_retry_interval: Duration,
}

impl Default for PrimaryConfig {
    fn default() -> Self {
        PrimaryConfig {
            address_size: AddressSize::One,
            line: LineSettings::default(),
            response_timeout: Duration::from_millis(500),
            retries: 2,
            automatic: true,
            poll_class2: true,
            poll_interval: Duration::ZERO,
            class1_burst: 16,
            failed_retry_interval: Duration::from_secs(10),
        }
    }
}

/// The state of one secondary as its primary sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkState {
    /// Not reset yet: the primary asks for the link status, then resets the link.
    Unknown,
    /// Link status answered, reset pending.
    Resetting,
    /// Reset and answering.
    Up,
    /// Unanswered after all repeats; tried again after the retry interval.
    Failed,
}

/// An answer of a secondary, as the primary read it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Answer {
    /// Positive acknowledgement (fixed frame or E5).
    Ack,
    /// NACK: busy, not accepted.
    Busy,
    /// User data (class 1 or 2).
    UserData(Vec<u8>),
    /// NACK: no data (fixed frame or E5).
    NoData,
    /// Status of link.
    LinkStatus,
    /// Link service not functioning: the link must be reset.
    NotFunctioning,
    /// Link service not implemented.
    NotImplemented,
}

/// What happened on the line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PrimaryEvent {
    /// A request was answered.
    Exchange {
        /// The secondary.
        address: u16,
        /// What was asked.
        request: PrimaryFunction,
        /// The answer.
        answer: Answer,
        /// ACD of the answer: class 1 data waiting.
        acd: bool,
        /// DFC of the answer.
        dfc: bool,
    },
    /// A broadcast (send/no reply) left.
    Broadcast {
        /// The function sent.
        function: PrimaryFunction,
    },
    /// A request went unanswered and is repeated (`attempt` 2 is the first repeat), or
    /// gave up after the last attempt.
    Timeout {
        /// The secondary.
        address: u16,
        /// What was asked.
        request: PrimaryFunction,
        /// The attempt that timed out, from 1.
        attempt: u8,
    },
    /// The secondary's link was reset and it answers.
    LinkUp {
        /// The secondary.
        address: u16,
    },
    /// The secondary stopped answering (all repeats timed out) or asked for a reset.
    LinkDown {
        /// The secondary.
        address: u16,
    },
    /// User data that could not be delivered because the secondary failed.
    Undelivered {
        /// The secondary.
        address: u16,
        /// The ASDU.
        asdu: Vec<u8>,
    },
    /// Octets that formed no frame, or a frame nobody asked for.
    LineError(LineError),
}

/// Something on the line that is not the awaited answer.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum LineError {
    /// Broken octets.
    #[error(transparent)]
    Frame(#[from] DeframeError),
    /// A valid frame that does not answer the outstanding request.
    #[error("unexpected frame: {0}")]
    Unexpected(Frame),
}

/// A request the primary cannot take.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum PrimaryError {
    /// The address is not a secondary of this primary.
    #[error("no secondary with link address {0} on this line")]
    UnknownStation(u16),
    /// The address does not fit the line's address field, or is the broadcast address.
    #[error("link address {0} does not fit this line's address field or is its broadcast address")]
    BadAddress(u16),
    /// The ASDU does not fit a frame.
    #[error(transparent)]
    Encode(#[from] super::frame::EncodeError),
}

/// Counters of one secondary.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StationStats {
    /// Requests sent, repeats included.
    pub requests: u64,
    /// Repeats after a timeout.
    pub repeats: u64,
    /// Requests that went unanswered in all attempts.
    pub failures: u64,
    /// User data frames received.
    pub user_data: u64,
    /// Completed class 2 polls (answered with data or no data).
    pub class2_polls: u64,
}

#[derive(Debug)]
struct Station {
    address: u16,
    state: LinkState,
    /// The FCB of the next new FCV = 1 frame.
    next_fcb: bool,
    acd: bool,
    dfc: bool,
    class1_in_row: u8,
    next_class2: Option<Instant>,
    retry_at: Option<Instant>,
    pending: VecDeque<Vec<u8>>,
    requested: VecDeque<PrimaryFunction>,
    stats: StationStats,
}

impl Station {
    fn new(address: u16) -> Station {
        Station {
            address,
            state: LinkState::Unknown,
            next_fcb: true,
            acd: false,
            dfc: false,
            class1_in_row: 0,
            next_class2: None,
            retry_at: None,
            pending: VecDeque::new(),
            requested: VecDeque::new(),
            stats: StationStats::default(),
        }
    }
}

#[derive(Debug)]
struct Outstanding {
    station: usize,
    function: PrimaryFunction,
    bytes: Vec<u8>,
    attempt: u8,
    /// When the answer is overdue; `None` for a repeat waiting for the line.
    deadline: Option<Instant>,
    /// Whether it was asked for with [`Primary::request`] (no automatic follow-up).
    manual: bool,
}

/// The primary station of an unbalanced line: polls one or many secondaries.
///
/// Only one request is on the line at a time. When the line is free the primary picks
/// the next request: a queued broadcast, a requested single telegram, then per
/// secondary in turn the start-up (request status of link, reset of remote link), user
/// data to deliver, class 1 while ACD is set, class 2 otherwise. A request that times
/// out is repeated with the same FCB; after the last repeat its secondary counts as
/// failed and is tried again only after `failed_retry_interval`, so a dead secondary
/// costs the others one timeout per interval, not one per cycle.
///
/// Feed it bytes with [`Primary::handle_bytes`], the clock with
/// [`Primary::handle_timeout`] at [`Primary::next_deadline`], and write what
/// [`Primary::poll_transmit`] returns.
#[derive(Debug)]
pub struct Primary {
    config: PrimaryConfig,
    deframer: Deframer,
    stations: Vec<Station>,
    cursor: usize,
    outstanding: Option<Outstanding>,
    broadcasts: VecDeque<(PrimaryFunction, Vec<u8>)>,
    /// When the line is free for the next transmission (our last frame has left it and
    /// the idle time has passed).
    line_free_at: Instant,
    events: VecDeque<PrimaryEvent>,
}

impl Primary {
    /// A primary with no secondaries yet.
    pub fn new(config: PrimaryConfig, now: Instant) -> Primary {
        Primary {
            deframer: Deframer::new(config.address_size),
            config,
            stations: Vec::new(),
            cursor: 0,
            outstanding: None,
            broadcasts: VecDeque::new(),
            line_free_at: now,
            events: VecDeque::new(),
        }
    }

    /// The settings.
    pub fn config(&self) -> &PrimaryConfig {
        &self.config
    }

    /// Adds a secondary to poll.
    pub fn add_station(&mut self, address: u16) -> Result<(), PrimaryError> {
        let size = self.config.address_size;
        if !size.fits(address) || size.broadcast() == Some(address) {
            return Err(PrimaryError::BadAddress(address));
        }
        if self.index(address).is_none() {
            self.stations.push(Station::new(address));
        }
        Ok(())
    }

    /// The state of a secondary's link.
    pub fn link_state(&self, address: u16) -> Option<LinkState> {
        self.index(address)
            .and_then(|index| self.stations.get(index))
            .map(|station| station.state)
    }

    /// The counters of a secondary.
    pub fn stats(&self, address: u16) -> Option<StationStats> {
        self.index(address)
            .and_then(|index| self.stations.get(index))
            .map(|station| station.stats)
    }

    /// Queues user data for a secondary, sent with send/confirm once its link is up.
    pub fn send(&mut self, address: u16, asdu: Vec<u8>) -> Result<(), PrimaryError> {
        self.check_fits(&asdu)?;
        let station = self.station_mut(address)?;
        station.pending.push_back(asdu);
        Ok(())
    }

    /// Queues user data for all secondaries (send/no reply to the broadcast address).
    pub fn broadcast(&mut self, asdu: Vec<u8>) -> Result<(), PrimaryError> {
        self.check_fits(&asdu)?;
        self.broadcasts
            .push_back((PrimaryFunction::UserDataNoReply, asdu));
        Ok(())
    }

    /// Queues a single telegram for a secondary (a test tool's "reset remote link",
    /// "request class 2" ...), sent before any automatic poll. FCB handling stays the
    /// primary's: a reset makes the next FCV frame carry FCB = 1.
    pub fn request(&mut self, address: u16, function: PrimaryFunction) -> Result<(), PrimaryError> {
        let station = self.station_mut(address)?;
        station.requested.push_back(function);
        Ok(())
    }

    /// Whether nothing is on the line and nothing is queued.
    pub fn is_idle(&self) -> bool {
        self.outstanding.is_none()
            && self.broadcasts.is_empty()
            && self
                .stations
                .iter()
                .all(|station| station.pending.is_empty() && station.requested.is_empty())
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<PrimaryEvent> {
        self.events.pop_front()
    }

    /// When [`Primary::handle_timeout`] or [`Primary::poll_transmit`] has something to
    /// do: the answer's deadline, the line becoming free, or the next poll falling due.
    pub fn next_deadline(&self) -> Option<Instant> {
        if let Some(outstanding) = &self.outstanding {
            return Some(outstanding.deadline.unwrap_or(self.line_free_at));
        }
        if !self.broadcasts.is_empty() {
            return Some(self.line_free_at);
        }
        let due = self
            .stations
            .iter()
            .filter_map(|station| self.due_at(station))
            .min()?;
        Some(due.max(self.line_free_at))
    }

    /// Octets received from the line.
    pub fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.deframer.push(bytes);
        while let Some(next) = self.deframer.next_frame() {
            match next {
                Ok(frame) => self.handle_frame(now, frame),
                Err(error) => {
                    // Discard and let the timer run out: the standard's answer to a
                    // broken frame is the primary's repeat.
                    self.keep_idle(now);
                    self.events
                        .push_back(PrimaryEvent::LineError(LineError::Frame(error)));
                }
            }
        }
    }

    /// The line has been quiet for longer than a frame may pause: a partial frame is
    /// dropped.
    pub fn handle_line_pause(&mut self, now: Instant) {
        if let Some(error) = self.deframer.abandon_partial() {
            self.keep_idle(now);
            self.events
                .push_back(PrimaryEvent::LineError(LineError::Frame(error)));
        }
    }

    /// Advances the clock: a request whose answer is overdue is repeated or given up.
    pub fn handle_timeout(&mut self, now: Instant) {
        let Some(outstanding) = self.outstanding.as_ref() else {
            return;
        };
        if outstanding.deadline.is_none_or(|deadline| now < deadline) {
            return;
        }
        let Some(outstanding) = self.outstanding.take() else {
            return;
        };
        let Some(station) = self.stations.get_mut(outstanding.station) else {
            return;
        };
        let address = station.address;
        self.events.push_back(PrimaryEvent::Timeout {
            address,
            request: outstanding.function,
            attempt: outstanding.attempt,
        });
        if outstanding.attempt <= self.config.retries && !outstanding.function.is_broadcast() {
            station.stats.repeats += 1;
            let attempt = outstanding.attempt + 1;
            self.transmit_later(Outstanding {
                attempt,
                ..outstanding
            });
            return;
        }
        station.stats.failures += 1;
        let was_up = station.state == LinkState::Up;
        station.state = LinkState::Failed;
        station.retry_at = Some(now + self.config.failed_retry_interval);
        station.acd = false;
        station.dfc = false;
        station.class1_in_row = 0;
        if was_up {
            self.events.push_back(PrimaryEvent::LinkDown { address });
        }
        // Commands for a dead station are not kept for later: executed minutes late they
        // would surprise whoever stands beside the switchgear.
        let in_flight = (outstanding.function == PrimaryFunction::UserDataConfirmed)
            .then(|| user_data_of(&outstanding.bytes, self.config.address_size))
            .flatten();
        let undelivered: Vec<Vec<u8>> = in_flight
            .into_iter()
            .chain(station.pending.drain(..))
            .collect();
        for asdu in undelivered {
            self.events
                .push_back(PrimaryEvent::Undelivered { address, asdu });
        }
        if !outstanding.manual {
            self.advance_cursor(outstanding.station);
        }
    }

    /// The octets to write now, if the line is free and something is due.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        if now < self.line_free_at {
            return None;
        }
        if let Some(outstanding) = self.outstanding.as_mut() {
            // A repeat waiting for the line to become free.
            if outstanding.deadline.is_none() {
                outstanding.deadline = Some(
                    now + self.config.line.transmit_time(outstanding.bytes.len())
                        + self.config.response_timeout,
                );
                let bytes = outstanding.bytes.clone();
                self.line_free_at = now + self.config.line.transmit_time(bytes.len());
                if let Some(station) = self.stations.get_mut(outstanding.station) {
                    station.stats.requests += 1;
                }
                return Some(bytes);
            }
            return None;
        }
        if let Some((function, asdu)) = self.broadcasts.pop_front() {
            let address = self.config.address_size.broadcast().unwrap_or(0);
            let frame = Frame::Variable {
                control: Control::primary(function, false, false),
                address,
                asdu,
            };
            let bytes = frame.to_bytes(self.config.address_size).ok()?;
            // Send/no reply: nobody answers, the line is free 33 bit times after the frame.
            self.line_free_at =
                now + self.config.line.transmit_time(bytes.len()) + self.config.line.idle_time();
            self.events.push_back(PrimaryEvent::Broadcast { function });
            return Some(bytes);
        }
        let (index, function, asdu, manual) = self.choose(now)?;
        let station = self.stations.get_mut(index)?;
        let fcv = function.uses_fcb();
        let control = Control::primary(function, fcv && station.next_fcb, fcv);
        let frame = match asdu {
            Some(asdu) => Frame::Variable {
                control,
                address: station.address,
                asdu,
            },
            None => Frame::Fixed {
                control,
                address: station.address,
            },
        };
        let bytes = frame.to_bytes(self.config.address_size).ok()?;
        station.stats.requests += 1;
        let on_line = self.config.line.transmit_time(bytes.len());
        self.line_free_at = now + on_line;
        self.outstanding = Some(Outstanding {
            station: index,
            function,
            bytes: bytes.clone(),
            attempt: 1,
            deadline: Some(now + on_line + self.config.response_timeout),
            manual,
        });
        Some(bytes)
    }

    /// What to send next: (station, function, user data, asked for by hand).
    fn choose(&mut self, now: Instant) -> Option<(usize, PrimaryFunction, Option<Vec<u8>>, bool)> {
        // Single telegrams first, in station order.
        for (index, station) in self.stations.iter_mut().enumerate() {
            if let Some(function) = station.requested.pop_front() {
                return Some((index, function, None, true));
            }
        }
        if !self.config.automatic {
            // Without automatic polling, user data still goes out once asked for.
            for (index, station) in self.stations.iter_mut().enumerate() {
                if let Some(asdu) = station.pending.pop_front() {
                    return Some((index, PrimaryFunction::UserDataConfirmed, Some(asdu), true));
                }
            }
            return None;
        }
        let count = self.stations.len();
        for step in 0..count {
            let index = (self.cursor + step) % count;
            let Some(station) = self.stations.get_mut(index) else {
                continue;
            };
            let due = match station.state {
                LinkState::Failed => station.retry_at.is_none_or(|at| at <= now),
                LinkState::Unknown | LinkState::Resetting => true,
                LinkState::Up => {
                    station.dfc
                        || !station.pending.is_empty()
                        || station.acd
                        || station.next_class2.is_none_or(|at| at <= now)
                }
            };
            if !due {
                continue;
            }
            self.cursor = index;
            let choice = match station.state {
                LinkState::Unknown | LinkState::Failed => {
                    (PrimaryFunction::RequestLinkStatus, None)
                }
                LinkState::Resetting => (PrimaryFunction::ResetRemoteLink, None),
                LinkState::Up if station.dfc => (PrimaryFunction::RequestLinkStatus, None),
                LinkState::Up => match station.pending.pop_front() {
                    Some(asdu) => (PrimaryFunction::UserDataConfirmed, Some(asdu)),
                    None if station.acd || !self.config.poll_class2 => {
                        (PrimaryFunction::RequestClass1, None)
                    }
                    None => (PrimaryFunction::RequestClass2, None),
                },
            };
            return Some((index, choice.0, choice.1, false));
        }
        None
    }

    /// When a secondary next wants the line by itself, `None` if only an answer or a
    /// request from the application will make it.
    fn due_at(&self, station: &Station) -> Option<Instant> {
        if !station.requested.is_empty() {
            return Some(self.line_free_at);
        }
        if !self.config.automatic {
            return (!station.pending.is_empty()).then_some(self.line_free_at);
        }
        match station.state {
            LinkState::Failed => Some(station.retry_at.unwrap_or(self.line_free_at)),
            LinkState::Unknown | LinkState::Resetting => Some(self.line_free_at),
            LinkState::Up => {
                if station.dfc || station.acd || !station.pending.is_empty() {
                    Some(self.line_free_at)
                } else {
                    Some(station.next_class2.unwrap_or(self.line_free_at))
                }
            }
        }
    }

    fn handle_frame(&mut self, now: Instant, frame: Frame) {
        self.keep_idle(now);
        let Some(outstanding) = self.outstanding.as_ref() else {
            self.events
                .push_back(PrimaryEvent::LineError(LineError::Unexpected(frame)));
            return;
        };
        let Some(station) = self.stations.get(outstanding.station) else {
            return;
        };
        let (answer, acd, dfc) = match &frame {
            Frame::SingleCharacter => {
                let answer = match outstanding.function {
                    PrimaryFunction::RequestClass1 | PrimaryFunction::RequestClass2 => {
                        Answer::NoData
                    }
                    PrimaryFunction::RequestLinkStatus => {
                        self.unexpected(frame);
                        return;
                    }
                    _ => Answer::Ack,
                };
                (answer, false, false)
            }
            Frame::Fixed { control, address }
            | Frame::Variable {
                control, address, ..
            } if control.is_primary() || *address != station.address => {
                self.unexpected(frame);
                return;
            }
            Frame::Fixed { control, .. } => {
                let answer = match control.secondary_function() {
                    SecondaryFunction::Ack => Answer::Ack,
                    SecondaryFunction::NackBusy => Answer::Busy,
                    SecondaryFunction::NackNoData => Answer::NoData,
                    SecondaryFunction::LinkStatus => Answer::LinkStatus,
                    SecondaryFunction::NotFunctioning => Answer::NotFunctioning,
                    SecondaryFunction::NotImplemented => Answer::NotImplemented,
                    SecondaryFunction::UserData | SecondaryFunction::Other(_) => {
                        self.unexpected(frame);
                        return;
                    }
                };
                (answer, control.acd(), control.dfc())
            }
            Frame::Variable { control, asdu, .. } => {
                if control.secondary_function() != SecondaryFunction::UserData {
                    self.unexpected(frame);
                    return;
                }
                (Answer::UserData(asdu.clone()), control.acd(), control.dfc())
            }
        };
        if !answers(outstanding.function, &answer) {
            self.unexpected(frame);
            return;
        }
        let Some(outstanding) = self.outstanding.take() else {
            return;
        };
        self.complete(now, outstanding, answer, acd, dfc);
    }

    fn complete(
        &mut self,
        now: Instant,
        outstanding: Outstanding,
        answer: Answer,
        acd: bool,
        dfc: bool,
    ) {
        let poll_interval = self.config.poll_interval;
        let Some(station) = self.stations.get_mut(outstanding.station) else {
            return;
        };
        let address = station.address;
        let function = outstanding.function;
        station.acd = acd;
        station.dfc = dfc;
        let mut link_up = false;
        let mut link_down = false;
        match (&answer, function) {
            (Answer::Ack, PrimaryFunction::ResetRemoteLink | PrimaryFunction::ResetFcb) => {
                station.next_fcb = true;
                link_up = station.state != LinkState::Up;
                station.state = LinkState::Up;
                station.retry_at = None;
            }
            (Answer::LinkStatus, PrimaryFunction::RequestLinkStatus)
                if station.state != LinkState::Up =>
            {
                station.state = LinkState::Resetting;
            }
            (Answer::NotFunctioning, _) => {
                link_down = station.state == LinkState::Up;
                station.state = LinkState::Unknown;
            }
            (Answer::Busy, PrimaryFunction::UserDataConfirmed) => {
                // Not accepted: offered again first, with a new FCB since this exchange
                // was answered.
                if let Some(asdu) = user_data_of(&outstanding.bytes, self.config.address_size) {
                    station.pending.push_front(asdu);
                }
            }
            _ => {}
        }
        if function.uses_fcb() && !matches!(answer, Answer::NotFunctioning) {
            station.next_fcb = !station.next_fcb;
        }
        match function {
            PrimaryFunction::RequestClass1 => {
                station.class1_in_row = station.class1_in_row.saturating_add(1);
            }
            PrimaryFunction::RequestClass2 => {
                station.stats.class2_polls += 1;
                station.next_class2 = Some(now + poll_interval);
                station.class1_in_row = 0;
            }
            _ => {}
        }
        if matches!(answer, Answer::UserData(_)) {
            station.stats.user_data += 1;
        }
        // Class 1 while ACD is set, but not for ever: after the burst the others get
        // their turn and this station's ACD is served on its next turn.
        let stay = station.state == LinkState::Up
            && station.acd
            && station.class1_in_row < self.config.class1_burst;
        let starting = matches!(station.state, LinkState::Resetting);
        if !stay {
            station.class1_in_row = 0;
        }
        if link_up {
            self.events.push_back(PrimaryEvent::LinkUp { address });
        }
        if link_down {
            self.events.push_back(PrimaryEvent::LinkDown { address });
        }
        self.events.push_back(PrimaryEvent::Exchange {
            address,
            request: function,
            answer,
            acd,
            dfc,
        });
        if !outstanding.manual && !stay && !starting {
            self.advance_cursor(outstanding.station);
        }
    }

    fn unexpected(&mut self, frame: Frame) {
        self.events
            .push_back(PrimaryEvent::LineError(LineError::Unexpected(frame)));
    }

    fn advance_cursor(&mut self, from: usize) {
        if !self.stations.is_empty() {
            self.cursor = (from + 1) % self.stations.len();
        }
    }

    /// Something arrived on the line: the next frame waits for 33 bit times of quiet.
    fn keep_idle(&mut self, now: Instant) {
        self.line_free_at = self.line_free_at.max(now + self.config.line.idle_time());
    }

    fn transmit_later(&mut self, outstanding: Outstanding) {
        self.outstanding = Some(Outstanding {
            deadline: None,
            ..outstanding
        });
    }

    fn index(&self, address: u16) -> Option<usize> {
        self.stations
            .iter()
            .position(|station| station.address == address)
    }

    fn station_mut(&mut self, address: u16) -> Result<&mut Station, PrimaryError> {
        let index = self
            .index(address)
            .ok_or(PrimaryError::UnknownStation(address))?;
        self.stations
            .get_mut(index)
            .ok_or(PrimaryError::UnknownStation(address))
    }

    fn check_fits(&self, asdu: &[u8]) -> Result<(), PrimaryError> {
        let max = super::frame::MAX_LENGTH_FIELD - 1 - self.config.address_size.octets();
        if asdu.len() > max {
            return Err(super::frame::EncodeError::TooLong {
                asdu_len: asdu.len(),
            }
            .into());
        }
        Ok(())
    }
}

/// Whether `answer` is a valid answer to `request`.
fn answers(request: PrimaryFunction, answer: &Answer) -> bool {
    match answer {
        Answer::NotFunctioning | Answer::NotImplemented => true,
        Answer::LinkStatus => request == PrimaryFunction::RequestLinkStatus,
        Answer::UserData(_) | Answer::NoData => matches!(
            request,
            PrimaryFunction::RequestClass1 | PrimaryFunction::RequestClass2
        ),
        // Some devices acknowledge a class request with no data by ACK.
        Answer::Ack => request != PrimaryFunction::RequestLinkStatus,
        Answer::Busy => !matches!(request, PrimaryFunction::RequestLinkStatus),
    }
}

/// The ASDU of an encoded variable frame.
fn user_data_of(bytes: &[u8], address_size: AddressSize) -> Option<Vec<u8>> {
    let start = 5 + address_size.octets();
    let end = bytes.len().checked_sub(2)?;
    bytes.get(start..end).map(<[u8]>::to_vec)
}
