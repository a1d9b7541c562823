//! FT1.2's ends of a line as [`LineEndpoint`]s of the serial-line crate (bytes and time
//! in, bytes out): the primary, a secondary with its application, several secondaries
//! on one line.

use std::task::{Context, Poll};
use std::time::Instant;

use serial_line::{LineEndpoint, LineSettings};

use super::deframer::{DeframeError, Deframer};
use super::frame::Frame;
use super::primary::Primary;
use super::secondary::{Secondary, SecondaryApplication};

impl LineEndpoint for Primary {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        Primary::handle_bytes(self, now, bytes);
    }
    fn handle_line_pause(&mut self, now: Instant) {
        Primary::handle_line_pause(self, now);
    }
    fn handle_timeout(&mut self, now: Instant) {
        Primary::handle_timeout(self, now);
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        Primary::poll_transmit(self, now)
    }
    fn next_deadline(&self) -> Option<Instant> {
        Primary::next_deadline(self)
    }
    fn line(&self) -> LineSettings {
        self.config().line
    }
}

/// An application behind a secondary that also keeps time (cyclic data, time tags).
pub trait TimedApplication: SecondaryApplication {
    /// The clock advanced to `now`.
    fn handle_timeout(&mut self, now: Instant);
    /// When the application next wants [`TimedApplication::handle_timeout`].
    fn next_deadline(&self) -> Option<Instant>;
    /// As [`LineEndpoint::poll_wake`]: ready when the application has news.
    fn poll_wake(&mut self, _context: &mut Context<'_>) -> Poll<()> {
        Poll::Pending
    }
}

/// A secondary station with its application as a line endpoint: it answers each
/// frame addressed to it once the line has been idle for 33 bit times.
pub struct SecondaryStation<A> {
    line: LineSettings,
    deframer: Deframer,
    secondary: Secondary,
    app: A,
    answer: Option<(Instant, Vec<u8>)>,
    frame_errors: u64,
    last_error: Option<DeframeError>,
}

impl<A: TimedApplication> SecondaryStation<A> {
    /// A station on a line.
    pub fn new(line: LineSettings, secondary: Secondary, app: A) -> SecondaryStation<A> {
        SecondaryStation {
            deframer: Deframer::new(secondary.config().address_size),
            line,
            secondary,
            app,
            answer: None,
            frame_errors: 0,
            last_error: None,
        }
    }

    /// The application.
    pub fn app(&mut self) -> &mut A {
        &mut self.app
    }

    /// The application, once the line is done with.
    pub fn into_app(self) -> A {
        self.app
    }

    /// The link layer.
    pub fn secondary(&self) -> &Secondary {
        &self.secondary
    }

    /// Broken frames seen, and the last one's error.
    pub fn frame_errors(&self) -> (u64, Option<&DeframeError>) {
        (self.frame_errors, self.last_error.as_ref())
    }

    fn handle_frame(&mut self, now: Instant, frame: &Frame) {
        if let Some(answer) = self.secondary.handle(frame, &mut self.app) {
            if let Ok(bytes) = answer.to_bytes(self.secondary.config().address_size) {
                self.answer = Some((now + self.line.idle_time(), bytes));
            }
        }
    }
}

impl<A: TimedApplication> LineEndpoint for SecondaryStation<A> {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        self.deframer.push(bytes);
        while let Some(next) = self.deframer.next_frame() {
            match next {
                Ok(frame) => self.handle_frame(now, &frame),
                Err(error) => {
                    self.frame_errors += 1;
                    self.last_error = Some(error);
                }
            }
        }
    }

    fn handle_line_pause(&mut self, _now: Instant) {
        if let Some(error) = self.deframer.abandon_partial() {
            self.frame_errors += 1;
            self.last_error = Some(error);
        }
    }

    fn handle_timeout(&mut self, now: Instant) {
        self.app.handle_timeout(now);
    }

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        match &self.answer {
            Some((at, _)) if *at <= now => self.answer.take().map(|(_, bytes)| bytes),
            _ => None,
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let answer = self.answer.as_ref().map(|(at, _)| *at);
        match (answer, self.app.next_deadline()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    fn line(&self) -> LineSettings {
        self.line
    }

    fn poll_wake(&mut self, context: &mut Context<'_>) -> Poll<()> {
        self.app.poll_wake(context)
    }
}

/// Several secondary stations on one line (a multi-drop RS-485 bus, or relays behind a
/// star coupler) as one endpoint: every station hears every frame, the one addressed
/// answers. For simulated lines of many devices.
pub struct SharedLine<A> {
    stations: Vec<SecondaryStation<A>>,
}

impl<A: TimedApplication> SharedLine<A> {
    /// A line with these stations (all at the same speed).
    pub fn new(stations: Vec<SecondaryStation<A>>) -> SharedLine<A> {
        SharedLine { stations }
    }

    /// Every station.
    pub fn stations_mut(&mut self) -> impl Iterator<Item = &mut SecondaryStation<A>> {
        self.stations.iter_mut()
    }

    /// The station with this link address.
    pub fn station(&mut self, address: u16) -> Option<&mut SecondaryStation<A>> {
        self.stations
            .iter_mut()
            .find(|station| station.secondary().config().address == address)
    }
}

impl<A: TimedApplication> LineEndpoint for SharedLine<A> {
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]) {
        for station in &mut self.stations {
            station.handle_bytes(now, bytes);
        }
    }

    fn handle_line_pause(&mut self, now: Instant) {
        for station in &mut self.stations {
            station.handle_line_pause(now);
        }
    }

    fn handle_timeout(&mut self, now: Instant) {
        for station in &mut self.stations {
            LineEndpoint::handle_timeout(station, now);
        }
    }

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        self.stations
            .iter_mut()
            .find_map(|station| station.poll_transmit(now))
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.stations
            .iter()
            .filter_map(LineEndpoint::next_deadline)
            .min()
    }

    fn line(&self) -> LineSettings {
        self.stations
            .first()
            .map_or_else(LineSettings::default, LineEndpoint::line)
    }
}
