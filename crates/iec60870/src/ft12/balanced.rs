//! Balanced transmission (IEC 60870-5-2, used by IEC 101 point to point): both stations
//! are primary and secondary at once, and the direction bit tells whose frames are
//! whose.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use serial_line::{LineEndpoint, LineSettings};

use super::deframer::Deframer;
use super::frame::{AddressSize, Control, Frame, PrimaryFunction, SecondaryFunction};
use super::primary::LineError;

/// Settings of one end of a balanced link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BalancedConfig {
    /// The link address field: 0, 1 or 2 octets.
    pub address_size: AddressSize,
    /// The link address both ends put in their frames (ignored without an address
    /// field, and cut to the field's size).
    pub address: u16,
    /// This end's direction bit: set at the controlling station (A), clear at the
    /// controlled one (B). Frames with our own direction bit are our echo and ignored.
    pub dir: bool,
    /// Speed and character format.
    pub line: LineSettings,
    /// How long to wait for an answer once a request has left the line.
    pub response_timeout: Duration,
    /// Repeats of an unanswered request before the link counts as down.
    pub retries: u8,
    /// A test of the link (function 2) after this long without traffic.
    pub test_interval: Duration,
    /// How long to wait before starting the link again after it went down.
    pub restart_interval: Duration,
}

impl BalancedConfig {
    /// One end at `address`, 1-octet address field, 9600 Bd.
    pub fn new(address: u16, dir: bool) -> BalancedConfig {
        BalancedConfig {
            address_size: AddressSize::One,
            address,
            dir,
            line: LineSettings::default(),
            response_timeout: Duration::from_millis(500),
            retries: 2,
            test_interval: Duration::from_secs(10),
            restart_interval: Duration::from_secs(5),
        }
    }
}

/// What happened on a balanced link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BalancedEvent {
    /// Our link to the other end was reset and answers: user data can go.
    LinkUp,
    /// Our requests went unanswered (or were refused as not functioning).
    LinkDown,
    /// The other end reset its link to us (it restarted).
    RemoteReset,
    /// User data from the other end, each ASDU once (repeats are answered, not passed on).
    UserData(Vec<u8>),
    /// Our oldest user data was confirmed.
    Confirmed,
    /// User data not delivered because the link went down.
    Undelivered(Vec<u8>),
    /// A request went unanswered (`attempt` from 1).
    Timeout {
        /// The request.
        request: PrimaryFunction,
        /// The attempt that timed out.
        attempt: u8,
    },
    /// Broken octets or an unexpected frame.
    LineError(LineError),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Asking for the link status.
    Unknown,
    /// Resetting the remote link.
    Resetting,
    Up,
    /// Down until the instant.
    Down(Instant),
}

#[derive(Debug)]
struct Request {
    function: PrimaryFunction,
    bytes: Vec<u8>,
    asdu: Option<Vec<u8>>,
    attempt: u8,
    /// `None` while waiting for the line.
    deadline: Option<Instant>,
}

/// One end of a balanced link.
#[derive(Debug)]
pub struct Balanced {
    config: BalancedConfig,
    deframer: Deframer,
    state: State,
    next_fcb: bool,
    outstanding: Option<Request>,
    queue: VecDeque<Vec<u8>>,
    /// The secondary half: FCB of the last accepted frame, and our answer to it.
    last_fcb: Option<bool>,
    last_answer: Option<Frame>,
    answers: VecDeque<Vec<u8>>,
    line_free_at: Instant,
    last_traffic: Instant,
    events: VecDeque<BalancedEvent>,
}

impl Balanced {
    /// An end that starts its link at once.
    pub fn new(mut config: BalancedConfig, now: Instant) -> Balanced {
        config.address = match config.address_size {
            AddressSize::None => 0,
            AddressSize::One => config.address & 0xFF,
            AddressSize::Two => config.address,
        };
        Balanced {
            deframer: Deframer::new(config.address_size),
            config,
            state: State::Unknown,
            next_fcb: true,
            outstanding: None,
            queue: VecDeque::new(),
            last_fcb: None,
            last_answer: None,
            answers: VecDeque::new(),
            line_free_at: now,
            last_traffic: now,
            events: VecDeque::new(),
        }
    }

    /// Whether our link to the other end is up.
    pub fn is_up(&self) -> bool {
        self.state == State::Up
    }

    /// Queues user data (send/confirm once the link is up).
    pub fn send(&mut self, asdu: Vec<u8>) {
        self.queue.push_back(asdu);
    }

