//! A serial line on a virtual clock: one primary, many secondaries, frames that take
//! the time the line takes, and faults on demand. For scenario tests and the polling
//! benchmark, where a real line would make every run last minutes and no run repeat
//! the one before.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::deframer::Deframer;
use super::frame::Frame;
use super::primary::Primary;
use super::secondary::{Secondary, SecondaryApplication};

/// What happens to the next frame on the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// It is lost entirely.
    Lose,
    /// One octet in its middle is flipped (the receiver sees a broken frame).
    Corrupt,
}

struct Station {
    secondary: Secondary,
    app: Box<dyn SecondaryApplication>,
    alive: bool,
}

/// One primary and its secondaries on a line simulated in virtual time.
///
/// A request occupies the line for its transmit time; the addressed secondary answers
/// after its turnaround time; the answer occupies the line for its own transmit time
/// and reaches the primary then. Nothing else shares the line, as in unbalanced
/// transmission.
pub struct SimulatedLine {
    primary: Primary,
    stations: Vec<Station>,
    secondary_deframer: Deframer,
    now: Instant,
    turnaround: Duration,
    request_faults: VecDeque<Fault>,
    answer_faults: VecDeque<Fault>,
    busy: Duration,
}

impl SimulatedLine {
    /// A line with `primary` at virtual time `start`; secondaries answer after
    /// `turnaround`.
    pub fn new(primary: Primary, start: Instant, turnaround: Duration) -> SimulatedLine {
        SimulatedLine {
            secondary_deframer: Deframer::new(primary.config().address_size),
            primary,
            stations: Vec::new(),
            now: start,
            turnaround,
            request_faults: VecDeque::new(),
            answer_faults: VecDeque::new(),
            busy: Duration::ZERO,
        }
    }

    /// Connects a secondary with its application to the line.
    pub fn attach(&mut self, secondary: Secondary, app: Box<dyn SecondaryApplication>) {
        self.stations.push(Station {
            secondary,
            app,
            alive: true,
        });
    }

    /// Switches a secondary off (it hears nothing and answers nothing) or on again.
    pub fn set_alive(&mut self, address: u16, alive: bool) {
        for station in &mut self.stations {
            if station.secondary.config().address == address {
                station.alive = alive;
            }
        }
    }

    /// Applies `fault` to the next request the primary sends.
    pub fn fault_next_request(&mut self, fault: Fault) {
        self.request_faults.push_back(fault);
    }

    /// Applies `fault` to the next answer a secondary sends.
    pub fn fault_next_answer(&mut self, fault: Fault) {
        self.answer_faults.push_back(fault);
    }

    /// The primary.
    pub fn primary(&mut self) -> &mut Primary {
        &mut self.primary
    }

    /// A secondary's link layer and application.
    pub fn station(
        &mut self,
        address: u16,
    ) -> Option<(&mut Secondary, &mut (dyn SecondaryApplication + 'static))> {
        self.stations
            .iter_mut()
            .find(|station| station.secondary.config().address == address)
            .map(|station| (&mut station.secondary, station.app.as_mut()))
    }

    /// The virtual time.
    pub fn now(&self) -> Instant {
        self.now
    }

    /// How long frames have occupied the line.
    pub fn busy_time(&self) -> Duration {
        self.busy
    }

    /// Runs one exchange (a request and its answer, or a timeout); returns `false` when
    /// the primary has nothing to do at all.
    pub fn step(&mut self) -> bool {
        self.primary.handle_timeout(self.now);
        let Some(request) = self.primary.poll_transmit(self.now) else {
            return match self.primary.next_deadline() {
                Some(deadline) => {
                    self.now = self.now.max(deadline);
                    true
                }
                None => false,
            };
        };
        let line = self.primary.config().line;
        let on_line = line.transmit_time(request.len());
        self.busy += on_line;
        self.now += on_line;
        let Some(request) = apply(self.request_faults.pop_front(), request) else {
            return true;
        };
        self.secondary_deframer.push(&request);
        let mut answers = Vec::new();
        while let Some(next) = self.secondary_deframer.next_frame() {
            let Ok(frame) = next else { continue };
            for station in self.stations.iter_mut().filter(|station| station.alive) {
                if let Some(answer) = station.secondary.handle(&frame, station.app.as_mut()) {
                    answers.push(answer);
                }
            }
        }
        for answer in answers {
            let Ok(bytes) = answer_bytes(&answer, self.primary.config().address_size) else {
                continue;
            };
            let on_line = line.transmit_time(bytes.len());
            self.now += self.turnaround + on_line;
            self.busy += on_line;
            if let Some(bytes) = apply(self.answer_faults.pop_front(), bytes) {
                self.primary.handle_bytes(self.now, &bytes);
            }
        }
        // A corrupted frame's tail never completes: the line goes quiet after it.
        self.primary.handle_line_pause(self.now);
        self.secondary_deframer.abandon_partial();
        true
    }
}

fn answer_bytes(
    frame: &Frame,
    size: super::frame::AddressSize,
) -> Result<Vec<u8>, super::frame::EncodeError> {
    frame.to_bytes(size)
}

fn apply(fault: Option<Fault>, mut bytes: Vec<u8>) -> Option<Vec<u8>> {
    match fault {
        None => Some(bytes),
        Some(Fault::Lose) => None,
        Some(Fault::Corrupt) => {
            let middle = bytes.len() / 2;
            if let Some(octet) = bytes.get_mut(middle) {
                *octet ^= 0x5A;
            }
            Some(bytes)
        }
    }
}