    /// User data queued and not yet confirmed.
    pub fn unconfirmed(&self) -> usize {
        self.queue.len() + usize::from(self.outstanding.as_ref().is_some_and(|r| r.asdu.is_some()))
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<BalancedEvent> {
        self.events.pop_front()
    }

    fn frame_bytes(&self, frame: &Frame) -> Option<Vec<u8>> {
        frame.to_bytes(self.config.address_size).ok()
    }

    fn primary_frame(&self, function: PrimaryFunction, asdu: Option<Vec<u8>>) -> Option<Vec<u8>> {
        let fcv = function.uses_fcb();
        let control =
            Control::primary(function, fcv && self.next_fcb, fcv).with_dir(self.config.dir);
        let frame = match asdu {
            Some(asdu) => Frame::Variable {
                control,
                address: self.config.address,
                asdu,
            },
            None => Frame::Fixed {
                control,
                address: self.config.address,
            },
        };
        self.frame_bytes(&frame)
    }

    fn secondary_frame(&self, function: SecondaryFunction) -> Frame {
        Frame::Fixed {
            control: Control::secondary(function, false, false).with_dir(self.config.dir),
            address: self.config.address,
        }
    }

    fn answer(&mut self, frame: &Frame) {
        if let Some(bytes) = self.frame_bytes(frame) {
            self.answers.push_back(bytes);
        }
    }

    /// A request from the other end: answer it as its secondary.
    fn handle_request(&mut self, control: Control, asdu: Option<&[u8]>) {
        let function = control.primary_function();
        if control.fcv() && function.uses_fcb() && self.last_fcb == Some(control.fcb()) {
            if let Some(last) = self.last_answer.clone() {
                self.answer(&last);
                return;
            }
        }
        let answer = match function {
            PrimaryFunction::ResetRemoteLink => {
                self.last_fcb = None;
                self.last_answer = None;
                self.events.push_back(BalancedEvent::RemoteReset);
                self.secondary_frame(SecondaryFunction::Ack)
            }
            PrimaryFunction::RequestLinkStatus => {
                self.secondary_frame(SecondaryFunction::LinkStatus)
            }
            PrimaryFunction::TestLink => self.secondary_frame(SecondaryFunction::Ack),
            PrimaryFunction::UserDataConfirmed => {
                if let Some(asdu) = asdu {
                    self.events
                        .push_back(BalancedEvent::UserData(asdu.to_vec()));
                }
                self.secondary_frame(SecondaryFunction::Ack)
            }
            PrimaryFunction::UserDataNoReply => {
                if let Some(asdu) = asdu {
                    self.events
                        .push_back(BalancedEvent::UserData(asdu.to_vec()));
                }
                return;
            }
            _ => self.secondary_frame(SecondaryFunction::NotImplemented),
        };
        if control.fcv() {
            self.last_fcb = Some(control.fcb());
            self.last_answer = Some(answer.clone());
        }
        self.answer(&answer);
    }

    /// An answer from the other end to our outstanding request.
    fn handle_answer(&mut self, now: Instant, control: Control) {
        let Some(request) = self.outstanding.take() else {
            self.events
                .push_back(BalancedEvent::LineError(LineError::Unexpected(
                    Frame::Fixed {
                        control,
                        address: self.config.address,
                    },
                )));
            return;
        };
        let answer = control.secondary_function();
        match (request.function, answer) {
            (PrimaryFunction::RequestLinkStatus, SecondaryFunction::LinkStatus) => {
                self.state = State::Resetting;
            }
            (PrimaryFunction::ResetRemoteLink, SecondaryFunction::Ack) => {
                self.state = State::Up;
                self.next_fcb = true;
                self.events.push_back(BalancedEvent::LinkUp);
            }
            (PrimaryFunction::UserDataConfirmed, SecondaryFunction::Ack) => {
                self.next_fcb = !self.next_fcb;
                self.events.push_back(BalancedEvent::Confirmed);
            }
            (PrimaryFunction::UserDataConfirmed, SecondaryFunction::NackBusy) => {
                self.next_fcb = !self.next_fcb;
                if let Some(asdu) = request.asdu {
                    self.queue.push_front(asdu);
                }
            }
            (PrimaryFunction::TestLink, SecondaryFunction::Ack) => {
                self.next_fcb = !self.next_fcb;
            }
            (_, SecondaryFunction::NotFunctioning) => {
                if let Some(asdu) = request.asdu {
                    self.queue.push_front(asdu);
                }
                self.go_down(now, false);
            }
            _ => {
                // Not an answer to this request: wait for the right one or the timeout.
                self.events
                    .push_back(BalancedEvent::LineError(LineError::Unexpected(
                        Frame::Fixed {
                            control,
                            address: self.config.address,
                        },
                    )));
                self.outstanding = Some(request);
            }
        }
    }

    fn go_down(&mut self, now: Instant, drop_data: bool) {
        if self.state == State::Up {
            self.events.push_back(BalancedEvent::LinkDown);
        }
        self.state = State::Down(now + self.config.restart_interval);
        if drop_data {
            for asdu in self.queue.drain(..) {
                self.events.push_back(BalancedEvent::Undelivered(asdu));
            }
        }
    }

    fn keep_idle(&mut self, now: Instant) {
        self.last_traffic = now;
        self.line_free_at = self.line_free_at.max(now + self.config.line.idle_time());
    }

    fn next_request(&mut self, now: Instant) -> Option<(PrimaryFunction, Option<Vec<u8>>)> {
        match self.state {
            State::Down(until) if now < until => None,
            State::Down(_) | State::Unknown => {
                self.state = State::Unknown;
                Some((PrimaryFunction::RequestLinkStatus, None))
            }
            State::Resetting => Some((PrimaryFunction::ResetRemoteLink, None)),
            State::Up => match self.queue.pop_front() {
                Some(asdu) => Some((PrimaryFunction::UserDataConfirmed, Some(asdu))),
                None if now >= self.last_traffic + self.config.test_interval => {
                    Some((PrimaryFunction::TestLink, None))
                }
                None => None,
            },
        }
    }
}

impl LineEndpoint for Balanced {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.deframer.push(bytes);
        while let Some(next) = self.deframer.next_frame() {
            self.keep_idle(now);
            let frame = match next {
                Ok(frame) => frame,
                Err(error) => {
                    self.events
                        .push_back(BalancedEvent::LineError(LineError::Frame(error)));
                    continue;
                }
            };
            let (control, address, asdu) = match &frame {
                Frame::Fixed { control, address } => (*control, *address, None),
                Frame::Variable {
                    control,
                    address,
                    asdu,
                } => (*control, *address, Some(asdu.clone())),
                Frame::SingleCharacter => {
                    // E5 stands for ACK in balanced mode too.
                    let ack = Control::secondary(SecondaryFunction::Ack, false, false);
                    self.handle_answer(now, ack);
                    continue;
                }
            };
            if control.dir() == self.config.dir || address != self.config.address {
                continue;
            }
            if control.is_primary() {
                self.handle_request(control, asdu.as_deref());
            } else {
                self.handle_answer(now, control);
            }
        }
    }

    fn handle_line_pause(&mut self, now: Instant) {
        if let Some(error) = self.deframer.abandon_partial() {
            self.keep_idle(now);
            self.events
                .push_back(BalancedEvent::LineError(LineError::Frame(error)));
        }
    }

    fn handle_timeout(&mut self, now: Instant) {
        let overdue = self
            .outstanding
            .as_ref()
            .and_then(|request| request.deadline)
            .is_some_and(|deadline| now >= deadline);
        if !overdue {
            return;
        }
        let Some(mut request) = self.outstanding.take() else {
            return;
        };
        self.events.push_back(BalancedEvent::Timeout {
            request: request.function,
            attempt: request.attempt,
        });
        if request.attempt <= self.config.retries {
            request.attempt += 1;
            request.deadline = None;
            self.outstanding = Some(request);
            return;
        }
        if let Some(asdu) = request.asdu {
            self.queue.push_front(asdu);
        }
        let was_up = self.state == State::Up;
        self.go_down(now, was_up);
    }

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        if now < self.line_free_at {
            return None;
        }
        let bytes = if let Some(answer) = self.answers.pop_front() {
            answer
        } else if let Some(request) = self.outstanding.as_mut() {
            if request.deadline.is_some() {
                return None;
            }
            let on_line = self.config.line.transmit_time(request.bytes.len());
            request.deadline = Some(now + on_line + self.config.response_timeout);
            request.bytes.clone()
        } else {
            let (function, asdu) = self.next_request(now)?;
            let bytes = self.primary_frame(function, asdu.clone())?;
            let on_line = self.config.line.transmit_time(bytes.len());
            self.outstanding = Some(Request {
                function,
                bytes: bytes.clone(),
                asdu,
                attempt: 1,
                deadline: Some(now + on_line + self.config.response_timeout),
            });
            bytes
        };
        self.line_free_at =
            now + self.config.line.transmit_time(bytes.len()) + self.config.line.idle_time();
        self.last_traffic = now;
        Some(bytes)
    }

    fn next_deadline(&self) -> Option<Instant> {
        if !self.answers.is_empty() {
            return Some(self.line_free_at);
        }
        if let Some(request) = &self.outstanding {
            return Some(request.deadline.unwrap_or(self.line_free_at));
        }
        let due = match self.state {
            State::Down(until) => until,
            State::Unknown | State::Resetting => self.line_free_at,
            State::Up if !self.queue.is_empty() => self.line_free_at,
            State::Up => self.last_traffic + self.config.test_interval,
        };
        Some(due.max(self.line_free_at))
    }

    fn line(&self) -> LineSettings {
        self.config.line
    }
}
